"""The scene environment (jswim.scenes): interface, media, contact, noise, dtypes."""

import functools
import json

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import quad

import jswim
from jswim.env import scene_rollout
from jswim.errors import ConfigError
from jswim.scenes import (
    Scene,
    decode_scene_action,
    encode_scene_action,
    scene_params,
    scene_reset,
    scene_step,
)

SQUARE = [(1, -1), (2, -1), (1, 1), (2, 1)]  # NG square stroke from (10, 10): arms 10 -> 6 -> 10


def collinear_velocity(d1, d2, r1, r2):
    """Middle-sphere velocity of three collinear point-force spheres (unit Stokes mobility,
    Oseen 3/(2 r) along the line), force-free, arm rates r1, r2: a 4 x 4 solve in NumPy."""
    x = np.array([-d1, 0.0, d2])
    r = np.abs(x[:, None] - x[None, :])
    m = np.eye(3) + np.where(r > 0, 1.5 / np.where(r > 0, r, 1), 0.0)
    a = np.zeros((4, 4))
    a[:3, :3] = m
    a[:3, 3] = -1.0
    a[3, :3] = 1.0
    sol = np.linalg.solve(a, np.array([-r1, 0.0, r2, 0.0]))
    return sol[3]


def collinear_square_cycle(lo=6.0, hi=10.0):
    moves = [(0, -1), (1, -1), (0, 1), (1, 1)]
    d = [hi, hi]
    total = 0.0
    for dof, sign in moves:
        start = list(d)

        def u(t, dof=dof, sign=sign, start=start):
            dd = list(start)
            dd[dof] += sign * t
            rr = [0.0, 0.0]
            rr[dof] = sign
            return collinear_velocity(dd[0], dd[1], *rr)

        total += quad(u, 0.0, hi - lo, epsabs=1e-13, epsrel=1e-13)[0]
        d[dof] += sign * (hi - lo)
    return total


def test_scene_json_round_trip_and_hash():
    s = Scene(
        medium="wall", height=7.5, tilt=0.1, swimmers=2, separation=40, obstacles=[(1, 20, 2)]
    )
    back = Scene.from_dict(json.loads(json.dumps(s.to_dict())))
    assert back == s and hash(back) == hash(s)
    assert isinstance(back.obstacles[0], tuple)


@pytest.mark.parametrize(
    "fields, word",
    [
        ({"medium": "honey"}, "medium"),
        ({"medium": "wall", "height": 0.5}, "height"),
        ({"tilt": 2.0}, "tilt"),
        ({"swimmers": 17}, "swimmers"),
        ({"swimmers": 0}, "swimmers"),
        ({"formation": "circle"}, "formation"),
        ({"swimmers": 2, "separation": -1.0}, "separation"),
        ({"medium": "free", "obstacles": ((0, 0, -1),)}, "radius"),
        ({"obstacles": ((0, 30, 1),)}, "obstacles"),
        ({"height": float("nan")}, "height"),
    ],
)
def test_scene_validate_one_line(fields, word):
    with pytest.raises(ValueError) as err:
        Scene(**fields).validate()
    assert word in str(err.value) and "\n" not in str(err.value)
    with pytest.raises(ConfigError):
        Scene.from_dict(
            Scene(**fields).to_dict() if fields.get("obstacles") is None else {**fields}
        )


def test_start_overlaps_refused():
    with pytest.raises(ConfigError, match="wall"):
        scene_params("ng", Scene(medium="wall", height=3.0, tilt=0.3))
    with pytest.raises(ConfigError, match="separation"):
        scene_params("ng", Scene(medium="free", swimmers=2, separation=15.0))
    # schools: swimmers 2 and 3 of a line 21 a apart would touch (arms 10: a 1 a gap between
    # spheres of radius 1), side by side 2 a apart the spheres overlap
    with pytest.raises(ConfigError, match="separation"):
        scene_params("ng", Scene(medium="free", swimmers=3, separation=21.0))
    with pytest.raises(ConfigError, match="separation"):
        scene_params("ng", Scene(medium="free", swimmers=4, separation=2.0, formation="side"))
    ok = scene_params(
        "ng", Scene(medium="wall", swimmers=3, separation=2.5, formation="side", height=3.0)
    )
    np.testing.assert_allclose(np.asarray(ok.centre0), [[0.0, 3.0], [0.0, 5.5], [0.0, 8.0]])
    with pytest.raises(ConfigError, match="ng"):
        scene_params("purcell", Scene())
    with pytest.raises(ConfigError):
        Scene.from_dict({"medium": "wall", "depth": 3})


