"""The motion table: exact rigid motions of any one-DOF move of a two-DOF swimmer.

At zero Reynolds number the motion of a move depends on its path in shape space only, and rigid
motions along a path compose. For a move of DOF ``k`` with the other DOF held at ``c`` (both as
fractions ``s`` of their ranges), let ``G_k(s, c)`` be the rigid motion from the shape with
``s_k = 0`` to the one with ``s_k = s``: its rotation ``Theta_k(s, c)`` and the position
``W_k(s, c)`` (a complex number) of the geometric centroid, both in the body frame of the shape
``s_k = 0``. The move ``a -> b`` is ``G_k(a)^{-1} G_k(b)``:

* rotation ``Theta(b) - Theta(a)``;
* centroid displacement ``exp(-i Theta(a)) (W(b) - W(a))``, in the body frame at the start.

``Theta`` and ``W`` are smooth (analytic) in both arguments, so each is a tensor Chebyshev series
in ``(s, c)`` built once per model in float64 from the spectral running integral of the body
velocity along ``s`` ([`jswim.integrate.chebyshev_rule`][jswim.integrate.chebyshev_rule]); the degrees are chosen where the
coefficients fall below ~1e-16 of the largest. A step then costs one small matrix product and
two short series instead of an integration.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.env.table_cache import cached, model_key
from jswim.integrate import chebyshev_rule
from jswim.swimmers.models import SwimmerModel

#: Degree of the grid the table is built on (then truncated where the coefficients vanish).
BUILD_DEGREE = 40
#: Coefficients below this fraction of the largest are dropped (sets the table's degrees).
CUTOFF = 2e-16


class MotionTable(NamedTuple):
    """Chebyshev coefficients of ``Theta_0`` and ``W_0`` (float64), for moves of DOF 1.

    ``coef[j, f, i]``: degree ``j`` in ``c`` (the held DOF), function ``f`` (``Theta, Re W, Im W``
    for planar swimmers; ``Re W`` for the sphere swimmers), degree ``i`` in ``s`` (the moving
    DOF). Moves of DOF 2 read the same table through the swimmer's end-to-end symmetry
    (`mirror`).
    """

    coef: np.ndarray  # (M + 1, F, N + 1)


def supported(model: SwimmerModel) -> bool:
    """Whether a motion table serves ``model`` (two-DOF swimmers; others use the integrator)."""
    return model.n_dof == 2


def mirror(
    model: SwimmerModel, a: Array, b: Array, c: Array, dof: Array
) -> tuple[Array, Array, Array]:
    """Map a move of DOF 2 onto one of DOF 1 (identity for DOF 1).

    Read from the other end, a two-DOF swimmer is the same swimmer with its DOFs swapped; for the
    link swimmers the hinge angles also change sign (``d -> -d``, i.e. ``frac -> 1 - frac`` on
    the symmetric range), and the body frame turns by pi, so the move's body-frame displacement
    changes sign and its rotation does not. Checked against the integrator when the table is
    built (`motion_table`) and in the tests.
    """
    if model.planar:
        flip = dof != 0
        a, b, c = (jnp.where(flip, 1.0 - v, v) for v in (a, b, c))
    return a, b, c


def _lobatto(n: int) -> np.ndarray:
    return (1.0 - np.cos(np.pi * np.arange(n + 1) / n)) / 2.0  # ascending on [0, 1]


def build_values(model: SwimmerModel, deg: int = BUILD_DEGREE) -> np.ndarray:
    """``(Theta, Re W, Im W)`` of moves of DOF 1 on the ``(deg + 1)^2`` Chebyshev-Lobatto grid
    of ``(s, c)``; shape ``(deg + 1, deg + 1, 3)`` (s nodes, c nodes, function)."""
    nodes, running = chebyshev_rule(deg)
    span = model.hi - model.lo
    grid_s, grid_c = np.meshgrid(nodes, _lobatto(deg), indexing="ij")
    frac = np.stack([grid_s, grid_c], axis=-1)
    rate = np.array([span, 0.0])  # d(d_1)/ds
    with jax.ensure_compile_time_eval(), jax.enable_x64(True):
        d = jnp.asarray(model.lo + span * frac).reshape(-1, 2)
        w = jax.jit(jax.vmap(lambda dd: model.body_velocity(dd, jnp.asarray(rate))))(d)
        off = jax.jit(jax.vmap(model.centroid_offset))(d)
        w, off = (
            np.asarray(w).reshape(grid_s.shape + (3,)),
            np.asarray(off).reshape(grid_s.shape + (2,)),
        )
    theta = running @ w[..., 2]  # running integral along s for every c
    z = running @ (np.exp(1j * theta) * (w[..., 0] + 1j * w[..., 1]))
    wpos = z + np.exp(1j * theta) * (off[..., 0] + 1j * off[..., 1])
    return np.stack([theta, wpos.real, wpos.imag], axis=-1)


@functools.lru_cache(maxsize=16)
def motion_table(model: SwimmerModel) -> MotionTable:
    """The motion table of a two-DOF ``model`` (float64, built once per model).

    Raises
    ------
    ValueError
        If ``model`` is not a two-DOF swimmer.
    """
    if not supported(model):
        raise ValueError(f"motion tables serve two-DOF swimmers, not {model.label}")
    key = f"{model_key(model)}|deg={BUILD_DEGREE}|cut={CUTOFF}"
    # (c degree, function, s degree), the degrees cut where the coefficients fall below CUTOFF
    shape = {"coef": (None, 3 if model.planar else 1, None)}
    return MotionTable(
        cached("motion", key, lambda: {"coef": _build_motion_table(model)}, shape)["coef"]
    )


def _build_motion_table(model: SwimmerModel) -> np.ndarray:
    deg = BUILD_DEGREE
    vander = np.linalg.inv(np.polynomial.chebyshev.chebvander(2 * _lobatto(deg) - 1, deg))
    funs = [0, 1, 2] if model.planar else [1]
    vals = build_values(model, deg)[..., funs]
    coef = np.einsum("ia,jb,abf->jfi", vander, vander, vals)  # (c degree, function, s degree)
    mag = np.abs(coef) / np.abs(coef).max()
    keep_s = int(np.max(np.nonzero(mag.max(axis=(0, 1)) > CUTOFF)[0]))
    keep_c = int(np.max(np.nonzero(mag.max(axis=(1, 2)) > CUTOFF)[0]))
    return np.ascontiguousarray(coef[: keep_c + 1, :, : keep_s + 1])


#: Patches per DOF and their degree: the global series is re-expanded on PATCHES x PATCHES
#: patches of degree PATCH_DEGREE in each DOF, so a step gathers two small blocks (one per end)
#: instead of summing the whole series (few, wide operations: what XLA runs fast on CPU).
PATCHES = 16
PATCH_DEGREE = 7


@functools.lru_cache(maxsize=16)
def patch_table(model: SwimmerModel) -> np.ndarray:
    """The motion table on patches: shape ``(PATCHES^2, F, q + 1, q + 1)`` (float64), row
    ``p_s PATCHES + p_c``, Chebyshev coefficients in the patch's local ``(s, c)``."""
    coef = motion_table(model).coef  # (c degree, F, s degree)
    q, n_p = PATCH_DEGREE, PATCHES
    local = _lobatto(q)
    pts = ((np.arange(n_p)[:, None] + local[None, :]) / n_p).reshape(-1)  # every patch's nodes
    cheb = np.polynomial.chebyshev
    ts, tc = (
        cheb.chebvander(2 * pts - 1, coef.shape[2] - 1),
        cheb.chebvander(2 * pts - 1, coef.shape[0] - 1),
    )
    vals = np.einsum("si,cj,jfi->scf", ts, tc, coef).reshape(n_p, q + 1, n_p, q + 1, -1)
    inv = np.linalg.inv(cheb.chebvander(2 * local - 1, q))
    out = np.einsum("ia,jb,PaQbf->PQfij", inv, inv, vals)
    return np.ascontiguousarray(out.reshape(n_p * n_p, coef.shape[1], q + 1, q + 1))


