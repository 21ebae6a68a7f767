"""Gymnasium environments of jswim's worlds (optional extra: ``pip install 'jswim[gym]'``).

``import jswim.gym`` registers, under the ``jswim/`` namespace:

============================  =====================================================
``jswim/Purcell-v0``          Purcell's three-link swimmer, the paper's world
``jswim/NG-v0``               Najafi-Golestanian's three-sphere swimmer, the paper's world
``jswim/NGWall-v0``           one NG swimmer 5 a above a no-slip wall (a scene)
``jswim/NGPair-v0``           two NG swimmers 30 a apart in the unbounded fluid (a scene)
============================  =====================================================

Each is [`JswimEnv`][jswim.gym.JswimEnv] over a world of [`jswim.make`][jswim.env.worlds.make]: actions are the world's integer
codes (``Discrete(n_actions)``; ``continuous=True``: ROC vectors in ``Box(-1, 1, (n_dof,))``),
observations its [`features`][jswim.env.base.Environment.features] (float32), the reward
``StepInfo.progress`` toward the target ``direction``; an episode is truncated after
``max_steps`` steps (200). Any [`jswim.make`][jswim.env.worlds.make] option goes by keyword::

    import gymnasium as gym
    import jswim.gym
    env = gym.make("jswim/NGWall-v0", zeta=0.5, direction="-x")
"""

from __future__ import annotations

from typing import Any, ClassVar

import gymnasium
import jax
import jax.numpy as jnp
import numpy as np
from gymnasium import spaces

from jswim.env.worlds import make

#: The registered ids and their [`jswim.make`][jswim.env.worlds.make] arguments.
ENVIRONMENTS: dict[str, dict[str, Any]] = {
    "jswim/Purcell-v0": {"swimmer": "purcell"},
    "jswim/NG-v0": {"swimmer": "ng"},
    "jswim/NGWall-v0": {"swimmer": "ng", "scene": {"medium": "wall", "height": 5.0}},
    "jswim/NGPair-v0": {
        "swimmer": "ng",
        "scene": {"medium": "free", "swimmers": 2, "separation": 30.0},
    },
}


def _step(world: Any, key: jax.Array, state: Any, action: Any, params: Any) -> tuple:
    state, info = world.step(key, state, action, params)
    return state, world.features(state, params), info


def _reset(world: Any, key: jax.Array, params: Any) -> tuple:
    state = world.reset(key, params)
    return state, world.features(state, params)


_step_jit = jax.jit(_step, static_argnums=0)
_reset_jit = jax.jit(_reset, static_argnums=0)


class JswimEnv(gymnasium.Env):
    """A jswim world as a Gymnasium environment (module docs).

    Parameters
    ----------
    swimmer, scene, **kwargs
        As [`jswim.make`][jswim.env.worlds.make] (``zeta``, ``direction``, ``init``, ``roc_levels``, ...).
    max_steps : int
        Steps per episode (truncation).
    continuous : bool
        Float ROC vectors as actions instead of integer codes.
    """

    metadata: ClassVar[dict[str, Any]] = {"render_modes": []}

    def __init__(
        self,
        swimmer: str = "purcell",
        scene: Any = None,
        *,
        max_steps: int = 200,
        continuous: bool = False,
        **kwargs: Any,
    ) -> None:
        self.world, self.params = make(swimmer, scene, **kwargs)
        self.max_steps = int(max_steps)
        self.continuous = bool(continuous)
        if self.continuous:
            self.action_space = spaces.Box(-1.0, 1.0, (self.world.n_dof,), np.float32)
        else:
            self.action_space = spaces.Discrete(self.world.n_actions)
        # The DOFs are scaled to [-1, 1]; what a world adds (a height, a tilt) is unbounded.
        extra = self.world.n_features - self.world.n_dof
        low = np.array([-1.0] * self.world.n_dof + [-np.inf] * extra, np.float32)
        self.observation_space = spaces.Box(low, -low, dtype=np.float32)
        self._state: Any = None
        self._t = 0

    def _key(self) -> jax.Array:
        # Every draw from the env's seeded generator: reset(seed=...) makes an episode repeatable.
        return jax.random.PRNGKey(int(self.np_random.integers(2**31)))

    def reset(
        self, *, seed: int | None = None, options: dict | None = None
    ) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        self._state, obs = _reset_jit(self.world, self._key(), self.params)
        self._t = 0
        return np.asarray(obs, np.float32), {}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict]:
        if self._state is None:
            raise RuntimeError("call reset() before step()")
        if self.continuous:
            a = jnp.asarray(
                np.clip(np.asarray(action, np.float64), -1.0, 1.0), jnp.result_type(float)
            )
        else:
            a = jnp.asarray(int(action), jnp.int32)
        self._state, obs, info = _step_jit(self.world, self._key(), self._state, a, self.params)
        self._t += 1
        position = np.asarray(self.world.observe(self._state, self.params).position, np.float64)
        extra = {"position": position, "stuck": bool(info.stuck), "contact": bool(info.contact)}
        return (
            np.asarray(obs, np.float32),
            float(info.progress),
            False,
            self._t >= self.max_steps,
            extra,
        )


def register() -> None:
    """Register `ENVIRONMENTS` with Gymnasium (done on import; again is harmless)."""
    for env_id, kwargs in ENVIRONMENTS.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(env_id, entry_point="jswim.gym:JswimEnv", kwargs=dict(kwargs))


register()
