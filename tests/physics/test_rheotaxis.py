"""Purcell's swimmer doing the square gait in plane Poiseuille flow swings upstream across the
centre line, as Zöttl & Stark's theory of a swimmer with Jeffery rotation says (PRL 108, 218104,
2012): with ``theta`` the heading (``pi``: upstream), ``y`` the lateral place and
``kappa = u_max / h^2``,

    dy/dt = v sin(theta),    dtheta/dt = kappa y (1 - B cos 2 theta),

a centre at ``(0, pi)`` with frequency ``Omega = sqrt(v kappa (1 - B))``, the invariant
``H = kappa y^2 / 2 + (v / S) artanh(K cos theta)`` (``S = sqrt(2 B (1 + B))``,
``K = sqrt(2 B / (1 + B))``), and a separatrix through the downstream saddle ``(0, 0)``.

The numbers the model is checked against come from outside the world's stepping:

- ``B`` and the offset ``c`` are the square gait's stroke averages in the still-fluid cycle:
  the rotation per cycle that `jswim.swimmers.flow_response.flow_velocity` gives along the
  still path is Jeffery's ``-(rate / 2)(1 - B cos 2 theta)`` in shear with ``B = 0.83753``
  (no ``sin 2 theta`` term: the gait's mirror image is itself half a cycle on), and the cycle's
  time-averaged centroid sits ``c = 0.018101 a`` to the side of the one sampled at the (+, +)
  corner. ``y`` is the sampled centroid's place plus ``c cos theta``: the averaged body's.
- The world (`jswim.make(..., flow=Poiseuille(...))`, the corner table and its flow rows) is
  sampled every cycle (4 steps) and compared with the theory's closed forms and its ODE.

Measured (float64, h = 6 .. 20 a, u_max = 0.5 .. 2 v, y0 = 0.5 .. 2 a upstream, 3 periods): the
period is the full theory's with that B to within ``0.34 kappa`` relative (9e-4 at h = 6 a,
u_max = 2 v; it depends on kappa alone, not on u_max and h apart), ``1 - Omega^2 / (v kappa)``
from the smallest swings 0.8370 .. 0.8375, the invariant within ``0.7 kappa`` (peak to peak,
relative). docs/physics.md ("Poiseuille: upstream swinging").
"""

from __future__ import annotations

import functools
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jswim
from jswim.action_codes import encode_action
from jswim.env.flows import SWIM_SPEED, Poiseuille, Shear
from jswim.env.state import narrow, start_state
from jswim.swimmers.flow_response import flow_velocity
from jswim.swimmers.models import make_model

V = SWIM_SPEED  # a per step, the square gait in still fluid
CYCLE = 0.19124724  # a per cycle of four steps (DESIGN.md)
#: The +x square gait from (+, +) as (dof, roc): D2 down, D1 down, D2 up, D1 up.
MOVES = ((2, -1), (1, -1), (2, 1), (1, 1))
SQUARE = tuple(encode_action(d, r) for d, r in MOVES)
#: Its mirror image (y -> -y turns every hinge angle over), from (-, -).
MIRRORED = tuple(encode_action(d, -r) for d, r in MOVES)
#: The stroke averages (`test_the_square_gait_turns_in_shear_as_a_jeffery_body`, to ~1e-6).
B = 0.83753
C = 0.018101
S, K = math.sqrt(2 * B * (1 + B)), math.sqrt(2 * B / (1 + B))

# -- the theory ----------------------------------------------------------------------------------


def invariant(y, theta, kappa):
    """Zöttl & Stark's conserved quantity, less its value at the centre ``(0, pi)``."""
    return kappa * np.square(y) / 2 + V / S * (np.arctanh(K * np.cos(theta)) + math.atanh(K))


def omega(kappa: float) -> float:
    """The small-amplitude swinging frequency (rad per step)."""
    return math.sqrt(V * kappa * (1 - B))


