"""``scene_rollout``: a given sequence of moves in a scene, per-step records, float64."""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.errors import ConfigError
from jswim.scenes.params import SceneParams, scene_params
from jswim.scenes.scene import Scene
from jswim.scenes.state import SceneState, scene_reset
from jswim.scenes.stepping import scene_step


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


def parse_scene_moves(moves: Any, n_swimmers: int) -> np.ndarray:
    """Moves as a float64 ``(steps, 3)`` array of 0-based ``(swimmer, dof, roc)``.

    Accepted: ``(dof, roc)`` pairs (one swimmer; dof 1-based as in the prompt) or
    ``(swimmer, dof, roc)`` triples (both 1-based).
    """
    arr = np.asarray(moves, dtype=object if not len(np.shape(moves)) else None)
    try:
        arr = np.asarray(moves, np.float64)
    except (TypeError, ValueError):
        raise ConfigError("scene moves must be numbers: (dof, roc) pairs or (swimmer, dof, roc) triples") from None
    if arr.ndim != 2 or arr.shape[1] not in (2, 3) or arr.shape[0] == 0:
        raise ConfigError(f"scene moves must have shape (steps, 2) or (steps, 3), got {arr.shape}")
    if arr.shape[1] == 2:
        if n_swimmers != 1:
            raise ConfigError("a scene with two swimmers needs (swimmer, dof, roc) triples")
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
        ``"ng"``.
    moves : array-like (steps, 2) or (steps, 3)
        ``(dof, roc)`` (one swimmer) or ``(swimmer, dof, roc)``, 1-based as in the prompt.
    scene : Scene
    key : int or PRNG key
        Noise seed (used when ``zeta > 0``).
    zeta : float
        Noise level.
    params : SceneParams, optional
        Built here from the rest by :func:`jswim.scenes.scene_params` (float64) if not given.
    **kwargs
        More options of :func:`scene_params` (``init``, ``nodes``, ``sweeps``, ``d_max``, ...).

    Returns
    -------
    SceneRollout
        NumPy float64 arrays, one entry per step (the state after it).
    """
    from jswim.env.rollouts import seed_key

    with jax.enable_x64(True):
        if params is None:
            params = scene_params(swimmer, scene, zeta=zeta, dtype=jnp.float64, **kwargs)
        acts = parse_scene_moves(moves, params.n_swimmers)
        k = seed_key(key) if isinstance(key, int) else key
        out = _scan(params, k, jnp.asarray(acts[:, 0], jnp.int32), jnp.asarray(acts[:, 1], jnp.int32),
                    jnp.asarray(acts[:, 2], params.arms0.dtype))
        return SceneRollout(*(np.asarray(v) for v in out))


@jax.jit
def _scan(params: SceneParams, key: Array, sw: Array, dof: Array, roc: Array) -> SceneRollout:
    keys = jax.random.split(key, sw.shape[0])

    def body(st: SceneState, inp: tuple[Array, ...]) -> tuple[SceneState, SceneRollout]:
        k, a, b, r = inp
        st, info = scene_step(params, st, (a, b, r), k)
        return st, SceneRollout(st.centre[:, 0], st.centre[:, 1], st.tilt, st.arms, info.dx, info.stuck,
                                info.contact, info.gap)

    _, out = jax.lax.scan(body, scene_reset(params), (keys, sw, dof, roc))
    return out
