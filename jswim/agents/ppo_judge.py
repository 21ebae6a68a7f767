"""Judging PPO's runs ([`jswim.agents.ppo`][jswim.agents.ppo]): the success criterion for real-valued strokes
([`jswim.judging.shape_judge.judge_shapes`][jswim.judging.shape_judge.judge_shapes]) on exact, noiseless displacements, for the
paper's swimmer ([`evaluate`][jswim.agents.ppo_judge.evaluate]) and per swimmer in any world, through the world's judge's view
([`evaluate_swimmers`][jswim.agents.ppo_judge.evaluate_swimmers]).
"""

from __future__ import annotations

from typing import Any
from collections.abc import Sequence

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim import env as _env
from jswim.judging.gait import PAPER, GaitReport
from jswim.judging.shape_judge import SHAPE_TOL, judge_shapes


def exact_x(run: Any, params: Any, *, replay: bool = False) -> np.ndarray:
    """Noiseless centroid x after each step of recorded runs, float64 (B, steps).

    The runs' actions replayed in ``params``'s world from their start shapes with ``zeta = 0``
    (the judge measures exact displacements, as [`jswim.judging.gait.judge`][jswim.judging.gait.judge] does); when no
    run had noise, the recorded ``x`` is returned as it is, unless ``replay`` (runs made in another
    world of the same swimmer, e.g. Purcell's above a wall, measured in ``params``'s).
    """
    actions = np.asarray(run.actions)
    b = actions.shape[0]
    if not replay and not np.any(np.asarray(params.zeta) != 0):
        return np.asarray(run.x, np.float64)
    model = params.model
    levels = np.rint((np.asarray(run.dofs0, np.float64) - model.lo) / (model.hi - model.lo)).astype(
        np.int32
    )
    replay_params = _env.broadcast_params(params, b, zeta=0.0, init=levels)
    return np.asarray(_replay(replay_params, jnp.asarray(actions)), np.float64)


@jax.jit
def _replay(params: Any, actions: Array) -> Array:
    keys = jax.random.split(jax.random.PRNGKey(0), actions.shape[0])  # unused: starts are given
    states = jax.vmap(_env.reset)(keys, params)

    def body(states, a):
        states, info = jax.vmap(lambda s, act, p: _env.advance(s, act, 0.0, p))(states, a, params)
        return states, info.x

    return jnp.moveaxis(jax.lax.scan(body, states, jnp.moveaxis(actions, 0, 1))[1], 0, 1)


def evaluate(
    run: Any, params: Any, *, criterion: Any = None, tol: float | None = None, replay: bool = False
) -> Any:
    """Judge training runs with the success criterion for real-valued strokes
    ([`jswim.judging.shape_judge.judge_shapes`][jswim.judging.shape_judge.judge_shapes]: a cycle is a return to the same shape within ``tol``
    of the range, default `jswim.judging.shape_judge.SHAPE_TOL`), on exact displacements.

    Runs of any other world are judged per swimmer through its judge's view
    ([`evaluate_swimmers`][jswim.agents.ppo_judge.evaluate_swimmers]). ``replay``: the displacements are those of the moves replayed in
    ``params``'s world ([`exact_x`][jswim.agents.ppo_judge.exact_x]), for runs trained in another world of the same swimmer.

    Returns
    -------
    GaitReport
        Per learner: ``learned``, ``steps_to_learn`` (from 1, -1 when never), ``success``, ...
    """
    b = np.asarray(run.x).shape[0]
    return judge_shapes(
        np.asarray(run.dofs),
        exact_x(run, params, replay=replay),
        _env.broadcast_params(params, b),
        dofs0=np.asarray(run.dofs0),
        criterion=PAPER if criterion is None else criterion,
        tol=SHAPE_TOL if tol is None else tol,
    )


