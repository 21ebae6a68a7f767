"""Dissipated work against independent computations: links discretised into many segments with the
force-free motion solved afresh (NumPy), the spheres' force-free point-force solve, the
first-order closed form of the three-sphere swimmer, positivity, time reversal and the minimum
principle."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jswim.env.work import (
    corner_work_table,
    lattice_step_work,
    lattice_work_table,
    step_work,
    stroke_work,
)
from jswim.swimmers import dissipation
from jswim.swimmers.models import make_model

PURCELL = make_model("purcell")
NG = make_model("ng")


# --- independent references (NumPy, written from the definitions) -----------------------------


def _chain(d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Link angles and centres of an N-link chain, middle link (index (N-1)//2) centred at the
    origin along x; hinge j turns link j against link j - 1 by d_j."""
    n = len(d) + 1
    m = (n - 1) // 2
    phi = np.concatenate([[0.0], np.cumsum(d)])
    phi = phi - phi[m]
    centres = np.zeros((n, 2))
    for i in range(m + 1, n):  # walk outwards: half a link, then half the next
        centres[i] = centres[i - 1] + 0.5 * (_unit(phi[i - 1]) + _unit(phi[i]))
    for i in range(m - 1, -1, -1):
        centres[i] = centres[i + 1] - 0.5 * (_unit(phi[i + 1]) + _unit(phi[i]))
    return phi, centres


def _unit(a: float) -> np.ndarray:
    return np.array([math.cos(a), math.sin(a)])


def _segments(d: np.ndarray, m_seg: int) -> tuple[np.ndarray, np.ndarray]:
    """Midpoints (N m_seg, 2) of m_seg equal segments per link, and each one's tangent."""
    phi, centres = _chain(d)
    s = (np.arange(m_seg) + 0.5) / m_seg - 0.5
    t = np.stack([np.cos(phi), np.sin(phi)], -1)
    pts = centres[:, None, :] + s[None, :, None] * t[:, None, :]
    return pts.reshape(-1, 2), np.repeat(t, m_seg, axis=0)


def rft_reference(d, d_dot, xi_perp=2.0, m_seg=1000):
    """Force-free body velocity and power of the N-link swimmer by direct quadrature of f.u over
    m_seg segments per link; the shape velocity of each point by central differences."""
    d, d_dot = np.asarray(d, float), np.asarray(d_dot, float)
    h = 1e-6
    pts, t = _segments(d, m_seg)
    w = (_segments(d + h * d_dot, m_seg)[0] - _segments(d - h * d_dot, m_seg)[0]) / (2 * h)
    nrm = np.stack([-t[:, 1], t[:, 0]], -1)
    ds = 1.0 / m_seg

    def force_torque(u):
        f = -(np.sum(u * t, 1)[:, None] * t + xi_perp * np.sum(u * nrm, 1)[:, None] * nrm)
        return np.array([*f.sum(0) * ds, np.sum(pts[:, 0] * f[:, 1] - pts[:, 1] * f[:, 0]) * ds])

    def velocity(q):
        return q[:2] + q[2] * np.stack([-pts[:, 1], pts[:, 0]], -1)

    b = force_torque(w)
    mat = np.stack([force_torque(velocity(e)) for e in np.eye(3)], 1)
    q = np.linalg.solve(mat, -b)
    u = velocity(q) + w
    p = np.sum(np.sum(u * t, 1) ** 2 + xi_perp * np.sum(u * nrm, 1) ** 2) * ds
    return q, p


def spheres_reference(d, d_dot):
    """Exactly force-free point-force three-sphere (or N-sphere) swimmer: (U, P)."""
    d, d_dot = np.asarray(d, float), np.asarray(d_dot, float)
    x = np.concatenate([[0.0], np.cumsum(d)])
    w = np.concatenate([[0.0], np.cumsum(d_dot)])
    n = len(x)
    r = np.abs(x[:, None] - x[None, :])
    mob = np.where(np.eye(n, dtype=bool), 1.0, 1.5 / np.where(r == 0, 1.0, r))
    # Unknowns F (n) and U: M F - U 1 = w, sum F = 0.
    a = np.zeros((n + 1, n + 1))
    a[:n, :n], a[:n, n], a[n, :n] = mob, -1.0, 1.0
    sol = np.linalg.solve(a, np.concatenate([w, [0.0]]))
    forces, u = sol[:n], sol[n]
    return u + np.mean(w), float(forces @ (u + w))


