"""A push past a limit in a non-uniform flow: the DOF moves at its ROC until it meets the limit,
then the shape holds for the rest of the step ("fast, then held": the motors' path, whose work
`jswim.env.work` charges). The world's flow step of such a push (the flow tables' own rows on the
K lattice, the RK4 reference of an `Integrated` flow, float ROC vectors off the tables) is checked
against an independent integration of that rule: SciPy's DOP853 at tight tolerances, the move and
the hold integrated as two pieces, float64; the default float32 to a looser tolerance. The rule it
replaced (the move spread over the whole step at a lower rate) is 1e-4 to 1e-3 a away at 0.9 v
(benchmarks/flow_accuracy.py --clipped), so each check would see a step on the old rule."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

import jswim
from jswim.env.flow_steps import Integrated
from jswim.env.flows import study_flow
from jswim.env.state import start_state
from jswim.env.stepping import advance
from jswim.swimmers.flow_response import flow_velocity

TG6 = study_flow("taylor-green", 0.9)  # cells of 6 a at 0.9 v: the flow whose tables err most
SHEAR = study_flow("shear", 0.9)


def _independent(model, flow, s0, rocs, pose):
    """Centroid (2,) and orientation after one step of ROC vector ``rocs`` (one DOF) from
    fractions ``s0`` and centroid pose ``pose``, fast then held, by DOP853 (float64)."""
    s0, rocs = np.asarray(s0, float), np.asarray(rocs, float)
    s1 = np.clip(s0 + rocs, 0.0, 1.0)
    moved = np.abs(s1 - s0).sum()
    t_move = moved / np.abs(rocs).sum() if moved > 0 else 1.0
    span = np.asarray(model.hi - model.lo)
    d0, d1 = model.lo + span * s0, model.lo + span * s1
    fast = (d1 - d0) / t_move  # the DOF's rate while it moves

    @jax.jit
    def rhs(t, ref, moving):
        d = jnp.where(moving, d0 + fast * t, d1)
        u = model.body_velocity(d, jnp.where(moving, fast, 0.0))
        c, s = jnp.cos(ref[2]), jnp.sin(ref[2])
        still = jnp.stack([c * u[0] - s * u[1], s * u[0] + c * u[1], u[2]])
        return still + flow_velocity(d, ref, flow.velocity, model.xi_ratio)

    with jax.enable_x64(True):
        off = np.asarray(model.centroid_offset(jnp.asarray(d0)))
        c, s = np.cos(pose[2]), np.sin(pose[2])
        ref = np.asarray(pose, float) - [c * off[0] - s * off[1], s * off[0] + c * off[1], 0.0]
        for a, b, moving in ((0.0, t_move, True), (t_move, 1.0, False)):
            if b > a:
                sol = solve_ivp(
                    lambda t, y, m=moving: np.asarray(rhs(t, jnp.asarray(y), m)),
                    (a, b),
                    ref,
                    method="DOP853",
                    rtol=1e-12,
                    atol=1e-13,
                )
                ref = sol.y[:, -1]
        off1 = np.asarray(model.centroid_offset(jnp.asarray(d1)))
    c, s = np.cos(ref[2]), np.sin(ref[2])
    end = ref[:2] + [c * off1[0] - s * off1[1], s * off1[0] + c * off1[1]]
    return end, ref[2]


def _world_step(flow, roc_levels, s0, action, pose):
    """The world's step from fractions ``s0`` at centroid pose ``pose`` (no noise): centroid and
    orientation, float64 (the pairs summed)."""
    _, params = jswim.make("purcell", roc_levels=roc_levels, flow=flow)
    dtype = jnp.result_type(float)
    st = start_state(params.model, jnp.asarray(s0), dtype)
    with jax.enable_x64(True):
        parts = [
            (np.asarray(v, np.float64), np.asarray(v - np.asarray(v, dtype).astype(np.float64)))
            for v in (pose[0], pose[1], pose[2], np.cos(pose[2]), np.sin(pose[2]))
        ]
    (xh, xl), (yh, yl), (th, tl), (ch, cl), (sh, sl) = (
        (jnp.asarray(h, dtype), jnp.asarray(lo, dtype)) for h, lo in parts
    )
    st = st._replace(x=xh, x_lo=xl, y=yh, y_lo=yl, theta=th, theta_lo=tl)
    st = st._replace(cos=ch, cos_lo=cl, sin=sh, sin_lo=sl)
    new, _ = jax.jit(advance, static_argnums=())(st, action, jnp.zeros((), dtype), params)
    x = np.float64(new.x) + np.float64(new.x_lo)
    y = np.float64(new.y) + np.float64(new.y_lo)
    return np.array([x, y]), np.float64(new.theta) + np.float64(new.theta_lo)


def _lattice_cases(n, seed):
    """K = 2 pushes by a whole range from the middle of a DOF (half the step, then held), other
    DOF anywhere on the lattice, random poses in [-6, 6]^2: (s0, code, rocs, pose)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(n):
        dof, up = int(rng.integers(0, 2)), bool(rng.integers(0, 2))
        s0 = np.full(2, rng.integers(0, 3) / 2.0)
        s0[dof] = 0.5
        k = 2 if up else -2
        rocs = np.zeros(2)
        rocs[dof] = k / 2
        pose = np.array([*rng.uniform(-6, 6, 2), rng.uniform(-np.pi, np.pi)])
        out.append((s0, jnp.asarray(dof * 5 + k + 2, jnp.int32), rocs, pose))
    return out