def test_numerics_and_numpy_numbers_checked_in_one_line():
    wall = Scene(medium="wall", height=5.0)
    for kw in (
        {"nodes": 0},
        {"nodes": 2.0},
        {"nodes": True},
        {"sweeps": 0},
        {"sweeps": True},
        {"sweeps": 2.5},
        {"sweeps": 65},
        {"sweeps": "3"},
    ):
        with pytest.raises(ConfigError) as err:
            scene_params("ng", wall, **kw)
        assert next(iter(kw)) in str(err.value) and "\n" not in str(err.value)
    # A NumPy number is the plain number it holds (static fields stay plain, hashable ints and floats).
    p = scene_params("ng", wall, nodes=np.int64(4), sweeps=np.int32(3))
    assert (p.nodes, p.sweeps) == (4, 3) and type(p.nodes) is int and type(p.sweeps) is int
    s = Scene(medium="wall", height=np.float32(5.0), swimmers=np.int64(2), separation=np.int32(30))
    assert (
        s == Scene(medium="wall", height=5.0, swimmers=2, separation=30.0)
        and type(s.swimmers) is int
    )


def test_start_beyond_the_dtype_refused(float32):
    # float32 rounds x to 2^-23 of its size: swimmer 2 at D >= 1024 a (its spheres out to D + 20 a)
    # would move in steps of >= 1.2e-4 a (at D = 1e7 a it does not move at all): refused, one line.
    scene_params("ng", Scene(medium="free", swimmers=2, separation=1000.0))
    for d in (1010.0, 1e5, 1e12):
        with pytest.raises(
            ConfigError, match="separation .* too far for float32 .* below 1004 a"
        ) as err:
            scene_params("ng", Scene(medium="free", swimmers=2, separation=d))
        assert "\n" not in str(err.value)
    for scene in (
        Scene(medium="wall", height=1e39),
        Scene(medium="free", obstacles=((1e39, 0.0, 1.0),)),
    ):
        with pytest.raises(ConfigError, match="overflow float32"):
            scene_params("ng", scene)
    with jax.enable_x64(True):  # float64 resolves 1e-4 a out to 2^39 a
        scene_params("ng", Scene(medium="free", swimmers=2, separation=1e10), dtype=jnp.float64)
        with pytest.raises(ConfigError, match="float64 positions"):
            jswim.env.rollout_moves(
                "ng", [(1, 1, -1)], scene=Scene(medium="free", swimmers=2, separation=1e12)
            )


def test_free_square_stroke_matches_independent_collinear_solve():
    want = collinear_square_cycle()
    assert abs(want - 0.1720914) < 1e-7  # extensions.md's independent number
    r = scene_rollout("ng", SQUARE * 2, Scene(medium="free"))
    # 6 Gauss nodes: ~5e-12 per cycle (nodes=8: ~1e-15)
    assert abs(r.x[3, 0] - want) < 1e-11 and abs(r.x[7, 0] - 2 * want) < 2e-11
    np.testing.assert_array_equal(r.z, 10.0)
    np.testing.assert_array_equal(r.tilt, 0.0)
    np.testing.assert_array_equal(r.arms[3], [[10.0, 10.0]])


