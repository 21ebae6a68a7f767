"""One table step through a non-uniform background flow: a row of `jswim.env.flow_tables` applied
at the step's pose, in float64.

Per step: one flow evaluation at the row's expansion point ``e`` (velocity, gradient and hessian,
or a Taylor-Green cell's two wave phases), turned into the start's body frame, the row's
first-order map, and a corrector for the second order. The corrector applies the same map again
to the flow as seen from the pose moved by half the first estimate (the rigid move that carries
the body half way, re-expanded about the moved point and turned with the body), linearised in
that small move. It is exact to second order for a held shape; for a moving one it leaves the
part that comes from how the response varies within the stroke (~1e-4 of the flow's effect at
0.9 of the swimming speed; docs/physics.md, "Background flows", gives the errors against the RK4
reference, `jswim.env.stepping.flow_step`, and where the model stops being true).

Everything is scalar arithmetic with no trigonometry from XLA (its float64 sine is a scalar call
on a CPU) and the result is stored once (`_materialise`): a step costs about twice a still-fluid
one (docs/performance.md, "Background flows").
"""

from __future__ import annotations

import math
from typing import Any

import jax
import jax.numpy as jnp
from jax import Array

from jswim.env.flow_tables import KEEP, flow_form
from jswim.env.flows import Flow, TaylorGreen
from jswim.errors import ConfigError

__all__ = ["Integrated", "flow_increment", "sincos", "small_sincos", "tabulated"]

_PIO2_HI = 1.57079632673412561417e00  # pi / 2 in 33 bits: n * _PIO2_HI is exact for |n| < 2^20
_PIO2_LO = 6.07710050650619224932e-11  # pi / 2 - _PIO2_HI


class Integrated(Flow):
    """``flow`` stepped by the reference integrator (`jswim.env.stepping.flow_step`: RK4 in
    ``substeps`` pieces through the full RFT response) instead of the tables: what the tables are
    checked against, and the way to step where their model does not hold (a flow that turns the
    body by much more than 0.1 rad in a step). The fluid moves as ``flow``'s does.

    Not a `jswim.env.flows.flow_from_dict` kind: a check, not a study's flow.

    Raises
    ------
    ConfigError
        ``flow`` not a `jswim.env.flows` flow, or ``substeps`` not a positive integer.
    """

    kind = "integrated"

    def __init__(self, flow: Flow, substeps: int = 16) -> None:
        if not isinstance(flow, Flow) or isinstance(flow, Integrated):
            raise ConfigError(f"Integrated wraps a jswim.env.flows flow, got {flow!r}")
        if isinstance(substeps, bool) or not isinstance(substeps, int) or substeps < 1:
            raise ConfigError(f"Integrated substeps must be a positive integer, got {substeps!r}")
        self.flow, self.substeps = flow, substeps

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Integrated) and (self.flow, self.substeps) == (
            other.flow,
            other.substeps,
        )

    def __hash__(self) -> int:
        return hash(("integrated", self.flow, self.substeps))

    def __repr__(self) -> str:
        return f"Integrated({self.flow!r}, substeps={self.substeps})"

    def velocity(self, x: Array) -> Array:
        return self.flow.velocity(x)

    def gradient(self, x: Array) -> Array:
        return self.flow.gradient(x)

    def hessian(self, x: Array) -> Array:
        return self.flow.hessian(x)

    @property
    def speed(self) -> float:
        return self.flow.speed

    @property
    def max_gradient(self) -> float:
        return self.flow.max_gradient

    def to_dict(self) -> dict[str, Any]:
        return {"kind": self.kind, "flow": self.flow.to_dict(), "substeps": self.substeps}


def tabulated(flow: Flow) -> bool:
    """Whether table steps in ``flow`` use the tables: a `TaylorGreen` cell or a flow with a
    ``hessian``, not an `Integrated` one (whose steps, like those off the tables, integrate)."""
    if isinstance(flow, Integrated):
        return False
    return isinstance(flow, TaylorGreen) or type(flow).hessian is not Flow.hessian


# --- float64 arithmetic that vectorises ------------------------------------------------------


def _taylor_sincos(r: Array, terms: int) -> tuple[Array, Array]:
    r2 = r * r
    sin_r, cos_r = 0.0, 0.0
    for k in range(terms - 1, -1, -1):  # Horner in r^2
        sin_r = sin_r * r2 + (-1.0) ** k / math.factorial(2 * k + 1)
        cos_r = cos_r * r2 + (-1.0) ** k / math.factorial(2 * k)
    return sin_r * r, cos_r