def zottl_stark(kappa: float, y0, theta0, cycles: int) -> tuple[np.ndarray, np.ndarray]:
    """The theory's ODE by RK4, one cycle (4 steps) a step: ``y, theta`` (starts, cycles + 1)."""
    z = np.stack([np.asarray(y0, float), np.asarray(theta0, float)])

    def rate(z):
        return np.stack([V * np.sin(z[1]), kappa * z[0] * (1 - B * np.cos(2 * z[1]))])

    out, h = [z], 4.0
    for _ in range(cycles):
        k1 = rate(z)
        k2 = rate(z + h / 2 * k1)
        k3 = rate(z + h / 2 * k2)
        z = z + h / 6 * (k1 + 2 * k2 + 2 * k3 + rate(z + h * k3))
        out.append(z)
    out = np.stack(out, axis=-1)
    return out[0], out[1]


def crossings(s: np.ndarray) -> np.ndarray:
    """Times (steps) at which a per-cycle series changes sign after its start (linear)."""
    t = 4.0 * np.arange(len(s))
    i = np.nonzero(np.sign(s[1:-1]) != np.sign(s[2:]))[0] + 1
    return t[i] - s[i] * 4.0 / (s[i + 1] - s[i])


def _mean(s: np.ndarray) -> float:
    """The trapezoid mean of a per-cycle series."""
    return float((s.sum() - (s[0] + s[-1]) / 2) / (len(s) - 1))


# -- the model -----------------------------------------------------------------------------------


def _placed(model, levels, y0: float, theta0: float, dtype):
    """A start state at (0, y0) heading theta0 (radians), its pairs full precision."""
    s = start_state(model, np.asarray(levels), dtype)
    with jax.enable_x64(True):
        t = jnp.asarray(theta0, jnp.float64)
        (yh, yl), (th, tl), (ch, cl), (sh, sl) = (
            narrow(v, dtype) for v in (jnp.asarray(y0, jnp.float64), t, jnp.cos(t), jnp.sin(t))
        )
    return s._replace(y=yh, y_lo=yl, theta=th, theta_lo=tl, cos=ch, cos_lo=cl, sin=sh, sin_lo=sl)


@functools.partial(jax.jit, static_argnums=(0, 4))
def _cycles(env, params, states, gaits, n: int):
    def one(state, gait):
        def move(s, code):
            return env.advance(s, code, jnp.zeros((1,), s.x.dtype), params)[0], None

        def cycle(s, _):
            s = jax.lax.scan(move, s, gait)[0]  # a loop, not unrolled: a quarter of the compile
            return s, jnp.stack([s.x, s.x_lo, s.y, s.y_lo, s.theta, s.theta_lo])

        return jax.lax.scan(cycle, state, None, length=n)[1]

    return jax.vmap(one)(states, gaits)


def swim(flow, starts, cycles: int) -> np.ndarray:
    """Sampled every cycle (the start first): ``(x, y, theta)`` (starts, cycles + 1, 3), float64.

    ``starts``: ``(y0, theta0)`` (the square gait from (+, +)) or ``(y0, theta0, "mirrored")``
    (its mirror image from (-, -)); one batch, one compile per flow and dtype."""
    env, params = jswim.make("purcell", roc_levels=1, flow=flow)
    dtype = jnp.result_type(float)
    states, gaits = [], []
    for start in starts:
        mirrored = len(start) > 2
        states.append(_placed(params.model, (0, 0) if mirrored else (1, 1), *start[:2], dtype))
        gaits.append(MIRRORED if mirrored else SQUARE)
    states = jax.tree.map(lambda *leaves: jnp.stack(leaves), *states)
    assert states.x.dtype == dtype
    out = np.asarray(_cycles(env, params, states, jnp.asarray(gaits, jnp.int32), cycles), float)
    sampled = np.stack(
        [out[..., 0] + out[..., 1], out[..., 2] + out[..., 3], out[..., 4] + out[..., 5]], -1
    )
    first = np.asarray([[0.0, s[0], s[1]] for s in starts])[:, None, :]
    return np.concatenate([first, sampled], axis=1)


