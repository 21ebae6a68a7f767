"""The worlds PPO learns in: one small adapter per environment (reset, observe, step).

:func:`jswim.agents.ppo._train` asks a world for a learner's start state, its observation and one
step (the DOF chosen, its real ROC in [-1, 1], the noise variables), and gets back the new state,
the step's reward and what the run records. Two worlds:

* :class:`BulkEnv`: the paper's swimmer alone in the fluid (:mod:`jswim.env`), observed through
  its DOFs scaled to [-1, 1]; the reward is ``StepInfo.progress``. The bulk PPO numbers are this
  world's.
* :class:`SceneEnv`: a scene of :mod:`jswim.scenes` (a wall, obstacles, a pair; issue 19). The
  DOFs are the joint arms (swimmer ``s`` owns DOFs ``2s``, ``2s + 1``, 0-based, as in
  :mod:`jswim.agents.scene_env`); with a wall the observation also holds each swimmer's height
  and tilt, scaled (``ln(z / 10 a)`` and ``tilt / 0.5 rad``: about [-1.6, 1.6] over the studies'
  3-50 a). The reward is the progress of the swimmers' mean centroid x in the target direction
  (:func:`jswim.agents.scene_env.centroid_x`, the quantity the other scene agents are rewarded on),
  noisy as the scene's step is (``(1 + zeta Y_s)`` per swimmer). It reaches the scenes through
  :mod:`jswim.agents.scene_env`, their one door.

A world is static (hashable, one compilation per world); its ``params`` travel as a pytree whose
mapped leaves :attr:`params_axes` names (``vmap``'s ``in_axes`` prefix).
"""

from __future__ import annotations

import dataclasses
from typing import Any, NamedTuple

import jax.numpy as jnp
from jax import Array

from jswim import env as _env
from jswim.agents import scene_env
from jswim.env.base import scaled  # DOF values from [lo, hi] to [-1, 1]
from jswim.env.scene_world import features as scene_features
from jswim.env.scene_world import SceneTask  # a scene learner's world: the scene (shared), the direction (per learner)


@dataclasses.dataclass(frozen=True)
class BulkEnv:
    """The bulk swimmer of :mod:`jswim.env`; ``params`` is an :class:`EnvParams` batched along B."""

    n_dof: int
    params_axes: Any = 0
    n_noise: int = 1

    @property
    def n_obs(self) -> int:
        return self.n_dof

    def reset(self, key: Array, params: Any) -> Any:
        return _env.reset(key, params)

    def dofs(self, state: Any, params: Any) -> Array:
        return _env.dof_values(state, params)

    def observe(self, state: Any, params: Any) -> Array:
        return scaled(_env.dof_values(state, params), params.model.lo, params.model.hi)

    def step(self, state: Any, dof: Array, roc: Array, action: Array, y: Array, params: Any) -> tuple[Any, Array, tuple]:
        state, info = _env.advance(state, action, y[0], params, exact=False)
        return state, info.progress, (state.x, _env.dof_values(state, params), state.y, state.theta)


class SceneRecord(NamedTuple):
    """What a scene step records beyond the bulk fields (:attr:`jswim.agents.ppo.PPORun.scene`):
    every swimmer's centroid x (absolute), height and tilt after the step ``(S,)``, whether a
    non-zero ROC could not move its arm (``stuck``) and whether the step was refused at contact
    (``contact``): what the scene studies' rows and fates read."""

    xs: Array
    z: Array
    tilt: Array
    stuck: Array
    contact: Array


@dataclasses.dataclass(frozen=True)
class SceneEnv:
    """A scene of :mod:`jswim.scenes` (module docs); ``params`` is a :class:`SceneTask`."""

    n_swimmers: int
    wall: bool
    medium: str
    params_axes: Any = SceneTask(None, 0)

    @property
    def n_dof(self) -> int:
        return 2 * self.n_swimmers

    @property
    def n_noise(self) -> int:
        return self.n_swimmers

    @property
    def n_obs(self) -> int:
        return self.n_dof + (2 * self.n_swimmers if self.wall else 0)

    def reset(self, key: Array, params: SceneTask) -> Any:
        return scene_env.scene_reset(params.scene)

    def dofs(self, state: Any, params: SceneTask) -> Array:
        return state.arms.reshape(-1)

    def _x(self, state: Any) -> Array:
        return jnp.mean(scene_env.centroid_x(state, self.medium))

    def observe(self, state: Any, params: SceneTask) -> Array:
        return scene_features(state, params.scene, self.wall)

    def step(self, state: Any, dof: Array, roc: Array, action: Array, y: Array, params: SceneTask
             ) -> tuple[Any, Array, tuple]:
        x0 = self._x(state)
        new, obs = scene_env.advance(params.scene, state, (dof // 2, dof % 2, roc), y)
        x1 = self._x(new)
        reward = (params.direction * (x1 - x0)).astype(action.dtype)
        record = SceneRecord(obs.xs, obs.z, obs.tilt, obs.stuck, obs.contact)
        return new, reward, (x1, new.arms.reshape(-1), new.centre[0, 1], new.tilt[0], record)


@dataclasses.dataclass(frozen=True)
class ProtocolEnv:
    """Any world of the protocol (:class:`jswim.env.base.Environment`) as PPO's world: it sees
    the world's :meth:`~jswim.env.base.Environment.features`, is rewarded with
    :attr:`StepInfo.progress <jswim.env.base.StepInfo>`, and records the swimmers' mean x, the
    joint DOFs, and swimmer 1's y and orientation. ``params_axes``: ``vmap``'s axes of the
    learners' params (None: shared)."""

    env: Any
    params_axes: Any = None

    @property
    def n_dof(self) -> int:
        return self.env.n_dof

    @property
    def n_noise(self) -> int:
        return self.env.n_swimmers

    @property
    def n_obs(self) -> int:
        return self.env.n_features

    def reset(self, key: Array, params: Any) -> Any:
        return self.env.reset(key, params)

    def dofs(self, state: Any, params: Any) -> Array:
        return self.env.observe(state, params).dofs

    def observe(self, state: Any, params: Any) -> Array:
        return self.env.features(state, params)

    def step(self, state: Any, dof: Array, roc: Array, action: Array, y: Array, params: Any) -> tuple[Any, Array, tuple]:
        new, info = self.env.advance(state, action, y, params)
        obs = self.env.observe(new, params)
        x = jnp.mean(obs.position[:, 0])
        return new, info.progress.astype(action.dtype), (x, obs.dofs, obs.position[0, 1], obs.orientation[0])
