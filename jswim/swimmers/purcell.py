"""Purcell's three-link swimmer: the closed-form velocities of Xu & Zhu (Materials and Methods).

Links of unit length, resistive force theory with ``xi_perp / xi_par = 2`` (the slender limit).
``d1`` and ``d2`` are the hinge angles, ``dc`` the orientation of the middle link. Time is scaled
so that a hinge sweeping its full range ``[-d_max, d_max]`` at ``|ROC| = 1`` has ``|d_dot| = 1``.
"""

from __future__ import annotations

import jax.numpy as jnp
from jax import Array


def delta(d1: Array, d2: Array, xp=jnp) -> Array:
    """The denominator ``Delta`` of the paper's closed form (positive for all shapes)."""
    c = xp.cos
    return 3.0 * (
        136 * c(d1)
        + 14 * c(2 * d1)
        - 8 * c(d1 - d2)
        - c(2 * (d1 - d2))
        - 4 * c(2 * d1 - d2)
        + 14 * c(2 * d2)
        + 56 * c(d1 + d2)
        + 136 * c(d2)
        + 3 * c(2 * (d1 + d2))
        + 12 * c(2 * d1 + d2)
        + 12 * c(d1 + 2 * d2)
        - 4 * c(d1 - 2 * d2)
        + 282
    )


def _phase_sum(f, d1: Array, d2: Array, dc: Array, d1_dot: Array, d2_dot: Array) -> Array:
    """The bracket shared by ``u`` (f = sin) and ``v`` (f = cos)."""
    a1 = (
        262 * f(dc - d1)
        - 26 * f(d1 + dc)
        - 2 * f(2 * d1 + dc)
        + 18 * f(dc - 2 * d1)
        - 16 * f(dc - d2)
        + 78 * f(-d1 - d2 + dc)
        - 18 * f(d1 - d2 + dc)
        + 8 * f(-2 * d1 - d2 + dc)
        + 104 * f(d2 + dc)
        + 126 * f(-d1 + d2 + dc)
        + 30 * f(d1 + d2 + dc)
        + 24 * f(2 * d2 + dc)
        + 21 * f(-d1 + 2 * d2 + dc)
        + f(d1 + 2 * d2 + dc)
        - 2 * f(2 * d1 + 2 * d2 + dc)
        - 4 * f(dc - 2 * d2)
        + 9 * f(-d1 - 2 * d2 + dc)
        - 3 * f(d1 - 2 * d2 + dc)
        + 2 * f(-2 * d1 - 2 * d2 + dc)
        + 36 * f(dc)
    )
    a2 = (
        104 * f(dc - d1)
        - 16 * f(d1 + dc)
        - 4 * f(2 * d1 + dc)
        + 24 * f(dc - 2 * d1)
        - 26 * f(dc - d2)
        + 30 * f(-d1 - d2 + dc)
        - 18 * f(d1 - d2 + dc)
        - 3 * f(2 * d1 - d2 + dc)
        + f(-2 * d1 - d2 + dc)
        + 262 * f(d2 + dc)
        + 126 * f(-d1 + d2 + dc)
        + 78 * f(d1 + d2 + dc)
        + 9 * f(2 * d1 + d2 + dc)
        + 21 * f(-2 * d1 + d2 + dc)
        + 18 * f(2 * d2 + dc)
        + 8 * f(d1 + 2 * d2 + dc)
        + 2 * f(2 * d1 + 2 * d2 + dc)
        - 2 * f(dc - 2 * d2)
        - 2 * f(-2 * d1 - 2 * d2 + dc)
        + 36 * f(dc)
    )
    return d1_dot * a1 + d2_dot * a2


def velocity(d: Array, d_dot: Array, dc: Array | float = 0.0, xp=jnp) -> Array:
    """Middle-link velocity ``(u, v, dc_dot)`` of Purcell's swimmer in the lab frame.

    Parameters
    ----------
    d : Array, shape (2,)
        Hinge angles ``(d1, d2)``.
    d_dot : Array, shape (2,)
        Their rates of change.
    dc : float
        Orientation of the middle link.
    xp : module
        Array namespace (``jax.numpy`` by default; ``numpy`` serves plain-Python references).

    Returns
    -------
    Array, shape (3,)
        ``u``, ``v`` (velocity of the middle link's centre) and ``dc_dot`` (its angular velocity).
    """
    d1, d2 = d[0], d[1]
    r1, r2 = d_dot[0], d_dot[1]
    den = delta(d1, d2, xp)
    u = _phase_sum(xp.sin, d1, d2, dc, r1, r2) / (2.0 * den)
    v = -_phase_sum(xp.cos, d1, d2, dc, r1, r2) / (2.0 * den)
    c = xp.cos
    w1 = (
        102 * c(d1)
        + 2 * c(2 * d1)
        - 6 * c(d1 - d2)
        - 4 * c(2 * d2)
        + 42 * c(d1 + d2)
        + 2 * c(2 * (d1 + d2))
        + 9 * c(d1 + 2 * d2)
        - 3 * c(d1 - 2 * d2)
        + 108
    )
    w2 = (
        4 * c(2 * d1)
        + 6 * c(d1 - d2)
        + 3 * c(2 * d1 - d2)
        - 102 * c(d2)
        - 2 * c(2 * d2)
        - 42 * c(d1 + d2)
        - 2 * c(2 * (d1 + d2))
        - 9 * c(2 * d1 + d2)
        - 108
    )
    dc_dot = 2.0 * (r1 * w1 + r2 * w2) / den
    return xp.stack([u, v, dc_dot])
