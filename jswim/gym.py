"""Gymnasium environments of jswim's worlds (optional extra: ``pip install 'jswim[gym]'``).

``import jswim.gym`` registers, under the ``jswim/`` namespace, every id of
`ENVIRONMENTS` with ``max_episode_steps=200`` (Gymnasium's ``TimeLimit``: override with
``gym.make(id, max_episode_steps=...)``) and a ``vector_entry_point`` on the batched JAX step
(`JswimVectorEnv`, what ``gym.make_vec(id, num_envs)`` builds):

==================================  ===============================================================
``jswim/Purcell-v0``                Purcell's three-link swimmer, the paper's world
``jswim/NG-v0``                     Najafi-Golestanian's three-sphere swimmer, the paper's world
``jswim/FourLink-v0``               the four-link swimmer (three hinges)
``jswim/FourSphere-v0``             the four-sphere swimmer (three arms)
``jswim/PurcellContinuous-v0``      Purcell with Box actions (every joint at its ROC each step)
``jswim/NGContinuous-v0``           NG with Box actions
``jswim/PurcellWall-v0``            Purcell's swimmer in a plane 2 link lengths above a no-slip wall
``jswim/NGWall-v0``                 one NG swimmer 5 a above a no-slip wall
``jswim/NGPair-v0``                 two NG swimmers 30 a apart in the unbounded fluid
``jswim/NGSchool-v0``               three NG swimmers in a line, 30 a apart
``jswim/NavigatePurcell-v0``        Purcell (K = 2) sent to a point 3 link lengths away at 90 degrees
``jswim/NavigatePurcellFlow-v0``    Purcell (K = 2) sent 3 link lengths straight ahead across a uniform
                                    stream of half its swimming speed (`jswim.env.door.NAVIGATE_FLOW`)
==================================  ===============================================================

A navigation id (a world with a ``target``, docs/navigation.md) ends its own episodes: it
terminates when the target is reached and truncates when its budget is spent
([`Environment.termination`][jswim.env.base.Environment.termination]); it registers no
``max_episode_steps``.

Each is a `JswimEnv` over a `jswim.env.door.Door`: actions are the world's integer
codes (``Discrete(n_actions)``) or, with ``continuous=True``, ``Box(-1, 1, (n_dof,))`` (every
DOF at once in the paper's worlds, the DOF of largest ``|a_i|`` in scenes); the observation and
its options (``history``, ``separation``) are `jswim.env.door`'s; the reward is
``StepInfo.progress`` toward the target ``direction`` (a navigation id: toward its target). Any
`jswim.make` option goes by keyword (``flow=`` a `jswim.env.flows` flow among them); an unknown
one is refused in one line naming the valid ones::

    import gymnasium as gym
    import jswim.gym
    env = gym.make("jswim/NGWall-v0", zeta=0.5, direction="-x", render_mode="rgb_array")
    envs = gym.make_vec("jswim/Purcell-v0", num_envs=4096)   # one jitted step for all

``render_mode``: ``"rgb_array"`` (frames drawn by `jswim.viz.frame`) or ``"human"`` (the
same frames in a matplotlib window). A forked worker (``AsyncVectorEnv``'s default context on
Linux) is refused in one line: JAX does not survive ``fork``; pass
``vector_kwargs={"context": "spawn"}``, or use the vector entry point.
"""

from __future__ import annotations

import os
from typing import Any, ClassVar

import gymnasium
import jax
import jax.numpy as jnp
import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from jswim.env.door import IDS, Door, DoorState, build
from jswim.env.randomness import noise
from jswim.errors import ConfigError

__all__ = [
    "ENVIRONMENTS",
    "MAX_EPISODE_STEPS",
    "RENDER_FPS",
    "JswimEnv",
    "JswimVectorEnv",
    "register",
]

