"""Any world of the protocol where gymnax environments go: [`GymnaxEnv`][jswim.env.gymnax_env.GymnaxEnv] has gymnax's
``Environment`` interface (gymnax 1.x) without importing gymnax, so gymnax's wrappers
(``LogWrapper``, ...) and PureJaxRL-style training loops take it as they take gymnax's own.

gymnax's calls differ from the protocol's: ``reset(key, params) -> (obs, state)`` and
``step(key, state, action, params) -> (obs, state, reward, terminated, truncated, info)``, with
an automatic reset when an episode ends; ``step_env``/``reset_env`` are the single transitions.
Here an episode is ``max_steps`` steps (truncated; a swimmer's task has no natural end), the
observation is the world's [`features`][jswim.env.base.Environment.features], the reward
``StepInfo.progress``; ``info`` carries the swimmers' mean x, ``stuck`` and ``contact``.
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
from jax import Array

from jswim.env.base import Box, Discrete, Environment


class GymnaxState(NamedTuple):
    """The world's state and the step count of the episode (gymnax's ``state.time``)."""

    env_state: Any
    time: Array


@dataclasses.dataclass(frozen=True)
class GymnaxEnv:
    """A world in gymnax's interface (module docs). ``continuous``: float ROC vectors as actions
    (a ``Box``) instead of integer codes (a ``Discrete``)."""

    world: Environment
    max_steps: int = 200
    continuous: bool = False

    @property
    def default_params(self) -> Any:
        return self.world.default_params

    @property
    def name(self) -> str:
        return type(self.world).__name__

    @property
    def num_actions(self) -> int:
        return self.world.n_actions

    @functools.partial(jax.jit, static_argnames=("self",))
    def step(self, key: Array, state: GymnaxState, action: Any, params: Any = None) -> tuple:
        """gymnax's step: `step_env`, then a fresh episode where this one ended."""
        if params is None:
            params = self.default_params
        key_step, key_reset = jax.random.split(key)
        obs_st, state_st, reward, terminated, info = self.step_env(key_step, state, action, params)
        truncated = self.is_truncated(state_st, params)
        done = jnp.logical_or(terminated, truncated)
        obs_re, state_re = self.reset_env(key_reset, params)
        state = jax.tree.map(lambda r, s: jax.lax.select(done, r, s), state_re, state_st)
        obs = jax.lax.select(done, obs_re, obs_st)
        info = {
            **info,
            "terminated": terminated,
            "truncated": truncated,
            "final_observation": obs_st,
        }
        return obs, state, reward, terminated, truncated, info

    @functools.partial(jax.jit, static_argnames=("self",))
    def reset(self, key: Array, params: Any = None) -> tuple[Array, GymnaxState]:
        if params is None:
            params = self.default_params
        return self.reset_env(key, params)

    def step_env(self, key: Array, state: GymnaxState, action: Any, params: Any) -> tuple:
        env_state, info = self.world.step(key, state.env_state, action, params)
        new = GymnaxState(env_state, state.time + 1)
        x = jnp.mean(self.world.observe(env_state, params).position[:, 0])
        extra = {"x": x, "stuck": info.stuck, "contact": info.contact}
        return self.get_obs(new, params), new, info.progress, jnp.zeros((), bool), extra

    def reset_env(self, key: Array, params: Any) -> tuple[Array, GymnaxState]:
        state = GymnaxState(self.world.reset(key, params), jnp.zeros((), jnp.int32))
        return self.get_obs(state, params), state

    def observe(self, key: Array, state: GymnaxState, action: Any, params: Any) -> Array:
        return self.get_obs(state, params, key)

    def get_obs(self, state: GymnaxState, params: Any = None, key: Array | None = None) -> Array:
        params = self.default_params if params is None else params
        return self.world.features(state.env_state, params).astype(jnp.float32)

    def is_truncated(self, state: GymnaxState, params: Any) -> Array:
        return state.time >= self.max_steps

    def is_terminated(self, state: GymnaxState, params: Any) -> Array:
        return jnp.zeros((), bool)

    is_terminal = is_terminated

    def discount(self, state: GymnaxState, params: Any) -> Array:
        return jnp.ones((), jnp.float32)

    def action_space(self, params: Any = None) -> Discrete | Box:
        return self.world.roc_space(params) if self.continuous else self.world.action_space(params)

    def observation_space(self, params: Any = None) -> Box:
        return Box(-jnp.inf, jnp.inf, (self.world.n_features,), jnp.float32)
