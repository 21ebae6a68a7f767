"""Scenes: three-sphere swimmers near a wall, among fixed obstacles and in pairs.

The hydrodynamics ([`jswim.swimmers.mobility`][jswim.swimmers.mobility], [`jswim.swimmers.forcefree`][jswim.swimmers.forcefree]) couples all
spheres of all swimmers and obstacles through point-force mobilities; each swimmer is force- and
torque-free and moves (x, z, tilt) in the vertical plane through its axis. A [`Scene`][jswim.scenes.scene.Scene] says
where; the environment is functional, in the gymnax style::

    scene = Scene(medium="wall", height=5.0)
    params = scene_params("ng", scene, zeta=0.0)
    state = scene_reset(params)
    state, info = scene_step(params, state, (0, 0, -1.0), key)   # swimmer 0, arm d1, ROC -1

One concept per module: [`scene`][jswim.scenes.scene] (``Scene``), [`params`][jswim.scenes.params]
(``SceneParams``, ``scene_params``), [`state`][jswim.scenes.state] (``SceneState``,
``SceneStepInfo``, ``scene_reset``), `actions` (codes),
`collocation` (the step's time integration), [`stepping`][jswim.scenes.stepping]
(``scene_step``), [`rollout`][jswim.scenes.rollout] (``scene_rollout``).
"""

from jswim.scenes.actions import decode_scene_action, encode_scene_action, split_action
from jswim.scenes.params import CONTACT_GAP, SceneParams, scene_params
from jswim.scenes.rollout import (
    SceneRollout,
    batch_starts,
    parse_scene_moves,
    scene_rollout,
    scene_rollout_batch,
)
from jswim.scenes.scene import MEDIA, Scene
from jswim.scenes.state import SceneState, SceneStepInfo, scene_positions, scene_reset
from jswim.scenes.stepping import (
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
    "SceneRollout",
    "SceneState",
    "SceneStepInfo",
    "batch_starts",
    "decode_scene_action",
    "encode_scene_action",
    "integrate_move",
    "parse_scene_moves",
    "scene_advance",
    "scene_params",
    "scene_positions",
    "scene_reset",
    "scene_rollout",
    "scene_rollout_batch",
    "scene_step",
    "scene_step_joint",
    "split_action",
    "surface_gap",
]
