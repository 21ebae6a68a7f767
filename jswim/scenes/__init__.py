"""Scenes: three-sphere swimmers near a wall, among fixed obstacles and in pairs.

The hydrodynamics ([`jswim.swimmers.mobility`][jswim.swimmers.mobility], [`jswim.swimmers.forcefree`][jswim.swimmers.forcefree]) couples all
spheres of all swimmers and obstacles through point-force mobilities; each swimmer is force- and
torque-free and moves (x, z, tilt) in the vertical plane through its axis. A [`Scene`][jswim.scenes.scene.Scene] says
where; the environment is functional, in the gymnax style::

    scene = Scene(medium="wall", height=5.0)
    params = scene_params("ng", scene, zeta=0.0)
    state = scene_reset(params)
    state, info = scene_step(params, state, (0, 0, -1.0), key)   # swimmer 0, arm d1, ROC -1

One concept per module: [`scene`][jswim.scenes.scene] (``Scene``),
[`scene_parameters`][jswim.scenes.scene_parameters] (``SceneParams``, ``scene_params``),
[`scene_state`][jswim.scenes.scene_state] (``SceneState``, ``SceneStepInfo``, ``scene_reset``),
`scene_actions` (codes), `collocation` (the step's time integration),
[`scene_stepping`][jswim.scenes.scene_stepping] (``scene_step``),
[`purcell_wall`][jswim.scenes.purcell_wall] (Purcell's swimmer above a wall, a model).

The scene physics sits below the worlds and imports nothing from `jswim.env`; a scene's
rollouts (``scene_rollout``, ``scene_rollout_batch``) and its world (``SceneWorld``) are in
`jswim.env`.
"""

from jswim.scenes.scene_actions import decode_scene_action, encode_scene_action, split_action
from jswim.scenes.scene_parameters import CONTACT_GAP, SceneParams, batch_starts, scene_params
from jswim.scenes.scene import MEDIA, Scene
from jswim.scenes.scene_state import SceneState, SceneStepInfo, scene_positions, scene_reset
from jswim.scenes.scene_stepping import (
    integrate_move,
    scene_advance,
    scene_step,
    scene_step_joint,
    surface_gap,
)

__all__ = [
    "CONTACT_GAP",
    "MEDIA",
    "Scene",
    "SceneParams",
    "SceneState",
    "SceneStepInfo",
    "batch_starts",
    "decode_scene_action",
    "encode_scene_action",
    "integrate_move",
    "scene_advance",
    "scene_params",
    "scene_positions",
    "scene_reset",
    "scene_step",
    "scene_step_joint",
    "split_action",
    "surface_gap",
]
