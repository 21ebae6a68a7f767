"""One rollout for any world of the protocol ([`jswim.env.base`][jswim.env.base]), one run or a batch.

``rollout(env, params, key, actions)`` resets with ``key`` and steps with ``split(key, T)``, the
keys the paper's world and the scenes' own stepping use, so a world's protocol rollout and its
own physics step through the same numbers. It is the one rollout loop of the library: the
moves-based shortcuts ([`rollout_moves`][jswim.env.rollouts.rollout_moves],
[`scene_rollout`][jswim.env.scene_rollouts.scene_rollout]) convert their moves to actions and
run it, keeping per step only the fields they return (``record``).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
from jax import Array

from jswim import reprs
from jswim.env.base import Environment, Observation, StepInfo
from jswim import sharding
from jswim.env.randomness import seed_key


class Trajectory(NamedTuple):
    """What a rollout did; leading axis = steps (after the batch axis of a batch).

    ``state`` and ``obs`` are the state after each step and its [`Observation`][jswim.env.base.Observation]; ``info``
    the step's [`StepInfo`][jswim.env.base.StepInfo]."""

    state: Any
    obs: Observation
    info: StepInfo

    __repr__ = reprs.trajectory_text
    _repr_html_ = reprs.trajectory_html


def _as_key(key: Array | int) -> Array:
    return seed_key(key) if isinstance(key, int) else key


def trajectory(env: Environment, params: Any, state: Any, info: StepInfo) -> Trajectory:
    """The default ``record`` of [`rollout`][jswim.env.episodes.rollout]: the state after the
    step, its observation and the step's info."""
    return Trajectory(state, env.observe(state, params), info)


#: What a rollout keeps of each step: ``record(env, params, state, info)`` -> a pytree of arrays
#: (``state`` after the step, ``info`` the step's); a module-level function, so that the jitted
#: loop is compiled once per world and record.
Record = Callable[[Environment, Any, Any, Any], Any]


def _scan(env: Environment, record: Record, params: Any, key: Array, actions: Array) -> Any:
    state = env.reset(key, params)
    keys = jax.random.split(key, actions.shape[0])

    def body(st: Any, inp: tuple[Array, Array]) -> tuple[Any, Any]:
        k, a = inp
        st, info = env.step(k, st, a, params)
        return st, record(env, params, st, info)

    _, out = jax.lax.scan(body, state, (keys, actions))
    return out


_run = jax.jit(_scan, static_argnums=(0, 1))


def rollout(
    env: Environment,
    params: Any,
    key: Array | int,
    actions: Any,
    *,
    record: Record = trajectory,
) -> Any:
    """Run given action sequences in any world: one run, or a batch in one vectorised scan.

    Parameters
    ----------
    env : Environment
        The world ([`jswim.make`][jswim.env.registry.make]).
    params : pytree
        Its params: shared, or for a batch with a value per run in the leaves the world batches
        ([`Environment.batch_params`][jswim.env.base.Environment.batch_params]).
    key : PRNG key or int, or keys ``(B, 2)``
        Run ``i`` of a batch resets with ``keys[i]`` (one key: ``split(key, B)[i]``); a run's step
        ``t`` draws its noise from ``split(run_key, T)[t]``.
    actions : array (T,) or (B, T) int, or (T, n_dof) or (B, T, n_dof) float
        Integer action codes or float ROC vectors ([`jswim.env.base`][jswim.env.base]); a leading axis ``B``
        makes a batch, sharded over every device (`jswim.sharding`).
    record : callable, optional
        What to keep of each step, ``record(env, params, state, info)`` (a module-level function:
        it is a static argument of the jitted loop). Default
        [`trajectory`][jswim.env.episodes.trajectory]: state, observation and info. A record that
        keeps less keeps a long batch's memory down (the rest is never stored).

    Returns
    -------
    Trajectory
        JAX arrays in the world's working dtype, one entry per step (after the batch axis); with
        ``record``, what it returns, stacked the same way.
    """
    actions = jnp.asarray(actions)
    one = 1 if jnp.issubdtype(actions.dtype, jnp.integer) else 2
    if actions.ndim == one:
        return _run(env, record, params, _as_key(key), actions)
    n = actions.shape[0]
    keys = jnp.asarray(_as_key(key))
    if keys.ndim == 1:
        keys = jax.random.split(keys, n)
    params, axes = env.batch_params(params, n)
    # The actions travel with the keys: on several devices both are padded and sharded by run.
    return sharding.apply_runs(
        lambda ka, p: _run_batch(env, record, p, *ka, axes), (keys, actions), params, axes, n
    )


@functools.partial(jax.jit, static_argnums=(0, 1, 5))
def _run_batch(
    env: Environment, record: Record, params: Any, keys: Array, actions: Array, params_axes: Any
) -> Any:
    return jax.vmap(_scan, in_axes=(None, None, params_axes, 0, 0))(
        env, record, params, keys, actions
    )
