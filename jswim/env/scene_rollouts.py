"""``scene_rollout``: a given sequence of moves in a scene, per-step records, float64.

The scene physics (`jswim.scenes`) sits below the worlds; its rollouts live here, beside the
paper's world's ([`jswim.env.rollouts`][jswim.env.rollouts]), and run the protocol's one rollout
([`jswim.env.episodes.rollout`][jswim.env.episodes.rollout]): Purcell's swimmer above a wall in
the paper's world ([`jswim.env.swimmer_world.SwimmerWorld`][jswim.env.swimmer_world.SwimmerWorld]),
NG swimmers through `SceneMoves`, the scene's own step of ``(swimmer, dof, roc)`` moves (a
record keeps the middle sphere's own step ``dx``, which the protocol's
[`StepInfo`][jswim.env.base.StepInfo] does not carry).
"""

from __future__ import annotations

import dataclasses
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.env.base import Environment, StepInfo
from jswim.env.episodes import rollout
from jswim.env.params import EnvParams, make_params
from jswim.env.swimmer_world import moves_rollout
from jswim.errors import ConfigError
from jswim.scenes import purcell_wall
from jswim.scenes.scene_parameters import SceneParams, scene_params
from jswim.scenes.scene import Scene
from jswim.scenes.scene_state import SceneState, SceneStepInfo, scene_reset
from jswim.scenes.scene_stepping import scene_advance
from jswim.swimmers.wall_rft import LINK_RADIUS


class SceneRollout(NamedTuple):
    """Per-step record (state after each step); NumPy, leading axis = steps, then swimmers."""

    x: np.ndarray  # (steps, S) middle sphere x
    z: np.ndarray  # (steps, S) middle sphere z (height above the wall in "wall")
    tilt: np.ndarray  # (steps, S) rad
    arms: np.ndarray  # (steps, S, 2)
    dx: np.ndarray  # (steps, S)
    stuck: np.ndarray  # (steps,)
    contact: np.ndarray  # (steps,)
    gap: np.ndarray  # (steps,)
    y: np.ndarray | None = None  # (steps, S) Purcell's swimmer above a wall: in-plane y (else None)
    orientation: np.ndarray | None = (
        None  # (steps, S) Purcell's: its middle link's angle in the plane
    )


def parse_scene_moves(moves: Any, n_swimmers: int) -> np.ndarray:
    """Moves as a float64 ``(steps, 3)`` array of 0-based ``(swimmer, dof, roc)``.

    Accepted: ``(dof, roc)`` pairs (one swimmer; dof 1-based as in the prompt) or
    ``(swimmer, dof, roc)`` triples (both 1-based).
    """
    arr = np.asarray(moves, dtype=object if not len(np.shape(moves)) else None)
    try:
        arr = np.asarray(moves, np.float64)
    except (TypeError, ValueError):
        raise ConfigError(
            "scene moves must be numbers: (dof, roc) pairs or (swimmer, dof, roc) triples"
        ) from None
    if arr.ndim != 2 or arr.shape[1] not in (2, 3) or arr.shape[0] == 0:
        raise ConfigError(f"scene moves must have shape (steps, 2) or (steps, 3), got {arr.shape}")
    if arr.shape[1] == 2:
        if n_swimmers != 1:
            raise ConfigError("a scene with two or more swimmers needs (swimmer, dof, roc) triples")
        arr = np.concatenate([np.ones((len(arr), 1)), arr], 1)
    if not np.all(np.isfinite(arr)):
        raise ConfigError("scene moves must be finite")
    sw, dof, roc = arr.T
    if np.any(sw != np.round(sw)) or np.any((sw < 1) | (sw > n_swimmers)):
        raise ConfigError(f"a move's swimmer must be an integer in 1..{n_swimmers}")
    if np.any(dof != np.round(dof)) or np.any((dof < 1) | (dof > 2)):
        raise ConfigError("a move's dof must be 1 or 2")
    if np.any(np.abs(roc) > 1):
        raise ConfigError("a move's roc must lie in [-1, 1]")
    return np.stack([sw - 1, dof - 1, roc], 1)