def averaged_y(track: np.ndarray) -> np.ndarray:
    """The lateral place of the stroke-averaged body: the sampled centroid's plus c cos theta."""
    return track[..., 1] + C * np.cos(track[..., 2])


# Channels: A (narrow, strong: the fastest swing), B (kappa 5.6x smaller), a strong flow in a
# wide channel (tumbling beside swinging inside the channel), and still fluid through the same path.
FLOW_A, KAPPA_A = Poiseuille(2 * V, 6.0), 2 * V / 36
FLOW_B, KAPPA_B = Poiseuille(V, 10.0), V / 100
FLOW_S, KAPPA_S = Poiseuille(8 * V, 20.0), 8 * V / 400
UP = math.pi

STARTS_A = {
    "up 0.5": (0.5, UP),
    "up -1": (-1.0, UP),
    "mirror image of up -1": (1.0, -UP, "mirrored"),
    "up -1 turned over about the averaged line": (1.0 + 2 * C, -UP),
    "up -1 turned over about y = 0": (1.0, -UP),
    "down 0.2": (0.2, 0.0),
}
CYCLES_A = 400  # 1.16 periods


@pytest.fixture(scope="module")
def tracks_a():
    out = swim(FLOW_A, list(STARTS_A.values()), CYCLES_A)
    return dict(zip(STARTS_A, out))


@pytest.fixture(scope="module")
def track_b():
    return swim(FLOW_B, [(1.0, UP)], 900)[0]  # 1.1 periods


# -- tests ---------------------------------------------------------------------------------------


def _still_cycle(model, m: int = 256):
    """The still-fluid square cycle from (+, +), heading 0, start centroid at the origin, at the
    midpoints of ``4 m`` equal pieces: shapes (4m, 2), reference poses (4m, 3), centroids (4m, 2)."""
    span = float(model.hi - model.lo)
    d, shapes, rates = np.array([model.hi, model.hi], float), [], []
    for dof, roc in MOVES:
        rate = np.zeros(2)
        rate[dof - 1] = roc * span
        shapes.append(d + rate * ((np.arange(m) + 0.5) / m)[:, None])
        rates.append(np.broadcast_to(rate, (m, 2)))
        d = d + rate
    shapes, rates = jnp.asarray(np.concatenate(shapes)), jnp.asarray(np.concatenate(rates))
    body = np.asarray(jax.vmap(model.body_velocity)(shapes, rates))
    h = 1.0 / m

    def mid(rate):  # a quantity at the midpoints from its rate there (second order)
        knots = np.concatenate([[0.0], np.cumsum(rate * h)])
        return (knots[1:] + knots[:-1]) / 2

    phi = mid(body[:, 2])
    ref = np.stack(
        [
            mid(np.cos(phi) * body[:, 0] - np.sin(phi) * body[:, 1]),
            mid(np.sin(phi) * body[:, 0] + np.cos(phi) * body[:, 1]),
        ],
        -1,
    )
    off = np.asarray(jax.vmap(model.centroid_offset)(shapes))
    cen = ref + np.stack(
        [
            np.cos(phi) * off[:, 0] - np.sin(phi) * off[:, 1],
            np.sin(phi) * off[:, 0] + np.cos(phi) * off[:, 1],
        ],
        -1,
    )
    start = np.asarray(model.centroid_offset(jnp.asarray([model.hi, model.hi])))
    return shapes, np.concatenate([ref - start, phi[:, None]], -1), cen - start, h


@functools.partial(jax.jit, static_argnums=(0, 1))
def _flow_turns(model, flow, shapes, poses, headings, y0s):
    def one(heading, y0):
        c, s = jnp.cos(heading), jnp.sin(heading)
        lab = jnp.stack(
            [
                c * poses[:, 0] - s * poses[:, 1],
                y0 + s * poses[:, 0] + c * poses[:, 1],
                heading + poses[:, 2],
            ],
            -1,
        )
        w = jax.vmap(lambda d, p: flow_velocity(d, p, flow.velocity, model.xi_ratio))(shapes, lab)
        return jnp.sum(w[:, 2])

    return jax.vmap(one)(headings, y0s)


