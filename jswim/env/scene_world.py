"""Scenes through the protocol: NG swimmers near a wall, among obstacles, in pairs (`jswim.scenes`).

The physics is `jswim.scenes`' own: `SceneWorld.step` of a joint action code is
[`jswim.scenes.scene_step`][jswim.scenes.scene_stepping.scene_step] of the code's ``(swimmer, dof, roc)`` (the same draw from the key,
the same state, bit for bit). What the world adds is the task: a target ``direction`` in its
params ([`SceneTask`][jswim.env.scene_world.SceneTask]), the reward ``progress`` and positions of each swimmer's centroid.

A swimmer's position is the centroid of its three spheres, the middle sphere's ``(x, z)`` plus
``(d2 - d1) / 3`` along its axis: the point whose velocity the paper's formula gives (the middle
sphere jumps by more than 1 a at every move while the swimmer nets about 0.17 a per cycle). In the
``"bulk"`` medium the state's centre already is the paper's X ([`jswim.scenes.scene_stepping`][jswim.scenes.scene_stepping]), so
there the position is the centre.
"""

from __future__ import annotations

import dataclasses
from typing import Any, NamedTuple

import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.env.base import Environment, Observation, Scenery, StepInfo, first_move, scaled
from jswim.env.discretiser import Cells, WallCells
from jswim.env.params import EnvParams, make_params
from jswim.errors import ConfigError
from jswim.scenes.scene_actions import decode_scene_action
from jswim.scenes.scene_parameters import SceneParams, scene_params
from jswim.scenes.scene import Scene
from jswim.scenes.scene_state import SceneState, centre_low, scene_reset
from jswim.scenes.scene_stepping import scene_advance
from jswim.swimmers.models import make_model

#: Arms (DOFs) of one NG swimmer.
ARMS = 2


class SceneTask(NamedTuple):
    """A scene world's params: the scene's own ([`jswim.scenes.SceneParams`][jswim.scenes.scene_parameters.SceneParams]) and the target
    direction (+1: +x, -1: -x); both may be batched (``vmap`` axes as a ``SceneTask`` prefix)."""

    scene: SceneParams
    direction: Any = 1.0


