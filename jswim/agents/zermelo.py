"""Zermelo's navigation problem: the least time a perfect steerer needs to reach a target through
a steady planar flow, the reference a swimmer's navigation time is measured against
(docs/zermelo.md).

The *perfect steerer* is a point that swims at the constant speed ``v`` (``a / tau``; default
`SWIM_SPEED`, the square gait's mean speed) in any heading it chooses, turning instantly, and is
carried by the background flow ``u(x)`` (`jswim.env.flows`): ``dx/dt = u(x) + v (cos h, sin h)``.
The target (a `jswim.env.targets` spec) is reached when the point comes within its radius.

* Uniform flow and still fluid (`uniform_time`): the optimal path is straight at a constant
  heading, and the least time is the smallest non-negative root of a quadratic (closed form).
* Any other flow: a shooting method over the field of extremals. Pontryagin's principle gives
  Zermelo's heading equation (Zermelo 1931, ZAMM 11, 114; Bryson & Ho, *Applied Optimal
  Control*, sec. 2.7), for ``u = (u1, u2)``::

      dh/dt = sin^2 h du2/dx + sin h cos h (du1/dx - du2/dy) - cos^2 h du1/dy

  (the costate ``p`` obeys ``dp/dt = -(grad u)^T p`` and the heading points along ``p``; in the
  shear ``u = (g y, 0)`` it reads ``d tan h / dt = -g``). The extremals from the start, one per
  initial heading, are integrated by fixed-step RK4 in float64 (all headings at once, as one
  batch, until the first of them has hit and a margin past it); the first time each comes within
  the radius is found inside its step by bisection on the cubic Hermite interpolant of the step.
  The least first-hit time over `HEADINGS` initial headings on ``[-pi, pi)``, refined around the
  best few local minima by `REFINE_ROUNDS` finer scans, is the optimum.

This is the field of extremals, the paths that satisfy the *necessary* conditions of optimality,
approximated by a finite heading scan: a basin of initial headings narrower than the scan's
spacing (0.5 degrees) could be missed, and the least time found is then an upper bound. Measured
(tests/agents/test_zermelo.py, docs/zermelo.md): the shooting method agrees with the closed form
in uniform flows to 6e-12 relative, with the shear's closed-form extremal to 3e-10 and with the
quadrature along a Taylor-Green cell's outflow axis to 2e-9; a quarter of the RK4 step changes
the study flows' times by at most 5e-7 steps (4e-9 relative).

Waypoints are solved leg by leg, each leg from where the previous one reached its disc: that is
leg-by-leg optimal, an upper bound on the joint optimum (which would aim each arrival at the
next leg).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import numbers
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array, lax

from jswim.env.flows import MAX_FLOW_SPEED, SWIM_SPEED, Flow, Uniform
from jswim.env.targets import MAX_DISTANCE, FixedTarget, MovingTarget, Waypoints
from jswim.errors import ConfigError

__all__ = [
    "HEADINGS",
    "HORIZON_FACTOR",
    "HORIZON_STEPS",
    "MAX_HORIZON",
    "MAX_RK4_STEPS",
    "REFINE_ROUNDS",
    "ZermeloPath",
    "heading_rate",
    "uniform_time",
    "zermelo",
]

#: Initial headings of the coarse scan, evenly on ``[-pi, pi)`` (spacing 0.5 degrees).
HEADINGS = 720

#: Local minima of the coarse scan that are refined (the global one may sit in any of them);
#: each finer scan has ``HEADINGS / REFINE_CANDIDATES`` headings (240) over two spacings.
REFINE_CANDIDATES = 3

#: Finer scans: each narrows the window 120-fold, so 2 rounds take the 0.5 degree spacing to
#: about 6e-7 rad, far below what moves the time (quadratic in the heading's error at a minimum:
#: ~1e-11 steps).
REFINE_ROUNDS = 2

#: The default horizon of a leg is ``HORIZON_FACTOR`` times its still-fluid time plus
#: ``HORIZON_STEPS``: the study flows at 0.9 v stretch a target 3 a away at most 2.5-fold
#: (Taylor-Green, upstream; docs/zermelo.md), and the steps keep short legs from a tight cut.
HORIZON_FACTOR = 4.0
HORIZON_STEPS = 64.0

#: A default horizon is raised to 1.25 times the time of holding the straight line to the target
#: against the fastest flow met on it, ``(L - r) / (v - max |u|)`` (a path that always exists
#: when ``max |u| < v``, so the optimum is no longer), but to at most this many still-fluid times.
STRAIGHT_LINE_CAP = 40.0

#: Largest horizon (steps) a call accepts: every step of it is one RK4 step of the whole batch.
MAX_HORIZON = 100_000.0

#: Largest number of RK4 steps of the batch a leg's horizon may take, ``horizon * substeps``
#: (the substeps per step: `STEP_RATE`): a bound on every call's work, so that a strong flow
#: is refused in one line instead of integrating for minutes (a shear of 100 a step took 142 s,
#: one of 1e6 never ended). It is `MAX_HORIZON` at one RK4 step a step, so every horizon a flow
#: of gradient below `STEP_RATE` takes (the study's flows up to 1 v) stays open; a leg does at
#: most three times this many (the scan and its two refinements; an unreachable target, one),
#: each ~0.3 ms on a busy CPU core (measured 2026-12-07: 1e4 steps a round in 2.8 s).
MAX_RK4_STEPS = 100_000

#: The RK4 step is ``min(1, STEP_RATE / |grad u|)`` steps, ``|grad u|`` the largest gradient
#: met on the straight line to the target: at ``h |grad u| <= 0.05`` RK4's error per step is
#: ~1e-9 of a heading.
STEP_RATE = 0.05

#: RK4 steps per whole step at the least (1; the accuracy checks raise it).
_MIN_SUBSTEPS = 1

#: Bisection steps of a hit inside its RK4 step (2^-50 of a step).
_BISECTIONS = 50

#: Beyond the first hit the batch goes on for this fraction of it plus 2 steps, so the local
#: minima slightly above the least one are found too (then refined).
_MARGIN = 0.05


@dataclasses.dataclass(frozen=True)
class ZermeloPath:
    """The time-optimal path of the perfect steerer (`zermelo`).

    Attributes
    ----------
    steps : float or None
        The least time (``tau``, world steps, fractional) to bring the point within the radius of
        the (last) target; None when that is not possible within the horizon.
    xy : ndarray (n, 2) float64
        The path (``a``, lab frame) at every whole step ``0, 1, ...`` and, last, at the hit time
        (``steps``). When unreachable: the path up to the last waypoint reached (the start alone
        if none).
    heading : ndarray (n,) float64
        The steering heading (rad, lab frame, in ``(-pi, pi]``) at those samples; NaN at a
        start-only path of an unreachable target.
    t : ndarray (n,) float64
        The times of the samples (``tau``).
    legs : tuple of float
        The time each waypoint was reached (one per target point reached, cumulative).
    """

    steps: float | None
    xy: np.ndarray
    heading: np.ndarray
    t: np.ndarray
    legs: tuple[float, ...] = ()

    @property
    def reachable(self) -> bool:
        """Whether the (last) target is reached within the horizon."""
        return self.steps is not None


def _number(value: Any, what: str, positive: bool = False, nonneg: bool = False) -> float:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ConfigError(f"{what} must be a number, got {value!r}")
    try:
        v = float(value)
    except OverflowError:  # an int past float's range
        v = math.inf
    if not math.isfinite(v) or (positive and v <= 0) or (nonneg and v < 0):
        limit = " > 0" if positive else " >= 0" if nonneg else ""
        shown = repr(value) if len(repr(value)) <= 40 else f"{repr(value)[:24]}..."
        raise ConfigError(f"{what} must be a finite number{limit}, got {shown}")
    return v


def _pair(value: Any, what: str) -> tuple[float, float]:
    if isinstance(value, (str, bytes)) or not hasattr(value, "__len__") or len(value) != 2:
        raise ConfigError(f"{what} must be two numbers (x, y), got {value!r}")
    return _number(value[0], f"{what} x"), _number(value[1], f"{what} y")


def uniform_time(
    u: tuple[float, float],
    point: tuple[float, float],
    radius: float,
    speed: float,
    velocity: tuple[float, float] = (0.0, 0.0),
) -> float | None:
    """The least time to within ``radius`` of a target through a uniform flow (closed form).

    The steerer starting at the origin reaches, at time ``T``, any point of the disc of radius
    ``v T`` around ``u T``; the target's disc is centred at ``P + w T``. They first meet when
    ``|P - q T| = v T + r`` with ``q = u - w``, and squaring (both sides are >= 0) gives
    ``A T^2 - 2 B T + C = 0`` with ``A = |q|^2 - v^2``, ``B = P.q + v r``, ``C = |P|^2 - r^2``.
    For ``C > 0`` the least non-negative root is ``T = C / (B + sqrt(B^2 - A C))`` in every case
    (``A > 0``: the smaller root, which exists when ``B > 0`` and ``B^2 >= A C``; ``A < 0``: the
    one positive root; ``A = 0``, ``|u - w| = v``: ``C / 2B``), and there is none when
    ``B^2 < A C`` or ``B + sqrt(B^2 - A C) <= 0``. The optimal heading is constant, along
    ``P - q T``. Still fluid, fixed target: ``T = (|P| - r) / v``.

    Parameters
    ----------
    u : (float, float)
        The flow (``a / tau``).
    point : (float, float)
        The target's centre relative to the start at time 0 (``a``).
    radius : float
        The target's radius (``a``, >= 0).
    speed : float
        The swimming speed ``v`` (``a / tau``, > 0).
    velocity : (float, float)
        The target's velocity ``w`` (``a / tau``).

    Returns
    -------
    float or None
        ``T`` (``tau``); 0 when the start is on or within the disc; None when never reached.

    Raises
    ------
    ConfigError
        A value that is not a finite number (a speed not > 0, a radius < 0).
    """
    ux, uy = _pair(u, "flow u")
    px, py = _pair(point, "point")
    wx, wy = _pair(velocity, "target velocity")
    r = _number(radius, "radius", nonneg=True)
    v = _number(speed, "speed", positive=True)
    return _uniform_time(ux - wx, uy - wy, px, py, r, v)


def _uniform_time(qx: float, qy: float, px: float, py: float, r: float, v: float) -> float | None:
    if math.hypot(px, py) <= r:
        return 0.0
    a = qx * qx + qy * qy - v * v
    b = px * qx + py * qy + v * r
    c = px * px + py * py - r * r
    disc = b * b - a * c
    if disc < 0:
        return None
    den = b + math.sqrt(disc)
    return c / den if den > 0 else None


def heading_rate(flow: Flow, xy: Array, heading: Array) -> Array:
    """Zermelo's heading equation: ``dh/dt`` (rad per ``tau``) of the optimal heading.

    ``dh/dt = sin^2 h g21 + sin h cos h (g11 - g22) - cos^2 h g12`` with ``g_ij = du_i/dx_j``
    (`jswim.env.flows`' ``gradient``); from the costate ``dp/dt = -(grad u)^T p``, heading along
    ``p`` (Zermelo 1931).

    Parameters
    ----------
    flow : Flow
        The background flow.
    xy : Array (..., 2)
        Positions (``a``).
    heading : Array (...)
        Headings (rad).

    Returns
    -------
    Array (...)
        ``dh/dt``.
    """
    g = flow.gradient(xy)
    c, s = jnp.cos(heading), jnp.sin(heading)
    return s * s * g[..., 1, 0] + s * c * (g[..., 0, 0] - g[..., 1, 1]) - c * c * g[..., 0, 1]


def _rhs(flow: Flow, speed: Array, state: Array) -> Array:
    """``d(x, y, h)/dt`` of states (..., 3)."""
    xy, h = state[..., :2], state[..., 2]
    swim = speed * jnp.stack([jnp.cos(h), jnp.sin(h)], axis=-1)
    return jnp.concatenate([flow.velocity(xy) + swim, heading_rate(flow, xy, h)[..., None]], -1)


def _rk4(flow: Flow, speed: Array, state: Array, h: Array) -> Array:
    """One classical RK4 step of states (..., 3); the four stages run as a loop, so the flow is
    traced (and compiled) once, not four times."""
    nodes = jnp.asarray([0.0, 0.5, 0.5, 1.0], state.dtype)
    weights = jnp.asarray([1.0, 2.0, 2.0, 1.0], state.dtype) / 6.0

    def stage(i: Array, carry: tuple[Array, Array]) -> tuple[Array, Array]:
        k, total = carry
        k = _rhs(flow, speed, state + nodes[i] * h * k)
        return k, total + weights[i] * k

    zero = jnp.zeros_like(state)
    _, total = lax.fori_loop(0, 4, stage, (zero, zero))
    return state + h * total


def _first_hits(
    flow: Flow,
    speed: Array,
    x0: Array,
    headings: Array,
    centre: Array,
    w: Array,
    r: Array,
    horizon: Array,
    h: Array,
) -> Array:
    """First time (``tau``, inf: none within ``horizon``) each extremal from ``x0`` with the
    initial ``headings`` (B,) comes within ``r`` of ``centre + w t``.

    The batch is stepped together until the horizon or until ``_MARGIN`` past its first hit
    (a later hit cannot be the least); a step hits when the chord of the relative positions
    passes within ``r`` (so a small disc is not stepped over), and the time inside the step is
    where the cubic Hermite interpolant of the step enters the disc, by bisection between the
    step's start and the chord's closest point.
    """
    b = headings.shape[0]
    s0 = jnp.concatenate([jnp.broadcast_to(x0, (b, 2)), headings[:, None]], axis=-1)
    inf = jnp.asarray(jnp.inf, s0.dtype)

    def chord_hit(sa: Array, sb: Array, ta: Array) -> tuple[Array, Array]:
        """Whether the chord passes within ``r``, and where along it it is closest."""
        a = sa[:, :2] - (centre + w * ta)
        d = sb[:, :2] - (centre + w * (ta + h)) - a
        sc = jnp.clip(-jnp.sum(a * d, -1) / jnp.maximum(jnp.sum(d * d, -1), 1e-300), 0.0, 1.0)
        return jnp.linalg.norm(a + sc[:, None] * d, axis=-1) < r, sc

    def cond(carry: tuple) -> Array:
        k, _, _, _, _, _, best = carry
        return (k * h < horizon) & (k * h <= (1.0 + _MARGIN) * best + 2.0)

    def body(carry: tuple) -> tuple:
        k, s, found, k_hit, s_hit, sc_hit, best = carry
        s1 = _rk4(flow, speed, s, h)
        hit, sc = chord_hit(s, s1, k * h)
        new = ~found & hit
        k_hit = jnp.where(new, k, k_hit)
        s_hit = jnp.where(new[:, None], s, s_hit)
        sc_hit = jnp.where(new, sc, sc_hit)
        best = jnp.where(jnp.any(new), jnp.minimum(best, (k + 1) * h), best)
        return k + 1, s1, found | new, k_hit, s_hit, sc_hit, best

    zeros = jnp.zeros(b, s0.dtype)
    start = (jnp.asarray(0.0, s0.dtype), s0, jnp.zeros(b, bool), zeros, s0, zeros, inf)
    _, _, found, k_hit, sa, sc, _ = lax.while_loop(cond, body, start)

    # where in its step each hit is: the step again, and its Hermite cubic
    sb = _rk4(flow, speed, sa, h)
    ma, mb = _rhs(flow, speed, sa)[:, :2] * h, _rhs(flow, speed, sb)[:, :2] * h
    pa, pb = sa[:, :2], sb[:, :2]
    ta = k_hit * h

    def outside(sigma: Array) -> Array:
        s2, s3 = sigma * sigma, sigma * sigma * sigma
        p = (
            (2 * s3 - 3 * s2 + 1)[:, None] * pa
            + (s3 - 2 * s2 + sigma)[:, None] * ma
            + (-2 * s3 + 3 * s2)[:, None] * pb
            + (s3 - s2)[:, None] * mb
        )
        rel = p - (centre + w * (ta + sigma * h)[:, None])
        return jnp.linalg.norm(rel, axis=-1) >= r

    def bisect(_: int, lohi: tuple[Array, Array]) -> tuple[Array, Array]:
        lo, hi = lohi
        mid = 0.5 * (lo + hi)
        out = outside(mid)
        return jnp.where(out, mid, lo), jnp.where(out, hi, mid)

    # from the step's start (outside) to the chord's closest point (inside, but for a graze)
    _, hi = lax.fori_loop(0, _BISECTIONS, bisect, (zeros, sc))
    t = ta + hi * h
    return jnp.where(found & (t <= horizon), t, inf)


def _flow_parts(flow: Flow) -> tuple[Any, tuple[float, ...]]:
    """``(static, numbers)`` of a flow: its numbers go into the jitted functions as arguments,
    so one compile serves every flow of a kind (a flow with a field that is not a number is
    static as a whole)."""
    if not dataclasses.is_dataclass(flow):
        return (flow, None, None), ()
    names = tuple(f.name for f in dataclasses.fields(flow))
    leaves, tree = jax.tree_util.tree_flatten(tuple(getattr(flow, n) for n in names))
    if not all(isinstance(v, numbers.Real) and not isinstance(v, bool) for v in leaves):
        return (flow, None, None), ()
    return (type(flow), names, tree), tuple(float(v) for v in leaves)


def _flow_join(static: Any, leaves: Any) -> Flow:
    """The flow of `_flow_parts` again, its numbers traced (the constructor's checks, which
    read Python numbers, are skipped: the numbers were checked when the flow was made)."""
    cls, names, tree = static
    if names is None:
        return cls
    flow = object.__new__(cls)
    for name, value in zip(names, jax.tree_util.tree_unflatten(tree, list(leaves))):
        object.__setattr__(flow, name, value)
    return flow


@functools.partial(jax.jit, static_argnums=(0,))
def _shoot(
    static: Any,
    leaves: tuple[Array, ...],
    speed: Array,
    x0: Array,
    centre: Array,
    w: Array,
    r: Array,
    horizon: Array,
    h: Array,
) -> tuple[Array, Array]:
    """``(heading0, T)`` of the least first hit over the heading scan and its refinement.

    One batch of `HEADINGS` extremals per round (one call site of the integration: one
    compile): round 0 is the coarse scan, whose least `REFINE_CANDIDATES` local minima on the
    circle of headings are each refined in the later rounds by a scan of ``HEADINGS /
    REFINE_CANDIDATES`` headings over one spacing either side of it.
    """
    flow = _flow_join(static, leaves)
    dtype = x0.dtype
    k, m = REFINE_CANDIDATES, HEADINGS // REFINE_CANDIDATES
    spacing = 2.0 * jnp.pi / HEADINGS
    coarse = (-jnp.pi + spacing * jnp.arange(k * m, dtype=dtype)).reshape(k, m)
    offsets = jnp.linspace(-1.0, 1.0, m, dtype=dtype)
    rows = jnp.arange(k)

    def one_round(i: Array, carry: tuple[Array, Array, Array]) -> tuple[Array, Array, Array]:
        centres, best, half = carry
        first = i == 0
        grid = jnp.where(first, coarse, centres[:, None] + half * offsets[None, :])
        # no extremal of the scan hit: nothing to refine, and the refinements take no step
        until = jnp.where(first | jnp.any(jnp.isfinite(best)), horizon, 0.0)
        t = _first_hits(flow, speed, x0, grid.ravel(), centre, w, r, until, h).reshape(k, m)
        # round 0: the least few local minima on the circle
        flat = t.ravel()
        is_min = jnp.isfinite(flat) & (flat <= jnp.roll(flat, 1)) & (flat <= jnp.roll(flat, -1))
        _, idx = lax.top_k(-jnp.where(is_min, flat, jnp.inf), k)
        # later rounds: each candidate's least, kept only where it improves
        j = jnp.argmin(t, axis=1)
        better = t[rows, j] < best
        refined = jnp.where(better, grid[rows, j], centres)
        least = jnp.where(better, t[rows, j], best)
        # the least of a unimodal sampled curve lies within one spacing of the sampled least
        return (
            jnp.where(first, coarse.ravel()[idx], refined),
            jnp.where(first, flat[idx], least),
            jnp.where(first, spacing, half * 2.0 / (m - 1)),
        )

    start = (jnp.zeros(k, dtype), jnp.full(k, jnp.inf, dtype), jnp.asarray(spacing, dtype))
    centres, best, _ = lax.fori_loop(0, 1 + REFINE_ROUNDS, one_round, start)
    n = jnp.argmin(best)
    return centres[n], best[n]


@functools.partial(jax.jit, static_argnums=(0, 5))
def _trajectory(
    static: Any, leaves: tuple[Array, ...], speed: Array, s0: Array, hs: Array, sub: int
) -> Array:
    """States (len(hs) + 1, 3) after each interval ``hs`` (``sub`` RK4 steps each; an interval
    of 0, the padding, leaves the state as it is)."""
    flow = _flow_join(static, leaves)

    def body(s: Array, dt: Array) -> tuple[Array, Array]:
        s = lax.fori_loop(0, sub, lambda _, x: _rk4(flow, speed, x, dt / sub), s)
        return s, s

    _, states = lax.scan(body, s0, hs)
    return jnp.concatenate([s0[None], states])


def _padded(n: int) -> int:
    """A length of at least ``n`` from few sizes (one compile each): powers of two from 256."""
    return max(256, 1 << max(0, n - 1).bit_length())


def _line_samples(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a + np.linspace(0.0, 1.0, 257)[:, None] * (b - a)


@dataclasses.dataclass(frozen=True)
class _Leg:
    t0: float  # when it starts (tau)
    x0: np.ndarray  # where (a)
    steps: float | None  # its least time (tau)
    heading0: float  # initial heading (rad)
    velocity: np.ndarray | None  # the constant velocity of a straight leg (closed form); else None
    sub: int = 1  # RK4 steps per whole step when redrawn


def zermelo(
    flow: Flow | None,
    target: FixedTarget | Waypoints | MovingTarget,
    speed: float = SWIM_SPEED,
    start: tuple[float, float] = (0.0, 0.0),
    horizon: float | None = None,
    method: str = "auto",
) -> ZermeloPath:
    """The time-optimal path of a perfect steerer from ``start`` to ``target`` through ``flow``.

    Parameters
    ----------
    flow : Flow or None
        The steady background flow (`jswim.env.flows`); None: still fluid.
    target : FixedTarget, Waypoints or MovingTarget
        The task (`jswim.env.targets`): its ``points()``, ``velocity`` (a moving target's point
        moves at it, ``a`` per step, from time 0) and ``radius`` (reached: strictly within it,
        as in the world; the time is the infimum of those times, when the distance is ``r``).
    speed : float
        The steerer's swimming speed ``v`` (``a / tau``, > 0; default `SWIM_SPEED`).
    start : (float, float)
        Where it starts (``a``, lab frame).
    horizon : float, optional
        Steps (``tau``) the whole task may take (at most `MAX_HORIZON`); beyond it the target
        counts as unreachable. Default: none for the closed form; for the shooting method, per
        leg, `HORIZON_FACTOR` times its still-fluid time plus `HORIZON_STEPS`, raised to 1.25
        times the straight-line time against the fastest flow on the line where that exists
        (at most `STRAIGHT_LINE_CAP` still-fluid times).
    method : {"auto", "closed", "shooting"}
        ``closed``: `uniform_time` (still fluid and `Uniform` only); ``shooting``: the field of
        extremals in any flow (in a uniform one, a check of the closed form); ``auto``: the
        closed form where it applies.

    Returns
    -------
    ZermeloPath
        The least time, and the path sampled at every whole step.

    Raises
    ------
    ConfigError
        A flow that is not a `jswim.env.flows` flow or None, a target that is not a target spec,
        a speed not finite and > 0 or past `jswim.env.flows.MAX_FLOW_SPEED`, a start not two
        finite numbers within `jswim.env.targets.MAX_DISTANCE`, a horizon not finite and > 0
        or past `MAX_HORIZON`, an unknown method or ``closed`` for a non-uniform flow; a leg
        whose horizon would take more than `MAX_RK4_STEPS` RK4 steps (a strong flow), or whose
        flow has no finite gradient, before it is integrated.
    """
    if flow is not None and not isinstance(flow, Flow):
        raise ConfigError(f"flow must be a jswim.env.flows flow or None, got {flow!r}")
    if not isinstance(target, (FixedTarget, Waypoints, MovingTarget)):
        raise ConfigError(
            f"target must be a FixedTarget, Waypoints or MovingTarget spec, got {target!r}"
        )
    v = _number(speed, "speed", positive=True)
    if v > MAX_FLOW_SPEED:  # the flows' own range, for the steerer's speed
        raise ConfigError(
            f"speed must be at most {MAX_FLOW_SPEED:.4g} a per step (1000 times the swimming "
            f"speed: jswim.env.flows.MAX_FLOW_SPEED), got {speed!r}"
        )
    x = np.asarray(_pair(start, "start"), np.float64)
    if np.abs(x).max() > MAX_DISTANCE:  # the targets' own range, for where it starts
        raise ConfigError(
            f"start must be within -{MAX_DISTANCE:g}..{MAX_DISTANCE:g} a in x and y "
            f"(jswim.env.targets.MAX_DISTANCE), got {start!r}"
        )
    if horizon is not None:
        horizon = _number(horizon, "horizon", positive=True)
        if horizon > MAX_HORIZON:
            raise ConfigError(f"horizon must be at most {MAX_HORIZON:,.0f} steps, got {horizon!r}")
    if method not in ("auto", "closed", "shooting"):
        raise ConfigError(f"method must be one of auto, closed, shooting, got {method!r}")
    uniform = flow is None or isinstance(flow, Uniform)
    if method == "closed" and not uniform:
        raise ConfigError(f"the closed form holds in still fluid and uniform flows, not {flow!r}")
    closed = uniform and method != "shooting"
    u = np.zeros(2) if flow is None else None
    if isinstance(flow, Uniform):
        u = np.asarray(flow.u, np.float64)
    shoot_flow = Uniform() if flow is None else flow

    w = np.asarray(target.velocity, np.float64)
    r = float(target.radius)
    legs: list[_Leg] = []
    t = 0.0
    with jax.enable_x64(True):
        for p in target.points():
            rel = np.asarray(p, np.float64) + w * t - x  # the target at the leg's start
            left = None if horizon is None else horizon - t
            if closed:
                leg = _closed_leg(u, rel, w, r, v, t, x)
                if leg.steps is not None and left is not None and leg.steps > left:
                    leg = dataclasses.replace(leg, steps=None)
            else:
                leg = _shooting_leg(shoot_flow, rel, w, r, v, t, x, left)
            legs.append(leg)
            if leg.steps is None:
                break
            t += leg.steps
            x = _leg_point(shoot_flow, v, leg, leg.steps)
        return _sampled(shoot_flow, v, legs)


def _closed_leg(
    u: np.ndarray, rel: np.ndarray, w: np.ndarray, r: float, v: float, t0: float, x0: np.ndarray
) -> _Leg:
    q = u - w
    steps = _uniform_time(q[0], q[1], rel[0], rel[1], r, v)
    aim = rel - q * (steps or 0.0)  # where the target's centre is, seen from the drifted start
    heading = math.atan2(aim[1], aim[0])
    vel = u + v * np.array([math.cos(heading), math.sin(heading)])
    return _Leg(t0, x0, steps, heading, vel)


def _shooting_leg(
    flow: Flow,
    rel: np.ndarray,
    w: np.ndarray,
    r: float,
    v: float,
    t0: float,
    x0: np.ndarray,
    left: float | None,
) -> _Leg:
    heading = math.atan2(rel[1], rel[0])
    if math.hypot(*rel) <= r:
        return _Leg(t0, x0, 0.0, heading, None)
    line = _line_samples(x0, x0 + rel)
    grad = np.asarray(flow.gradient(jnp.asarray(line)))
    rate = float(np.max(np.linalg.norm(grad, axis=(-2, -1))))
    if not math.isfinite(rate):  # a flow of no jswim.env.flows range (they keep it finite)
        raise ConfigError(f"{flow!r} has no finite velocity gradient on the way to the target")
    if left is None:
        left = _default_horizon(flow, rel, w, r, v, line)
    if left <= 0:
        return _Leg(t0, x0, None, heading, None)
    # the work bound: every RK4 step of the horizon, before any is taken
    sub = max(_MIN_SUBSTEPS, math.ceil(min(rate / STEP_RATE, 2.0 * MAX_RK4_STEPS)))
    if sub * math.ceil(left) > MAX_RK4_STEPS:
        raise ConfigError(
            f"zermelo: {flow!r} has a velocity gradient of {rate:.3g} per step on the way to "
            f"the target ({math.hypot(*rel):.3g} a away), {sub} RK4 steps a step over a horizon "
            f"of {left:,.0f} steps: past the {MAX_RK4_STEPS:,} RK4 steps a leg may take "
            "(MAX_RK4_STEPS); give a weaker flow, a nearer target or a shorter horizon"
        )
    h = 1.0 / sub  # whole steps are whole numbers of RK4 steps
    centre = x0 + rel  # the target's centre at the leg's start; it moves at w
    static, leaves = _flow_parts(flow)
    h0, steps = _shoot(
        static,
        tuple(jnp.asarray(a, jnp.float64) for a in leaves),
        *(jnp.asarray(a, jnp.float64) for a in (v, x0, centre, w, r, left, h)),
    )
    steps = float(steps)
    return _Leg(t0, x0, steps if math.isfinite(steps) else None, float(h0), None, sub)


def _default_horizon(
    flow: Flow, rel: np.ndarray, w: np.ndarray, r: float, v: float, line: np.ndarray
) -> float:
    still = _uniform_time(-w[0], -w[1], rel[0], rel[1], r, v)
    if still is None:  # a target faster than the steerer: only a flow can bring it in reach
        still = (math.hypot(*rel) - r) / v
    horizon = HORIZON_FACTOR * still + HORIZON_STEPS
    if not w.any():
        fastest = float(
            np.max(np.linalg.norm(np.asarray(flow.velocity(jnp.asarray(line))), axis=-1))
        )
        if fastest < v:
            straight = (math.hypot(*rel) - r) / (v - fastest)
            horizon = max(horizon, min(1.25 * straight, STRAIGHT_LINE_CAP * still))
    return min(horizon, MAX_HORIZON)


def _leg_states(flow: Flow, v: float, leg: _Leg, times: np.ndarray) -> np.ndarray:
    """States (len(times), 3): position and heading on ``leg`` at the absolute ``times``."""
    if leg.velocity is not None:
        xy = leg.x0 + np.outer(times - leg.t0, leg.velocity)
        return np.column_stack([xy, np.full(len(times), leg.heading0)])
    hs = np.diff(np.concatenate([[leg.t0], times]))
    padded = np.zeros(_padded(len(hs)))
    padded[: len(hs)] = hs
    s0 = np.array([leg.x0[0], leg.x0[1], leg.heading0])
    static, leaves = _flow_parts(flow)
    f64 = jnp.float64
    states = _trajectory(
        static,
        tuple(jnp.asarray(a, f64) for a in leaves),
        jnp.asarray(v, f64),
        jnp.asarray(s0, f64),
        jnp.asarray(padded, f64),
        leg.sub,
    )
    return np.asarray(states, np.float64)[1 : len(hs) + 1]


def _leg_point(flow: Flow, v: float, leg: _Leg, steps: float) -> np.ndarray:
    return _leg_states(flow, v, leg, np.array([leg.t0 + steps]))[0, :2]


def _sampled(flow: Flow, v: float, legs: list[_Leg]) -> ZermeloPath:
    """The path through ``legs`` at every whole step and at the end."""
    done = [leg for leg in legs if leg.steps is not None]
    reached = len(done) == len(legs)
    ends = [leg.t0 + leg.steps for leg in done]  # type: ignore[operator]
    end = ends[-1] if ends else 0.0
    times = np.arange(math.floor(end) + 1, dtype=np.float64)
    if times[-1] < end:
        times = np.append(times, end)
    states = np.empty((len(times), 3))
    states[0] = [*legs[0].x0, legs[0].heading0 if done else np.nan]
    for leg, stop in zip(done, ends):
        pick = (times > leg.t0) & (times <= stop)
        if pick.any():
            states[pick] = _leg_states(flow, v, leg, times[pick])
    heading = np.arctan2(np.sin(states[:, 2]), np.cos(states[:, 2]))
    return ZermeloPath(
        steps=float(end) if reached else None,
        xy=states[:, :2].copy(),
        heading=heading,
        t=times,
        legs=tuple(float(e) for e in ends),
    )