def sincos(x: Array) -> tuple[Array, Array]:
    """``(sin x, cos x)`` in float64 to ~1e-16 for ``|x| < 1e6`` (Cody-Waite reduction by pi/2,
    Taylor polynomials on [-pi/4, pi/4]): plain arithmetic, which vectorises; XLA's float64 sine
    and cosine are scalar calls on a CPU, each ~half the cost of a still-fluid step."""
    n = jnp.floor(x * (2.0 / math.pi) + 0.5)
    r = (x - n * _PIO2_HI) - n * _PIO2_LO
    sin_r, cos_r = _taylor_sincos(r, 9)  # to r^17 and r^18: below 1e-17 on |r| <= pi/4
    q = n.astype(jnp.int32)
    odd = (q & 1) == 1
    s = jnp.where(odd, cos_r, sin_r)
    c = jnp.where(odd, sin_r, cos_r)
    return jnp.where((q & 2) == 2, -s, s), jnp.where(((q + 1) & 2) == 2, -c, c)


def small_sincos(x: Array) -> tuple[Array, Array]:
    """``(sin x, cos x)`` of a small angle (a flow's turn in one step) in float64, without
    reduction: the Taylor polynomials at ``x / 4``, then two doublings (~1e-16 for ``|x| < 1``,
    ~1e-10 at 4)."""
    s, c = _taylor_sincos(0.25 * x, 7)
    for _ in range(2):
        s, c = 2.0 * s * c, (c - s) * (c + s)
    return s, c


def _materialise(*values: Array) -> tuple[Array, ...]:
    """``values`` unchanged, computed together in one kernel and stored once.

    XLA copies cheap arithmetic into every consumer, so a flow step whose few outputs feed a
    dozen (the pose's words, the info, the observation) would recompute the whole flow model once
    per consumer (~10 x the step), and `jax.lax.optimization_barrier` is gone before fusion on a
    CPU. A variadic reduction (of each value and a zero) is one kernel with all its outputs: the
    model is computed once. Exact (``v + 0 = v``)."""
    ops = [jnp.stack([v, jnp.zeros_like(v)]) for v in values]
    zeros = [jnp.zeros((), v.dtype) for v in values]
    return tuple(jax.lax.reduce(ops, zeros, lambda a, b: [x + y for x, y in zip(a, b)], (0,)))


# --- the corrector's move ------------------------------------------------------------------


def _shift(first: list[Array], beta: Array, e: Array, p1: tuple) -> tuple[Array, Array]:
    """Where the expansion point goes in the corrector (start frame): the rigid move about the
    start point that carries the body half way, ``(dX - dtheta J p(1)) / 2`` (a turn moves the
    end point by ``dtheta J p(1)``, not the body on the way), then ``e`` turned by ``beta``."""
    sx = 0.5 * first[0] + beta * p1[1]
    sy = 0.5 * first[1] - beta * p1[0]
    return sx - beta * e[1], sy + beta * e[0]


def _back(mid: list[Array], beta: Array) -> tuple[Array, Array, Array]:
    """The corrector's estimate, found in the frame turned by ``beta``, in the start frame."""
    return mid[0] - beta * mid[1], mid[1] + beta * mid[0], mid[2]


# --- polynomial flows ----------------------------------------------------------------------


def _turned(t: dict, c: Array, s: Array) -> dict:
    """A tensor (dict: index tuple -> scalar) seen from a frame turned by ``(c, s)``: ``R^T`` on
    every index. Scalars, not small arrays: stacking inside a vmapped step costs more than it."""
    for _ in range(len(next(iter(t)))):  # turn the last index, then move it to the front
        out = {}
        for key in {k[:-1] for k in t}:
            v0, v1 = t[key + (0,)], t[key + (1,)]
            out[(0,) + key], out[(1,) + key] = c * v0 + s * v1, c * v1 - s * v0
        t = out
    return t


def _spun(t: dict) -> dict:
    """The rate of change of `_turned` with the angle, at 0: ``J^T`` on each index in turn."""
    out = {k: 0.0 * v for k, v in t.items()}
    for k in t:
        for pos in range(len(k)):
            other = k[:pos] + (1 - k[pos],) + k[pos + 1 :]  # J^T = [[0, 1], [-1, 0]]
            out[k] = out[k] + (t[other] if k[pos] == 0 else -t[other])
    return out


