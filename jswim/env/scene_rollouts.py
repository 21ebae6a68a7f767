"""``scene_rollout``: a given sequence of moves in a scene, per-step records, float64.

The scene physics (`jswim.scenes`) sits below the worlds; its rollouts live here,
beside the paper's world's ([`jswim.env.rollouts`][jswim.env.rollouts]), because Purcell's
swimmer above a wall rolls out through the paper's world
([`jswim.env.swimmer_world.SwimmerWorld`][jswim.env.swimmer_world.SwimmerWorld]).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.action_codes import encode_action
from jswim.env.episodes import rollout as world_rollout
from jswim.env.params import make_params
from jswim.env.randomness import seed_key
from jswim.env.swimmer_world import SwimmerWorld
from jswim.errors import ConfigError
from jswim.scenes import purcell_wall
from jswim.scenes.scene_parameters import SceneParams, scene_params
from jswim.scenes.scene import Scene
from jswim.scenes.scene_state import SceneState, scene_reset
from jswim.scenes.scene_stepping import scene_step
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
        return SceneRollout(
            **_purcell_wall_rollout(
                parse_scene_moves(moves, 1), scene, key=key, zeta=zeta, **kwargs
            )
        )
    with jax.enable_x64(True):
        if params is None:
            params = scene_params(swimmer, scene, zeta=zeta, dtype=jnp.float64, **kwargs)
        acts = parse_scene_moves(moves, params.n_swimmers)
        k = seed_key(key) if isinstance(key, int) else key
        out = _scan(
            params,
            k,
            jnp.asarray(acts[:, 0], jnp.int32),
            jnp.asarray(acts[:, 1], jnp.int32),
            jnp.asarray(acts[:, 2], params.arms0.dtype),
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
) -> dict[str, np.ndarray]:
    """The fields of a `SceneRollout` of ``moves`` by Purcell's swimmer above a wall, float64.

    ``moves``: ``(steps, 3)`` 0-based ``(swimmer, dof, roc)`` (`parse_scene_moves`); the model
    is [`jswim.scenes.purcell_wall.model`][jswim.scenes.purcell_wall.model] of ``scene``.

    ``x``, ``y``: the centroid (as [`jswim.env.rollout_moves`][jswim.env.rollouts.rollout_moves]); ``z``: the plane's height (fixed);
    ``tilt``: 0 (the links stay parallel to the wall); ``orientation``: the middle link's angle in
    the plane; ``arms``: the hinge angles; ``gap``: the links' surface above the wall, ``h - b``.
    """
    m = purcell_wall.model(
        scene, link_radius=link_radius, d_max=d_max, **other
    )  # wall_model in other
    dof, roc = np.asarray(moves, np.float64)[:, 1:].T
    with jax.enable_x64(True):
        params = make_params(m, zeta=zeta, init=init)
        if np.all(
            np.isin(roc, (-1.0, 0.0, 1.0))
        ):  # the paper's ROCs: integer codes, the exact corner table
            acts = jnp.asarray(encode_action(dof + 1, roc), jnp.int32)
        else:  # real ROCs: ROC vectors, the integrator (as jswim.env.rollout_moves does)
            acts = jnp.asarray(np.eye(2)[dof.astype(int)] * roc[:, None], jnp.float64)
        t = world_rollout(SwimmerWorld(m), params, key, acts)
        pos = np.asarray(t.obs.position[:, 0], np.float64)  # (steps, 2): the centroid
        out = {
            "x": pos[:, :1],
            "arms": np.asarray(t.obs.dofs, np.float64)[:, None, :],
            "dx": np.asarray(t.info.displacement[:, 0, :1], np.float64),
            "stuck": np.asarray(t.info.stuck),
            "y": pos[:, 1:],
            "orientation": np.asarray(t.obs.orientation, np.float64),
        }
    steps = pos.shape[0]
    return {
        **out,
        "z": np.full((steps, 1), m.height),
        "tilt": np.zeros((steps, 1)),
        "contact": np.zeros(steps, bool),
        "gap": np.full(steps, m.height - m.link_radius),
    }


@jax.jit
def _scan(params: SceneParams, key: Array, sw: Array, dof: Array, roc: Array) -> SceneRollout:
    keys = jax.random.split(key, sw.shape[0])

    def body(st: SceneState, inp: tuple[Array, ...]) -> tuple[SceneState, SceneRollout]:
        k, a, b, r = inp
        st, info = scene_step(params, st, (a, b, r), k)
        return st, SceneRollout(
            st.centre[:, 0],
            st.centre[:, 1],
            st.tilt,
            st.arms,
            info.dx,
            info.stuck,
            info.contact,
            info.gap,
        )

    _, out = jax.lax.scan(body, scene_reset(params), (keys, sw, dof, roc))
    return out


def scene_rollout_batch(params: SceneParams, moves: Any, *, key: Array | int = 0) -> SceneRollout:
    """[`scene_rollout`][jswim.env.scene_rollouts.scene_rollout] of the same moves from each start of [`jswim.scenes.batch_starts`][jswim.scenes.scene_parameters.batch_starts] (float64
    when ``params`` is). Leading axes of the result: (batch, steps, ...)."""
    with jax.enable_x64(True):
        acts = parse_scene_moves(moves, params.n_swimmers)
        k = seed_key(key) if isinstance(key, int) else key
        b = params.centre0.shape[0]
        out = _scan_starts(
            params,
            jax.random.split(k, b),
            jnp.asarray(acts[:, 0], jnp.int32),
            jnp.asarray(acts[:, 1], jnp.int32),
            jnp.asarray(acts[:, 2], params.arms0.dtype),
        )
        return SceneRollout(*(np.asarray(v) for v in out))


@jax.jit
def _scan_starts(
    params: SceneParams, keys: Array, sw: Array, dof: Array, roc: Array
) -> SceneRollout:
    axes = params.replace(zeta=None, centre0=0, tilt0=0, arms0=None, obstacles=None)
    return jax.vmap(_scan, in_axes=(axes, 0, None, None, None))(params, keys, sw, dof, roc)