def gauss_work(power_fn, d0, rate, duration, nodes=24):
    """int_0^duration power(d0 + rate s, rate) ds by Gauss-Legendre quadrature."""
    x, wts = np.polynomial.legendre.leggauss(nodes)
    s = (x + 1) / 2 * duration
    return sum(wk * duration / 2 * power_fn(d0 + rate * sk, rate) for sk, wk in zip(s, wts))


# --- the power --------------------------------------------------------------------------------


@pytest.mark.parametrize("n_links", [3, 4])
def test_link_power_equals_direct_quadrature_of_f_dot_u(n_links):
    model = PURCELL if n_links == 3 else make_model("nlink", n_links=4)
    rng = np.random.default_rng(n_links)
    for _ in range(4):
        d = rng.uniform(-1.2, 1.2, n_links - 1)
        d_dot = rng.normal(size=n_links - 1)
        q, p_ref = rft_reference(d, d_dot)
        got = float(dissipation.power(model, jnp.asarray(d), jnp.asarray(d_dot)))
        np.testing.assert_allclose(np.asarray(model.body_velocity(d, d_dot)), q, atol=1e-6)
        np.testing.assert_allclose(got, p_ref, rtol=1e-6)


def test_link_power_other_drag_ratio():
    model = make_model("purcell", xi_ratio=3.0)
    d, d_dot = np.array([0.7, -0.4]), np.array([0.3, 1.1])
    _, p_ref = rft_reference(d, d_dot, xi_perp=3.0)
    np.testing.assert_allclose(float(dissipation.power(model, d, d_dot)), p_ref, rtol=1e-6)


def test_sphere_power_against_the_force_free_point_force_solve():
    rng = np.random.default_rng(3)
    # NG's formula is the velocity of a point (1/6) ln(d2/d1) away from the mean sphere position:
    # first order in a/d in the velocity, second in the power (0.41 % at most over 200 shapes).
    for model, rtol in ((NG, 5e-3), (make_model("nsphere"), 3e-4)):
        for _ in range(4):
            d = rng.uniform(6.0, 10.0, model.n_dof)
            d_dot = rng.normal(size=model.n_dof)
            _, p_ref = spheres_reference(d, d_dot)
            got = float(dissipation.power(model, jnp.asarray(d), jnp.asarray(d_dot)))
            np.testing.assert_allclose(got, p_ref, rtol=rtol)
            assert got >= p_ref * (1 - 1e-12)  # the force-free motion dissipates least


def test_ng_move_work_against_first_order_closed_form():
    """One arm from d_min to d_max at rate rho, the other at c: to first order in a/d,
    W = rho L (2/3) + rho [(2/3) ln(M/m) + (2/3) ln((M + c)/(m + c)) - (1/3) L / c], L = M - m
    (the free spheres' (2/3)(d1_dot^2 + d1_dot d2_dot + d2_dot^2) plus the Oseen correction)."""
    m, big = NG.lo, NG.hi
    length = big - m
    table = corner_work_table(NG)
    for c in (m, big):
        rho = length  # one step of unit duration
        closed = rho * length * 2 / 3 + rho * (
            2 / 3 * math.log(big / m) + 2 / 3 * math.log((big + c) / (m + c)) - length / (3 * c)
        )
        row = 0 if c == m else 2  # corner (lo, lo) or (lo, hi), DOF 1
        got = table[row * 2 + 0]
        zeroth = rho * length * 2 / 3
        # The first-order term is ~12 % of the total; what remains is second order.
        assert abs(got - closed) < 0.03 * got
        assert abs(got - closed) < 0.25 * abs(closed - zeroth)


@pytest.mark.parametrize("kind", ["purcell", "nlink", "ng", "nsphere"])
def test_dissipation_matrix_is_positive_definite_and_gives_the_power(kind, float32):
    model = make_model(kind)
    rng = np.random.default_rng(7)
    matrix = jax.jit(dissipation.dissipation_matrix, static_argnums=0)
    power = jax.jit(dissipation.power, static_argnums=0)
    for _ in range(3):
        d = jnp.asarray(rng.uniform(model.lo, model.hi, model.n_dof), jnp.float32)
        d_dot = jnp.asarray(rng.normal(size=model.n_dof), jnp.float32)
        q = matrix(model, d)
        assert q.dtype == jnp.float32
        np.testing.assert_allclose(q, q.T, rtol=1e-5, atol=1e-6)
        assert np.linalg.eigvalsh(np.asarray(q, np.float64)).min() > 0
        p = power(model, d, d_dot)
        assert p.dtype == jnp.float32
        np.testing.assert_allclose(float(d_dot @ q @ d_dot), float(p), rtol=1e-4)
        # time reversal, and no cost for a still shape (a force-free body moves rigidly only with it)
        np.testing.assert_allclose(float(power(model, d, -d_dot)), float(p), rtol=1e-6)
        assert float(power(model, d, jnp.zeros_like(d_dot))) == 0.0


