"""STAND-IN for :mod:`jswim.scenes` (issue 19, part A), used only until that package lands.

Same names and signatures as the agreed contract; the physics is the bulk NG formula for each
swimmer on its own (no wall, no interaction): heights and tilts never change. It lets the agents
and studies of part B be built and tested; :mod:`jswim.agents.scene_env` imports the real
package whenever it exists and falls back to this module otherwise. Delete this file once
``jswim.scenes`` is on main.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp

from jswim.errors import ConfigError

MEDIA = ("bulk", "free", "wall")


@dataclass(frozen=True)
class Scene:
    medium: str = "bulk"
    height: float = 10.0
    tilt: float = 0.0
    swimmers: int = 1
    separation: float = 30.0
    obstacles: tuple[tuple[float, float, float], ...] = ()

    def validate(self) -> "Scene":
        if self.medium not in MEDIA:
            raise ConfigError(f"medium must be one of {', '.join(MEDIA)}, got {self.medium!r}")
        if self.swimmers not in (1, 2):
            raise ConfigError(f"swimmers must be 1 or 2, got {self.swimmers}")
        if not (math.isfinite(self.height) and self.height > 1.0):
            raise ConfigError(f"height must be > 1 (sphere radii), got {self.height}")
        return self

    def to_dict(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        d["obstacles"] = [list(o) for o in self.obstacles]
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "Scene":
        d = dict(d)
        d["obstacles"] = tuple(tuple(float(v) for v in o) for o in d.get("obstacles", ()))
        return cls(**d).validate()


class SceneState(NamedTuple):
    arms: jax.Array  # (S, 2)
    centre: jax.Array  # (S, 2): x, z
    tilt: jax.Array  # (S,)
    t: jax.Array  # int32 steps taken


class SceneInfo(NamedTuple):
    dx: jax.Array
    dz: jax.Array
    dtilt: jax.Array
    stuck: jax.Array
    contact: jax.Array


class SceneParams(NamedTuple):
    scene: Scene
    zeta: float
    lo: float
    hi: float
    roc_levels: int
    init: tuple[int, ...]


def scene_params(swimmer: str, scene: Scene, *, zeta: float = 0.0, roc_levels: int = 1, dtype: Any = None,
                 init: Any = None) -> SceneParams:
    if swimmer != "ng":
        raise ConfigError("scenes hold NG (three-sphere) swimmers only")
    return SceneParams(scene.validate(), float(zeta), 6.0, 10.0, int(roc_levels),
                       tuple(init) if init is not None else (1, 1))


def scene_reset(params: SceneParams) -> SceneState:
    s = params.scene
    n = s.swimmers
    levels = jnp.asarray(params.init, jnp.result_type(float))
    arms = jnp.tile(params.lo + levels * (params.hi - params.lo), (n, 1))
    x = s.separation * jnp.arange(n, dtype=arms.dtype)  # swimmer 2 starts D ahead of swimmer 1
    centre = jnp.stack([x, jnp.full((n,), s.height, arms.dtype)], axis=1)
    return SceneState(arms, centre, jnp.full((n,), s.tilt, arms.dtype), jnp.zeros((), jnp.int32))


def _move_dx(d1a, d1b, d2a, d2b, dof):
    # The NG closed form of a one-arm move (jswim.swimmers.ng.arm_move_displacement), in JAX.
    arm1 = (-jnp.log((d1b + d2a) / (d1a + d2a)) + 2.0 * (d1b - d1a) / d2a) / 6.0
    arm2 = (jnp.log((d1a + d2b) / (d1a + d2a)) - 2.0 * (d2b - d2a) / d1a) / 6.0
    return jnp.where(dof == 0, arm1, arm2)


def scene_step(params: SceneParams, state: SceneState, action: tuple, key: jax.Array):
    sw, dof, roc = action
    sw = jnp.asarray(sw, jnp.int32)
    dof = jnp.asarray(dof, jnp.int32)
    arms = state.arms
    old = arms[sw]
    span = params.hi - params.lo
    new_val = jnp.clip(old[dof] + jnp.asarray(roc, arms.dtype) * span, params.lo, params.hi)
    new = old.at[dof].set(new_val)
    dx1 = _move_dx(old[0], new[0], old[1], new[1], dof)
    if params.zeta:  # the paper's (1 + zeta Y), Y uniform in [-1, 1]
        dx1 = dx1 * (1.0 + params.zeta * jax.random.uniform(key, (), arms.dtype, -1.0, 1.0))
    n = arms.shape[0]
    onehot = jnp.arange(n) == sw
    dx = jnp.where(onehot, dx1, 0.0)
    stuck = (jnp.asarray(roc) != 0) & (new_val == old[dof])
    new_state = SceneState(arms.at[sw].set(new), state.centre.at[:, 0].add(dx), state.tilt, state.t + 1)
    zeros = jnp.zeros((n,), arms.dtype)
    return new_state, SceneInfo(dx, zeros, zeros, stuck, jnp.zeros((), bool))