def turns_per_cycle(model, cycle, flow, headings, y0s=0.0) -> np.ndarray:
    """First order in the flow: the rotation the flow gives over one cycle along the still path,
    turned to each heading with its start centroid at (0, y0)."""
    shapes, poses, _, h = cycle
    headings = np.asarray(headings, float)
    y0s = np.broadcast_to(np.asarray(y0s, float), headings.shape)
    turns = _flow_turns(
        model, flow, shapes, jnp.asarray(poses), jnp.asarray(headings), jnp.asarray(y0s)
    )
    return np.asarray(turns) * h


def test_the_square_gait_turns_in_shear_as_a_jeffery_body():
    model = make_model("purcell")
    cycle = _still_cycle(model)
    rate = 0.01
    headings = np.linspace(0.0, 2 * math.pi, 12, endpoint=False)
    turn = turns_per_cycle(model, cycle, Shear(rate), headings)
    # Per cycle (4 steps): -(rate / 2)(1 - B cos 2t - E sin 2t) + odd harmonics, fitted.
    basis = np.stack(
        [
            np.ones_like(headings),
            np.cos(2 * headings),
            np.sin(2 * headings),
            np.cos(headings),
            np.sin(headings),
            np.cos(3 * headings),
        ],
        -1,
    )
    coef = np.linalg.lstsq(basis, turn / (-2.0 * rate), rcond=None)[0]
    assert coef[0] == pytest.approx(1.0, abs=1e-12)  # half the vorticity, whatever the shape
    assert -coef[1] == pytest.approx(B, abs=2e-5)  # Bretherton's B of the averaged body
    np.testing.assert_allclose(coef[2:], 0.0, atol=1e-12)  # the gait's mirror symmetry: no sin 2t
    # The averaged body's centre: the cycle's time-averaged centroid, c to the side and half a
    # cycle's swim (2 v) ahead of the one sampled at (+, +) ...
    mean = cycle[2].mean(axis=0)
    assert mean[0] == pytest.approx(2 * V, rel=1e-6) and mean[1] == pytest.approx(C, abs=2e-6)
    # ... and heading upstream in Poiseuille the flow turns the sampled body not at all from
    # y = c, with the shear there: kappa (1 - B) per unit y, per step.
    flow = Poiseuille(0.05, 10.0)
    kappa = 0.05 / 100.0
    at = turns_per_cycle(model, cycle, flow, [UP, UP], [0.0, 1.0])
    assert (at[1] - at[0]) / (4 * kappa) == pytest.approx(1 - B, abs=2e-5)
    assert -at[0] / (at[1] - at[0]) == pytest.approx(C, abs=2e-6)


def test_an_upstream_swimmer_swings_across_the_centre_line(tracks_a):
    for track, kappa in ((tracks_a["up 0.5"], KAPPA_A), (tracks_a["up -1"], KAPPA_A)):
        y, psi = averaged_y(track), track[:, 2] - UP
        y0 = y[0]
        # across the centre line to -y0 (measured 3e-5 relative) and back (8e-6)
        assert (y.min() if y0 > 0 else y.max()) == pytest.approx(-y0, rel=2e-4)
        period = crossings(psi)[1]  # psi starts at 0; back through 0 the same way one period on
        k = round(period / 4)
        assert y[k] == pytest.approx(y0, rel=5e-5)
        # heading within the theory's amplitude of upstream, about upstream
        psi_max = math.pi - math.acos(math.tanh(S * kappa * y0**2 / (2 * V) - math.atanh(K)) / K)
        assert np.abs(psi).max() == pytest.approx(psi_max, rel=3e-3)  # measured 9e-4
        assert abs(_mean(psi[: k + 1])) < 1e-5 * psi_max  # measured 1.2e-6
        # the stroke-averaged body swings about y = 0, the sampled centroid about y = c (6e-4)
        assert abs(_mean(track[: k + 1, 1]) - C) < 2e-3 * abs(y0)