def test_force_free_motion_minimises_the_power():
    """Helmholtz: adding any rigid motion to the force-free one dissipates more; the gradient of
    the links' power with respect to the body velocity vanishes there."""
    d, d_dot = jnp.array([0.5, -0.9]), jnp.array([1.0, 0.4])
    body = PURCELL.body_velocity(d, d_dot)

    def p_of(v):
        tangent, cv, om = dissipation.link_motion(d, d_dot, v)
        return jnp.sum(dissipation.link_power(cv, om, tangent))

    np.testing.assert_allclose(jax.grad(p_of)(body), 0.0, atol=1e-12)
    assert float(p_of(body + jnp.array([0.01, 0.0, 0.0]))) > float(p_of(body))


def test_isotropic_drag_rigid_rotation_of_one_link():
    """xi_perp = xi_par = 1, a single straight link spinning about its centre at w: w^2 / 12."""
    got = dissipation.link_power(jnp.zeros(2), jnp.asarray(2.0), jnp.array([1.0, 0.0]), 1.0, 1.0)
    np.testing.assert_allclose(float(got), 4.0 / 12.0, rtol=1e-15)


# --- work per step and the tables -------------------------------------------------------------


def _reference_power(model):
    if model.planar:
        # midpoint rule's error ~ 1/m^2: Richardson's extrapolation of 200 and 400 segments
        return lambda d, r: (
            (4 * rft_reference(d, r, m_seg=400)[1] - rft_reference(d, r, m_seg=200)[1]) / 3
        )
    return lambda d, r: spheres_reference(d, r)[1]


@pytest.mark.parametrize("model", [PURCELL, make_model("purcell", d_max=math.pi / 4)], ids=str)
def test_square_gait_work_per_cycle_against_direct_quadrature(model):
    """The corner table's four moves of the square gait against Gauss quadrature of the
    independently discretised power (extrapolated from 200 and 400 segments per link)."""
    table = corner_work_table(model)
    span = model.hi - model.lo
    # From (hi, hi): d2 down, d1 down, d2 up, d1 up (levels -> corner index sum l_k 2^k).
    moves, levels, ref, got = [(1, -1), (0, -1), (1, 1), (0, 1)], [1, 1], 0.0, 0.0
    for k, sign in moves:
        d0 = np.array([model.lo + span * lv for lv in levels])
        rate = np.zeros(2)
        rate[k] = sign * span
        ref += gauss_work(_reference_power(model), d0, rate, 1.0, nodes=16)
        got += table[(levels[0] + 2 * levels[1]) * 2 + k]
        levels[k] = 1 - levels[k]
    np.testing.assert_allclose(got, ref, rtol=1e-9)


def test_ng_square_gait_work_against_force_free_solve():
    table = corner_work_table(NG)
    span = NG.hi - NG.lo
    moves, levels, ref, got = [(0, 1), (1, 1), (0, -1), (1, -1)], [0, 0], 0.0, 0.0
    for k, sign in moves:
        d0 = np.array([NG.lo + span * lv for lv in levels])
        rate = np.zeros(2)
        rate[k] = sign * span
        ref += gauss_work(_reference_power(NG), d0, rate, 1.0)
        got += table[(levels[0] + 2 * levels[1]) * 2 + k]
        levels[k] = 1 - levels[k]
    np.testing.assert_allclose(got, ref, rtol=5e-3)


def test_work_is_even_under_time_reversal_and_scales_with_roc():
    big_k = 2
    table = lattice_work_table(PURCELL, big_k)
    n = PURCELL.n_dof

    def row(levels, dof, end):
        shape = levels[0] + (big_k + 1) * levels[1]
        return table[(shape * n + dof) * (big_k + 1) + end]

    # forward and backward along the same segment of shape space
    np.testing.assert_allclose(row([0, 1], 0, 2), row([2, 1], 0, 0), rtol=1e-12)
    np.testing.assert_allclose(row([1, 0], 1, 2), row([1, 2], 1, 0), rtol=1e-12)
    assert row([1, 1], 0, 1) == 0.0
    # half the ROC over half the path: with P ~ rate^2 and time ~ 1 / rate, the work of the two
    # halves at ROC 1/2 sums to half of the whole at ROC 1.
    halves = row([0, 1], 0, 1) + row([1, 1], 0, 2)
    np.testing.assert_allclose(halves, 0.5 * row([0, 1], 0, 2), rtol=1e-12)
    # lattice and corner tables agree at K = 1
    np.testing.assert_allclose(
        corner_work_table(PURCELL)[:-1].sum(), lattice_work_table(PURCELL, 1).sum() / 1, rtol=1e-12
    )


