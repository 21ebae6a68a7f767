"""Continuous strokes: any shape, any ROC in [-1, 1], exact against independent numbers.

Reference values: the square gaits' displacements per cycle (0.19124724 for Purcell at
d_max = pi/3, README and the paper's Fig. 2; NG's closed form 0.15626494 for arms 6..10), a
plain RK4 written here on the paper's closed-form Purcell velocities, the spectral integrator,
and the symmetries of zero-Reynolds-number swimming (rate independence, reversal, e^2 scaling).
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jswim import env
from jswim.env import motion
from jswim.errors import ConfigError
from jswim.integrate import centroid, integrate_stroke
from jswim.swimmers import ng, nlink, purcell

PURCELL_CYCLE = 0.19124724  # d_max = pi/3, from (+, +): (2,-), (1,-), (2,+), (1,+)
NG_CYCLE = 0.15626494  # arms 6..10, from (-, -): (1,+), (2,+), (1,-), (2,-)


def _stepper(params):
    """One jitted noiseless step for ``params`` (one compilation per dtype)."""
    return jax.jit(lambda s, a: env.advance(s, a, jnp.zeros((), s.x.dtype), params))


def _walk(params, frac0, moves):
    """Apply ``(dof, roc)`` moves as float ROC vectors from ``frac0``; return the states."""
    step = _stepper(params)
    s = env.start_state(params.model, jnp.asarray(frac0, jnp.float64))
    out = []
    for dof, roc in moves:
        s, info = step(s, jnp.asarray(env.roc_vector(dof, roc, params.n_dof), s.x.dtype))
        out.append((s, info))
    return out


def _x(state):
    return float(env.position(state)[0][()])


def test_unit_rocs_on_the_continuous_path_give_the_square_gaits():
    p = env.make_params("purcell")
    states = _walk(p, [1.0, 1.0], [(2, -1.0), (1, -1.0), (2, 1.0), (1, 1.0)])
    assert abs(_x(states[-1][0]) - PURCELL_CYCLE) < 5e-9
    q = env.make_params("ng")
    states = _walk(q, [0.0, 0.0], [(1, 1.0), (2, 1.0), (1, -1.0), (2, -1.0)])
    assert abs(_x(states[-1][0]) - NG_CYCLE) < 5e-9
    assert abs(_x(states[-1][0]) - ng.square_cycle_displacement(6.0, 10.0)) < 1e-12


@pytest.mark.slow  # builds and compiles the lattice table for each K (56 s under load 8)
def test_lattice_codes_give_the_square_gaits_at_any_k():
    for big_k in (2, 5):
        p = env.make_params("purcell", roc_levels=big_k)
        seq = [(2, -1)] * big_k + [(1, -1)] * big_k + [(2, 1)] * big_k + [(1, 1)] * big_k
        r = env.rollout_moves("purcell", [(d, k / big_k) for d, k in seq])
        assert abs(float(r.x[-1]) - PURCELL_CYCLE) < 5e-9
        step = jax.jit(lambda s, a: env.advance(s, a, jnp.zeros(()), p))
        s = env.start_state(p.model, jnp.ones(2))
        for d, k in seq:
            s, _ = step(s, env.encode_action(d, k, big_k))
        assert abs(_x(s) - PURCELL_CYCLE) < 5e-9
        np.testing.assert_array_equal(np.asarray(s.frac), [1.0, 1.0])  # the lattice closes exactly


def test_rate_independence_and_reversal():
    p = env.make_params("purcell")
    loop = [(2, -1.0), (1, -1.0), (2, 1.0), (1, 1.0)]
    one = _x(_walk(p, [1.0, 1.0], loop)[-1][0])
    halves = _x(_walk(p, [1.0, 1.0], [(d, r / 2) for d, r in loop for _ in range(2)])[-1][0])
    assert abs(one - halves) <= 1e-12 * abs(one)
    # Reversed, the loop gives exactly minus (the square closes with no net rotation).
    back = [(d, -r / 2) for d, r in reversed(loop) for _ in range(2)]
    assert abs(_x(_walk(p, [1.0, 1.0], back)[-1][0]) + one) <= 1e-12 * abs(one)
    # A loop around an inner shape of the sphere swimmer (which does not rotate), both ways.
    q = env.make_params("ng")
    inner = [(1, 0.3), (2, -0.4), (1, -0.3), (2, 0.4)]
    fwd = _x(_walk(q, [0.35, 0.6], inner)[-1][0])
    rev = _x(_walk(q, [0.35, 0.6], [(d, -r) for d, r in reversed(inner)])[-1][0])
    assert fwd != 0 and abs(fwd + rev) <= 1e-12 * abs(fwd)


def _rk4_square(d_lo, d_hi, substeps=400):
    """Lab-frame centroid displacement of Purcell's square between hinge angles d_lo and d_hi,
    walked from (d_hi, d_hi) as (2,-), (1,-), (2,+), (1,+): plain RK4 on the closed form."""
    d = np.array([d_hi, d_hi])
    pose = np.zeros(3)
    start = np.asarray(
        centroid(env.make_params("purcell").model, jnp.asarray(d), jnp.asarray(pose))
    )
    for k, target in ((1, d_lo), (0, d_lo), (1, d_hi), (0, d_hi)):
        rate = np.zeros(2)
        rate[k] = np.sign(target - d[k])
        h = abs(target - d[k]) / substeps
        base = d.copy()
        for i in range(substeps):
            f = lambda t, q: purcell.velocity(base + rate * t, rate, q[2], xp=np)
            t = i * h
            k1 = f(t, pose)
            k2 = f(t + h / 2, pose + h / 2 * k1)
            k3 = f(t + h / 2, pose + h / 2 * k2)
            k4 = f(t + h, pose + h * k3)
            pose = pose + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        d[k] = target
    off = np.asarray(nlink.centroid_offset(jnp.asarray(d)))
    c, s = math.cos(pose[2]), math.sin(pose[2])
    return pose[0] + c * off[0] - s * off[1] - start[0], pose[2]


@pytest.mark.slow  # compiles RK4 and the spectral integrator (17 s under load 8)
def test_half_amplitude_square_matches_rk4_and_the_spectral_integrator():
    p = env.make_params("purcell")
    m = p.model
    states = _walk(p, [0.75, 0.75], [(2, -0.5), (1, -0.5), (2, 0.5), (1, 0.5)])
    x, theta = _x(states[-1][0]), float(states[-1][0].theta + states[-1][0].theta_lo)
    span = m.hi - m.lo
    rk_x, rk_theta = _rk4_square(m.lo + span / 4, m.hi - span / 4)
    # The spectral integrator, side by side, from the same start.
    d, pose = np.array([m.hi - span / 4] * 2), jnp.zeros(3)
    c0 = centroid(m, jnp.asarray(d), pose)
    for k, sign in ((1, -1), (0, -1), (1, 1), (0, 1)):
        rate = np.zeros(2)
        rate[k] = sign * span / 2
        pose = integrate_stroke(m, jnp.asarray(d), jnp.asarray(rate), 1.0, pose, n_sub=32)
        d[k] += rate[k]
    sp_x = float((centroid(m, jnp.asarray(d), pose) - c0)[0])
    assert abs(x) > 1e-3
    assert abs(x - rk_x) <= 1e-10 * abs(x) and abs(x - sp_x) <= 1e-10 * abs(x)
    assert abs(theta - rk_theta) <= 1e-10 and abs(theta - float(pose[2])) <= 1e-10


@pytest.mark.parametrize("swimmer", ["purcell", "ng"])
def test_small_loops_scale_as_e_squared(swimmer):
    p = env.make_params(swimmer)

    def loop(e):
        return _x(_walk(p, [0.5, 0.5], [(1, e), (2, e), (1, -e), (2, -e)])[-1][0])

    ratio = loop(0.02) / loop(0.01)
    assert abs(ratio - 4.0) <= 0.04


@pytest.mark.parametrize("swimmer", ["purcell", "ng"])
def test_motion_table_matches_the_integrator_for_any_one_dof_move(swimmer):
    m = env.make_params(swimmer).model
    rng = np.random.default_rng(7)
    s0 = rng.uniform(size=(64, 2))
    dof = rng.integers(0, 2, 64)
    s1 = s0.copy()
    s1[np.arange(64), dof] = np.clip(
        s0[np.arange(64), dof] + rng.choice([-1, 1], 64) * 10.0 ** rng.uniform(-3, 0, 64), 0, 1
    )
    table = jax.jit(jax.vmap(lambda a, b, k: motion.move_increment(m, a, b, k)))(s0, s1, dof)

    def direct(a, b):
        span = m.hi - m.lo
        d0, d1 = m.lo + span * a, m.lo + span * b
        pose = integrate_stroke(m, d0, (b - a) * span, 1.0, n_sub=40)
        disp = centroid(m, d1, pose) - centroid(m, d0, jnp.zeros(3))
        return jnp.stack([disp[0], disp[1], pose[2]])

    ref = np.asarray(jax.jit(jax.vmap(direct))(s0, s1))
    scale = np.maximum(np.abs(ref).max(axis=1), 1e-300)
    assert np.max(np.abs(np.asarray(table)[:, :3] - ref).max(axis=1) / scale) <= 1e-12


def test_a_push_past_a_limit_moves_exactly_to_it():
    p = env.make_params("purcell")
    ((s, info),) = _walk(p, [0.7, 0.2], [(1, 0.5)])
    assert (
        float(s.frac[0]) == 1.0
        and float(s.frac_lo[0]) == 0.0
        and bool(info.moved)
        and not bool(info.stuck)
    )
    assert float(env.dof_values(s, p)[0]) == p.hi
    ((exact, _),) = _walk(p, [0.7, 0.2], [(1, 0.3)])
    assert abs(_x(s) - _x(exact)) <= 1e-15
    ((s2, info2),) = _walk(p, [1.0, 0.2], [(1, 0.5)])
    assert bool(info2.stuck) and not bool(info2.moved) and _x(s2) == 0.0
    ((s3, _info3),) = _walk(p, [0.3, 0.2], [(2, -0.9)])
    assert float(s3.frac[1]) == 0.0 and float(env.dof_values(s3, p)[1]) == p.lo


def test_diagonal_strokes_follow_the_bent_path():
    p = env.make_params("purcell", diagonal=True)
    step = _stepper(p)
    start = env.start_state(p.model, jnp.asarray([0.8, 0.5]))
    # DOF 1 reaches its limit half-way: the path bends there.
    diag, _ = step(start, jnp.asarray([0.4, -0.4]))
    first, _ = step(start, jnp.asarray([0.2, -0.2]))
    two, _ = step(first, jnp.asarray([0.0, -0.2]))
    assert abs(_x(diag) - _x(two)) <= 1e-12 * abs(_x(diag))
    np.testing.assert_allclose(env.fractions(diag), [1.0, 0.1], atol=1e-15)
    # Without the option, only the first non-zero ROC moves.
    one_dof, _ = _stepper(env.make_params("purcell"))(start, jnp.asarray([0.1, -0.4]))
    np.testing.assert_allclose(env.fractions(one_dof), [0.9, 0.5], atol=1e-15)


def test_noise_scales_the_continuous_displacement():
    key = jax.random.PRNGKey(5)
    a = jnp.asarray([0.0, -0.35])
    s = env.start_state(env.make_params("purcell").model, jnp.asarray([0.6, 0.9]))
    quiet, qi = env.step(key, s, a, env.make_params("purcell"))
    noisy, ni = env.step(key, s, a, env.make_params("purcell", zeta=0.5))
    y = float(jax.random.uniform(key, (), jnp.float64, -1.0, 1.0))
    assert float(ni.dx) == pytest.approx(float(qi.dx) * (1 + 0.5 * y), rel=1e-12)
    assert float(ni.dy) == pytest.approx(float(qi.dy) * (1 + 0.5 * y), rel=1e-12)
    assert float(noisy.theta) == float(quiet.theta)  # the rotation is not perturbed


@pytest.mark.slow  # a million steps in both dtypes (32 s under load 8)
def test_float32_positions_stay_within_1e9_of_float64_over_a_million_steps(float32):
    def run(dtype, steps=1_000_000, n=3):
        p = env.make_params("purcell", roc_levels=4)
        codes = jnp.asarray(
            np.random.default_rng(2).integers(0, p.n_actions, (steps, n)), jnp.int32
        )
        s0 = jax.vmap(lambda _: env.start_state(p.model, jnp.ones(2), dtype))(jnp.arange(n))

        def body(s, a):
            s, _ = jax.vmap(env.advance, in_axes=(0, 0, None, None))(s, a, jnp.zeros((), dtype), p)
            return s, None

        s, _ = jax.jit(lambda s, c: jax.lax.scan(body, s, c))(s0, codes)
        return env.position(s)[0], env.fractions(s)

    x32, f32 = run(jnp.float32)
    with jax.enable_x64(True):
        x64, f64 = run(jnp.float64)
    assert np.all(np.abs(x64) > 1e-2)
    np.testing.assert_allclose(x32, x64, rtol=1e-9)
    np.testing.assert_array_equal(f32, f64)


def test_real_rocs_in_float32_keep_the_shape_exact(float32):
    p = env.make_params("purcell")
    rocs = np.random.default_rng(1).uniform(-1, 1, (300,)).astype(np.float32)
    dofs = np.arange(300) % 2
    acts = jnp.asarray(np.eye(2, dtype=np.float32)[dofs] * rocs[:, None])

    def run(dtype):
        s0 = env.start_state(p.model, jnp.asarray([1.0, 1.0]), dtype)

        def body(s, a):
            s, _ = env.advance(s, a.astype(dtype), jnp.zeros((), dtype), p)
            return s, None

        s, _ = jax.jit(lambda s, a: jax.lax.scan(body, s, a))(s0, acts)
        return env.position(s)[0], env.fractions(s)

    x32, f32 = run(jnp.float32)
    with jax.enable_x64(True):
        x64, f64 = run(jnp.float64)
    np.testing.assert_allclose(f32, f64, atol=1e-13)
    np.testing.assert_allclose(x32, x64, rtol=1e-10)


def test_rollout_takes_real_rocs_and_refuses_bad_ones():
    r = env.rollout_moves("purcell", [(1, -0.5), (2, -0.5), (1, 0.25)])
    np.testing.assert_allclose(r.dofs[-1], [-math.pi / 3 + 0.75 * 2 * math.pi / 3, 0.0], atol=1e-15)
    assert list(r.stuck) == [False, False, False]
    for bad, word in (([(1, 1.5)], "roc"), ([(3, 0.5)], "dof"), ([(1, float("nan"))], "finite")):
        with pytest.raises(ConfigError, match=word):
            env.rollout_moves("purcell", bad)


def test_integer_codes_and_params():
    assert env.encode_action(2, -1) == 3 and env.decode_action(3) == (2, -1)
    assert env.encode_action(2, 3, 5) == 11 + 8 and env.decode_action(19, 5) == (2, 3)
    assert env.make_params("ng", roc_levels=5).n_actions == 22
    with pytest.raises(ConfigError, match="roc_levels"):
        env.make_params("purcell", roc_levels=0)