def _c9(u: dict, g: dict, h: dict) -> list[Array]:
    """The free coefficients (`jswim.env.flow_tables.EMBED`) of velocity, gradient, hessian."""
    return [u[(0,)], u[(1,)], g[0, 0], g[0, 1], g[1, 0]] + [
        h[0, 0, 0], h[0, 0, 1], h[0, 1, 1], h[1, 0, 0]
    ]  # fmt: skip


def _polynomial_step(flow: Flow, row: tuple, keep: tuple[int, ...], at: Array, c, s, p1):
    """``(dx, dy, dtheta)`` of the reference point (start frame) in a polynomial flow."""
    n = len(keep)
    lin, e = row[: 3 * n], row[-6:-4]
    idx2 = [(i, j) for i in range(2) for j in range(2)]
    uv, gv = flow.velocity(at), flow.gradient(at)
    u = _turned({(i,): uv[i] for i in range(2)}, c, s)
    g = _turned({k: gv[k] for k in idx2}, c, s)
    quadratic = n > 3
    if quadratic:
        hv = flow.hessian(at)
        h = _turned({(i, j, k): hv[i, j, k] for i, j in idx2 for k in range(2)}, c, s)
    else:
        h = {(i, j, k): 0.0 for i, j in idx2 for k in range(2)}

    def apply(cf: list[Array]) -> list[Array]:
        out = [cf[0], cf[1], 0.0]  # the uniform part moves the body by exactly u
        for k in range(3):
            for j, col in enumerate(keep):
                out[k] = out[k] + lin[n * k + j] * cf[col]
        return out

    first = apply(_c9(u, g, h))
    # The moved pose sees the flow re-expanded about its own expansion point (the gradient and
    # hessian carry it there: exact for a quadratic flow), turned by beta.
    beta = 0.5 * first[2]
    shift = _shift(first, beta, e, p1)
    du = {(i,): g[i, 0] * shift[0] + g[i, 1] * shift[1] for i in range(2)}
    dg = {(i, j): h[i, j, 0] * shift[0] + h[i, j, 1] * shift[1] for i, j in idx2}
    su, sg = _spun(u), _spun(g)
    moved = _c9(
        {k: u[k] + du[k] + beta * su[k] for k in u},
        {k: g[k] + dg[k] + beta * sg[k] for k in g},
        {k: v + beta * w for (k, v), w in zip(h.items(), _spun(h).values())} if quadratic else h,
    )
    return _back(apply(moved), beta)


# --- Taylor-Green cells --------------------------------------------------------------------


def _wave_sums(row: tuple, z: tuple[Array, Array], out: int, n_harm: int) -> list[Array]:
    """For output ``out``: ``S1 = sum_n m_n z^n`` and ``S2 = sum_n m_n (-i z)^n`` over all
    integers ``n`` (``m_{-n} = -(-1)^n conj(m_n)``), and their ``n``-weighted sums (their rate of
    change as the body turns), as ``(Re, Im)`` pairs: ``[S1, S2, N1, N2]``."""
    s1r, s1i, s2r, s2i = 0.0, row[out], 0.0, row[out]  # n = 0: m_0 is imaginary
    n1r = n1i = n2r = n2i = 0.0
    zr, zi = z
    pr, pi = 1.0, 0.0
    for n in range(1, n_harm + 1):
        pr, pi = pr * zr - pi * zi, pr * zi + pi * zr  # z^n
        mr, mi = row[3 + 6 * (n - 1) + out], row[6 + 6 * (n - 1) + out]
        wr, wi = mr * pr - mi * pi, mr * pi + mi * pr  # w = m_n z^n
        # the pair n, -n: w - (-1)^n conj(w) = 2 Re w (odd n), 2i Im w (even n); its n-weighted
        # sum n (w + (-1)^n conj(w)) = 2i n Im w (odd), 2 n Re w (even); wave 2 has (-i)^n w
        w2r, w2i = [(wr, wi), (wi, -wr), (-wr, -wi), (-wi, wr)][n % 4]
        if n % 2:
            s1r, s2r = s1r + 2 * wr, s2r + 2 * w2r
            n1i, n2i = n1i + 2 * n * wi, n2i + 2 * n * w2i
        else:
            s1i, s2i = s1i + 2 * wi, s2i + 2 * w2i
            n1r, n2r = n1r + 2 * n * wr, n2r + 2 * n * w2r
    return [(s1r, s1i), (s2r, s2i), (n1r, n1i), (n2r, n2i)]


