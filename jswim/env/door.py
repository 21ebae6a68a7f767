"""What the RL doors (`jswim.gym`, `jswim.gymnax`) share: a world of `jswim.make`
as an episode with a step count, the observation a policy reads and the reading of a Box action.

A `Door` is static and hashable (one compilation per door, as a world); its functions are
pure JAX, so the Gymnasium door jits them for one swimmer, the vector door vmaps them over
``num_envs`` and the gymnax door is them. Nothing here imports Gymnasium or gymnax.

Observation (float32, finite bounds `Door.bounds`), in this order:

1. the world's `jswim.env.base.Environment.features`: every joint DOF scaled to [-1, 1];
   above a wall also each swimmer's ``ln(z / 10 a)`` and ``tilt / 0.5 rad``; with a ``target``
   the target's ``cos(bearing)``, ``sin(bearing)`` and ``distance / 4 a``
   (`jswim.env.navigation.DISTANCE_SCALE`), and with
   a ``flow`` as well the local flow in the body frame over `jswim.env.flows.SWIM_SPEED`
   (along the middle link, then across it; its size at most ``flow.speed / SWIM_SPEED`` in a
   uniform stream or Taylor-Green cells, growing with ``|y|`` in shear and Poiseuille flow).
   Each entry past the DOFs is clipped to [-`EXTRA_BOUND`, `EXTRA_BOUND`] (|tilt| <= 5 rad,
   z <= 2.2e5 a, a flow of at most 10 swimming speeds; a swimmer in a faster one is carried
   along whatever it does). Without a target a flow moves the swimmer but adds no entries;
2. ``separation`` (worlds of two or more swimmers; on by default there): swimmer ``s + 1``'s
   centroid minus swimmer ``s``'s, ``(dx, dy)`` for ``s = 0 .. S - 2``, in units of the scene's
   start separation D (1.0 along the line at the start), clipped to [-10, 10];
3. ``history = n`` (default 0): the positions the prompt's last ``n`` records give an LLM (the
   swimmers' mean centroid ``(x, y)`` after each of the ``n`` steps before the current one),
   oldest first, relative to the current position, in ``a``, clipped to
   [-`HISTORY_BOUND`, `HISTORY_BOUND`]; before ``n`` steps are taken the missing
   records are the start position.

Box actions (``continuous=True``): a vector ``a`` of ``n_dof`` entries, clipped to [-1, 1]. In the
paper's worlds (one swimmer, bulk or above a wall as a plane) every DOF moves at once: DOF ``i``
at ROC ``a_i`` along the path the motors follow (the integrator's diagonal stroke,
`jswim.env.make_params` ``diagonal=True``), so a Gaussian policy moves every joint at every
step. Scenes move one arm per step: the DOF of largest ``|a_i|`` at ROC ``a_i`` (ties: the first).
"""

from __future__ import annotations

import dataclasses
from typing import Any, NamedTuple

import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.env.base import Environment, StepInfo
from jswim.env.flows import Uniform, study_flow
from jswim.env.targets import FixedTarget
from jswim.env.scene_world import SceneWorld
from jswim.env.swimmer_world import SwimmerWorld
from jswim.env.registry import make
from jswim.errors import ConfigError

#: Bound of the clipped wall features (log height, scaled tilt).
EXTRA_BOUND = 10.0
#: Bound of a separation component, in units of the start separation D.
SEPARATION_BOUND = 10.0
#: Bound of a history component, in ``a`` per record.
HISTORY_BOUND = 10.0

#: The door's own options, what `jswim.make` takes by name, and the model and scene options
#: it passes on: the keywords `build` accepts.
DOOR_OPTIONS = ("continuous", "history", "separation")
MAKE_OPTIONS = (
    "swimmer",
    "scene",
    "zeta",
    "direction",
    "init",
    "roc_levels",
    "dtype",
    "target",
    "bearing_bins",
    "lattice",
    "flow",
)
MODEL_OPTIONS = (
    "d_max",
    "d_min",
    "n_links",
    "n_spheres",
    "xi_ratio",
    "link_radius",
    "nodes",
    "sweeps",
    "contact_gap",
)

#: The target of ``NavigatePurcell-v0``: a point 3 link lengths away at 90 degrees to the left,
#: reached within a quarter link length (budget: the steering controller's measured default,
#: 256 steps; docs/navigation.md).
NAVIGATE_TARGET = FixedTarget(3.0, 90.0)