def scene_rollout(
    swimmer: str,
    moves: Any,
    scene: Scene = Scene(),
    *,
    key: Array | int = 0,
    zeta: float = 0.0,
    params: SceneParams | None = None,
    **kwargs: Any,
) -> SceneRollout:
    """Run a sequence of moves in a scene, in float64.

    Parameters
    ----------
    swimmer : str
        ``"ng"``, or ``"purcell"`` above a wall ([`jswim.scenes.purcell_wall`][jswim.scenes.purcell_wall]: its plane
        ``scene.height`` link lengths above the wall; ``link_radius``, ``d_max`` by keyword).
    moves : array-like (steps, 2) or (steps, 3)
        ``(dof, roc)`` (one swimmer) or ``(swimmer, dof, roc)``, 1-based as in the prompt.
    scene : Scene
    key : int or PRNG key
        Noise seed (used when ``zeta > 0``).
    zeta : float
        Noise level.
    params : SceneParams, optional
        Built here from the rest by [`jswim.scenes.scene_params`][jswim.scenes.scene_parameters.scene_params] (float64) if not given.
    **kwargs
        More options of [`scene_params`][jswim.scenes.scene_parameters.scene_params] (``init``, ``nodes``, ``sweeps``, ``d_max``, ...).

    Returns
    -------
    SceneRollout
        NumPy float64 arrays, one entry per step (the state after it).
    """
    if purcell_wall.is_purcell(swimmer) and params is None:
        return _purcell_wall_rollout(
            parse_scene_moves(moves, 1), scene, key=key, zeta=zeta, **kwargs
        )
    with jax.enable_x64(True):
        if params is None:
            params = scene_params(swimmer, scene, zeta=zeta, dtype=jnp.float64, **kwargs)
        acts = parse_scene_moves(moves, params.n_swimmers)
        out = rollout(
            SceneMoves(params.n_swimmers),
            params,
            key,
            jnp.asarray(acts, params.arms0.dtype),
            record=_scene_record,
        )
        return SceneRollout(*(np.asarray(v) for v in out))


def _purcell_wall_rollout(
    moves: np.ndarray,
    scene: Scene,
    *,
    key: Any = 0,
    zeta: float = 0.0,
    init: Any = None,
    link_radius: float = LINK_RADIUS,
    d_max: float | None = None,
    **other: Any,
) -> SceneRollout:
    """The `SceneRollout` of ``moves`` by Purcell's swimmer above a wall, float64.

    ``moves``: ``(steps, 3)`` 0-based ``(swimmer, dof, roc)`` (`parse_scene_moves`); the model
    is [`jswim.scenes.purcell_wall.model`][jswim.scenes.purcell_wall.model] of ``scene``, run in
    the paper's world as [`jswim.env.rollout_moves`][jswim.env.rollouts.rollout_moves] runs it.

    ``x``, ``y``: the centroid; ``z``: the plane's height (fixed); ``tilt``: 0 (the links stay
    parallel to the wall); ``orientation``: the middle link's angle in the plane; ``arms``: the
    hinge angles; ``gap``: the links' surface above the wall, ``h - b``.
    """
    m = purcell_wall.model(
        scene, link_radius=link_radius, d_max=d_max, **other
    )  # wall_model in other
    with jax.enable_x64(True):
        params = make_params(m, zeta=zeta, init=init)
    pairs = np.asarray(moves, np.float64)[:, 1:] + np.array([1.0, 0.0])  # (dof 1-based, roc)
    t = moves_rollout(params, pairs, key, record=_wall_record)
    steps = t.x.shape[0]
    return SceneRollout(
        x=t.x,
        z=np.full((steps, 1), m.height),
        tilt=np.zeros((steps, 1)),
        arms=t.arms,
        dx=t.dx,
        stuck=t.stuck,
        contact=np.zeros(steps, bool),
        gap=np.full(steps, m.height - m.link_radius),
        y=t.y,
        orientation=t.orientation,
    )