def _wave_step(flow: TaylorGreen, row: tuple, at: Array, c, s, p1):
    """``(dx, dy, dtheta)`` of the reference point (start frame) in a Taylor-Green cell:
    ``u = (u0 / sqrt 2) Im[-t(pi/4) exp(i q1 . x) + t(-pi/4) exp(i q2 . x)]`` with
    ``q1 = k (1, 1)``, ``q2 = k (1, -1)``, ``t(b) = (-sin b, cos b)``."""
    n_harm = (len(row) - 9) // 6
    e, k = row[-6:-4], flow.k
    sx, cx = sincos(k * at[0])
    sy, cy = sincos(k * at[1])
    phases = [(cx * cy - sx * sy, sx * cy + cx * sy), (cx * cy + sx * sy, sx * cy - cx * sy)]
    r2 = math.sqrt(0.5)
    # wave 1 meets the body at alpha = pi/4 - theta0: z = exp(i alpha); wave 2 at -i z
    sums = [_wave_sums(row, (r2 * (c + s), r2 * (c - s)), out, n_harm) for out in range(3)]
    q_lab = ((k, k), (k, -k))

    def total(beta: Array | float, shift: tuple) -> list[Array]:
        """``dP`` of the pose moved by ``shift`` (start frame) and turned by ``beta``, to first
        order in both: ``S(alpha - beta) = S - i beta N``, phases times ``1 + i q . shift``."""
        lab = (c * shift[0] - s * shift[1], s * shift[0] + c * shift[1])
        dq = [q[0] * lab[0] + q[1] * lab[1] for q in q_lab]
        out3 = []
        for o in range(3):
            acc = 0.0
            for j, sign in ((0, -1.0), (1, 1.0)):
                (sr, si), (nr, ni) = sums[o][j], sums[o][2 + j]
                tr, ti = sr + beta * ni, si - beta * nr
                ph_r = phases[j][0] - dq[j] * phases[j][1]
                ph_i = phases[j][1] + dq[j] * phases[j][0]
                acc = acc + sign * (ph_r * ti + ph_i * tr)  # Im(phase S)
            out3.append(flow.u0 * r2 * acc)
        return out3

    first = total(0.0, (0.0, 0.0))
    beta = 0.5 * first[2]
    return _back(total(beta, _shift(first, beta, e, p1)), beta)


def flow_increment(
    flow: Flow, row: tuple[Array, ...], still: Array, x: Array, y: Array, c: Array, s: Array
) -> tuple[Array, Array, Array, Array, Array]:
    """What ``flow`` adds to one table step: ``(dx, dy)`` of the centroid (``a``, the start's body
    frame), ``dtheta`` of the orientation (rad) and its cosine and sine; float64 (call under
    ``jax.enable_x64``).

    Parameters
    ----------
    flow : Flow
        A flow the tables model (`tabulated`).
    row : tuple of Array ()
        The step's `jswim.env.flow_tables.flow_table` row (`jswim.env.flow_tables.gather_row`).
    still : Array (2,)
        The still-fluid step's centroid displacement, start frame (``a``; the step table's).
    x, y, c, s : Array ()
        The start centroid (``a``) and the cosine and sine of the start orientation.
    """
    e, e_c, o1 = row[-6:-4], row[-4:-2], row[-2:]
    # the still stroke's end reference point, start frame
    p1 = (still[0] + e[0] - e_c[0] - o1[0], still[1] + e[1] - e_c[1] - o1[1])
    at = jnp.stack([x + c * e_c[0] - s * e_c[1], y + s * e_c[0] + c * e_c[1]])
    form = flow_form(flow)
    if form[0] == "waves":
        dx, dy, turn = _wave_step(flow, row, at, c, s, p1)
    else:
        dx, dy, turn = _polynomial_step(flow, row, KEEP[form[0]], at, c, s, p1)
    # The centroid rides on the body: the end offset o1 turns with the flow's extra turn.
    st, ct = small_sincos(turn)
    dx = dx + (ct - 1.0) * o1[0] - st * o1[1]
    dy = dy + st * o1[0] + (ct - 1.0) * o1[1]
    return _materialise(dx, dy, turn, ct, st)