#: The flow of ``NavigatePurcellFlow-v0``: a uniform stream of half the swimming speed across
#: the start heading, ``u = (0, 0.5 SWIM_SPEED)`` (the navigation study's ``--flow uniform``
#: at 0.5; `jswim.env.flows.study_flow`).
NAVIGATE_FLOW = study_flow("uniform", 0.5)
#: The target of ``NavigatePurcellFlow-v0``: 3 link lengths straight ahead, across the stream.
#: Cross-stream rather than ``NAVIGATE_TARGET``'s 90 degrees: that one lies downstream, where
#: the stream alone carries a swimmer that does nothing to it (there in 116 steps, inside its
#: 256), while here the stream alone never reaches it and the square gait straight ahead passes
#: 1.35 a from it: the policy must head ~30 degrees into the stream (Zermelo's crab),
#: which is what the flow entries of the observation are for. Budget: the navigation study's rule
#: in a flow (`jswim.studies.kinds.navigate.with_budgets`), 4 x Zermelo's least time of 65.6 steps
#: (the still-fluid budget straight ahead is 96); tests/env/test_flow_door.py recomputes it.
NAVIGATE_FLOW_TARGET = FixedTarget(3.0, 0.0, budget=263)

#: The worlds every door names (Gymnasium: ``jswim/<name>``; gymnax: ``<name>``) and their
#: `build` arguments.
IDS: dict[str, dict[str, Any]] = {
    "Purcell-v0": {"swimmer": "purcell"},
    "NG-v0": {"swimmer": "ng"},
    "FourLink-v0": {"swimmer": "nlink"},
    "FourSphere-v0": {"swimmer": "nsphere"},
    "PurcellContinuous-v0": {"swimmer": "purcell", "continuous": True},
    "NGContinuous-v0": {"swimmer": "ng", "continuous": True},
    "PurcellWall-v0": {"swimmer": "purcell", "scene": {"medium": "wall", "height": 2.0}},
    "NGWall-v0": {"swimmer": "ng", "scene": {"medium": "wall", "height": 5.0}},
    "NGPair-v0": {
        "swimmer": "ng",
        "scene": {"medium": "free", "swimmers": 2, "separation": 30.0},
    },
    "NGSchool-v0": {
        "swimmer": "ng",
        "scene": {"medium": "free", "swimmers": 3, "separation": 30.0},
    },
    "NavigatePurcell-v0": {"swimmer": "purcell", "roc_levels": 2, "target": NAVIGATE_TARGET},
    "NavigatePurcellFlow-v0": {
        "swimmer": "purcell",
        "roc_levels": 2,
        "target": NAVIGATE_FLOW_TARGET,
        "flow": NAVIGATE_FLOW,
    },
}


class DoorState(NamedTuple):
    """The world's state, the step count of the episode and the position history.

    Attributes
    ----------
    env_state : pytree
        The world's state.
    time : Array () int32
        Steps taken in this episode (gymnax's ``state.time``).
    history : Array (n, 2)
        The swimmers' mean centroid after each of the last ``n`` steps before the current one,
        oldest first (``n = Door.history``; ``(0, 2)`` when off).
    """

    env_state: Any
    time: Array
    history: Array