class _WallStep(NamedTuple):
    x: Array
    y: Array
    orientation: Array
    arms: Array
    dx: Array
    stuck: Array


def _wall_record(env: Environment, params: EnvParams, state: Any, info: StepInfo) -> _WallStep:
    """Purcell's step above a wall, shaped as a one-swimmer `SceneRollout`'s entries."""
    obs = env.observe(state, params)
    pos = obs.position[0]  # the centroid
    return _WallStep(
        pos[:1], pos[1:], obs.orientation, obs.dofs[None, :], info.displacement[0, :1], info.stuck
    )


@dataclasses.dataclass(frozen=True)
class SceneMoves(Environment):
    """A scene's own physics stepped by ``(swimmer, dof, roc)`` moves: what
    [`scene_rollout`][jswim.env.scene_rollouts.scene_rollout] runs through the protocol's one
    rollout. ``params`` is a [`SceneParams`][jswim.scenes.scene_parameters.SceneParams] (with a
    leading batch axis of starts from [`jswim.scenes.batch_starts`][jswim.scenes.scene_parameters.batch_starts]);
    an action is a float row ``(3,)``: 0-based swimmer and DOF, then the ROC (`parse_scene_moves`).

    The step is [`jswim.scenes.scene_step`][jswim.scenes.scene_stepping.scene_step] of the move, bit for bit (the
    same noise draw from the key). Its info is the scene's own
    [`SceneStepInfo`][jswim.scenes.scene_state.SceneStepInfo], not the protocol's
    ``StepInfo``, and it observes nothing: a world for records of the scene's state
    (`SceneRollout`), not for agents ([`SceneWorld`][jswim.env.scene_world.SceneWorld] is theirs).
    """

    swimmers: int = 1

    @property
    def n_swimmers(self) -> int:
        return self.swimmers

    @property
    def n_dof(self) -> int:
        return 2 * self.swimmers

    def reset(self, key: Array, params: SceneParams) -> SceneState:
        return scene_reset(params)

    def dtype(self, state: SceneState) -> Any:
        return state.arms.dtype

    def advance(  # type: ignore[override]  (the scene's own info)
        self, state: SceneState, action: Array, noise: Array, params: SceneParams
    ) -> tuple[SceneState, SceneStepInfo]:
        return scene_advance(params, state, action, noise)

    def batch_params(self, params: SceneParams, n: int) -> tuple[SceneParams, SceneParams]:
        """Start poses per run where ``params`` has them (``centre0`` ``(B, S, 2)``, ``tilt0``
        ``(B, S)``: `batch_starts`), the rest shared."""
        if jnp.ndim(params.centre0) == 2:
            return params, params.replace(
                zeta=None, centre0=None, tilt0=None, arms0=None, obstacles=None
            )
        return params, params.replace(zeta=None, centre0=0, tilt0=0, arms0=None, obstacles=None)


def _scene_record(
    env: Environment, params: SceneParams, state: SceneState, info: SceneStepInfo
) -> SceneRollout:
    """A `SceneRollout`'s entry of one step: the scene's state after it and its own info."""
    return SceneRollout(
        state.centre[:, 0],
        state.centre[:, 1],
        state.tilt,
        state.arms,
        info.dx,
        info.stuck,
        info.contact,
        info.gap,
    )


def scene_rollout_batch(params: SceneParams, moves: Any, *, key: Array | int = 0) -> SceneRollout:
    """[`scene_rollout`][jswim.env.scene_rollouts.scene_rollout] of the same moves from each start of [`jswim.scenes.batch_starts`][jswim.scenes.scene_parameters.batch_starts] (float64
    when ``params`` is). Leading axes of the result: (batch, steps, ...)."""
    with jax.enable_x64(True):
        acts = parse_scene_moves(moves, params.n_swimmers)
        b = params.centre0.shape[0]
        out = rollout(
            SceneMoves(params.n_swimmers),
            params,
            key,
            jnp.broadcast_to(jnp.asarray(acts, params.arms0.dtype), (b, *acts.shape)),
            record=_scene_record,
        )
        return SceneRollout(*(np.asarray(v) for v in out))
