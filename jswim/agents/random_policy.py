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

from jswim import sharding
from jswim.action_codes import check_action_set
from jswim.agents.qlearning import pick_uniform
from jswim.env.base import Environment
from jswim.env.discretiser import Cells
from jswim.env.episodes import Trajectory


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
        action = pick_uniform(mask, u[0])
        state, info = env.learner_advance(state, action, 2.0 * u[1:] - 1.0, params)
        x, y, theta = env.pose(state, params)
        return state, (
            action,
            x,
            y,
            theta,
            Trajectory(state, env.observe(state, params), info) if trace else None,
        )

    u = jax.random.uniform(k_run, (steps, 1 + env.n_swimmers))
    _, (acts, xs, ys, thetas, tr) = jax.lax.scan(body, state0, u)
    return RandomRun(acts, xs, cells.positions(state0, params), ys, thetas, tr)


def run(
    env: Environment,
    params: Any,
    key: Array,
    steps: int,
    action_set: str = "all",
    *,
    rocs: tuple[int, ...] | None = None,
    trace: bool = False,
    cells: Cells | None = None,
) -> RandomRun:
    """The random policy in any world ([`jswim.make`][jswim.env.registry.make]): every step a uniformly random code
    among those offered.

    Parameters
    ----------
    env : Environment
        The world (static).
    params : pytree
        Its params, shared by the runs or with a value per run in the leaves the world batches
        ([`Environment.batch_params`][jswim.env.base.Environment.batch_params]).
    key : PRNG key ``(2,)``, or keys ``(B, 2)``
        One run per key (start configuration when random, actions and noise); a batch is one
        scan vmapped over runs, sharded over every device.
    steps : int
        Steps per run.
    action_set : {"all", "shape-changing"}
        Offered actions (``jswim.action_codes.ACTION_SETS``), as in the LLM's prompt;
        the world's discretiser ([`Environment.cells`][jswim.env.base.Environment.cells]) says
        which moves change the shape.
    rocs : tuple of int, optional
        ROCs ``k`` offered (default: the world's; the paper's swimmer's
        [`offered_rocs`][jswim.action_codes.offered_rocs]).
    trace : bool
        Also record the world's state, observation and step info after each step.
    cells : Cells, optional
        A discretiser other than the world's.

    Returns
    -------
    RandomRun
        Per-step executed actions and X (the swimmers' mean x), start levels, swimmer 1's y and
        orientation (leading axis B for a batch of keys).

    Raises
    ------
    ConfigError
        An unknown ``action_set``.
    """
    check_action_set(action_set)
    cells = env.cells() if cells is None else cells
    rocs = None if rocs is None else tuple(rocs)
    key = jnp.asarray(key)
    if key.ndim == 1:
        return jax.tree.map(
            lambda v: v[0],
            run(env, params, key[None], steps, action_set, rocs=rocs, trace=trace, cells=cells),
        )
    n = key.shape[0]
    params, axes = env.batch_params(params, n)
    fn = functools.partial(
        _jitted, steps=steps, action_set=action_set, rocs=rocs, cells=cells, trace=trace, axes=axes
    )
    return sharding.apply_runs(fn, key, params, axes, n)


@functools.partial(
    jax.jit, static_argnames=("steps", "action_set", "rocs", "cells", "trace", "axes")
)
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