def _check(flow, roc_levels, cases, tol_pos, tol_ang):
    model = jswim.make("purcell")[1].model
    for s0, action, rocs, pose in cases:
        want_xy, want_th = _independent(model, flow, s0, rocs, pose)
        got_xy, got_th = _world_step(flow, roc_levels, s0, action, pose)
        assert np.hypot(*(got_xy - want_xy)) < tol_pos, (s0, rocs, got_xy - want_xy)
        assert abs(got_th - want_th) < tol_ang, (s0, rocs, got_th - want_th)


# Tolerances: about 3 x the largest error of 8 cases measured (TG6 6.5e-6 a, 9.2e-6 rad; shear
# 3.7e-6 a, 2.9e-6 rad: the tables' own second-order error), far below the old rule's 1e-4 a.
@pytest.mark.parametrize(
    "flow, tol", [(TG6, (2e-5, 3e-5)), (SHEAR, (1.2e-5, 1e-5))], ids=["taylor-green", "shear"]
)
def test_a_clipped_lattice_push_through_the_tables_moves_fast_then_holds(flow, tol):
    _check(flow, 2, _lattice_cases(4, seed=0), *tol)


def test_the_same_in_the_default_float32(float32):
    # float32 pairs keep the pose to ~1e-12; the check is the float64 step's, rounded once
    _check(TG6, 2, _lattice_cases(3, seed=1), 2e-5, 3e-5)


@pytest.mark.slow  # compiles the unrolled RK4 step of the move and of the hold (32 pieces)
def test_a_clipped_push_through_the_rk4_reference_moves_fast_then_holds():
    _check(Integrated(TG6), 2, _lattice_cases(3, seed=2), 2e-8, 2e-8)


@pytest.mark.slow  # compiles the unrolled RK4 step of the move and of the hold (32 pieces)
def test_a_clipped_float_roc_push_moves_fast_then_holds_for_any_fraction_of_the_step():
    rng = np.random.default_rng(3)
    cases = []
    for _ in range(4):
        dof = int(rng.integers(0, 2))
        s0 = rng.uniform(0.0, 1.0, 2)
        rocs = np.zeros(2)
        rocs[dof] = rng.choice([-1, 1]) * rng.uniform(0.3, 1.0)
        s0[dof] = rng.uniform(0.05, 0.9) * abs(rocs[dof])  # room below the push: it clips
        if rocs[dof] > 0:
            s0[dof] = 1.0 - s0[dof]
        pose = np.array([*rng.uniform(-6, 6, 2), rng.uniform(-np.pi, np.pi)])
        cases.append((s0, jnp.asarray(rocs, jnp.result_type(float)), rocs, pose))
    _check(TG6, 1, cases, 2e-8, 2e-8)