def test_the_swinging_period_is_zottl_stark_s_with_one_b_for_every_channel(tracks_a, track_b):
    t_a, t_b = crossings(tracks_a["up 0.5"][:, 2] - UP)[1], crossings(track_b[:, 2] - UP)[1]
    # B from channel A's small swing (amplitude 0.48 a): the stroke average's, to 5.6e-4
    b_a = 1 - (2 * math.pi / t_a) ** 2 / (V * KAPPA_A)
    assert b_a == pytest.approx(B, abs=2e-3)
    # ... predicts channel B's period (kappa 5.6x smaller, amplitude 1 a): measured 7e-5
    assert t_b == pytest.approx(2 * math.pi / math.sqrt(V * KAPPA_B * (1 - b_a)), rel=3e-4)
    # Both against the full theory with the stroke average's B (measured 9e-4 and 1.6e-4: the
    # model's swing is slower by 0.34 kappa, relative).
    for track, kappa, tol in ((tracks_a["up 0.5"], KAPPA_A, 3e-3), (track_b, KAPPA_B, 6e-4)):
        _, theta = zottl_stark(kappa, averaged_y(track)[0], UP, len(track) + 100)
        assert crossings(track[:, 2] - UP)[1] == pytest.approx(crossings(theta - UP)[1], rel=tol)
        # a swing of finite amplitude is quicker: the turning stiffens as 1 - B cos 2 theta grows
        # (2.6e-3 and 1.9e-3 here)
        assert 0 < 1 - crossings(theta - UP)[1] * omega(kappa) / (2 * math.pi) < 5e-3


def test_the_swing_keeps_zottl_stark_s_invariant(tracks_a, track_b):
    for track, kappa, tol in (
        (tracks_a["up 0.5"], KAPPA_A, 5e-3),
        (tracks_a["up -1"], KAPPA_A, 5e-3),
        (track_b, KAPPA_B, 1e-3),
    ):
        h = invariant(averaged_y(track), track[:, 2], kappa)
        # peak to peak within 0.7 kappa of its value, relative (measured 1.7e-3 in A, 3e-4 in B)
        assert np.ptp(h) < tol * h[0]


