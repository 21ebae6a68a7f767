"""What a background flow does to each table step, tabulated once per model (float64).

The drag is linear (resistive force theory), so a body's rigid velocity in a flow is its
still-fluid one plus the flow's response, which is linear in the flow
(`jswim.swimmers.flow_response.flow_velocity`). Over one step (one ``tau``) the shape moves
straight between two table shapes (in the whole step, or, pushed past a limit, in its first part
and then held), so the still-fluid path of the body, ``p(t), phi(t)`` in the
body frame at the step's start, is the same for every step of a table row. To first order in the
flow the step's extra change of the pose (reference point, orientation) is the flow's response
along that path, each instant's turn carried through the rest of the stroke,

    dP = int_0^1 (V(t) + Omega(t) J (p(1) - p(t)), Omega(t)) dt,

a linear functional of the flow near the body. A row holds it in one of two forms:

* polynomial flows: about the expansion point ``e`` (the step-averaged centroid) the flow is
  ``u + G (x - e) + H[x - e, x - e] / 2``, exact for `Shear` (linear) and `Poiseuille`
  (quadratic), the Taylor model of any other flow with a ``hessian``; ``dP = (u, 0) + T c``, ``c``
  the 7 free coefficients of ``(G, H)`` of an incompressible flow (3 for a linear one)
  (`step_flow_map`);
* `TaylorGreen` cells: two standing plane waves of wavenumber ``K = sqrt(2) pi / cell``; the
  response to a unit transverse wave whose wavevector makes the angle ``alpha`` with the body
  frame, ``m(alpha)``, by its Fourier harmonics, which fall as the Bessel function
  ``J_n(K L)`` of the body's size ``L`` (`step_wave_map`): exact in space to `WAVE_CUTOFF`, where
  a Taylor model is off by ``~(L / cell)^2`` (10 % of the flow's turn in a cell of 6 a).

`jswim.env.flow_steps` applies a row (one flow evaluation and small contractions per step, and a
corrector for the second order). Rows follow the step tables: `flow_table` for the K lattice (one
row per push, `lattice_flow_row`: a push past a limit moves at its ROC until the limit, then
holds, the path `jswim.env.work` charges) and the paper's corner world (`corner_flow_row`: one
hold row per corner, since a held shape still feels the flow).
"""

from __future__ import annotations

import functools
import hashlib
import inspect
import math
from pathlib import Path
from typing import Any
from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.env.flows import Flow, Shear, TaylorGreen
from jswim.env.state import corner_values
from jswim.env.step_tables import lattice_moves
from jswim.env.table_cache import cached, model_key
from jswim.integrate import chebyshev_rule
from jswim.swimmers import flow_response
from jswim.swimmers.flow_response import flow_velocity
from jswim.swimmers.models import SwimmerModel

__all__ = [
    "FLOW_TABLE_DEGREE",
    "KEEP",
    "WAVE_CUTOFF",
    "corner_flow_row",
    "flow_form",
    "flow_table",
    "gather_row",
    "lattice_flow_row",
    "step_flow_map",
    "step_wave_map",
]

#: Chebyshev degree of the quadrature over a step that builds a row (converged to ~1e-16).
FLOW_TABLE_DEGREE = 32

#: Gauss nodes per link for the response (exact for quadratic flows; ~1e-12 for the waves).
NODES = 6

#: Harmonics of a wave row are kept down to this fraction of the largest (the relative error of
#: the first-order response; the step's second order is ~100 x larger).
WAVE_CUTOFF = 1e-6

#: Angles the wave response is sampled at for its Fourier transform (harmonics below half of it).
WAVE_ANGLES = 64

#: Incompressible (Stokes) flows: ``(u, G, H)`` (2 + 4 + 8 numbers) hold 9 free ones,
#: ``c9 = (u_x, u_y, G_xx, G_xy, G_yx, H_xxx, H_xxy, H_xyy, H_yxx)``: ``G_yy = -G_xx``,
#: ``H_yxy = H_yyx = -H_xxx``, ``H_yyy = -H_xxy`` (``div u = 0`` and its gradient).
EMBED = np.zeros((14, 9))
for _row, _col, _sign in (
    (0, 0, 1), (1, 1, 1), (2, 2, 1), (3, 3, 1), (4, 4, 1), (5, 2, -1),
    (6, 5, 1), (7, 6, 1), (8, 6, 1), (9, 7, 1), (10, 8, 1), (11, 5, -1), (12, 5, -1), (13, 6, -1),
):  # fmt: skip
    EMBED[_row, _col] = _sign

