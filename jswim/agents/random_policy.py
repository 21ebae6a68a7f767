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
from jswim.agents.defaults import default_rocs
from jswim.agents.qlearning import _k, _pick, offered_mask, positions
from jswim.env import EnvParams, advance, reset


class RandomRun(NamedTuple):
    """Per-run record (leading batch axis): executed actions, X after each step, start levels, and
    the centroid y and orientation (rad) after each step."""

    actions: Array
    x: Array
    levels0: Array
    y: Array
    orientation: Array


def _one(key: Array, params: EnvParams, steps: int, action_set: str, rocs: tuple[int, ...]) -> RandomRun:
    k_reset, k_run = jax.random.split(key)
    state0 = reset(k_reset, params)
    big_k = _k(params)

    def body(state, u):
        mask = offered_mask(positions(state, big_k), params.model, action_set, rocs, big_k)
        action = _pick(mask, u[0])
        state, _ = advance(state, action, 2.0 * u[1] - 1.0, params, exact=False)
        return state, (action, state.x, state.y, state.theta)

    _, (acts, xs, ys, thetas) = jax.lax.scan(body, state0, jax.random.uniform(k_run, (steps, 2)))
    return RandomRun(acts, xs, positions(state0, big_k), ys, thetas)


def run_batch(
    keys: Array, params: EnvParams, steps: int, action_set: str = "all", rocs: tuple[int, ...] | None = None
) -> RandomRun:
    """Run one random policy per key; ``params`` leaves may carry a leading batch axis.

    Parameters
    ----------
    keys : Array (B, 2)
        One key per run (start configuration when random, actions and noise).
    params : EnvParams
        Shared or batched (see :func:`jswim.agents.qlearning.batch_params`).
    steps : int
        Steps per run.
    action_set : {"all", "shape-changing"}
        Offered actions (:data:`jswim.actions.ACTION_SETS`), as in the LLM's prompt.
    rocs : tuple of int, optional
        ROCs offered (default: the swimmer's, e.g. (-1, 0, 1); every ``k`` in ``-K..K`` on the
        environment's ROC lattice, ``params.roc_levels``).
    """
    check_action_set(action_set)
    rocs = tuple(default_rocs(params.model, _k(params)) if rocs is None else rocs)
    return _jitted(bool(jnp.ndim(params.zeta) > 0))(keys, params, steps, action_set, rocs)


@functools.lru_cache(maxsize=None)
def _jitted(batched: bool):
    # One jitted function per batching mode: a new jax.jit object per call would compile again
    # at every call (about 2 s for a study's random-policy batch).
    fn = jax.vmap(_one, in_axes=(0, 0 if batched else None, None, None, None))
    return jax.jit(fn, static_argnums=(2, 3, 4))


class WorldRun(NamedTuple):
    """Per-step record of :func:`run_env` (leading axes: runs, steps): the action codes, the
    reward, and each swimmer's position ``(S, 2)`` after the step."""

    actions: Array
    progress: Array
    position: Array


def run_env(env: Any, params: Any, keys: Array, steps: int) -> WorldRun:
    """The random policy in any world of the protocol (:class:`jswim.env.base.Environment`):
    every step a uniformly random integer code of ``env.action_space(params)``, one run per key,
    one scan vmapped over runs (``params`` shared)."""
    return _run_env(env, params, keys, steps)


@functools.partial(jax.jit, static_argnums=(0, 3))
def _run_env(env: Any, params: Any, keys: Array, steps: int) -> WorldRun:
    space = env.action_space(params)

    def one(key: Array) -> WorldRun:
        k_reset, k_run = jax.random.split(key)

        def body(state, k):
            k_act, k_step = jax.random.split(k)
            action = space.sample(k_act)
            state, info = env.step(k_step, state, action, params)
            return state, WorldRun(action, info.progress, env.observe(state, params).position)

        return jax.lax.scan(body, env.reset(k_reset, params), jax.random.split(k_run, steps))[1]

    return jax.vmap(one)(keys)
