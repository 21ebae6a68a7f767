"""Schools of N >= 3 NG swimmers through the scene API, the world protocol and the study grid."""

import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jswim
from jswim.errors import ConfigError
from jswim.scenes import (
    Scene,
    scene_params,
    scene_positions,
    scene_reset,
    scene_step,
    scene_step_joint,
)

SQUARE = [(0, -1), (1, -1), (0, 1), (1, 1)]  # 0-based arm, ROC


def test_formation_json_and_starts():
    line = Scene(medium="free", swimmers=4, separation=25.0)
    assert (
        "formation" not in line.to_dict()
    )  # the default: earlier scenes' JSON and run ids unchanged
    side = Scene(medium="wall", swimmers=3, separation=4.0, formation="side", height=3.0)
    back = Scene.from_dict(json.loads(json.dumps(side.to_dict())))
    assert back == side and back.to_dict()["formation"] == "side"
    np.testing.assert_array_equal(line.start_offsets(), [[0, 0], [1, 0], [2, 0], [3, 0]])
    p = scene_params("ng", side)
    np.testing.assert_allclose(np.asarray(p.centre0), [[0.0, 3.0], [0.0, 7.0], [0.0, 11.0]])
    with pytest.raises(ConfigError, match="formation"):
        Scene(formation="ring").validate()


def test_school_world_through_the_protocol():
    # the bulk medium (the paper's formula, swimmers independent): the joint DOFs and codes of N
    env, params = jswim.make("ng", scene=Scene(medium="bulk", swimmers=3, separation=40.0))
    assert (env.n_swimmers, env.n_dof, env.n_actions) == (3, 6, 18)
    assert env.dof_names == ("D1", "D2", "D3", "D4", "D5", "D6")
    assert env.dof_swimmer == (0, 0, 1, 1, 2, 2)
    state = env.reset(jax.random.PRNGKey(0), params)
    obs = env.observe(state, params)
    assert obs.position.shape == (3, 2) and obs.dofs.shape == (6,)
    np.testing.assert_allclose(np.asarray(obs.position[:, 0]), [0.0, 40.0, 80.0])
    # code (dof - 1) * 3 + roc + 1: DOF 5 (swimmer 3's first arm) at ROC -1 is code 12
    new, info = env.step(jax.random.PRNGKey(1), state, jnp.asarray(12), params)
    np.testing.assert_allclose(np.asarray(new.arms), [[10, 10], [10, 10], [6, 10]])
    assert info.displacement.shape == (3, 2)
    assert float(info.displacement[0, 0]) == 0.0 and float(info.displacement[2, 0]) != 0.0
    # the same move as a ROC vector
    vec = jnp.zeros(6).at[4].set(-1.0)
    new2, _ = env.step(jax.random.PRNGKey(1), state, vec, params)
    np.testing.assert_array_equal(np.asarray(new2.arms), np.asarray(new.arms))
    # the scene API's own step, bit for bit
    ref, _ = scene_step(params.scene, state, (2, 0, -1.0), jax.random.PRNGKey(1))
    np.testing.assert_array_equal(np.asarray(ref.centre), np.asarray(new.centre))


def test_school_study_cells():
    from jswim.studies import StudyOptions
    from jswim.studies.specs import build
    from jswim.studies.scene_studies import stroke_codes

    plans = build(
        "school",
        StudyOptions(school_sizes=(1, 3), separations=(30.0,), formations=("line", "side")),
    )
    assert [p.agent for p in plans] == ["stroke"] * 3
    scenes = [json.loads(p.scene) for p in plans]
    assert [s["swimmers"] for s in scenes] == [1, 3, 3]
    assert scenes[2]["formation"] == "side" and "formation" not in scenes[1]
    # every swimmer in turn makes the same move of its square: codes of swimmers 1, 2, 3
    np.testing.assert_array_equal(stroke_codes("phase0", 1, 6, 3), [5, 11, 17, 0, 6, 12])
    # a pair's phase 0 is the same rule
    np.testing.assert_array_equal(stroke_codes("phase0", 1, 4, 2), [5, 11, 0, 6])
    with pytest.raises(ConfigError, match="school-sizes"):
        build("pair", StudyOptions(school_sizes=(3,)))
    with pytest.raises(ConfigError, match="school-sizes"):
        StudyOptions(school_sizes=(0, 3))
    with pytest.raises(ConfigError, match="formations"):
        StudyOptions(formations=("ring",))


@pytest.mark.slow  # compiles a school of three in float32 and float64 (~1 min under load)
def test_float32_school_positions_do_not_drift(float32):
    # Positions as float32 pairs (two-sum): after 40 in-phase square cycles of a line of three
    # 30 a apart, each position is the exact sum of the float32 steps' displacements (to 1e-9 a;
    # plain float32 sums would be off by ~1e-5 a at x = 30-60 a). The steps themselves carry
    # float32's own error (~1.3e-6 of a step, docs/scenes.md): the spacings, which really change
    # here by 0.41 a (the middle swimmer gains ~1e-2 a per cycle on the ends), agree with float64
    # to 2.9e-4 a (7e-4 of the change); a pair's symmetric separation cancels that error.
    def run(dtype):
        params = scene_params("ng", Scene(medium="free", swimmers=3, separation=30.0), dtype=dtype)
        dofs = jnp.asarray([[d] * 3 for d, _ in SQUARE] * 40, jnp.int32)
        rocs = jnp.asarray([[k] * 3 for _, k in SQUARE] * 40, dtype)

        @jax.jit
        def go(st):
            def body(st, a):
                st, info = scene_step_joint(params, st, a[0], a[1], jax.random.PRNGKey(0))
                return st, info.dx

            return jax.lax.scan(body, st, (dofs, rocs))

        st, dx = go(scene_reset(params))
        assert st.centre.dtype == dtype
        x = scene_positions(st)[:, 0]
        summed = np.asarray(params.centre0, np.float64)[:, 0] + np.asarray(dx, np.float64).sum(0)
        return x, summed

    x32, summed32 = run(jnp.float32)
    np.testing.assert_allclose(x32, summed32, atol=1e-9, rtol=0)
    with jax.enable_x64(True):
        x64, _ = run(jnp.float64)
    s32, s64 = np.diff(x32), np.diff(x64)
    assert s64[0] > 30.1 and s64[1] < 29.9  # the middle one closes on the front one
    np.testing.assert_allclose(s32 - 30.0, s64 - 30.0, rtol=1e-3)