#: The ``c9`` a polynomial row keeps: the gradient's 3 and the hessian's 4, or the gradient's
#: alone for a linear flow (`Shear`). The uniform part ``c9[:2]`` moves the body by exactly ``u``.
KEEP = {"quadratic": (2, 3, 4, 5, 6, 7, 8), "linear": (2, 3, 4)}


def flow_form(flow: Flow) -> tuple[Any, ...]:
    """How the rows model ``flow``: ``("waves", K)`` (`TaylorGreen`), ``("linear",)`` (`Shear`)
    or ``("quadratic",)`` (any other flow with a ``hessian``: its Taylor model)."""
    if isinstance(flow, TaylorGreen):
        return ("waves", math.sqrt(2.0) * flow.k)
    if isinstance(flow, Shear):
        return ("linear",)
    return ("quadratic",)


# --- one row (float64, traceable) ----------------------------------------------------------


def _still_path(
    model: SwimmerModel, s0: Array, s1: Array, degree: int, duration: Array | float = 1.0
) -> dict[str, Array]:
    """The still-fluid path of the straight move ``s0 -> s1`` on Chebyshev-Lobatto nodes (the
    integrator's two nested quadratures): shapes ``d``, reference poses and centroids in the
    start frame, centroid offsets and the time weights ``w`` of the step.

    The move takes the first ``duration`` of the step (in ``tau``, in (0, 1]) and the shape then
    holds ``s1``: a push clipped at a limit, fast then held. At zero Reynolds number the path
    does not depend on the rate, so only the weights change: the Clenshaw-Curtis weights of the
    move times ``duration``, plus ``1 - duration`` on the last node (the held end shape)."""
    f64 = jnp.float64
    span = model.hi - model.lo
    d0, d_dot = corner_values(model, s0), (s1 - s0) * span
    nodes, running = chebyshev_rule(degree)
    t, running = jnp.asarray(nodes, f64), jnp.asarray(running, f64)
    d = d0[None, :] + t[:, None] * d_dot[None, :]
    body = jax.vmap(lambda dk: model.body_velocity(dk, d_dot))(d)  # (m, 3), body frame
    phi = running @ body[:, 2]
    c, s = jnp.cos(phi), jnp.sin(phi)
    px = running @ (c * body[:, 0] - s * body[:, 1])
    py = running @ (s * body[:, 0] + c * body[:, 1])
    off = jax.vmap(model.centroid_offset)(d)
    cx, cy = px + c * off[:, 0] - s * off[:, 1], py + s * off[:, 0] + c * off[:, 1]
    duration = jnp.asarray(duration, f64)
    last = jnp.zeros(len(nodes), f64).at[-1].set(1.0)  # the last Lobatto node is t = 1
    w = duration * running[-1] + (1.0 - duration) * last
    return dict(w=w, d=d, poses=jnp.stack([px, py, phi], -1), cx=cx, cy=cy, off=off)


def _first_order(
    model: SwimmerModel, path: dict[str, Array], field: Callable[[Array], Array]
) -> Array:
    """``dP`` (3,) of a start-frame flow ``field`` (positions (..., 2) -> velocities (..., 2))
    along ``path``: the response at every node, its turn carried to the step's end."""
    resp = jax.vmap(lambda dk, pk: flow_velocity(dk, pk, field, model.xi_ratio, NODES))(
        path["d"], path["poses"]
    )
    px, py, w = path["poses"][:, 0], path["poses"][:, 1], path["w"]
    vx = resp[:, 0] - resp[:, 2] * (py[-1] - py)
    vy = resp[:, 1] + resp[:, 2] * (px[-1] - px)
    return jnp.stack([w @ vx, w @ vy, w @ resp[:, 2]])


