"""The LLM step group above a wall: the heights it hands the prompt (H) are the middle sphere's, as
jswim.scenes' state records them, and its positions the centroid's, from the full float32 pair."""

import asyncio

import jax
import numpy as np
import pytest

import jswim
from jswim.agents.step_batcher import StepGroup
from jswim.judging import lattice
from jswim.scenes import Scene, decode_scene_action, scene_step


@pytest.mark.slow  # compiles the group's start and step and scene_step (~10 s under load)
def test_wall_heights_are_the_middle_sphere_s_and_x_the_centroid_s(float32):
    # Tilted from the start: once the arms differ (10, 6), the centroid sits (d2 - d1) / 3 along the
    # axis from the middle sphere, about (-4 / 3) sin 0.3 = -0.39 a below it.
    env, task = jswim.make("ng", Scene(medium="wall", height=6.0, tilt=0.3), zeta=0.4)
    group = StepGroup([0], env, [task], [7], lattice.encode(1, 0, 1), (6.0, 6.0), (10.0, 10.0))
    assert group.start["heights"][0, 0] == 6.0 and group.start["y"][0] == 6.0
    codes = [3, 5, 0, 2, 3]

    async def drive():
        return [await group.submit(0, c) for c in codes]

    outs = asyncio.run(drive())
    # The same steps through jswim.scenes (the group folds each step's key from its own count).
    key = jax.random.split(jax.random.PRNGKey(7))[1]
    state = env.reset(key, task)
    x0 = float(state.centre[0, 0])  # arms (10, 10): the centroid is the middle sphere
    apart = []
    for t, (c, out) in enumerate(zip(codes, outs)):
        state, _ = scene_step(
            task.scene, state, decode_scene_action(np.int32(c)), jax.random.fold_in(key, t)
        )
        z = np.asarray(state.centre[0, 1])
        assert z.dtype == np.float32 and out["heights"][0] == float(z) and out["y"] == z
        d1, d2 = np.asarray(state.arms[0], np.float64)
        tilt = float(state.tilt[0])
        assert out["tilts"][0] == tilt
        # x: the full pair centre + centre_lo (exact in float64) plus the centroid's offset.
        x = float(state.centre[0, 0]) + float(state.centre_lo[0, 0]) + (d2 - d1) / 3 * np.cos(tilt)
        assert out["xs"][0] == pytest.approx(x - x0, abs=1e-12)
        apart.append(abs((d2 - d1) / 3 * np.sin(tilt)))
    # Not the centroid's height: that one is (d2 - d1) / 3 sin(tilt) off, 0.39 a at some steps.
    assert max(apart) > 0.3