def _chebyshev(x: Array, deg: int) -> list[Array]:
    """``T_0 .. T_deg`` at ``2 x - 1`` (three-term recurrence), as a list of scalars."""
    t = 2.0 * x - 1.0
    out = [jnp.ones_like(t), t]
    for _ in range(deg - 1):
        out.append(2.0 * t * out[-1] - out[-2])
    return out[: deg + 1]


def _patch_eval(table: Array, x: Array, pc: Array, tv: Array) -> Array:
    """The functions at moving-DOF value ``x`` in the patch column ``pc`` (local basis ``tv``)."""
    n_p = PATCHES
    ps = jnp.clip(jnp.floor(x * n_p), 0, n_p - 1)
    u = x * n_p - ps  # in [0, 1] within the patch
    tu = jnp.stack(_chebyshev(u, PATCH_DEGREE))
    block = table[(ps.astype(jnp.int32) * n_p + pc)]  # (F, q + 1, q + 1)
    return jnp.sum(block * tu[None, :, None] * tv[None, None, :], axis=(1, 2))


def move_increment(model: SwimmerModel, s0: Array, s1: Array, dof: Array) -> Array:
    """Body-frame step row ``(dx, dy, dtheta, cos dtheta, sin dtheta)`` (float64) of the move of
    DOF ``dof`` (0-based) from fractions ``s0`` to ``s1`` (the other DOF held); call under
    ``jax.enable_x64``. Works under ``vmap``: two gathers of one patch block each.
    """
    table = jnp.asarray(patch_table(model), jnp.float64)
    first = dof == 0
    a, b, c = (jnp.where(first, u[0], u[1]) for u in (s0, s1, s0[::-1]))
    a, b, c = mirror(model, a, b, c, dof)
    n_p = PATCHES
    pcf = jnp.clip(jnp.floor(c * n_p), 0, n_p - 1)
    tv = jnp.stack(_chebyshev(c * n_p - pcf, PATCH_DEGREE))
    pc = pcf.astype(jnp.int32)
    fa, fb = _patch_eval(table, a, pc, tv), _patch_eval(table, b, pc, tv)
    sign = jnp.where(first, 1.0, -1.0)
    if not model.planar:
        zero = jnp.zeros_like(a)
        return jnp.stack([sign * (fb[0] - fa[0]), zero, zero, zero + 1.0, zero])
    dth = fb[0] - fa[0]
    ca, sa = jnp.cos(fa[0]), jnp.sin(fa[0])
    dwx, dwy = fb[1] - fa[1], fb[2] - fa[2]
    return jnp.stack(
        [
            sign * (ca * dwx + sa * dwy),
            sign * (ca * dwy - sa * dwx),
            dth,
            jnp.cos(dth),
            jnp.sin(dth),
        ]
    )
