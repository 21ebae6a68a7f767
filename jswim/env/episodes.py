"""One rollout for any world of the protocol ([`jswim.env.base`][jswim.env.base]), and its batch.

``rollout(env, params, key, actions)`` resets with ``key`` and steps with ``split(key, T)``, the
keys [`jswim.env.rollout`][jswim.env.rollouts.rollout] and [`jswim.scenes.scene_rollout`][jswim.scenes.rollout.scene_rollout] use, so a world's protocol
rollout and its own rollout step through the same numbers.
"""

from __future__ import annotations

import functools
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
from jax import Array

from jswim import reprs
from jswim.env.base import Environment, Observation, StepInfo
from jswim.env.randomness import seed_key


class Trajectory(NamedTuple):
    """What a rollout did; leading axis = steps (after a batch axis for [`rollout_batch`][jswim.env.episodes.rollout_batch]).

    ``state`` and ``obs`` are the state after each step and its [`Observation`][jswim.env.base.Observation]; ``info``
    the step's [`StepInfo`][jswim.env.base.StepInfo]."""

    state: Any
    obs: Observation
    info: StepInfo

    __repr__ = reprs.trajectory_text
    _repr_html_ = reprs.trajectory_html


def _as_key(key: Array | int) -> Array:
    return seed_key(key) if isinstance(key, int) else key


def _scan(env: Environment, params: Any, key: Array, actions: Array) -> Trajectory:
    state = env.reset(key, params)
    keys = jax.random.split(key, actions.shape[0])

    def body(st: Any, inp: tuple[Array, Array]) -> tuple[Any, Trajectory]:
        k, a = inp
        st, info = env.step(k, st, a, params)
        return st, Trajectory(st, env.observe(st, params), info)

    _, out = jax.lax.scan(body, state, (keys, actions))
    return out


_run = jax.jit(_scan, static_argnums=0)


def rollout(env: Environment, params: Any, key: Array | int, actions: Any) -> Trajectory:
    """Run a given action sequence in any world.

    Parameters
    ----------
    env : Environment
        The world ([`jswim.make`][jswim.env.worlds.make]).
    params : pytree
        Its params (unbatched).
    key : PRNG key or int
        Reset key; step ``t`` draws its noise from ``split(key, T)[t]``.
    actions : array (T,) int or (T, n_dof) float
        Integer action codes or float ROC vectors ([`jswim.env.base`][jswim.env.base]).

    Returns
    -------
    Trajectory
        JAX arrays in the world's working dtype, one entry per step.
    """
    return _run(env, params, _as_key(key), jnp.asarray(actions))


@functools.partial(jax.jit, static_argnums=(0, 4))
def _run_batch(
    env: Environment, params: Any, keys: Array, actions: Array, params_axes: Any
) -> Trajectory:
    return jax.vmap(_scan, in_axes=(None, params_axes, 0, 0))(env, params, keys, actions)


def rollout_batch(
    env: Environment, params: Any, key: Array | int, actions: Any, *, params_axes: Any = None
) -> Trajectory:
    """[`rollout`][jswim.env.episodes.rollout] of a batch: ``actions`` ``(B, T)`` / ``(B, T, n_dof)``, member ``i`` with
    key ``split(key, B)[i]``, one vectorised scan (``vmap``, no Python loop over members).

    ``params_axes`` is ``vmap``'s ``in_axes`` prefix for ``params`` (``None``: shared; e.g.
    [`jswim.env.param_axes`][jswim.env.params.param_axes] for per-member ``zeta`` or ``direction``); it must be hashable.
    """
    actions = jnp.asarray(actions)
    keys = jax.random.split(_as_key(key), actions.shape[0])
    return _run_batch(env, params, keys, actions, params_axes)