@dataclasses.dataclass(frozen=True)
class Door:
    """A world as an RL environment (module docs). Build one with `build`.

    Attributes
    ----------
    world : Environment
    continuous : bool
        Box actions (module docs) instead of the world's integer codes.
    history : int
        Records of past positions in the observation (>= 0).
    separation : bool
        The swimmers' separations in the observation (worlds of two or more swimmers).
    """

    world: Environment
    continuous: bool = False
    history: int = 0
    separation: bool = False

    @property
    def n_obs(self) -> int:
        """Length of the observation."""
        sep = 2 * (self.world.n_swimmers - 1) if self.separation else 0
        return self.world.n_features + sep + 2 * self.history

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """``(low, high)`` of the observation, float32 ``(n_obs,)``, every entry finite."""
        n, f = self.world.n_dof, self.world.n_features
        high = np.concatenate(
            [
                np.ones(n),
                np.full(f - n, EXTRA_BOUND),
                np.full(self.n_obs - f - 2 * self.history, SEPARATION_BOUND),
                np.full(2 * self.history, HISTORY_BOUND),
            ]
        ).astype(np.float32)
        return -high, high

    def world_action(self, action: Any) -> Array:
        """The world's action for a door action: an integer code, or a Box vector read as the
        module docs say (paper's worlds: every DOF at its ROC; scenes: the largest ``|a_i|``)."""
        if not self.continuous:
            return jnp.asarray(action, jnp.int32)
        a = jnp.clip(jnp.asarray(action, jnp.result_type(float)), -1.0, 1.0)
        if isinstance(self.world, SwimmerWorld) and self.world.diagonal:
            return a
        i = jnp.argmax(jnp.abs(a))
        return jnp.where(jnp.arange(self.world.n_dof) == i, a, 0.0)

    def position(self, state: Any, params: Any) -> Array:
        """The swimmers' mean centroid ``(x, y)`` (the records' position)."""
        return jnp.mean(self.world.observe(state, params).position, axis=0)

    def observation(self, state: DoorState, params: Any) -> Array:
        """The observation of ``state`` (module docs), float32 ``(n_obs,)``."""
        f = self.world.features(state.env_state, params)
        n = self.world.n_dof
        # (the scaled DOFs may round a hair past +-1)
        parts = [jnp.clip(f[:n], -1.0, 1.0), jnp.clip(f[n:], -EXTRA_BOUND, EXTRA_BOUND)]
        obs = self.world.observe(state.env_state, params)
        if self.separation and self.world.n_swimmers > 1:
            scale = (
                float(self.world.scene.separation) if isinstance(self.world, SceneWorld) else 1.0
            )
            gaps = (obs.position[1:] - obs.position[:-1]) / scale
            parts.append(jnp.clip(gaps.reshape(-1), -SEPARATION_BOUND, SEPARATION_BOUND))
        if self.history:
            rel = state.history - jnp.mean(obs.position, axis=0)
            parts.append(jnp.clip(rel.reshape(-1), -HISTORY_BOUND, HISTORY_BOUND))
        return jnp.concatenate([p.astype(jnp.float32) for p in parts])

    def reset(self, key: Array, params: Any) -> tuple[DoorState, Array]:
        """A fresh episode: ``(state, observation)``."""
        env_state = self.world.reset(key, params)
        pos = self.position(env_state, params)
        history = jnp.broadcast_to(pos, (self.history, 2))
        state = DoorState(env_state, jnp.zeros((), jnp.int32), history)
        return state, self.observation(state, params)

    def step(
        self, key: Array, state: DoorState, action: Any, params: Any
    ) -> tuple[DoorState, Array, StepInfo]:
        """One step, its noise drawn from ``key`` as the world's ``step`` draws it:
        ``(state, observation, info)``; the reward is ``info.progress``."""
        return self.advance(state, action, self.world.noise(key, state.env_state), params)

    def advance(
        self, state: DoorState, action: Any, noise: Array, params: Any
    ) -> tuple[DoorState, Array, StepInfo]:
        """One step for given noise variables ``(n_swimmers,)`` in [-1, 1] (the world's
        ``advance``): ``(state, observation, info)``."""
        before = self.position(state.env_state, params)
        env_state, info = self.world.advance(
            state.env_state, self.world_action(action), noise, params
        )
        history = (
            jnp.concatenate([state.history[1:], before[None].astype(state.history.dtype)])
            if self.history
            else state.history
        )
        new = DoorState(env_state, state.time + 1, history)
        return new, self.observation(new, params), info


def build(swimmer: str = "purcell", scene: Any = None, **options: Any) -> tuple[Door, Any]:
    """A `Door` and its world's params.

    Parameters
    ----------
    swimmer, scene
        As `jswim.make`.
    **options
        ``continuous`` (bool), ``history`` (int >= 0), ``separation`` (bool; default: on for two
        or more swimmers), and `jswim.make`'s options (`MAKE_OPTIONS`,
        `MODEL_OPTIONS`), ``flow`` among them (a `jswim.env.flows` flow: planar swimmers in the
        bulk, as `jswim.make` takes it).

    Raises
    ------
    ConfigError
        An unknown keyword (one line naming the valid ones) or an invalid value; a flow
        `jswim.make` refuses (a sphere swimmer, a scene, a registered world, not a flow), or
        ``continuous=True`` in a flow other than `jswim.env.flows.Uniform` without a target.
    """
    unknown = sorted(set(options) - set(DOOR_OPTIONS + MAKE_OPTIONS + MODEL_OPTIONS))
    if unknown:
        valid = ", ".join(DOOR_OPTIONS + MAKE_OPTIONS[2:] + MODEL_OPTIONS)
        raise ConfigError(
            f"unknown option{'s' if len(unknown) > 1 else ''} {', '.join(map(repr, unknown))}; "
            f"valid: {valid}"
        )
    continuous = bool(options.pop("continuous", False))
    history = options.pop("history", 0)
    if isinstance(history, bool) or not isinstance(history, (int, np.integer)) or history < 0:
        raise ConfigError(f"history must be a whole number of records >= 0, got {history!r}")
    separation = options.pop("separation", None)
    world, params = make(swimmer, scene, **options)
    flow = options.get("flow")
    if (
        continuous
        and isinstance(world, SwimmerWorld)
        and not isinstance(flow, (Uniform, type(None)))
    ):
        # make's own refusal would name the diagonal strokes, which the caller never asked for
        raise ConfigError(
            f"continuous=True moves every joint at once, which a {type(flow).__name__} flow does "
            "not offer (its steps follow one DOF's move at a time); use a Uniform "
            "flow, a target (one DOF a step) or leave continuous off"
        )
    if continuous and isinstance(world, SwimmerWorld):
        world, params = make(swimmer, scene, diagonal=True, **options)
    if separation is None:
        separation = world.n_swimmers > 1
    return Door(world, continuous, int(history), bool(separation)), params
