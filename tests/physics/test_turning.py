"""Turning loops against an independent RFT integration, their symmetries, and the steering
controller driving the environment's Purcell swimmer to targets at every bearing."""

import math

import jax.numpy as jnp
import numpy as np
import pytest

from jswim.env import make_params
from jswim.env.loops import lattice_loops, loop_motion, steer, steering_budget, steering_plan
from jswim.swimmers import purcell
from jswim.swimmers.models import make_model
from jswim.swimmers.turning import (
    Loop,
    choose_cycle,
    quarter_loop,
    rectangle,
    square_gait,
)
from tests.physics.test_dissipation import _chain, rft_reference

PURCELL = make_model("purcell")
#: The issue's number: the quarter loop from (pi/3, pi/3) turns Purcell's swimmer by +0.0584 rad.
QUARTER_TURN = 0.0584


def _vertices_to_shapes(model, loop, big_k):
    span = model.hi - model.lo
    return [
        np.array([model.lo + span * i / big_k, model.lo + span * j / big_k])
        for i, j in loop.vertices
    ]


def independent_rotation(model, loop, big_k, nodes=12):
    """Net rotation of a cycle: the angular velocity of the discretised RFT solve (extrapolated
    from 200 and 400 segments per link), Gauss-Legendre along each side."""
    shapes = _vertices_to_shapes(model, loop, big_k)
    x, w = np.polynomial.legendre.leggauss(nodes)
    total = 0.0
    for a, b in zip(shapes, shapes[1:] + shapes[:1]):
        rate = b - a  # unit duration per side
        for xk, wk in zip(x, w):
            d = a + rate * (xk + 1) / 2
            om = [rft_reference(d, rate, m_seg=m)[0][2] for m in (200, 400)]
            total += wk / 2 * (4 * om[1] - om[0]) / 3
    return total


def independent_cycle(model, loop, big_k, substeps=150):
    """Centroid displacement (body frame at the start) and rotation of a cycle by classical RK4
    on the closed-form velocities evaluated with NumPy, the centroid from an independent chain."""
    shapes = _vertices_to_shapes(model, loop, big_k)
    pose = np.zeros(3)

    def rate(p, d, r):
        u, v, om = purcell.velocity(d, r, p[2], xp=np)
        return np.array([u, v, om])

    def centroid(p, d):
        _phi, centres = _chain(d)
        off = centres.mean(0)
        c, s = math.cos(p[2]), math.sin(p[2])
        return p[:2] + np.array([c * off[0] - s * off[1], s * off[0] + c * off[1]])

    start = centroid(pose, shapes[0])
    h = 1.0 / substeps
    for a, b in zip(shapes, shapes[1:] + shapes[:1]):
        r = b - a
        for i in range(substeps):
            t = i * h
            k1 = rate(pose, a + r * t, r)
            k2 = rate(pose + h / 2 * k1, a + r * (t + h / 2), r)
            k3 = rate(pose + h / 2 * k2, a + r * (t + h / 2), r)
            k4 = rate(pose + h * k3, a + r * (t + h), r)
            pose = pose + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return centroid(pose, shapes[0]) - start, pose[2]


def closed_form_rotation(model, loop, big_k, nodes=24):
    """Net rotation of a cycle: Gauss-Legendre quadrature of the closed-form angular velocity."""
    shapes = _vertices_to_shapes(model, loop, big_k)
    x, w = np.polynomial.legendre.leggauss(nodes)
    return sum(
        wk / 2 * purcell.velocity(a + (b - a) * (xk + 1) / 2, b - a, 0.0, xp=np)[2]
        for a, b in zip(shapes, shapes[1:] + shapes[:1])
        for xk, wk in zip(x, w)
    )


def test_quarter_loop_turns_by_the_issues_angle():
    loop = quarter_loop(2)
    assert loop.vertices == ((2, 2), (2, 1), (1, 1), (1, 2))  # (pi/3,pi/3) (pi/3,0) (0,0) (0,pi/3)
    got = loop_motion(PURCELL, 2, loop)
    np.testing.assert_allclose(got.rotation, closed_form_rotation(PURCELL, loop, 2), atol=1e-13)
    assert abs(got.rotation - QUARTER_TURN) < 5e-5
    # about 27 quarter loops to turn 90 degrees (the issue's count)
    assert round(math.pi / 2 / got.rotation) == 27


@pytest.mark.slow  # ~5 s of NumPy: 96 discretised force-free solves
def test_quarter_loop_turns_as_an_independent_rft_integration():
    loop = quarter_loop(2)
    got = loop_motion(PURCELL, 2, loop)
    np.testing.assert_allclose(got.rotation, independent_rotation(PURCELL, loop, 2), atol=1e-9)


@pytest.mark.slow  # ~3 s of NumPy RK4
def test_quarter_loop_displacement_as_an_independent_rk4_integration():
    got = loop_motion(PURCELL, 2, quarter_loop(2))
    disp, rot = independent_cycle(PURCELL, quarter_loop(2), 2)
    np.testing.assert_allclose([got.dx, got.dy], disp, atol=1e-10)
    np.testing.assert_allclose(got.rotation, rot, atol=1e-12)