def test_bulk_is_todays_environment():
    moves = SQUARE * 3 + [(1, -0.5), (2, 0.3), (1, 1), (2, -1), (2, 1), (1, 0)]
    today = jswim.env.rollout_moves("ng", moves)
    same = jswim.env.rollout_moves("ng", moves, scene=Scene())
    np.testing.assert_array_equal(today.x, same.x)
    r = scene_rollout("ng", moves, Scene())
    np.testing.assert_allclose(r.x[:, 0], today.x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(r.arms[:, 0], today.dofs, atol=1e-12)
    np.testing.assert_array_equal(r.stuck, today.stuck)
    assert abs(r.x[3, 0] - 0.15626494) < 5e-9
    # two swimmers in bulk: independent, each the paper's number
    two = scene_rollout(
        "ng", [(2, d, k) for d, k in SQUARE] + [(1, d, k) for d, k in SQUARE], Scene(swimmers=2)
    )
    np.testing.assert_allclose(two.x[-1], [r.x[3, 0], 30.0 + r.x[3, 0]], atol=1e-12)


def test_rollout_routes_scenes():
    r = jswim.env.rollout_moves("ng", SQUARE, scene=Scene(medium="free"))
    assert r.x.shape == (4, 1) and abs(r.x[-1, 0] - 0.1720914) < 1e-7
    with pytest.raises(ConfigError):
        jswim.env.rollout_moves("ng", SQUARE, scene="wall")
    with pytest.raises(ConfigError, match="triples"):
        scene_rollout("ng", SQUARE, Scene(swimmers=2))


def test_action_codes():
    for k_levels in (1, 3):
        for sw in (0, 1):
            for dof in (0, 1):
                for k in range(-k_levels, k_levels + 1):
                    c = encode_scene_action(sw, dof, k, k_levels)
                    s, d, roc = decode_scene_action(c, k_levels)
                    assert (int(s), int(d)) == (sw, dof) and abs(float(roc) - k / k_levels) < 1e-7
    assert [encode_scene_action(0, d, k) for d in (0, 1) for k in (-1, 0, 1)] == list(range(6))


@pytest.mark.slow  # compiles the scene step with obstacles (30 s under load 8)
def test_contact_refuses_the_step_and_stuck():
    # the RPB self terms let the low sphere reach 0.03 a in this move; the exact normal
    # mobility (~gap near contact) slows it to stop at 0.13 a, not refused (checked below)
    scene = Scene(medium="wall", height=2.5, tilt=-0.2, self_mobility="rpb")
    r = scene_rollout("ng", [(2, 1), (2, -1), (1, 0.5)], scene, init=(0, 0))
    assert r.contact.tolist() == [True, False, False] and r.stuck.tolist() == [False, True, False]
    np.testing.assert_array_equal(r.arms[0], [[6.0, 6.0]])  # refused: nothing moved
    assert r.x[0, 0] == 0.0 and r.z[0, 0] == 2.5
    assert r.gap[0] < 0.1
    e = scene_rollout("ng", [(2, 1)], Scene(medium="wall", height=2.5, tilt=-0.2), init=(0, 0))
    assert not e.contact[0] and 0.1 < e.gap[0] < 0.2
    s = scene_rollout("ng", [(1, 1), (1, -1)], Scene(medium="wall", height=20.0))
    assert s.stuck.tolist() == [True, False] and s.x[0, 0] == 0.0


@pytest.mark.slow  # compiles the wall scene's noisy step (5 CPU-s); the unbounded world's noise: tests/env/test_env.py
def test_noise_scales_the_displacement_not_the_tilt():
    scene = Scene(medium="wall", height=6.0)
    clean = scene_rollout("ng", [(1, -1)], scene)
    key = jax.random.PRNGKey(5)
    noisy = scene_rollout("ng", [(1, -1)], scene, zeta=0.5, key=key)
    with jax.enable_x64(True):
        y = float(jax.random.uniform(jax.random.split(key, 1)[0], (), jnp.float64, -1.0, 1.0))
    np.testing.assert_allclose(noisy.x[0, 0], clean.x[0, 0] * (1 + 0.5 * y), rtol=1e-13)
    np.testing.assert_allclose(
        noisy.z[0, 0] - 6.0, (clean.z[0, 0] - 6.0) * (1 + 0.5 * y), rtol=1e-10
    )
    assert noisy.tilt[0, 0] == clean.tilt[0, 0]


@pytest.mark.slow  # compiles the scene step in float32 under jit and vmap (116 s under load 8)
def test_float32_jit_vmap(float32):
    params = scene_params("ng", Scene(medium="wall", height=5.0, swimmers=2, separation=30.0))
    assert params.arms0.dtype == jnp.float32
    b = 4
    states = jax.tree.map(lambda v: jnp.broadcast_to(v, (b,) + v.shape), scene_reset(params))
    acts = (
        jnp.array([0, 1, 0, 1], jnp.int32),
        jnp.array([0, 0, 1, 1], jnp.int32),
        jnp.array([-1.0, -1.0, -0.5, 1.0]),
    )
    keys = jax.random.split(jax.random.PRNGKey(0), b)
    step = jax.jit(jax.vmap(scene_step, in_axes=(None, 0, 0, 0)))
    new, info = step(params, states, acts, keys)
    assert new.centre.dtype == jnp.float32 and info.dx.shape == (b, 2)
    assert bool(info.stuck[3]) and not bool(info.stuck[0])
    with jax.enable_x64(True):
        ref = scene_rollout(
            "ng", [(1, 1, -1)], Scene(medium="wall", height=5.0, swimmers=2, separation=30.0)
        )
    np.testing.assert_allclose(
        np.asarray(new.centre[0]), np.stack([ref.x[0], ref.z[0]], -1), atol=2e-5
    )


@pytest.mark.slow  # compiles the free pair's body-frame path in both dtypes (47 s under load 8)
def test_float32_pair_in_the_free_fluid(float32):
    # the free fluid's pair path (body-frame responses, jswim.swimmers.bodyframe) in the dtype users
    # get: each swimmer's square cycle in turn, within float32 rounding of float64
    scene = Scene(medium="free", swimmers=2, separation=30.0)
    params = scene_params("ng", scene)
    moves = [(s, d, k) for s in (1, 2) for d, k in SQUARE]
    step = jax.jit(scene_step)
    st = scene_reset(params)
    for s, d, k in moves:
        st, info = step(params, st, (s - 1, d - 1, float(k)), jax.random.PRNGKey(0))
        assert not bool(info.contact)
    assert st.centre.dtype == jnp.float32
    with jax.enable_x64(True):
        ref = scene_rollout("ng", moves, scene)
    np.testing.assert_allclose(np.asarray(st.centre[:, 0]), ref.x[-1], atol=2e-5)
    assert (
        abs(ref.x[-1, 1] - 30.0) > 0.1
    )  # swimmer 2 swam its own cycle (and was pushed by swimmer 1's)
    np.testing.assert_allclose(np.asarray(st.centre[:, 1]), ref.z[-1], atol=1e-6)


@pytest.mark.slow
def test_float32_pair_separation_does_not_drift(float32):
    # Positions held as float32 pairs (two-sum). A pair at D = 30 a stroking together
    # (joint square strokes) for 100 cycles keeps its separation within 1e-5 a of float64; plain
    # float32 positions were off by -8.8e-5 a (swimmer 2's x rounded alike every cycle), and the
    # true drift is zero (README's mirror-and-time-reversal argument).
    from jswim.scenes import scene_positions, scene_step_joint

    def separation(dtype):
        params = scene_params("ng", Scene(medium="free", swimmers=2, separation=30.0), dtype=dtype)
        dofs = jnp.asarray([[d - 1, d - 1] for d, _ in SQUARE] * 100, jnp.int32)
        rocs = jnp.asarray([[k, k] for _, k in SQUARE] * 100, dtype)

        @jax.jit
        def run(st):
            body = lambda st, a: (
                scene_step_joint(params, st, a[0], a[1], jax.random.PRNGKey(0))[0],
                None,
            )
            return jax.lax.scan(body, st, (dofs, rocs))[0]

        st = run(scene_reset(params))
        assert st.centre.dtype == dtype
        pos = scene_positions(st)
        return pos[1, 0] - pos[0, 0]

    s32 = separation(jnp.float32)
    with jax.enable_x64(True):
        s64 = separation(jnp.float64)
    assert abs(s64 - 30.0) < 1e-9  # the true drift is zero
    # a float32 ulp at 30 a is 1.9e-6: within ~10 ulp after 400 steps (1.24e-5 measured on an AMD
    # EPYC, under 1e-5 on another CPU: XLA's code differs between processors)
    assert abs(s32 - s64) < 2e-5


@pytest.mark.slow  # compiles the wall scene in float32 and float64 (77 s under load 8)
def test_float32_one_swimmer_near_a_wall(float32):
    # the unrolled solve in the dtype users get: a square cycle within float32 rounding of float64
    params = scene_params("ng", Scene(medium="wall", height=4.0))
    step = jax.jit(scene_step)
    st = scene_reset(params)
    for d, k in SQUARE:
        st, _info = step(params, st, (0, d - 1, float(k)), jax.random.PRNGKey(0))
    assert st.centre.dtype == jnp.float32
    with jax.enable_x64(True):
        ref = scene_rollout("ng", SQUARE, Scene(medium="wall", height=4.0))
    np.testing.assert_allclose(np.asarray(st.centre[0]), [ref.x[-1, 0], ref.z[-1, 0]], atol=2e-5)
    assert abs(float(st.tilt[0]) - ref.tilt[-1, 0]) < 2e-6


# -- adaptive Picard sweeps (speed) ------------------------------------------------------------

NEAR_WALL = Scene(medium="wall", height=3.5)


def _pose_change(scene, dtype, x0=0.0, **kw):
    """One D1 lengthening 6 -> 10 from arms (6, 10), tilt 0.3, at x0: (dx, dz, dtilt), float64."""
    from jswim.scenes.scene_stepping import pose_change

    p = scene_params("ng", scene, dtype=dtype, **kw)
    pose0 = jnp.asarray([[x0, scene.height, 0.3]], dtype)
    arms, rates = jnp.asarray([[6.0, 10.0]], dtype), jnp.asarray([[1.0, 0.0]], dtype)
    inc, _ = jax.jit(lambda p0: pose_change(p, p0, arms, rates, jnp.asarray(4.0, dtype)))(pose0)
    return np.asarray(inc, np.float64)[0]


@functools.lru_cache(maxsize=1)
def _converged_near_wall():
    """The same step, 12 nodes x 14 fixed sweeps in float64 (converged to ~1e-15)."""
    with jax.enable_x64(True):
        return _pose_change(NEAR_WALL, jnp.float64, nodes=12, sweeps=14)


@pytest.mark.slow  # compiles the scene solver at several sweep counts (125 s under load 8)
def test_adaptive_sweeps_reach_the_converged_step_in_float64():
    # the default (adaptive sweeps, 6 nodes) against the converged step: near the wall the Picard
    # iteration gains only ~20x per sweep, so a fixed 3 sweeps is far off there
    ref = _converged_near_wall()
    with jax.enable_x64(True):
        auto = _pose_change(NEAR_WALL, jnp.float64)
        three = _pose_change(NEAR_WALL, jnp.float64, sweeps=3)
    scale = np.abs(ref[:2]).max()
    assert np.abs(auto[:2] - ref[:2]).max() < 5e-11 * scale and abs(auto[2] - ref[2]) < 1e-11
    assert np.abs(three[:2] - ref[:2]).max() > 1e-6 * scale  # the case the adaptive rule is for


@pytest.mark.slow  # compiles the scene step in both dtypes (50 s under load 8)
def test_float32_default_numerics_within_rounding_of_float64_far_from_the_origin(float32):
    # 4 nodes and adaptive sweeps in float32: within float32 rounding of the float64 step, also
    # 1e5 a from x = 0, where float32 positions are only good to ~4e-3 a (the solve works relative
    # to swimmer 1's x)
    assert scene_params("ng", NEAR_WALL).nodes == 4
    ref = _converged_near_wall()
    for x0 in (0.0, 1e5):
        got = _pose_change(NEAR_WALL, jnp.float32, x0=x0)
        np.testing.assert_allclose(got[:2], ref[:2], rtol=0, atol=2e-6 * np.abs(ref[:2]).max())
        assert abs(got[2] - ref[2]) < 1e-7


@pytest.mark.slow  # compiles the pair scene at two batch sizes (49 s under load 8)
def test_adaptive_sweeps_per_swimmer_do_not_depend_on_the_batch():
    # under vmap the sweep loop runs until the slowest swimmer converges; the others keep their
    # converged values, so a swimmer's step is the same next to a fast or a slow one
    with jax.enable_x64(True):
        p = scene_params("ng", Scene(medium="wall", height=40.0))
        far, near = scene_reset(p), scene_reset(scene_params("ng", NEAR_WALL))
        step = jax.jit(jax.vmap(scene_step, in_axes=(None, 0, None, None)))
        pairs = [jax.tree.map(lambda a, b: jnp.stack([a, b]), far, other) for other in (far, near)]
        (same, _), (mixed, _) = (step(p, s, (0, 0, -1.0), jax.random.PRNGKey(0)) for s in pairs)
    np.testing.assert_array_equal(np.asarray(mixed.centre[0]), np.asarray(same.centre[0]))
    np.testing.assert_array_equal(np.asarray(mixed.tilt[0]), np.asarray(same.tilt[0]))
    assert not np.array_equal(np.asarray(mixed.centre[1]), np.asarray(same.centre[1]))