@dataclasses.dataclass(frozen=True)
class SceneWorld(Environment):
    """A [`jswim.scenes.Scene`][jswim.scenes.scene.Scene] as a world; ``params`` is a [`SceneTask`][jswim.env.scene_world.SceneTask].

    Swimmer ``s`` (0-based) owns joint DOFs ``2s + 1, 2s + 2`` (1-based), so a joint code is the
    paper's code over the joint DOFs (one swimmer's codes are the bulk swimmer's).
    """

    scene: Scene
    k: int = 1

    @property
    def n_dof(self) -> int:
        return ARMS * self.scene.swimmers

    @property
    def n_swimmers(self) -> int:
        return self.scene.swimmers

    @property
    def roc_levels(self) -> int:
        return self.k

    @property
    def wall(self) -> bool:
        return self.scene.medium == "wall"

    def scenery(self) -> Scenery:
        """NG swimmers by their outline, the wall and the obstacles of the scene, seen from the side."""
        return Scenery(
            model=make_model("ng"),
            wall=self.wall,
            obstacles=tuple(tuple(map(float, o)) for o in self.scene.obstacles),
            side_view=True,
        )

    @property
    def default_params(self) -> SceneTask:
        return SceneTask(scene_params("ng", self.scene, roc_levels=self.k), 1.0)

    def reset(self, key: Array, params: SceneTask) -> SceneState:
        """The scene's start (deterministic: ``key`` is not used)."""
        return scene_reset(params.scene)

    def dtype(self, state: SceneState) -> Any:
        return state.arms.dtype

    def move(self, action: Array) -> tuple[Array, Array, Array]:
        """``(swimmer, arm, roc)`` of an integer joint code or a float ROC vector ``(n_dof,)``
        (its first non-zero entry)."""
        action = jnp.asarray(action)
        if jnp.issubdtype(action.dtype, jnp.integer):
            if action.ndim != 0:
                raise ValueError(f"an integer action code is a scalar, got shape {action.shape}")
            return decode_scene_action(action, self.k)
        if action.shape != (self.n_dof,):
            raise ValueError(
                f"a float action is a ROC vector of shape ({self.n_dof},), got {action.shape}"
            )
        i, roc = first_move(action)
        return i // ARMS, i % ARMS, roc

    def offset(self, state: SceneState) -> Array:
        """Each swimmer's centroid minus its middle sphere ``(S, 2)`` (0 in the bulk medium)."""
        if self.scene.medium == "bulk":
            return jnp.zeros_like(state.centre)
        along = (state.arms[:, 1] - state.arms[:, 0]) / 3.0
        return jnp.stack([along * jnp.cos(state.tilt), along * jnp.sin(state.tilt)], -1)

    def advance(
        self, state: SceneState, action: Array, noise: Array, params: SceneTask
    ) -> tuple[SceneState, StepInfo]:
        """[`jswim.scenes.scene_advance`][jswim.scenes.scene_stepping.scene_advance] of the action, with noise ``(S,)``."""
        new, info = scene_advance(params.scene, state, self.move(action), noise)
        dtype = new.arms.dtype
        disp = jnp.stack([info.dx, info.dz], -1) + (self.offset(new) - self.offset(state))
        progress = jnp.asarray(params.direction, dtype) * jnp.mean(disp[:, 0])
        return new, StepInfo(
            disp,
            progress,
            jnp.asarray(info.stuck),
            info.moved,
            info.contact,
            jnp.asarray(info.gap, dtype),
            # Not counted: the sum of F.V over the scene's force-free solve is not wired in.
            jnp.asarray(jnp.nan, dtype),
        )

    def observe(self, state: SceneState, params: SceneTask) -> Observation:
        """Positions: each swimmer's centroid from the full pair ``centre + centre_lo`` (in the
        state's dtype the sum is ``centre``; widened to float64 it is exact, drift-free); height:
        the middle sphere's ``z`` ([`jswim.scenes.SceneState`][jswim.scenes.scene_state.SceneState]'s, what the scenes record)."""
        centre = state.centre + centre_low(state)
        return Observation(
            state.arms.reshape(-1), centre + self.offset(state), state.tilt, centre[:, 1]
        )

    def features(self, state: SceneState, params: SceneTask) -> Array:
        """The arms scaled to [-1, 1]; with a wall also each swimmer's middle-sphere height as
        ``ln(z / 10 a)`` and tilt as ``tilt / 0.5 rad`` (about [-1.6, 1.6] over 3-50 a), as the
        PPO baseline reads them."""
        return features(state, params.scene, self.wall)

    @property
    def n_features(self) -> int:
        return self.n_dof + (2 * self.n_swimmers if self.wall else 0)

    def cells(self) -> Cells:
        """The joint corner; with a wall, times swimmer 1's height bin ([`WallCells`][jswim.env.discretiser.WallCells])."""
        return WallCells(self) if self.wall else Cells(self)

    def judge_view(self, params: SceneTask) -> tuple[EnvParams, ...]:
        """Each swimmer's moves judged with the bulk NG swimmer's displacements, from its start
        arms (the paper's formula, noiseless).

        Raises
        ------
        ConfigError
            When the scene's arm limits are not the bulk swimmer's.
        """
        sp = params.scene
        lo, hi = float(sp.lo), float(sp.hi)
        arms0 = np.asarray(sp.arms0, np.float64).reshape(self.n_swimmers, ARMS)
        views = []
        for arms in arms0:
            levels = tuple(int(v) for v in np.rint((arms - lo) / (hi - lo)))
            bulk = make_params("ng", init=levels)
            if not (np.isclose(float(bulk.model.lo), lo) and np.isclose(float(bulk.model.hi), hi)):
                raise ConfigError(
                    "a scene's runs are judged only with the bulk swimmer's arm limits"
                )
            views.append(bulk)
        return tuple(views)

    def batch_params(self, params: SceneTask, n: int) -> tuple[SceneTask, SceneTask]:
        """The scene's params shared by the runs; the direction per run where it has an axis."""
        return params, SceneTask(None, 0 if jnp.ndim(params.direction) > 0 else None)


def features(state: SceneState, params: SceneParams, wall: bool) -> Array:
    """[`SceneWorld.features`][jswim.env.scene_world.SceneWorld.features] of a scene's state (also the PPO scene world's observation)."""
    obs = scaled(state.arms.reshape(-1), params.lo, params.hi)
    if not wall:
        return obs
    # Heights below 0.1 a are contacts the step refuses; the floor only keeps the log finite.
    z = jnp.log(jnp.maximum(state.centre[:, 1], 0.1) / 10.0)
    return jnp.concatenate([obs, z.astype(obs.dtype), (state.tilt / 0.5).astype(obs.dtype)])
