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
velocity along ``s`` (:func:`jswim.integrate.chebyshev_rule`); the degrees are chosen where the
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

from jswim.integrate import chebyshev_rule
from jswim.swimmers.models import SwimmerModel

#: Degree of the grid the table is built on (then truncated where the coefficients vanish).
BUILD_DEGREE = 40
#: Coefficients below this fraction of the largest are dropped (sets the table's degrees).
CUTOFF = 2e-16


class MotionTable(NamedTuple):
    """Chebyshev coefficients of ``Theta_k`` and ``W_k`` (float64).

    ``coef[k]`` has shape ``(M + 1, F (N + 1))``: rows are degrees in ``c`` (the held DOF), columns
    the functions (``Theta, Re W, Im W`` for planar swimmers; ``Re W`` for the sphere swimmers) by
    degree in ``s`` (the moving DOF), function-major.
    """

    coef: np.ndarray  # (n_dof, M + 1, F * (N + 1))
    n: int  # degree N in s
    m: int  # degree M in c
    n_fun: int  # F


def supported(model: SwimmerModel) -> bool:
    """Whether a motion table serves ``model`` (two-DOF swimmers; others use the integrator)."""
    return model.n_dof == 2


def _lobatto(n: int) -> np.ndarray:
    return (1.0 - np.cos(np.pi * np.arange(n + 1) / n)) / 2.0  # ascending on [0, 1]


def build_values(model: SwimmerModel, k: int, deg: int = BUILD_DEGREE) -> np.ndarray:
    """``(Theta, Re W, Im W)`` of moves of DOF ``k`` on the ``(deg + 1)^2`` Chebyshev-Lobatto grid
    of ``(s, c)``; shape ``(deg + 1, deg + 1, 3)`` (s nodes, c nodes, function)."""
    nodes, running = chebyshev_rule(deg)
    span = model.hi - model.lo
    grid_s, grid_c = np.meshgrid(nodes, _lobatto(deg), indexing="ij")
    frac = np.zeros(grid_s.shape + (2,))
    frac[..., k], frac[..., 1 - k] = grid_s, grid_c
    rate = np.zeros(2)
    rate[k] = span  # d(d_k)/ds
    with jax.ensure_compile_time_eval(), jax.enable_x64(True):
        d = jnp.asarray(model.lo + span * frac).reshape(-1, 2)
        w = jax.vmap(lambda dd: model.body_velocity(dd, jnp.asarray(rate)))(d)
        off = jax.vmap(model.centroid_offset)(d)
        w, off = np.asarray(w).reshape(grid_s.shape + (3,)), np.asarray(off).reshape(grid_s.shape + (2,))
    theta = running @ w[..., 2]  # running integral along s for every c
    vel = np.exp(1j * theta) * (w[..., 0] + 1j * w[..., 1])
    z = running @ vel
    wpos = z + np.exp(1j * theta) * (off[..., 0] + 1j * off[..., 1])
    return np.stack([theta, wpos.real, wpos.imag], axis=-1)


@functools.lru_cache(maxsize=16)
def motion_table(model: SwimmerModel) -> MotionTable:
    """The motion table of a two-DOF ``model`` (float64, built once per model)."""
    deg = BUILD_DEGREE
    vander = np.linalg.inv(np.polynomial.chebyshev.chebvander(2 * _lobatto(deg) - 1, deg))
    funs = [0, 1, 2] if model.planar else [1]
    coefs = []
    for k in range(model.n_dof):
        vals = build_values(model, k, deg)[..., funs]
        coefs.append(np.einsum("ia,jb,abf->jfi", vander, vander, vals))  # (c degree, function, s degree)
    coef = np.stack(coefs)  # (n_dof, deg + 1, F, deg + 1)
    mag = np.abs(coef) / np.abs(coef).max()
    keep_s = int(np.max(np.nonzero(mag.max(axis=(0, 1, 2)) > CUTOFF)[0]))
    keep_c = int(np.max(np.nonzero(mag.max(axis=(0, 2, 3)) > CUTOFF)[0]))
    coef = coef[:, : keep_c + 1, :, : keep_s + 1]
    return MotionTable(coef.reshape(model.n_dof, keep_c + 1, -1), keep_s, keep_c, len(funs))


def _chebyshev(x: Array, deg: int) -> Array:
    """``T_0 .. T_deg`` at ``2 x - 1`` on a last axis (three-term recurrence)."""
    t = 2.0 * x - 1.0
    out = [jnp.ones_like(t), t]
    for _ in range(deg - 1):
        out.append(2.0 * t * out[-1] - out[-2])
    return jnp.stack(out[: deg + 1], axis=-1)


def move_increment(model: SwimmerModel, s0: Array, s1: Array, dof: Array) -> Array:
    """Body-frame step row ``(dx, dy, dtheta, cos dtheta, sin dtheta)`` (float64) of the move of
    DOF ``dof`` from fractions ``s0`` to ``s1`` (the other DOF held); call under
    ``jax.enable_x64``. Works under ``vmap``."""
    tab = motion_table(model)
    coef = jnp.asarray(tab.coef, jnp.float64)
    other = 1 - dof
    c = jnp.where(dof == 0, s0[1], s0[0])
    a = jnp.where(dof == 0, s0[0], s0[1])
    b = jnp.where(dof == 0, s1[0], s1[1])
    tc = _chebyshev(c, tab.m)
    # Contract the held DOF first (for both DOFs' tables: a matrix product under vmap), then pick.
    v = jnp.where(dof == 0, tc @ coef[0], tc @ coef[1]).reshape(tab.n_fun, tab.n + 1)
    del other
    fa, fb = v @ _chebyshev(a, tab.n), v @ _chebyshev(b, tab.n)
    if not model.planar:
        return jnp.stack([fb[0] - fa[0], jnp.zeros(()), jnp.zeros(()), jnp.ones(()), jnp.zeros(())])
    dth = fb[0] - fa[0]
    ca, sa = jnp.cos(fa[0]), jnp.sin(fa[0])
    dwx, dwy = fb[1] - fa[1], fb[2] - fa[2]
    return jnp.stack([ca * dwx + sa * dwy, ca * dwy - sa * dwx, dth, jnp.cos(dth), jnp.sin(dth)])
