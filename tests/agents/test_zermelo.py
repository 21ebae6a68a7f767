"""Zermelo's reference (jswim.agents.zermelo) against independent numbers: the still-fluid
distance over speed, the uniform-flow quadratic against the shooting method (two independent
computations), the shear's closed-form extremal solved here by Newton, the Taylor-Green cells'
mirror symmetries, and constant-heading paths integrated here in NumPy."""

import math
import time

import numpy as np
import pytest

import jswim.agents.zermelo as zermelo_module
from jswim.agents.zermelo import ZermeloPath, uniform_time, zermelo
from jswim.env.flows import SWIM_SPEED, Poiseuille, Shear, TaylorGreen, Uniform, study_flow
from jswim.env.targets import FixedTarget, MovingTarget, Waypoints
from jswim.errors import ConfigError

V = SWIM_SPEED
R = 0.25


def _rel(a, b):
    return abs(a - b) / abs(b)


def _check_path(z: ZermeloPath, start, centre, radius=R):
    """Samples at every whole step from the start, the last at the hit time, on the disc."""
    n = math.floor(z.steps)
    assert z.xy.shape == (len(z.t), 2) and z.heading.shape == z.t.shape
    np.testing.assert_array_equal(z.t[: n + 1], np.arange(n + 1))
    assert z.t[-1] == pytest.approx(z.steps, abs=1e-12)
    np.testing.assert_allclose(z.xy[0], start, atol=1e-12)
    assert math.hypot(*(z.xy[-1] - np.asarray(centre))) == pytest.approx(radius, abs=1e-6)


# ---------------------------------------------------------------- still fluid and uniform flows


@pytest.mark.parametrize("bearing", [0.0, 90.0, 180.0, -135.0])
def test_still_fluid_is_distance_over_speed(bearing):
    spec = FixedTarget(3.0, bearing)
    z = zermelo(None, spec)
    assert z.reachable and z.steps == pytest.approx((3.0 - R) / V, rel=1e-14)
    _check_path(z, (0.0, 0.0), spec.points()[0])
    np.testing.assert_allclose(z.heading, math.radians(bearing), atol=1e-12)


@pytest.mark.parametrize(
    ("u", "bearing"),
    [
        ((0.0, 0.5 * V), 0.0),
        ((0.0, 0.9 * V), 90.0),
        ((0.3 * V, -0.6 * V), 135.0),
        # 415 steps, past 4 still-fluid times: the default horizon's straight-line bound
        ((0.0, 0.9 * V), -45.0),
    ],
)
def test_uniform_closed_form_matches_shooting(u, bearing):
    flow, spec = Uniform(u), FixedTarget(3.0, bearing)
    closed = zermelo(flow, spec, method="closed")
    shot = zermelo(flow, spec, method="shooting")
    assert _rel(shot.steps, closed.steps) < 1e-6  # measured ~1e-15
    # the heading is resolved to ~6e-7 rad (the time only to second order in it), so the end
    # point, first order in it, to ~v T 6e-7
    assert shot.heading[0] == pytest.approx(closed.heading[0], abs=1e-6)
    np.testing.assert_allclose(shot.xy[-1], closed.xy[-1], atol=1e-5)
    _check_path(shot, (0.0, 0.0), spec.points()[0])


def test_uniform_flow_faster_than_the_steerer():
    flow = Uniform((0.0, 1.5 * V))
    # across the stream: carried off faster than it can swim back
    assert uniform_time(flow.u, (3.0, 0.0), R, V) is None
    across = zermelo(flow, FixedTarget(3.0, 0.0))
    assert not across.reachable and across.xy.shape == (1, 2) and np.isnan(across.heading[0])
    # the shooting method finds no extremal either, within its horizon
    assert zermelo(flow, FixedTarget(3.0, 0.0), method="shooting").steps is None
    # downstream: straight down the stream at v + |u|
    down = zermelo(flow, FixedTarget(3.0, 90.0))
    assert down.steps == pytest.approx((3.0 - R) / (2.5 * V), rel=1e-13)