@pytest.mark.parametrize(
    "dm",
    [math.pi / 3, pytest.param(math.pi / 4, marks=pytest.mark.slow)],  # slow: its tables
)
def test_loops_rotate_by_the_sign_of_their_orientation_and_cost_the_same_both_ways(dm):
    model = make_model("purcell", d_max=dm)
    square = loop_motion(model, 2, square_gait(2))
    assert abs(square.rotation) < 1e-14  # centred: no turn
    for motion in lattice_loops(model, 2):
        back = loop_motion(model, 2, motion.loop.reversed())
        np.testing.assert_allclose(back.rotation, -motion.rotation, atol=1e-14)
        np.testing.assert_allclose(back.work, motion.work, rtol=1e-12)
        # the reverse cycle undoes the rigid motion: (dx, dy) -> -R(-rotation) (dx, dy)
        c, s = math.cos(motion.rotation), math.sin(motion.rotation)
        undo = [-(c * motion.dx + s * motion.dy), -(-s * motion.dx + c * motion.dy)]
        np.testing.assert_allclose([back.dx, back.dy], undo, atol=1e-14)


def test_k2_lattice_loops_are_nine_rectangles_with_two_rotations():
    motions = lattice_loops(PURCELL, 2)
    assert len(motions) == 9
    rotations = sorted({round(abs(m.rotation), 9) for m in motions})
    assert rotations == [0.0, round(loop_motion(PURCELL, 2, quarter_loop(2)).rotation, 9)]
    # the quarter loop turns as much as either half rectangle through it, for less work
    quarter = loop_motion(PURCELL, 2, quarter_loop(2))
    half = loop_motion(PURCELL, 2, rectangle((1, 0), (2, 2), (2, 2)))
    np.testing.assert_allclose(half.rotation, quarter.rotation, rtol=1e-12)
    assert quarter.work < 0.5 * half.work


def test_loop_checks():
    with pytest.raises(ValueError, match="one DOF"):
        Loop(((0, 0), (1, 1))).moves()
    with pytest.raises(ValueError, match="even K"):
        quarter_loop(3)
    with pytest.raises(ValueError, match="line"):
        steering_plan(make_model("ng"))


def test_choose_cycle_from_the_bearing():
    plan = steering_plan(PURCELL, 2)
    np.testing.assert_allclose(plan.heading, 0.0, atol=1e-15)
    assert plan.turn > 0

    def pick(hub, bearings, p=plan):
        return [int(choose_cycle(p, hub, b)) for b in bearings]

    bearings = (0.0, 0.05, 0.5, -0.5, math.pi, 3.1, -3.1, 3.0, -3.0)
    # hub 0, (hi, hi): straight = half a gait forward (0) or backward (2); left turns here (4);
    # a right turn first swims half a gait to hub 1; behind: backward, 3.0 rad is 0.14 rad right
    # of the backward heading (a negative turn while swimming backward: cycle 5, here)
    assert pick(0, bearings) == [0, 0, 4, 0, 2, 2, 2, 5, 2]
    # hub 1, (lo, lo): right turns here (6), left turns backward here (7)
    assert pick(1, bearings) == [1, 1, 1, 6, 3, 3, 3, 3, 7]
    no_reverse = plan._replace(reverse=False)
    assert pick(0, (math.pi - 0.1, -math.pi + 0.1), no_reverse) == [4, 0]


def test_each_turning_cycle_turns_its_way_and_moves_along_its_heading():
    from jswim.swimmers import turning

    plan = steering_plan(PURCELL, 2)
    for cycle, sign, forward in [
        (turning.LEFT_FORWARD, 1, True),
        (turning.RIGHT_BACKWARD, -1, False),
        (turning.RIGHT_FORWARD, -1, True),
        (turning.LEFT_BACKWARD, 1, False),
    ]:
        hub = int(plan.hub[cycle])
        start = (2, 2) if hub == 0 else (0, 0)
        verts, cur = [start], list(start)
        for dof, q in np.asarray(plan.moves[cycle][: plan.lengths[cycle]]).tolist()[:-1]:
            cur[dof] += q
            verts.append(tuple(cur))
        m = loop_motion(PURCELL, 2, Loop(tuple(verts)))
        assert np.sign(m.rotation) == sign and (m.dx > 0) == forward
        np.testing.assert_allclose(abs(m.rotation), plan.turn, rtol=1e-12)


BEARINGS = (0.0, 90.0, 180.0, -90.0)
DISTANCE, RADIUS = 3.0, 0.25


@pytest.mark.parametrize("reverse", [True, pytest.param(False, marks=pytest.mark.slow)])
def test_controller_reaches_targets_at_every_bearing_within_its_budget(reverse, float32):
    angles = np.radians(BEARINGS)
    targets = jnp.asarray(
        np.stack([DISTANCE * np.cos(angles), DISTANCE * np.sin(angles)], -1), jnp.float32
    )
    budgets = [steering_budget(PURCELL, DISTANCE, a, reverse=reverse) for a in angles]
    params = make_params("purcell", roc_levels=2)
    plan = steering_plan(params.model, 2, reverse=reverse)
    run = steer(params, plan, targets, max(budgets), RADIUS)
    steps = np.asarray(run.steps)
    assert np.all(steps > 0), steps
    assert np.all(steps <= np.array(budgets)), (steps, budgets)
    # straight ahead takes about D / dX square-gait cycles: no turning
    gait = loop_motion(PURCELL, 2, square_gait(2))
    assert steps[0] <= 4 * math.ceil((DISTANCE - RADIUS) / gait.displacement) + 4
    # the work is the tables': straight ahead, whole square-gait cycles of the gait's work
    work = np.asarray(run.work, np.float64)
    assert run.work.dtype == jnp.float32  # the working dtype
    cycles = steps[0] // 4
    np.testing.assert_allclose(work[0, : 4 * cycles].sum(), cycles * gait.work, rtol=1e-5)
    assert np.all(work >= 0)