def evaluate_swimmers(
    run: Any,
    view: Sequence[Any],
    direction: Any = 1,
    *,
    criterion: Any = None,
    tol: float | None = None,
) -> Any:
    """Judge runs as the scene studies judge their agents (lattice moves:
    `jswim.studies.scene_studies._judge`): the success criterion on each swimmer's own moves, with
    the displacements of the paper's swimmer of the world's judge's view
    ([`Environment.judge_view`][jswim.env.base.Environment.judge_view]: noiseless, bulk fluid,
    one per swimmer, from its start); here the shape judge for real ROCs
    ([`jswim.judging.shape_judge.judge_shapes`][jswim.judging.shape_judge.judge_shapes]), each swimmer's moves replayed in
    `jswim.env`.

    One swimmer: its run judged as it is. A pair (a learner steering both swimmers): swimmer ``s``'s
    own moves (the steps whose DOF is one of its arms), in order, are its stroke; the other
    swimmer's steps are left out, as if it paused. The pair **succeeds** when both swimmers'
    own move sequences do (and has learned when both have); fewer than four own moves (the
    shortest stroke) fail. ``steps_to_learn`` is the later of the two swimmers', counted in their
    own moves (the lattice judge's convention); ``period`` is the sum of the two periods (the
    length of the joint stroke when the swimmers alternate); ``per_step`` and ``fraction`` are the
    mean of the two swimmers' (each per own move); ``cycle`` is swimmer 1's.

    Parameters
    ----------
    run : PPORun
        Leading axis B.
    view : sequence of EnvParams
        The world's judge's view, one paper's swimmer per swimmer.
    direction : int or array (B,)
        Each run's target direction.

    Returns
    -------
    GaitReport
        One verdict per learner (leading axis B).
    """
    criterion = PAPER if criterion is None else criterion
    tol = SHAPE_TOL if tol is None else tol
    n_sw = len(view)
    actions = np.asarray(run.actions)
    dofs = np.asarray(run.dofs, np.float64)
    owner = (np.asarray(run.dof, np.int64) - 1) // 2  # the swimmer each step moved (0-based)
    b = actions.shape[0]
    dirs = np.broadcast_to(np.asarray(direction, np.int32), (b,))
    reports = []
    for s, bulk in enumerate(view):
        model = bulk.model
        start = np.where(np.asarray(bulk.init) > 0, float(model.hi), float(model.lo))
        # The other swimmer's steps replayed as zero ROCs: no move, no displacement.
        own_actions = np.where((owner == s)[..., None], actions[..., 2 * s : 2 * s + 2], 0.0)
        x = np.asarray(
            _replay(_env.broadcast_params(bulk, b), jnp.asarray(own_actions)), np.float64
        )
        arms = dofs[..., 2 * s : 2 * s + 2]
        if n_sw == 1:
            reports.append(
                judge_shapes(
                    arms,
                    x,
                    _env.broadcast_params(bulk, b, direction=dirs),
                    dofs0=start,
                    criterion=criterion,
                    tol=tol,
                )
            )
            continue
        per = []
        for i in range(b):
            own = np.flatnonzero(owner[i] == s)
            if own.size < 4:
                per.append(None)
                continue
            per.append(
                judge_shapes(
                    arms[i, own][None],
                    x[i, own][None],
                    bulk.replace(direction=float(dirs[i])),
                    dofs0=start,
                    criterion=criterion,
                    tol=tol,
                )
            )
        reports.append(per)
    if n_sw == 1:
        return reports[0]

    def field(name: str, fill: Any) -> np.ndarray:  # (S, B): one swimmer's verdicts per learner
        return np.array(
            [[getattr(r, name)[0] if r is not None else fill for r in per] for per in reports]
        )

    learned = field("learned", False).all(0)
    success = field("success", False).all(0)
    stl = np.where(learned, field("steps_to_learn", -1).max(0), -1)
    period = np.where(learned, field("period", 0).sum(0), 0)
    per_step = np.where(learned, field("per_step", np.nan).mean(0), np.nan)
    fraction = np.where(learned, field("fraction", np.nan).mean(0), np.nan)
    width = max([r.cycle.shape[1] for per in reports for r in per if r is not None] or [1])
    cycle = np.full((b, width), -1, np.int64)
    for i, r in enumerate(reports[0]):
        if r is not None and learned[i]:
            cycle[i, : r.cycle.shape[1]] = r.cycle[0]
    return GaitReport(
        learned, stl, success, period, cycle, per_step, fraction, np.where(learned, stl - 1, -1)
    )
