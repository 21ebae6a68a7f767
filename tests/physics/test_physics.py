"""Swimmer physics against independent numbers: closed forms, DESIGN.md references, symmetries."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jswim.integrate import centroid, integrate_stroke
from jswim.swimmers import ng, nlink, nsphere, purcell
from jswim.swimmers.models import make_model

# Square gaits as (dof index, rate sign) moves, from the (hi, hi) corner and from (lo, lo).
PURCELL_PLUS_X = [(1, -1), (0, -1), (1, 1), (0, 1)]  # from (hi, hi)
NG_PLUS_X = [(0, 1), (1, 1), (0, -1), (1, -1)]  # from (lo, lo)


def run_cycle(model, moves, start, method="chebyshev", n_sub=16, theta0=0.0):
    """Integrate a sequence of full-range moves; return (centroid displacement, rotation)."""
    d = jnp.asarray(start, jnp.float64)
    pose = jnp.array([0.0, 0.0, theta0])
    c0 = centroid(model, d, pose)
    for k, sign in moves:
        rate = jnp.zeros(model.n_dof).at[k].set(float(sign))
        pose = integrate_stroke(model, d, rate, model.duration, pose, n_sub=n_sub, method=method)
        d = d + rate * model.duration
    return np.asarray(centroid(model, d, pose) - c0), float(pose[2] - theta0)


def test_purcell_closed_form_equals_general_rft_solve():
    rng = np.random.default_rng(1)
    for _ in range(50):
        d = jnp.asarray(rng.uniform(-2.5, 2.5, 2))
        rate = jnp.asarray(rng.normal(size=2))
        theta = rng.uniform(-math.pi, math.pi)
        np.testing.assert_allclose(
            purcell.velocity(d, rate, theta), nlink.velocity(d, rate, theta), rtol=0, atol=1e-12
        )


@pytest.mark.parametrize("d_max, reference", [(math.pi / 4, 0.12660803), (math.pi / 3, 0.19124724)])
def test_purcell_square_gait_matches_design_reference(d_max, reference):
    model = make_model("purcell", d_max=d_max)
    disp, rot = run_cycle(model, PURCELL_PLUS_X, (d_max, d_max))
    # DESIGN.md gives 8 decimals: agree to half a unit in the last place.
    assert abs(disp[0] - reference) <= 5e-9
    assert abs(disp[1]) < 1e-12 and abs(rot) < 1e-12


def test_ng_square_gait_matches_closed_form():
    model = make_model("ng")
    disp, _ = run_cycle(model, NG_PLUS_X, (6.0, 6.0))
    exact = ng.square_cycle_displacement(6.0, 10.0)
    assert abs(disp[0] - exact) <= 1e-8 * exact
    assert abs(exact - 0.15626494) <= 5e-9  # DESIGN.md, 8 decimals


def test_ng_each_move_matches_closed_form():
    model = make_model("ng", d_min=5.0, d_max=9.0)
    d = [5.0, 5.0]
    for k, sign in NG_PLUS_X:
        end = list(d)
        end[k] += sign * 4.0
        disp, _ = run_cycle(model, [(k, sign)], d)
        exact = ng.arm_move_displacement(d[0], end[0], d[1], end[1])
        assert abs(disp[0] - exact) <= 1e-12 * abs(exact)
        d = end


@pytest.mark.parametrize(
    "swimmer, gait, start",
    [
        ("purcell", PURCELL_PLUS_X, "hi"),
        ("ng", NG_PLUS_X, "lo"),
    ],
)
def test_reversed_cycle_gives_opposite_displacement(swimmer, gait, start):
    model = make_model(swimmer)
    corner = (model.hi,) * 2 if start == "hi" else (model.lo,) * 2
    fwd, rot_f = run_cycle(model, gait, corner)
    back = [(k, -s) for k, s in reversed(gait)]
    rev, rot_r = run_cycle(model, back, corner)
    np.testing.assert_allclose(rev, -fwd, atol=1e-13)
    assert abs(rot_f) < 1e-12 and abs(rot_r) < 1e-12
    assert abs(fwd[0]) > 0.1


@pytest.mark.slow  # a cycle compiled for a third drag model (~3 s); the scallop test keeps the symmetry fast
def test_isotropic_drag_gives_no_net_displacement():
    model = make_model("purcell", xi_ratio=1.0)
    assert model.kind == "nlink"  # the closed form is for xi_perp/xi_par = 2 only
    disp, rot = run_cycle(model, PURCELL_PLUS_X, (model.hi, model.hi))
    assert np.all(np.abs(disp) < 1e-12) and abs(rot) < 1e-12
    # With isotropic drag zero force pins the centroid even within a stroke, while the middle
    # link still moves and turns: the model is not trivially frozen.
    one, _ = run_cycle(model, PURCELL_PLUS_X[:1], (model.hi, model.hi))
    assert np.abs(one).max() < 1e-12
    pose = integrate_stroke(
        model, jnp.array([model.hi, model.hi]), jnp.array([0.0, -1.0]), model.duration
    )
    assert abs(float(pose[2])) > 0.1 and float(jnp.hypot(pose[0], pose[1])) > 1e-3


def test_rotating_start_orientation_rotates_step_displacement():
    model = make_model("purcell")
    base, rot0 = run_cycle(model, [(0, -1)], (model.hi, model.hi))
    for theta in (0.3, -1.2, 2.9):
        disp, rot = run_cycle(model, [(0, -1)], (model.hi, model.hi), theta0=theta)
        c, s = math.cos(theta), math.sin(theta)
        np.testing.assert_allclose(
            disp, [c * base[0] - s * base[1], s * base[0] + c * base[1]], atol=1e-13
        )
        assert abs(rot - rot0) < 1e-13


@pytest.mark.slow  # compiles the RK4 integrator (~3.5 s); the non-corner convergence test stays fast
def test_chebyshev_integrator_agrees_with_rk4():
    model = make_model("purcell")
    cheb, _ = run_cycle(model, PURCELL_PLUS_X, (model.hi, model.hi))
    rk4, _ = run_cycle(model, PURCELL_PLUS_X, (model.hi, model.hi), method="rk4", n_sub=96)
    assert abs(cheb[0] - rk4[0]) <= 1e-9 * abs(cheb[0])


def test_integrator_on_a_non_corner_stroke_is_converged():
    # A diagonal stroke from an arbitrary shape (not a table move): both DOFs change at once.
    model = make_model("purcell")
    d0, rate = jnp.array([0.2, -0.7]), jnp.array([0.4, 0.9])
    a = integrate_stroke(model, d0, rate, 1.3, method="rk4", n_sub=400)
    b = integrate_stroke(model, d0, rate, 1.3, n_sub=24)
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-11)


def test_nsphere_three_matches_ng_over_a_cycle_not_within():
    ng_model = make_model("ng")
    three = make_model("nsphere", n_spheres=3)
    full_ng, _ = run_cycle(ng_model, NG_PLUS_X, (6.0, 6.0))
    full_3, _ = run_cycle(three, NG_PLUS_X, (6.0, 6.0))
    assert abs(full_ng[0] - full_3[0]) <= 1e-12
    step_ng, _ = run_cycle(ng_model, NG_PLUS_X[:1], (6.0, 6.0))
    step_3, _ = run_cycle(three, NG_PLUS_X[:1], (6.0, 6.0))
    # Within the cycle they differ by ln(d2/d1) / 6 evaluated along the move.
    assert abs((step_3[0] - step_ng[0]) - (-math.log(10 / 6) / 6)) < 1e-12


def test_nsphere_velocity_has_the_ng_first_order_form():
    d, rate = jnp.array([7.0, 8.5]), jnp.array([0.3, -1.1])
    d1, d2 = d
    r1, r2 = rate
    expected = ((r2 - r1) / (d1 + d2) - (r1 + 2 * r2) / d1 + (2 * r1 + r2) / d2) / 6
    assert abs(float(nsphere.velocity(d, rate)) - float(expected)) < 1e-14


def test_scallop_theorem_one_dof_swimmers():
    # Two links or two spheres: one DOF, any stroke is reciprocal, no net motion.
    for model in (make_model("nlink", n_links=2, d_max=1.0), make_model("nsphere", n_spheres=2)):
        lo = (model.lo,)
        disp, rot = run_cycle(model, [(0, 1), (0, -1)], lo)
        assert np.all(np.abs(disp) < 1e-12) and abs(rot) < 1e-12


def test_link_geometry_is_consistent():
    d = jnp.array([0.4, -0.9, 0.2])
    c = nlink.link_centres(d, 0.0)
    phi = nlink.link_angles(d, 0.0)
    # Adjacent links meet at their shared hinge.
    ends = c + 0.5 * jnp.stack([jnp.cos(phi), jnp.sin(phi)], -1)
    starts = c - 0.5 * jnp.stack([jnp.cos(phi), jnp.sin(phi)], -1)
    np.testing.assert_allclose(ends[:-1], starts[1:], atol=1e-14)
    np.testing.assert_allclose(jnp.diff(phi), d, atol=1e-14)
    assert float(phi[(len(phi) - 1) // 2]) == 0.0


def test_force_free_and_torque_free_by_finite_motion_of_rigid_body():
    # A rigid body (no shape change) does not move in Stokes flow.
    v = nlink.velocity(jnp.array([0.5, -0.3]), jnp.zeros(2), 0.7)
    assert np.all(np.abs(np.asarray(v)) < 1e-15)


def test_jit_and_vmap_of_velocity():
    d = jnp.asarray(np.random.default_rng(0).uniform(-1, 1, (5, 2)))
    r = jnp.ones((5, 2))
    batched = jax.jit(jax.vmap(purcell.velocity))(d, r, jnp.zeros(5))
    single = np.stack([purcell.velocity(d[i], r[i], 0.0) for i in range(5)])
    np.testing.assert_allclose(batched, single, atol=1e-14)