#: The registered ids (`jswim.env.door.IDS` under ``jswim/``) and their
#: `jswim.env.door.build` arguments.
ENVIRONMENTS: dict[str, dict[str, Any]] = {f"jswim/{name}": kw for name, kw in IDS.items()}

#: Steps per episode of every registered id (Gymnasium's ``max_episode_steps``).
MAX_EPISODE_STEPS = 200
#: Frames per second of ``render_mode="human"`` (and the ``render_fps`` recorders read).
RENDER_FPS = 8

_forked = False


def _mark_forked() -> None:
    global _forked
    _forked = True


os.register_at_fork(after_in_child=_mark_forked)


def _refuse_fork() -> None:
    if _forked:
        raise ConfigError(
            "jswim environments cannot run in a forked process (JAX does not survive fork): "
            "use gym.make_vec(id, num_envs) (one batched step), or "
            "vectorization_mode='async' with vector_kwargs={'context': 'spawn'}"
        )


def _check_render_mode(mode: str | None, modes: list[str]) -> str | None:
    if mode is not None and mode not in modes:
        raise ConfigError(f"render_mode must be one of {', '.join(modes)} or None, got {mode!r}")
    return mode


def _reset(door: Door, key: jax.Array, params: Any) -> tuple[DoorState, jax.Array]:
    return door.reset(key, params)


def _step(door: Door, key: jax.Array, state: DoorState, action: Any, params: Any) -> tuple:
    state, obs, info = door.step(key, state, action, params)
    terminated, truncated = door.world.termination(state.env_state, params)
    return (
        state,
        obs,
        info.progress,
        door.position(state.env_state, params),
        info.stuck,
        info.contact,
        terminated,
        truncated,
    )


_reset_jit = jax.jit(_reset, static_argnums=0)
_step_jit = jax.jit(_step, static_argnums=0)


def _spaces(door: Door) -> tuple[spaces.Space, spaces.Box]:
    n = door.world.n_dof
    action = (
        spaces.Box(-1.0, 1.0, (n,), np.float32)
        if door.continuous
        else spaces.Discrete(door.world.n_actions)
    )
    low, high = door.bounds()
    return action, spaces.Box(low, high, dtype=np.float32)


class JswimEnv(gymnasium.Env):
    """A jswim world as a Gymnasium environment (module docs).

    Parameters
    ----------
    swimmer, scene
        As `jswim.make`.
    render_mode : {"rgb_array", "human"}, optional
    **options
        ``continuous``, ``history``, ``separation`` (`jswim.env.door.build`) and
        `jswim.make`'s options (``zeta``, ``direction``, ``init``, ``roc_levels``, ``target``,
        ``flow``, model options).

    Raises
    ------
    ConfigError
        An unknown keyword or value (one line), or construction in a forked process.
    """

    metadata: ClassVar[dict[str, Any]] = {
        "render_modes": ["rgb_array", "human"],
        "render_fps": RENDER_FPS,
    }

    def __init__(
        self,
        swimmer: str = "purcell",
        scene: Any = None,
        *,
        render_mode: str | None = None,
        **options: Any,
    ) -> None:
        _refuse_fork()
        self.render_mode = _check_render_mode(render_mode, self.metadata["render_modes"])
        self.door, self.params = build(swimmer, scene, **options)
        self.action_space, self.observation_space = _spaces(self.door)
        self._state: DoorState | None = None
        self._window: dict[str, Any] = {}

    def _key(self) -> jax.Array:
        # Every draw from the env's seeded generator: reset(seed=...) makes an episode repeatable.
        return jax.random.PRNGKey(int(self.np_random.integers(2**31)))

    def reset(
        self, *, seed: int | None = None, options: dict | None = None
    ) -> tuple[np.ndarray, dict]:
        super().reset(seed=seed)
        self._state, obs = _reset_jit(self.door, self._key(), self.params)
        if self.render_mode == "human":
            self.render()
        return np.asarray(obs, np.float32), {}

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict]:
        if self._state is None:
            raise RuntimeError("call reset() before step()")
        a = np.asarray(action, np.float32) if self.door.continuous else np.int32(action)
        self._state, obs, reward, position, stuck, contact, terminated, truncated = _step_jit(
            self.door, self._key(), self._state, a, self.params
        )
        info = {
            "position": np.asarray(position, np.float64),
            "stuck": bool(stuck),
            "contact": bool(contact),
        }
        if self.render_mode == "human":
            self.render()
        return np.asarray(obs, np.float32), float(reward), bool(terminated), bool(truncated), info

    def render(self) -> np.ndarray | None:
        """The current state as an RGB array ``(360, 480, 3)`` uint8 (``"rgb_array"``), or shown
        in a window (``"human"``); ``None`` without a render mode."""
        if self.render_mode is None or self._state is None:
            return None
        from jswim.viz.frame import state_frame  # lazy: matplotlib only when frames are asked for

        frame = state_frame(
            self.door.world, self._state.env_state, self.params, int(self._state.time)
        )
        if self.render_mode == "human":
            from jswim.viz.frame import show_frame  # lazy: a window only when one is asked for

            show_frame(frame, RENDER_FPS, self._window)
            return None
        return frame


