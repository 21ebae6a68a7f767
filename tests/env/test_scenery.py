"""Each world says what its pictures draw (`Environment.scenery`); the pictures never ask which
kind of world they hold."""

from __future__ import annotations

import jax
import numpy as np

import jswim
from jswim.env import Environment, Scenery
from jswim.scenes import Scene
from jswim.viz.frame import state_frame


def test_each_world_supplies_its_scenery():
    env, _ = jswim.make("purcell")
    s = env.scenery()
    assert s.model is env.model and not s.wall and s.plane_height is None and not s.side_view

    env, _ = jswim.make("ng", Scene(medium="wall", height=5.0))
    s = env.scenery()
    assert s.wall and s.model is not None and s.model.kind == "ng" and s.obstacles == ()
    assert s.side_view  # heights and tilts in the vertical plane

    assert Environment.scenery(env) == Scenery()  # the default: markers, no wall


def test_a_frame_draws_from_the_scenery_alone():
    env, params = jswim.make("ng", Scene(medium="wall", height=5.0))
    state = env.reset(jax.random.key(0), params)
    frame = state_frame(env, state, params, 0)
    assert frame.ndim == 3 and frame.shape[2] == 3 and frame.dtype == np.uint8
    assert frame.std() > 0  # something was drawn