def test_uniform_time_edge_cases():
    # |u - w| = v exactly (the quadratic is linear): upstream against a stream of speed v ...
    assert uniform_time((V, 0.0), (-3.0, 0.0), R, V) is None
    assert uniform_time((-V, 0.0), (3.0, 0.0), R, V) is None
    # ... downstream with it: 2v
    assert uniform_time((V, 0.0), (3.0, 0.0), R, V) == pytest.approx((3.0 - R) / (2 * V))
    # a target moving off at v + v/2 in still fluid: never; one coming at v/2: 1.5v
    assert uniform_time((0.0, 0.0), (3.0, 0.0), R, V, velocity=(1.5 * V, 0.0)) is None
    assert uniform_time((0.0, 0.0), (3.0, 0.0), R, V, velocity=(-0.5 * V, 0.0)) == pytest.approx(
        (3.0 - R) / (1.5 * V)
    )
    # across a stream of speed v: |P - u T| = v T + r solved by hand, T = (9 - r^2) / (2 v r)
    assert uniform_time((V, 0.0), (0.0, 3.0), R, V) == pytest.approx((9 - R * R) / (2 * V * R))
    # the start on or inside the disc
    assert uniform_time((0.0, 0.0), (0.1, 0.0), R, V) == 0.0


def test_moving_target_in_still_fluid():
    w = (0.0, 0.3 * V)
    spec = MovingTarget(3.0, 0.0, velocity=w)
    # the meeting time by bisection on |P + w T| - v T - r (decreasing here)
    lo, hi = 0.0, 1000.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if math.hypot(3.0, w[1] * mid) - V * mid - R > 0 else (lo, mid)
    z = zermelo(None, spec)
    assert z.steps == pytest.approx(hi, rel=1e-12)
    assert uniform_time((0.0, 0.0), (3.0, 0.0), R, V, velocity=w) == pytest.approx(hi, rel=1e-12)
    _check_path(z, (0.0, 0.0), (3.0, w[1] * z.steps))
    # the shooting method on the same moving target
    shot = zermelo(Uniform((0.0, 0.0)), spec, method="shooting")
    assert _rel(shot.steps, hi) < 1e-6


def test_start_inside_the_radius():
    z = zermelo(None, FixedTarget(3.0, 0.0), start=(2.9, 0.05))
    assert z.steps == 0.0 and z.xy.shape == (1, 2) and z.legs == (0.0,)
    assert zermelo(Shear(0.01), FixedTarget(3.0), start=(2.9, 0.0)).steps == 0.0


def test_waypoints_leg_by_leg():
    spec = Waypoints(((3.0, 0.0), (3.0, 3.0)))
    z = zermelo(None, spec)
    first = (3.0 - R) / V  # reached at (2.75, 0)
    second = (math.hypot(0.25, 3.0) - R) / V
    assert z.legs == pytest.approx((first, first + second), rel=1e-13)
    assert z.steps == pytest.approx(first + second, rel=1e-13)
    _check_path(z, (0.0, 0.0), (3.0, 3.0))
    # the shooting method, leg by leg through the same (still) fluid
    shot = zermelo(Uniform((0.0, 0.0)), spec, method="shooting")
    assert shot.legs == pytest.approx(z.legs, rel=1e-6)


# ---------------------------------------------------------------- shear: the closed-form extremal


def _shear_extremal(theta0, t, g, v=V):
    """The extremal of u = (g y, 0) from the origin, from d tan h / dt = -g: with t = tan h
    (t0 at the start) and s the sign of cos h0 (the heading never crosses +-pi/2),
    y = (v / g)(sec h0 - sec h) and x = v sec h0 t + (v s / 2g)[asinh t0 - asinh t
    + t sqrt(1 + t^2) - t0 sqrt(1 + t0^2)] (integrals of sin h, cos h and g y over d tan h).
    Works on a complex ``theta0`` (complex-step derivatives)."""
    s = np.sign(np.cos(np.real(theta0)))
    tau0 = np.tan(theta0)
    tau = tau0 - g * t
    root0, root = np.sqrt(1 + tau0 * tau0), np.sqrt(1 + tau * tau)
    y = v / g * s * (root0 - root)
    x = v * s * root0 * t + v * s / (2 * g) * (
        np.arcsinh(tau0) - np.arcsinh(tau) + tau * root - tau0 * root0
    )
    return x, y