def _frame(path: dict[str, Array]) -> tuple[Array, Array, Array]:
    """``e`` (the step-averaged centroid, from the start reference point), ``e - c0`` (from the
    start centroid) and ``o1`` (the end centroid offset ``R(phi(1)) offset(d1)``), start frame."""
    w = path["w"]
    e = jnp.stack([w @ path["cx"], w @ path["cy"]])
    phi1, off1 = path["poses"][-1, 2], path["off"][-1]
    c, s = jnp.cos(phi1), jnp.sin(phi1)
    o1 = jnp.stack([c * off1[0] - s * off1[1], s * off1[0] + c * off1[1]])
    return e, e - path["off"][0], o1


def _poly(coef: Array, x: Array, e: Array) -> Array:
    """The flow polynomial of ``coef`` (14,: ``u``, ``G`` row-major, ``H``) about ``e``."""
    u, g, h = coef[:2], coef[2:6].reshape(2, 2), coef[6:].reshape(2, 2, 2)
    r = x - e
    return u + jnp.einsum("ij,...j->...i", g, r) + 0.5 * jnp.einsum("ijk,...j,...k->...i", h, r, r)


def step_flow_map(
    model: SwimmerModel,
    s0: Array,
    s1: Array,
    degree: int = FLOW_TABLE_DEGREE,
    duration: Array | float = 1.0,
) -> tuple[Array, Array, Array, Array]:
    """The first-order map of one step (one unit of time) that moves the shape straight from
    ``s0`` to ``s1`` (fractions of the range) in its first ``duration`` and then holds ``s1``
    (``duration`` 1: the move takes the whole step; less: a push clipped at a limit) for
    polynomial flows; float64, traceable (call under ``jax.enable_x64``).

    Returns
    -------
    tmat : Array (3, 14)
        ``dP = tmat @ (u, G, H)``: the flow's coefficients about ``e`` in the start frame
        (``a / tau``, ``1 / tau``, ``1 / (a tau)``; ``G`` row-major, ``H[i, j, k]``) to the change
        of the reference point (``a``) and orientation (rad), start frame. Its ``u`` columns are
        exactly ``(I, 0)`` (Galilean invariance).
    e, e_c, o1 : Array (2,)
        The expansion point from the start reference point and from the start centroid, and the
        end centroid offset ``R(phi(1)) offset(d1)`` (``a``, start frame).
    """
    f64 = jnp.float64
    path = _still_path(model, jnp.asarray(s0, f64), jnp.asarray(s1, f64), degree, duration)
    e, e_c, o1 = _frame(path)
    tmat = jax.jacfwd(lambda coef: _first_order(model, path, lambda x: _poly(coef, x, e)))(
        jnp.zeros(14, f64)
    )  # exact: the map is linear
    return tmat, e, e_c, o1