def _vector_reset(door: Door, keys: jax.Array, params: Any) -> tuple[DoorState, jax.Array]:
    return jax.vmap(door.reset, in_axes=(0, None))(keys, params)


def _vector_step(
    door: Door,
    max_steps: int,
    key: jax.Array,
    states: DoorState,
    done: jax.Array,
    actions: jax.Array,
    params: Any,
) -> tuple:
    """Every env one step; an env whose episode ended at the previous call starts afresh
    instead (Gymnasium's next-step autoreset: reward 0, not done, the action ignored). The noise
    of the batch is counter-based (`jswim.env.noise`: one hash per two swimmers), and the
    resets are computed only in the steps that have one."""
    n = done.shape[0]
    k_step, k_reset = jax.random.split(key)
    s = door.world.n_swimmers
    dtype = door.world.dtype(states.env_state)
    y = noise(k_step, n * s).astype(dtype).reshape(n, s)
    stepped, obs, info = jax.vmap(door.advance, in_axes=(0, 0, 0, None))(states, actions, y, params)
    ended, cut = jax.vmap(door.world.termination, in_axes=(0, None))(stepped.env_state, params)

    def restart(carry):
        stepped, obs = carry
        fresh, obs0 = _vector_reset(door, jax.random.split(k_reset, n), params)
        pick = lambda a, b: jnp.where(jnp.reshape(done, (n,) + (1,) * (a.ndim - 1)), a, b)
        return jax.tree.map(pick, fresh, stepped), pick(obs0, obs)

    states, obs = jax.lax.cond(jnp.any(done), restart, lambda c: c, (stepped, obs))
    reward = jnp.where(done, 0.0, info.progress)
    terminated = ~done & ended
    truncated = ~done & ~ended & (cut | (states.time >= max_steps))
    return states, obs, reward, terminated, truncated


_vector_reset_jit = jax.jit(_vector_reset, static_argnums=0)
_vector_step_jit = jax.jit(_vector_step, static_argnums=(0, 1))