def _shear_optimum(g, centre, r=R):
    """(T, theta0) of the time-optimal extremal: |X(theta0, T) - c| = r with the front tangent
    to the disc there, (X - c) . dX/dtheta0 = 0 (the hit time stationary in theta0), by Newton
    from the best of a coarse scan."""
    c = np.asarray(centre)
    thetas = np.linspace(-math.pi, math.pi, 721)[:-1]
    ts = np.linspace(0.0, 150.0, 1501)
    x, y = _shear_extremal(thetas[:, None], ts[None, :], g)
    inside = np.hypot(x - c[0], y - c[1]) < max(r, 0.1)  # a seed: the grid resolves 0.1 a
    first = np.where(inside.any(1), inside.argmax(1), ts.size)
    i = int(np.argmin(first))

    def f(q):
        x, y = _shear_extremal(q[0], q[1], g)
        xc, yc = _shear_extremal(q[0] + 1e-30j, q[1], g)
        dx, dy = np.imag(xc) / 1e-30, np.imag(yc) / 1e-30
        return np.array(
            [(x - c[0]) ** 2 + (y - c[1]) ** 2 - r * r, (x - c[0]) * dx + (y - c[1]) * dy]
        )

    q = np.array([thetas[i], ts[first[i]]])
    steps = np.array([1e-7, 1e-6])
    for _ in range(20):
        jac = np.column_stack(
            [(f(q + np.eye(2)[k] * steps[k]) - f(q)) / steps[k] for k in range(2)]
        )
        q = q - np.linalg.solve(jac, f(q))
    assert np.max(np.abs(f(q))) < 1e-12
    return q[1], q[0]


@pytest.mark.parametrize(
    ("fraction", "bearing", "radius"),
    # a radius of 0.01 a is a fifth of a step's travel: found by the chord test, not stepped over
    [(0.9, 90.0, R), (0.5, 45.0, R), (0.9, 0.0, R), (0.9, 120.0, 0.01)],
)
def test_shear_matches_the_closed_form_extremal(fraction, bearing, radius):
    flow = study_flow("shear", fraction)
    spec = FixedTarget(3.0, bearing, radius=radius)
    t_exact, theta0 = _shear_optimum(flow.rate, spec.points()[0], radius)
    z = zermelo(flow, spec)
    assert _rel(z.steps, t_exact) < 1e-6  # measured ~1e-9
    assert z.heading[0] == pytest.approx(theta0, abs=1e-4)
    # the path is the closed-form extremal of its own start heading, headings included
    x, y = _shear_extremal(z.heading[0], z.t, flow.rate)
    np.testing.assert_allclose(z.xy, np.column_stack([x, y]), atol=1e-8)
    tan = np.tan(z.heading[0]) - flow.rate * z.t
    np.testing.assert_allclose(np.tan(z.heading), tan, rtol=1e-8, atol=1e-8)
    _check_path(z, (0.0, 0.0), spec.points()[0], radius)


def test_shear_point_symmetry():
    # u(-x) = -u(x): the target at b and at b + 180 take the same time
    flow = study_flow("shear", 0.9)
    assert zermelo(flow, FixedTarget(3.0, 30.0)).steps == pytest.approx(
        zermelo(flow, FixedTarget(3.0, -150.0)).steps, rel=1e-9
    )


# ---------------------------------------------------------------- Taylor-Green cells