def test_the_swing_mirrors_exactly_with_the_gait_s_mirror_image(tracks_a):
    a, m = tracks_a["up -1"], tracks_a["mirror image of up -1"]
    np.testing.assert_allclose(m[:, 0], a[:, 0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(m[:, 1], -a[:, 1], rtol=0, atol=1e-12)
    np.testing.assert_allclose(m[:, 2], -a[:, 2], rtol=0, atol=1e-12)
    # The same gait is chiral: its sampled centroid rides c to one side of the averaged body,
    # so turned over about y = 0 the swing is off by 4c; about the averaged body's line it
    # mirrors to what the stroke average leaves (measured 3.5e-6 a and 7.4e-6 rad).
    same = tracks_a["up -1 turned over about the averaged line"]
    np.testing.assert_allclose(averaged_y(same), -averaged_y(a), rtol=0, atol=2e-5)
    np.testing.assert_allclose(same[:, 2], -a[:, 2], rtol=0, atol=3e-5)
    naive = tracks_a["up -1 turned over about y = 0"]
    assert np.abs(naive[:, 1] + a[:, 1]).max() > 3 * C


def test_a_downstream_swimmer_leaves_the_centre_line_from_the_saddle(tracks_a):
    track = tracks_a["down 0.2"]
    y, theta = averaged_y(track), track[:, 2]
    w, t = omega(KAPPA_A), 4.0 * np.arange(len(track))
    n = int(1.0 / w / 4)  # to Omega t = 1: the linear saddle
    # y = y0 cosh(Omega t), psi = (y0 Omega / v) sinh(Omega t) (measured 1.0e-3 and 2.3e-3)
    np.testing.assert_allclose(y[:n], y[0] * np.cosh(w * t[:n]), rtol=5e-3)
    np.testing.assert_allclose(theta[1:n], y[0] * w / V * np.sinh(w * t[1:n]), rtol=1e-2)
    # Then one tumble just outside the separatrix: upstream at its farthest, where H gives
    # y^2 = y0^2 + y_sep^2 (measured 4e-5 relative), past the wall at h = 6 a (not modelled:
    # the profile goes on), and back to the centre line heading downstream again.
    y_sep = math.sqrt(4 * V * math.atanh(K) / (S * KAPPA_A))
    far = int(np.argmax(y))
    assert y[far] == pytest.approx(math.hypot(y[0], y_sep), rel=2e-4) and y[far] > 6.0
    assert theta[far] == pytest.approx(UP, abs=0.02)
    assert theta[-1] > 1.5 * math.pi and abs(y[-1]) < 1.0
    zy, zt = zottl_stark(KAPPA_A, y[0], 0.0, len(track) - 1)  # measured 0.026 a, 0.016 rad
    np.testing.assert_allclose(theta, zt, rtol=0, atol=0.05)
    np.testing.assert_allclose(y, zy, rtol=0, atol=0.08)


def test_a_strong_flow_splits_swinging_from_tumbling_at_the_separatrix():
    # u_max = 8 v > 4.3 v: the separatrix |y| = h sqrt(4 artanh(K) v / (S u_max)) lies inside
    y_sep = math.sqrt(4 * V * math.atanh(K) / (S * KAPPA_S))
    assert 14.0 - C < y_sep < 16.0 - C < 20.0
    track = swim(FLOW_S, [(14.0, UP), (16.0, UP)], 700)
    swing, tumble = np.unwrap(track[0, :, 2]), np.unwrap(track[1, :, 2])
    assert 0.0 < swing.min() < 0.5 and swing.max() < 2 * math.pi  # never through downstream
    assert tumble.max() > 3 * math.pi  # through downstream and on round
    # the full theory, to 1.4e-3 and 3.8e-3 rad with the reference integrator
    # (`jswim.env.flow_tables.Integrated`), 3.0e-3 and 4.2e-3 with the flow tables
    _, zt = zottl_stark(KAPPA_S, averaged_y(track[:, 0]), [UP, UP], 700)
    np.testing.assert_allclose(swing, zt[0], rtol=0, atol=1e-2)
    np.testing.assert_allclose(tumble, zt[1], rtol=0, atol=1.5e-2)


def test_no_flow_no_turning():
    headings = [UP, 0.0, 1.0, -2.3]
    track = swim(Poiseuille(0.0, 6.0), [(0.7, t) for t in headings], 40)
    n = np.arange(41)
    for i, t in enumerate(headings):
        np.testing.assert_allclose(track[i, :, 2], t, rtol=0, atol=1e-13)
        # CYCLE holds 8 decimals: 2e-9 a per cycle
        assert np.all(np.abs(track[i, :, 0] - CYCLE * math.cos(t) * n) <= 5e-9 * n + 1e-13)
        assert np.all(np.abs(track[i, :, 1] - 0.7 - CYCLE * math.sin(t) * n) <= 5e-9 * n + 1e-13)


def test_the_swing_in_the_default_float32(tracks_a, float32):
    assert jnp.result_type(float) == jnp.float32
    track = swim(FLOW_A, [(0.5, UP)], CYCLES_A)[0]
    ref = tracks_a["up 0.5"]
    # the pose pairs hold ~48 bits: the float32 swing is the float64 one (measured 1.2e-13 a and
    # rad, 1.8e-12 a along the channel, 3e-13 of the period)
    np.testing.assert_allclose(track[:, 1:], ref[:, 1:], rtol=0, atol=1e-11)
    np.testing.assert_allclose(track[:, 0], ref[:, 0], rtol=0, atol=1e-10)
    assert crossings(track[:, 2] - UP)[1] == pytest.approx(crossings(ref[:, 2] - UP)[1], rel=1e-10)
