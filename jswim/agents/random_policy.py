"""Random baseline: uniformly random actions from the same action set the LLM is offered.

It is the floor an LLM has to beat: a model that "swims" no better than this has learned nothing.
Runs are vectorised like the Q-learner (one ``lax.scan``, ``vmap`` over learners).
"""

from __future__ import annotations

import functools

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
from jax import Array

from jswim.actions import check_action_set
from jswim.agents import worlds
from jswim.agents.defaults import default_rocs
from jswim.agents.qlearning import _k, _paper, _pick
from jswim.agents.worlds import Cells
from jswim.env import EnvParams
from jswim.env.base import Environment


class RandomRun(NamedTuple):
    """Per-run record (leading batch axis): executed actions, X after each step (the swimmers'
    mean x), start levels (lattice positions), and swimmer 1's y (its height above a wall) and
    orientation (rad) after each step; ``trace`` (``trace=True``): the world's state, observation
    and step info after each step ([`jswim.env.episodes.Trajectory`][jswim.env.episodes.Trajectory])."""

    actions: Array
    x: Array
    levels0: Array
    y: Array
    orientation: Array
    trace: Any = None


def _one(
    key: Array,
    params: Any,
    steps: int,
    action_set: str,
    rocs: tuple[int, ...] | None,
    cells: Cells,
    trace: bool = False,
) -> RandomRun:
    env = cells.env
    k_reset, k_run = jax.random.split(key)
    state0 = env.reset(k_reset, params)

    def body(state, u):
        mask = cells.mask(cells.positions(state, params), params, action_set, rocs)
        action = _pick(mask, u[0])
        state, info = worlds.step(env, state, action, 2.0 * u[1:] - 1.0, params)
        x, y, theta = worlds.pose(env, state, params)
        return state, (
            action,
            x,
            y,
            theta,
            worlds.trace(env, state, info, params) if trace else None,
        )

    u = jax.random.uniform(k_run, (steps, 1 + env.n_swimmers))
    _, (acts, xs, ys, thetas, tr) = jax.lax.scan(body, state0, u)
    return RandomRun(acts, xs, cells.positions(state0, params), ys, thetas, tr)


def run_batch(
    keys: Array,
    params: EnvParams,
    steps: int,
    action_set: str = "all",
    rocs: tuple[int, ...] | None = None,
) -> RandomRun:
    """Run one random policy per key; ``params`` leaves may carry a leading batch axis.

    Parameters
    ----------
    keys : Array (B, 2)
        One key per run (start configuration when random, actions and noise).
    params : EnvParams
        Shared or batched (see `jswim.agents.qlearning.batch_params`).
    steps : int
        Steps per run.
    action_set : {"all", "shape-changing"}
        Offered actions (`jswim.actions.ACTION_SETS`), as in the LLM's prompt.
    rocs : tuple of int, optional
        ROCs offered (default: the swimmer's, e.g. (-1, 0, 1); every ``k`` in ``-K..K`` on the
        environment's ROC lattice, ``params.roc_levels``).
    """
    check_action_set(action_set)
    rocs = tuple(default_rocs(params.model, _k(params)) if rocs is None else rocs)
    axes = 0 if jnp.ndim(params.zeta) > 0 else None
    return _jitted(keys, params, steps, action_set, rocs, _paper(params), False, axes)


def run_env(
    env: Environment,
    params: Any,
    keys: Array,
    steps: int,
    action_set: str = "all",
    *,
    rocs: tuple[int, ...] | None = None,
    params_axes: Any = None,
    cells: Cells | None = None,
    trace: bool = False,
) -> RandomRun:
    """The random policy in any world of the protocol ([`jswim.env.base.Environment`][jswim.env.base.Environment], e.g.
    from [`jswim.make`][jswim.env.worlds.make]): every step a uniformly random code among those offered
    (``action_set``, ``rocs``: by default every ROC, the swimmer's own in the paper's world), one
    run per key, one scan vmapped over runs. ``params`` are shared, or batched along the runs as
    ``params_axes`` (hashable) says; ``cells`` the world's discretiser
    ([`jswim.agents.worlds.cells`][jswim.agents.worlds.cells]), whose lattice point says which moves change the shape.
    In the paper's world the runs of [`run_batch`][jswim.agents.random_policy.run_batch], number for number."""
    check_action_set(action_set)
    cells = worlds.cells(env) if cells is None else cells
    return _jitted(
        keys,
        params,
        steps,
        action_set,
        None if rocs is None else tuple(rocs),
        cells,
        trace,
        params_axes,
    )


@functools.partial(jax.jit, static_argnums=(2, 3, 4, 5, 6, 7))
def _jitted(
    keys: Array,
    params: Any,
    steps: int,
    action_set: str,
    rocs: Any,
    cells: Cells,
    trace: bool,
    axes: Any,
) -> RandomRun:
    return jax.vmap(_one, in_axes=(0, axes, None, None, None, None, None))(
        keys, params, steps, action_set, rocs, cells, trace
    )