def test_lattice_step_work_reads_the_table_and_scales_clipped_pushes():
    big_k = 2
    work = jax.jit(lambda lv, k: lattice_step_work(PURCELL, big_k, lv, 0, k))
    with jax.enable_x64(True):
        full = float(work(jnp.array([0, 1]), 2))
        clipped = float(work(jnp.array([1, 1]), 2))
        half = float(work(jnp.array([1, 1]), 1))
        stuck = float(work(jnp.array([2, 1]), 1))
        # the clipped push moves at ROC 1 for half a step: as the float-ROC step says
        ref = float(step_work(PURCELL, jnp.array([0.5, 0.5]), jnp.array([1.0, 0.0])))
    np.testing.assert_allclose(clipped, 2 * half, rtol=1e-12)
    np.testing.assert_allclose(clipped, ref, rtol=1e-12)
    assert stuck == 0.0 and full > clipped


def test_step_work_float32_matches_float64(float32):
    s0, rocs = jnp.array([1.0, 0.25], jnp.float32), jnp.array([-0.75, 0.5], jnp.float32)
    w32 = step_work(PURCELL, s0, rocs)
    assert w32.dtype == jnp.float32
    with jax.enable_x64(True):
        w64 = step_work(PURCELL, jnp.asarray(s0, jnp.float64), jnp.asarray(rocs, jnp.float64))
        # a diagonal step whose DOFs stay inside their ranges is one straight stroke; one whose
        # second DOF reaches its limit at t = 0.75 bends there: two straight pieces
        span = PURCELL.hi - PURCELL.lo
        d0 = PURCELL.lo + span * jnp.array([1.0, 0.25])
        np.testing.assert_allclose(
            float(w64),
            float(stroke_work(PURCELL, d0, jnp.array([-0.75, 0.5]) * span, 1.0)),
            rtol=1e-12,
        )
        bent = step_work(PURCELL, jnp.array([1.0, 0.25]), jnp.array([-0.5, 1.0]))
        first = stroke_work(PURCELL, d0, jnp.array([-0.5, 1.0]) * span, 0.75)
        d1 = d0 + jnp.array([-0.5, 1.0]) * span * 0.75
        second = stroke_work(PURCELL, d1, jnp.array([-0.5, 0.0]) * span, 0.25)
    np.testing.assert_allclose(float(w32), float(w64), rtol=1e-5)
    np.testing.assert_allclose(float(bent), float(first + second), rtol=1e-12)


def test_wall_coefficients_scale_the_power():
    """Above a wall the links keep RFT with their own (xi_par, xi_perp): the power is xi_par
    times that of the ratio xi_perp / xi_par (the velocities depend on the ratio only)."""
    from jswim.swimmers.wall_rft import wall_model

    model = wall_model(0.3)
    d, d_dot = np.array([0.4, 0.9]), np.array([-1.0, 0.5])
    _, p_ref = rft_reference(d, d_dot, xi_perp=model.xi_perp / model.xi_par)
    got = float(dissipation.power(model, jnp.asarray(d), jnp.asarray(d_dot)))
    np.testing.assert_allclose(got, model.xi_par * p_ref, rtol=1e-6)


@pytest.mark.parametrize(
    "kind",
    ["purcell", pytest.param("nlink", marks=pytest.mark.slow)],  # slow: its K = 2 table
)
def test_step_work_of_a_lattice_move_is_its_table_row(kind):
    """The float-ROC step (the stepping's path) and the lattice table agree, three-DOF too."""
    model = make_model(kind)
    big_k, n = 2, model.n_dof
    table = lattice_work_table(model, big_k)
    levels = [2, 0, 1][:n]
    work = jax.jit(step_work, static_argnums=0)
    for dof, end in [(0, 0), (1, 2), (n - 1, 1)]:
        shape = sum(lv * (big_k + 1) ** m for m, lv in enumerate(levels))
        row = (shape * n + dof) * (big_k + 1) + end
        rocs = np.zeros(n)
        rocs[dof] = (end - levels[dof]) / big_k
        got = work(model, jnp.asarray(levels, float) / big_k, jnp.asarray(rocs))
        np.testing.assert_allclose(float(got), table[row], rtol=1e-12, atol=1e-15)
    corner = corner_work_table(model)
    assert corner.shape == (2**n * n + 1,) and corner[-1] == 0.0 and np.all(corner[:-1] > 0)