class JswimVectorEnv(VectorEnv):
    """``num_envs`` copies of a world stepped by one jitted, vmapped JAX call (the
    ``vector_entry_point`` of every registered id).

    Autoreset follows Gymnasium 1.x's default, ``AutoresetMode.NEXT_STEP``: the step after an
    episode ends resets that env (its action ignored, reward 0, neither flag set). Episodes are
    truncated after ``max_episode_steps`` (default 200; a navigation world: its own budget), and
    a navigation world's terminate at the target. ``reset(seed=s)``: env ``i``'s
    randomness comes from ``s`` (a list: its first entry) and ``i``.

    Parameters
    ----------
    num_envs : int
    swimmer, scene, render_mode, **options
        As `JswimEnv`; ``render_mode="rgb_array"`` draws env 0.
    max_episode_steps : int
    """

    metadata: ClassVar[dict[str, Any]] = {
        "render_modes": ["rgb_array"],
        "render_fps": RENDER_FPS,
        "autoreset_mode": AutoresetMode.NEXT_STEP,
    }

    def __init__(
        self,
        num_envs: int = 1,
        swimmer: str = "purcell",
        scene: Any = None,
        *,
        max_episode_steps: int | None = None,
        render_mode: str | None = None,
        **options: Any,
    ) -> None:
        _refuse_fork()
        if max_episode_steps is None:  # a navigation world truncates at its own budget
            max_episode_steps = 2**31 - 1 if "target" in options else MAX_EPISODE_STEPS
        if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
            raise ConfigError(f"num_envs must be a whole number >= 1, got {num_envs!r}")
        if (
            isinstance(max_episode_steps, bool)
            or not isinstance(max_episode_steps, int)
            or max_episode_steps < 1
        ):
            raise ConfigError(
                f"max_episode_steps must be a whole number >= 1, got {max_episode_steps!r}"
            )
        self.render_mode = _check_render_mode(render_mode, self.metadata["render_modes"])
        self.door, self.params = build(swimmer, scene, **options)
        self.num_envs = num_envs
        self.max_episode_steps = max_episode_steps
        self.single_action_space, self.single_observation_space = _spaces(self.door)
        self.action_space = batch_space(self.single_action_space, num_envs)
        self.observation_space = batch_space(self.single_observation_space, num_envs)
        self._key = jax.random.PRNGKey(0)
        self._states: DoorState | None = None
        self._done = jnp.zeros((num_envs,), bool)

    def reset(
        self, *, seed: int | list[int] | None = None, options: dict | None = None
    ) -> tuple[np.ndarray, dict]:
        if isinstance(seed, (list, tuple)):
            seed = seed[0]
        if seed is not None:
            self._key = jax.random.PRNGKey(int(seed))
        self._key, k = jax.random.split(self._key)
        self._states, obs = _vector_reset_jit(
            self.door, jax.random.split(k, self.num_envs), self.params
        )
        self._done = jnp.zeros((self.num_envs,), bool)
        return np.asarray(obs, np.float32), {}

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
        if self._states is None:
            raise RuntimeError("call reset() before step()")
        dtype = np.float32 if self.door.continuous else np.int32
        actions = jnp.asarray(np.asarray(actions, dtype))
        self._key, k = jax.random.split(self._key)
        self._states, obs, reward, terminated, truncated = _vector_step_jit(
            self.door, self.max_episode_steps, k, self._states, self._done, actions, self.params
        )
        self._done = terminated | truncated
        return (
            np.asarray(obs, np.float32),
            np.asarray(reward, np.float64),
            np.asarray(terminated),
            np.asarray(truncated),
            {},
        )

    def render(self) -> np.ndarray | None:
        """Env 0's state as an RGB array (``render_mode="rgb_array"``), else ``None``."""
        if self.render_mode is None or self._states is None:
            return None
        from jswim.viz.frame import state_frame  # lazy: matplotlib only when frames are asked for

        first = jax.tree.map(lambda v: v[0], self._states)
        return state_frame(self.door.world, first.env_state, self.params, int(first.time))


def register() -> None:
    """Register `ENVIRONMENTS` with Gymnasium (done on import; again is harmless)."""
    for env_id, kwargs in ENVIRONMENTS.items():
        if env_id not in gymnasium.registry:
            gymnasium.register(
                env_id,
                entry_point="jswim.gym:JswimEnv",
                vector_entry_point="jswim.gym:JswimVectorEnv",
                # a navigation world ends its own episodes (its budget)
                max_episode_steps=None if "target" in kwargs else MAX_EPISODE_STEPS,
                kwargs=dict(kwargs),
            )


register()