def _constant_heading_best(flow, centre, headings, r=R, dt=0.25, t_max=300.0):
    """The least first-hit time over constant headings, each path by RK4 in NumPy."""
    k, u0 = flow.k, flow.u0
    c = np.asarray(centre)
    e = V * np.column_stack([np.cos(headings), np.sin(headings)])

    def vel(p):
        sx, cx = np.sin(k * p[:, 0]), np.cos(k * p[:, 0])
        sy, cy = np.sin(k * p[:, 1]), np.cos(k * p[:, 1])
        return u0 * np.column_stack([sx * cy, -cx * sy]) + e

    p = np.zeros((len(headings), 2))
    best = np.full(len(headings), np.inf)
    d_old = np.hypot(*(p - c).T)
    for n in range(int(t_max / dt)):
        k1 = vel(p)
        k2 = vel(p + 0.5 * dt * k1)
        k3 = vel(p + 0.5 * dt * k2)
        k4 = vel(p + dt * k3)
        p = p + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        d = np.hypot(*(p - c).T)
        new = np.isinf(best) & (d < r)
        best[new] = (n + (d_old[new] - r) / (d_old[new] - d[new])) * dt
        d_old = d
    return best.min()


def test_taylor_green_mirror_symmetry():
    # u = u0 (sin kx cos ky, -cos kx sin ky): u1(x, -y) = u1(x, y), u2(x, -y) = -u2(x, y), so
    # the flow is its own mirror image in the x axis (and in the y axis): b and -b, b and 180 - b
    flow = TaylorGreen(0.5 * V, 6.0)
    t = [zermelo(flow, FixedTarget(3.0, b)).steps for b in (60.0, -60.0, 120.0)]
    assert t[1] == pytest.approx(t[0], rel=1e-9)
    assert t[2] == pytest.approx(t[0], rel=1e-9)


@pytest.mark.parametrize("fraction", [0.5, 0.9])
def test_taylor_green_beats_constant_headings(fraction):
    flow = study_flow("taylor-green", fraction)
    spec = FixedTarget(3.0, 90.0)
    z = zermelo(flow, spec)
    headings = np.radians(np.arange(30, 151, 1.0))
    straight = _constant_heading_best(flow, spec.points()[0], headings, t_max=600.0)
    assert z.steps <= straight + 1e-3  # the NumPy paths' hits are interpolated linearly
    if fraction == 0.9:
        # upstream along the y axis against 0.9 v the optimum swings round through the cells
        assert z.steps < 0.8 * straight
    else:
        # at 0.5 v the optimum is the straight line up the axis (heading 90 throughout)
        assert z.steps == pytest.approx(straight, abs=1e-3)
        np.testing.assert_allclose(z.heading, math.pi / 2, atol=1e-9)
    _check_path(z, (0.0, 0.0), spec.points()[0])


def test_taylor_green_along_the_outflow_axis():
    # on y = 0 the flow is (u0 sin kx, 0) and the heading equation keeps h = 0 (du1/dy = 0
    # there): the extremal is the axis, T = int_0^(3 - r) dx / (v + u0 sin kx) (Simpson here)
    flow = study_flow("taylor-green", 0.5)
    x = np.linspace(0.0, 3.0 - R, 20001)
    f = 1.0 / (V + flow.u0 * np.sin(flow.k * x))
    simpson = (x[1] - x[0]) / 3 * (f[0] + f[-1] + 4 * f[1:-1:2].sum() + 2 * f[2:-1:2].sum())
    z = zermelo(flow, FixedTarget(3.0, 0.0))
    assert _rel(z.steps, simpson) < 1e-6
    np.testing.assert_allclose(z.xy[:, 1], 0.0, atol=1e-12)


def test_taylor_green_weak_flow_tends_to_still_fluid():
    still = (3.0 - R) / V
    gap = [
        still - zermelo(TaylorGreen(f * V, 6.0), FixedTarget(3.0, 30.0)).steps for f in (0.02, 0.01)
    ]
    assert 0 < gap[0] / still < 0.02
    # first order in u0: half the flow, half the gain
    assert gap[1] == pytest.approx(gap[0] / 2, rel=0.05)