def step_wave_map(
    model: SwimmerModel,
    s0: Array,
    s1: Array,
    wavenumber: float,
    angles: int = WAVE_ANGLES,
    degree: int = FLOW_TABLE_DEGREE,
    duration: Array | float = 1.0,
) -> tuple[Array, Array, Array, Array]:
    """The first-order response of the step of `step_flow_map` (the move ``s0 -> s1`` in its
    first ``duration``, then held) to a transverse plane wave, the
    start-frame flow ``t(alpha) exp(i K k(alpha) . (x - e))`` (``k = (cos, sin)``,
    ``t = (-sin, cos)``, ``K = wavenumber`` in ``1 / a``), by its Fourier harmonics in
    ``alpha``; float64, traceable (call under ``jax.enable_x64``).

    Returns
    -------
    harmonics : Array (angles // 2, 3) complex128
        ``m_n``, ``n = 0, 1, ..``: ``m(alpha) = sum_n m_n exp(i n alpha)`` (over all integers
        ``n``), with ``m_{-n} = -(-1)^n conj(m_n)`` (the opposite wave is the conjugate one).
    e, e_c, o1 : Array (2,)
        As in `step_flow_map`.
    """
    f64 = jnp.float64
    path = _still_path(model, jnp.asarray(s0, f64), jnp.asarray(s1, f64), degree, duration)
    e, e_c, o1 = _frame(path)

    def response(alpha: Array) -> Array:
        kvec = wavenumber * jnp.stack([jnp.cos(alpha), jnp.sin(alpha)])
        pol = jnp.stack([-jnp.sin(alpha), jnp.cos(alpha)])

        def part(fn: Callable[[Array], Array]) -> Array:
            return _first_order(model, path, lambda x: pol * fn((x - e) @ kvec)[..., None])

        return part(jnp.cos) + 1j * part(jnp.sin)

    alpha = 2 * math.pi * jnp.arange(angles, dtype=f64) / angles
    m = jax.vmap(response)(alpha)  # (angles, 3)
    harmonics = jnp.fft.fft(m, axis=0) / angles  # index n: the coefficient of exp(i n alpha)
    return harmonics[: angles // 2], e, e_c, o1


# --- the tables ----------------------------------------------------------------------------


def _source_key() -> str:
    """The source of the modules a row depends on beyond the table cache's own list."""
    h = hashlib.blake2b(digest_size=8)
    for mod in (flow_response, inspect.getmodule(_source_key)):
        try:
            h.update(Path(inspect.getfile(mod)).read_bytes())
        except (OSError, TypeError):
            h.update(str(mod).encode())
    return h.hexdigest()


def _moves(
    model: SwimmerModel, roc_levels: int | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Start and end fractions of every row and the part of the step the move takes: the
    lattice pushes (`lattice_flow_row`), or the corner rows (`corner_flow_row`, all 1)."""
    n = model.n_dof
    if roc_levels is not None:
        big_k = roc_levels
        shapes = lattice_moves(n, big_k)[0][:: n * (big_k + 1)]  # every lattice point, in order
        start = np.repeat(shapes, n * (2 * big_k + 1), axis=0)
        dof = np.tile(np.repeat(np.arange(n), 2 * big_k + 1), len(shapes))
        push = np.tile(np.arange(-big_k, big_k + 1), len(shapes) * n)
        rows = np.arange(len(start))
        end = start.copy()
        end[rows, dof] = np.clip(start[rows, dof] + push, 0, big_k)
        moved = np.abs(end[rows, dof] - start[rows, dof])
        # fast, then held: the DOF moves at its ROC push / K until it meets the limit
        duration = np.where(moved > 0, moved / np.maximum(np.abs(push), 1), 1.0)
        return start / big_k, end / big_k, duration
    corners = np.array([[(c >> k) & 1 for k in range(n)] for c in range(2**n)], np.float64)
    start = np.repeat(corners, n + 1, axis=0)
    end = start.copy()
    for k in range(n):
        end[k :: n + 1, k] = 1.0 - end[k :: n + 1, k]
    return start, end, np.ones(len(start))


def _build(
    fn: Callable[[Array, Array, Array], Array],
    start: np.ndarray,
    end: np.ndarray,
    duration: np.ndarray,
) -> np.ndarray:
    # Evaluate now even when first called while tracing a step (the table is a constant).
    with jax.ensure_compile_time_eval(), jax.enable_x64(True):
        rows = jax.jit(jax.vmap(fn))(*(jnp.asarray(v, jnp.float64) for v in (start, end, duration)))
        return np.asarray(rows)


def _polynomial_rows(model: SwimmerModel, keep: tuple[int, ...], moves) -> np.ndarray:
    def row(a: Array, b: Array, t: Array) -> Array:
        tmat, e, e_c, o1 = step_flow_map(model, a, b, duration=t)
        lin = (tmat @ jnp.asarray(EMBED, jnp.float64))[:, list(keep)]
        return jnp.concatenate([lin.reshape(-1), e, e_c, o1])

    return _build(row, *moves)


def _wave_rows(model: SwimmerModel, wavenumber: float, moves) -> np.ndarray:
    def row(a: Array, b: Array, t: Array) -> Array:
        m, e, e_c, o1 = step_wave_map(model, a, b, wavenumber, duration=t)
        # m_0 is imaginary (m_0 = -conj(m_0)): Im m_0, then Re and Im of m_1, m_2, ...
        parts = [jnp.imag(m[0])] + [jnp.concatenate([jnp.real(mn), jnp.imag(mn)]) for mn in m[1:]]
        return jnp.concatenate(parts + [e, e_c, o1])

    rows = _build(row, *moves)
    size = np.abs(rows[:, :-6]).max(axis=0)
    per = [size[:3].max()] + [
        size[3 + 6 * i : 9 + 6 * i].max() for i in range(WAVE_ANGLES // 2 - 1)
    ]
    last = max(n for n, v in enumerate(per) if v >= WAVE_CUTOFF * max(per))
    return np.concatenate([rows[:, : 3 + 6 * last], rows[:, -6:]], axis=1)


@functools.lru_cache(maxsize=64)
def flow_table(model: SwimmerModel, flow: Flow, roc_levels: int | None = None) -> np.ndarray:
    """The rows of ``model``'s table steps in ``flow`` (float64, built once per model and flow
    form, `flow_form`: the flow's strength and place do not enter; cached on disk like the step
    tables).

    ``roc_levels=None``: the paper's corner world, row ``corner * (n_dof + 1) + k`` moving DOF
    ``k`` to its other level and row ``corner * (n_dof + 1) + n_dof`` holding the corner's shape
    (`corner_flow_row`). Else the K lattice: one row per lattice point, DOF and push ``q`` in
    ``-K..K`` (`lattice_flow_row`), since a push past a limit is not the move that lands on the
    limit in the whole step: the DOF moves at the ROC ``q / K`` until it meets the limit, then
    holds (the path whose work `jswim.env.work` charges), and a flow acts on the held shape too.

    Returns
    -------
    ndarray, shape (rows, width)
        Polynomial flows: ``T`` on the `KEEP` coefficients (3 x 7, or 3 x 3 for a linear flow,
        row-major), then ``e``, ``e - c0`` and ``o1`` (`step_flow_map`). Taylor-Green cells:
        ``Im m_0`` (3), then ``Re m_n`` and ``Im m_n`` (3 each) for ``n = 1 .. N`` (N from
        `WAVE_CUTOFF`), then ``e``, ``e - c0``, ``o1`` (`step_wave_map`).
    """
    form = flow_form(flow)
    moves = _moves(model, roc_levels)
    key = f"{model_key(model)}|K={roc_levels}|{form}|deg={FLOW_TABLE_DEGREE}|{_source_key()}"
    if form[0] == "waves":
        key += f"|cut={WAVE_CUTOFF}"
        shape = {"rows": (len(moves[0]), None)}  # the harmonics kept depend on the model
        rows = cached("flow", key, lambda: {"rows": _wave_rows(model, form[1], moves)}, shape)
        return rows["rows"]
    keep = KEEP[form[0]]
    shape = {"rows": (len(moves[0]), 3 * len(keep) + 6)}
    rows = cached("flow", key, lambda: {"rows": _polynomial_rows(model, keep, moves)}, shape)
    return rows["rows"]


def corner_flow_row(corner: Array, dof: Array, moved: Array, n_dof: int) -> Array:
    """The corner `flow_table` row (int32) of a corner step: DOF ``dof`` (0-based) moved to its
    other level, or the corner's hold row."""
    return corner * (n_dof + 1) + jnp.where(moved, dof, n_dof).astype(jnp.int32)


def lattice_flow_row(shape: Array, dof: Array, push: Array, n_dof: int, roc_levels: int) -> Array:
    """The K-lattice `flow_table` row (int32) of the push of DOF ``dof`` (0-based) by ``push``
    lattice units (the ROC ``push / K``, in ``-K..K``) from lattice point ``shape``
    (``sum_m j_m (K + 1)^m``): ``(shape n_dof + dof)(2 K + 1) + push + K``."""
    width = 2 * roc_levels + 1
    return ((shape * n_dof + dof) * width + push + roc_levels).astype(jnp.int32)


def gather_row(table: np.ndarray, index: Array) -> tuple[Array, ...]:
    """Row ``index`` of a flow table as scalars (float64; call under ``jax.enable_x64``), one
    column at a time: under vmap a gather per column is ~2 x faster on a CPU than one of rows."""
    return tuple(jnp.asarray(np.ascontiguousarray(col), jnp.float64)[index] for col in table.T)
