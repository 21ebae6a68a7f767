"""gymnax environments of jswim's worlds (optional extra: ``pip install 'jswim[gymnax]'``).

``jswim.gymnax.make(name, **options) -> (env, params)`` as ``gymnax.make`` does, for every name of
`jswim.env.door.IDS` (``"Purcell-v0"``, ``"NGPair-v0"``, ...; the Gymnasium ids without
``jswim/`` are the same worlds with the same observation, bounds and actions)::

    import jax
    import jswim.gymnax
    from gymnax.wrappers.purerl import FlattenObservationWrapper, LogWrapper

    env, params = jswim.gymnax.make("Purcell-v0")
    env = LogWrapper(FlattenObservationWrapper(env))
    obs, state = env.reset(jax.random.PRNGKey(0), params)
    obs, state, reward, terminated, truncated, info = env.step(key, state, action, params)

`JswimGymnax` subclasses gymnax's ``Environment`` and answers with gymnax's own spaces
(``Discrete``, ``Box`` with the finite bounds of `jswim.env.door.Door.bounds`), so gymnax's
wrappers (``LogWrapper``, ``FlattenObservationWrapper``, ``GymnaxToGymWrapper``,
``GymnaxToVectorGymWrapper``) and PureJaxRL's scripts take it as they take gymnax's own
environments. It is a plain object (wrappers may set attributes on it). Its params,
`Params`, hold the world's params and ``max_steps_in_episode`` (200 unless
``make(..., max_steps_in_episode=n)``): an episode is truncated there, and a navigation world's
(``"NavigatePurcell-v0"``; ``"NavigatePurcellFlow-v0"`` in a uniform cross-stream) also ends at
its target or its budget. The
reward is ``StepInfo.progress`` (float32); ``info`` carries the swimmers' mean ``x``, ``stuck``
and ``contact``.
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
from flax import struct
from gymnax.environments import environment, spaces
from jax import Array

from jswim.env.door import IDS, Door, DoorState, build
from jswim.errors import ConfigError

__all__ = ["MAX_STEPS_IN_EPISODE", "JswimGymnax", "Params", "make", "registered"]

#: Steps per episode unless ``make(..., max_steps_in_episode=n)``.
MAX_STEPS_IN_EPISODE = 200


@struct.dataclass
class Params:
    """gymnax params of a jswim world.

    Attributes
    ----------
    world : pytree
        The world's params (`jswim.make`'s second value; batched leaves may be vmapped).
    max_steps_in_episode : int
        Steps after which an episode is truncated.
    """

    world: Any = None
    max_steps_in_episode: int = MAX_STEPS_IN_EPISODE


class JswimGymnax(environment.Environment):
    """A jswim world in gymnax's interface (module docs).

    Parameters
    ----------
    door : Door
        The world, its observation and its action reading (`jswim.env.door.build`).
    world_params : pytree
        The world's params, the default `Params`' ``world``.
    max_steps_in_episode : int
    """

    def __init__(
        self, door: Door, world_params: Any, max_steps_in_episode: int = MAX_STEPS_IN_EPISODE
    ) -> None:
        super().__init__()
        self.door = door
        self._params = Params(world_params, int(max_steps_in_episode))

    @property
    def default_params(self) -> Params:
        return self._params

    @property
    def name(self) -> str:
        return f"jswim/{type(self.door.world).__name__}"

    @property
    def num_actions(self) -> int:
        return self.door.world.n_actions

    def step_env(
        self, key: Array, state: DoorState, action: Any, params: Params
    ) -> tuple[Array, DoorState, Array, Array, dict[str, Any]]:
        state, obs, info = self.door.step(key, state, action, params.world)
        extra = {
            "x": self.door.position(state.env_state, params.world)[0],
            "stuck": info.stuck,
            "contact": info.contact,
        }
        done = self.is_terminated(state, params)
        return obs, state, info.progress.astype(jnp.float32), done, extra

    def reset_env(self, key: Array, params: Params) -> tuple[Array, DoorState]:
        state, obs = self.door.reset(key, params.world)
        return obs, state

    def get_obs(self, state: DoorState, params: Params | None = None, key: Any = None) -> Array:
        params = self.default_params if params is None else params
        return self.door.observation(state, params.world)

    def is_terminated(self, state: DoorState, params: Params) -> Array:
        """The world's end of an episode (a navigation target reached or its budget spent;
        never in the other worlds); gymnax adds the ``max_steps_in_episode`` truncation."""
        terminated, truncated = self.door.world.termination(state.env_state, params.world)
        return terminated | truncated

    def action_space(self, params: Params | None = None) -> spaces.Discrete | spaces.Box:
        """``Discrete(n_actions)``, or ``Box(-1, 1, (n_dof,))`` with ``continuous=True``."""
        if self.door.continuous:
            return spaces.Box(-1.0, 1.0, (self.door.world.n_dof,), jnp.float32)
        return spaces.Discrete(self.door.world.n_actions)

    def observation_space(self, params: Params | None = None) -> spaces.Box:
        """The observation's finite bounds (`jswim.env.door.Door.bounds`), float32."""
        low, high = self.door.bounds()
        return spaces.Box(jnp.asarray(low), jnp.asarray(high), low.shape, jnp.float32)

    def render(self, state: DoorState, params: Params | None = None) -> Any:
        """The state as an RGB array (what ``GymnaxToGymWrapper.render`` returns)."""
        from jswim.viz.frame import state_frame  # lazy: matplotlib only when frames are asked for

        params = self.default_params if params is None else params
        return state_frame(self.door.world, state.env_state, params.world, int(state.time))


def make(
    name: str, max_steps_in_episode: int = MAX_STEPS_IN_EPISODE, **options: Any
) -> tuple[JswimGymnax, Params]:
    """A gymnax environment and its params, as ``gymnax.make`` gives them.

    Parameters
    ----------
    name : str
        A name of `jswim.env.door.IDS` (``"jswim/"`` in front is accepted).
    max_steps_in_episode : int
        Steps per episode (truncation); a navigation world's default is its target's budget.
    **options
        `jswim.env.door.build`'s options over the name's own (``zeta``, ``direction``,
        ``history``, ``continuous``, ...).

    Raises
    ------
    ConfigError
        An unknown name or option (one line naming the valid ones), or an invalid value.
    """
    key = name.removeprefix("jswim/") if isinstance(name, str) else name
    if key not in IDS:
        raise ConfigError(f"unknown environment {name!r}; choose one of {', '.join(IDS)}")
    if (
        isinstance(max_steps_in_episode, bool)
        or not isinstance(max_steps_in_episode, int)
        or max_steps_in_episode < 1
    ):
        raise ConfigError(
            f"max_steps_in_episode must be a whole number >= 1, got {max_steps_in_episode!r}"
        )
    door, world_params = build(**{**IDS[key], **options})
    target = getattr(world_params, "target", None)
    if target is not None and max_steps_in_episode == MAX_STEPS_IN_EPISODE:
        # a navigation world's episodes last its budget unless told otherwise
        max_steps_in_episode = int(target.budget)
    env = JswimGymnax(door, world_params, max_steps_in_episode)
    return env, env.default_params


def registered() -> tuple[str, ...]:
    """The names `make` takes."""
    return tuple(IDS)