# ---------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"speed": 0.0}, "speed"),
        ({"speed": -1.0}, "speed"),
        ({"speed": float("nan")}, "speed"),
        ({"speed": float("inf")}, "speed"),
        ({"speed": "fast"}, "speed"),
        ({"speed": True}, "speed"),
        ({"target": (3.0, 0.0)}, "target"),
        ({"target": {"kind": "fixed", "distance": 3.0}}, "target"),
        ({"flow": "shear"}, "flow"),
        ({"start": (0.0,)}, "start"),
        ({"start": (0.0, float("nan"))}, "start"),
        ({"start": (1e300, 0.0)}, "start"),  # past the targets' range (1e4 a)
        ({"start": (0.0, -2e4)}, "start"),
        ({"speed": 10**400}, "speed"),  # an int past float's range: OverflowError
        ({"speed": 48.0}, "speed"),  # past the flows' range (1000 v)
        ({"horizon": 0}, "horizon"),
        ({"horizon": 1e9}, "horizon"),
        ({"method": "guess"}, "method"),
        ({"flow": Shear(0.01), "method": "closed"}, "closed form"),
    ],
)
def test_bad_input(kwargs, match):
    args = {"flow": None, "target": FixedTarget(3.0)} | kwargs
    with pytest.raises(ConfigError, match=match) as info:
        zermelo(**args)
    assert "\n" not in str(info.value)


def test_bad_closed_form_input():
    with pytest.raises(ConfigError, match="speed"):
        uniform_time((0.0, 0.0), (3.0, 0.0), R, 0.0)
    with pytest.raises(ConfigError, match="radius"):
        uniform_time((0.0, 0.0), (3.0, 0.0), -1.0, V)


# ---------------------------------------------------------------- the work bound (issue 61)


def _past_the_ranges(cls, **fields):
    """A flow made past the constructor's checks: what ``Shear(100)`` was before they existed."""
    flow = object.__new__(cls)
    for name, value in fields.items():
        object.__setattr__(flow, name, value)
    return flow


@pytest.mark.parametrize(
    ("flow", "start", "says"),
    [
        # the issue's: 142 s, and unfinished after 240 s
        (_past_the_ranges(Shear, rate=100.0), (0.0, 0.0), "MAX_RK4_STEPS"),
        (_past_the_ranges(Shear, rate=1e6), (0.0, 0.0), "MAX_RK4_STEPS"),
        # a channel in range, the way to the target far outside it (gradient 2e3 a step there)
        (Poiseuille(0.5, 1.0), (0.0, 2e3), "MAX_RK4_STEPS"),
        # the issue's "cannot convert float NaN to integer"
        (_past_the_ranges(Poiseuille, u_max=1.0, half_width=1e-300), (0.0, 0.0), "finite"),
    ],
    ids=["shear 100", "shear 1e6", "off the channel", "nan"],
)
def test_a_flow_past_its_range_is_refused_at_once_in_one_line(flow, start, says):
    t0 = time.perf_counter()
    with pytest.raises(ConfigError, match=says) as info:
        zermelo(flow, FixedTarget(3.0, 90.0), start=start)
    assert "\n" not in str(info.value)
    assert time.perf_counter() - t0 < 5.0  # before any integration (measured 0.1 to 0.4 s)


def test_the_issue_s_shear_is_refused_where_it_is_made():
    with pytest.raises(ConfigError, match="rate"):
        zermelo(Shear(100), FixedTarget(3.0, 90.0))


def test_a_leg_takes_at_most_max_rk4_steps(monkeypatch):
    # Shear(0.1): 2 RK4 steps a step over the default horizon, 4 x 57.5 + 64 = 294 steps
    flow, spec = Shear(0.1), FixedTarget(3.0, 90.0)
    monkeypatch.setattr(zermelo_module, "MAX_RK4_STEPS", 587)
    with pytest.raises(ConfigError, match="2 RK4 steps a step over a horizon of 294 steps"):
        zermelo(flow, spec)
    with pytest.raises(ConfigError, match="MAX_RK4_STEPS"):  # a horizon given counts alike
        zermelo(flow, spec, horizon=400.0)
    monkeypatch.setattr(zermelo_module, "MAX_RK4_STEPS", 590)
    bounded = zermelo(flow, spec)
    monkeypatch.undo()
    assert bounded.steps == zermelo(flow, spec).steps and bounded.reachable
