"""The rigid motion a background flow gives a link swimmer, in resistive force theory.

A link element at ``x`` moving at ``v`` through fluid moving at ``u_inf(x)`` feels the drag
``f = -K(t) (v - u_inf(x))``, ``K = xi_par t t + xi_perp (I - t t)`` (Gray & Hancock 1955; Lighthill
1975, ch. 3), the same local law the still-fluid velocities of `jswim.swimmers.purcell` and
`jswim.swimmers.nlink` use. The body stays force- and torque-free, and the drag is linear in the
velocities, so its rigid velocity is the still-fluid one (from its shape change) plus the one that
balances the flow's drag alone: with rigid modes ``v = U + Omega z x r``,

    M (U, Omega) = (sum int K u_inf ds, sum int r x K u_inf ds),

``M`` the body's 3 x 3 resistance to rigid motion. This module returns that second part.

Along each unit link the integrals are Gauss-Legendre quadratures; ``nodes`` of them are exact for
flows polynomial in position up to degree ``2 nodes - 2`` (uniform, shear and Poiseuille flows:
two nodes suffice), and converge spectrally for smooth flows (a Taylor-Green cell many links wide).

Units are the paper's: link length ``a``, time ``tau`` (a hinge sweeping its range at |ROC| = 1 in
unit time); flow velocities in ``a / tau``.
"""

from __future__ import annotations

import functools
from collections.abc import Callable

import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.swimmers.nlink import link_angles, link_centres

__all__ = ["flow_velocity", "link_points"]


@functools.lru_cache(maxsize=8)
def _gauss(nodes: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes on a unit link ``[-1/2, 1/2]`` and weights summing to 1."""
    s, w = np.polynomial.legendre.leggauss(nodes)
    return s / 2.0, w / 2.0


def link_points(d: Array, pose: Array, nodes: int = 4) -> tuple[Array, Array, Array]:
    """The quadrature points of every link: their offsets from the reference point ``r``
    (N, nodes, 2, lab frame, ``a``), the link tangents ``t`` (N, 2) and the weights (nodes,).

    ``d`` (N - 1,) are the hinge angles, ``pose`` (3,) the reference point ``(x, y)`` and the
    middle link's orientation ``theta`` (rad)."""
    dtype = jnp.result_type(d, pose)
    theta = pose[2]
    phi = link_angles(jnp.asarray(d, dtype), theta)
    t = jnp.stack([jnp.cos(phi), jnp.sin(phi)], axis=-1)
    s, w = _gauss(nodes)
    s = jnp.asarray(s, dtype)
    r = link_centres(jnp.asarray(d, dtype), theta)[:, None, :] + s[None, :, None] * t[:, None, :]
    return r, t, jnp.asarray(w, dtype)


def flow_velocity(
    d: Array,
    pose: Array,
    flow_at: Callable[[Array], Array],
    xi_ratio: float = 2.0,
    nodes: int = 4,
) -> Array:
    """Lab-frame rigid velocity ``(U_x, U_y, Omega)`` of the reference point that a background
    flow gives a force- and torque-free link swimmer (to be added to its still-fluid velocity).

    Parameters
    ----------
    d : Array (N - 1,)
        Hinge angles (rad); N links of unit length (`jswim.swimmers.nlink`'s conventions).
    pose : Array (3,)
        ``(x, y, theta)``: the middle link's centre (``a``) and orientation (rad), lab frame.
    flow_at : callable
        The background flow ``u_inf``: positions (..., 2) -> velocities (..., 2) (``a / tau``),
        traceable by JAX (a `jswim.env.flows` flow's ``velocity``).
    xi_ratio : float
        ``xi_perp / xi_par`` (the paper's 2, the slender limit).
    nodes : int
        Gauss-Legendre nodes per link (exact for flows of degree <= 2 nodes - 2 in position).

    Returns
    -------
    Array (3,)
        ``U_x, U_y`` (``a / tau``) and ``Omega`` (rad / tau), in ``pose``'s dtype.

    Notes
    -----
    A uniform flow gives exactly ``(u, 0)`` (Galilean invariance); a straight rod in the shear
    ``u = (gamma y, 0)`` turns at ``Omega = -gamma sin^2(theta)``, Jeffery's orbit in the slender
    limit (Jeffery 1922, aspect ratio to infinity), whatever ``xi_ratio``.
    """
    pose = jnp.asarray(pose)
    r, t, w = link_points(d, pose, nodes)
    tt = t[:, None, :]

    def drag(v: Array) -> Array:  # K v at every point, xi_par = 1
        par = jnp.sum(v * tt, axis=-1, keepdims=True) * tt
        return par + xi_ratio * (v - par)

    def wrench(v: Array) -> Array:  # total force and torque about the reference point of K v
        kv = drag(v)
        # Elementwise sums, not einsum: under vmap a tiny dot_general per swimmer is slow.
        force = jnp.sum(w[None, :, None] * kv, axis=(0, 1))
        torque = jnp.sum(w[None, :] * (r[..., 0] * kv[..., 1] - r[..., 1] * kv[..., 0]))
        return jnp.concatenate([force, torque[None]])

    ones = jnp.ones_like(r[..., :1])
    modes = (
        jnp.concatenate([ones, 0.0 * ones], axis=-1),
        jnp.concatenate([0.0 * ones, ones], axis=-1),
        jnp.stack([-r[..., 1], r[..., 0]], axis=-1),
    )
    resistance = jnp.stack([wrench(m) for m in modes], axis=1)
    u_inf = flow_at(pose[:2] + r)
    return _solve3(resistance, wrench(u_inf))


def _solve3(m: Array, b: Array) -> Array:
    """``m^-1 b`` for one 3 x 3 system by Cramer's rule: unrolled arithmetic, which vmaps to
    plain vector code (a batched LAPACK call per swimmer and RK stage is ~100 x slower on a CPU).
    ``m`` is the body's resistance, symmetric positive definite and well conditioned."""
    c0 = jnp.cross(m[:, 1], m[:, 2])
    c1 = jnp.cross(m[:, 2], m[:, 0])
    c2 = jnp.cross(m[:, 0], m[:, 1])
    det = jnp.dot(m[:, 0], c0)
    return jnp.stack([jnp.dot(b, c0), jnp.dot(b, c1), jnp.dot(b, c2)]) / det
