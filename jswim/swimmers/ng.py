"""Najafi-Golestanian three-sphere swimmer, with the paper's velocity formula.

Spheres of unit radius on the x-axis, arm lengths ``d1`` and ``d2``. Lengths are in sphere radii
and time such that an arm changing at ``|ROC| = 1`` has ``|d_dot| = 1``.
"""

from __future__ import annotations

import math

from jax import Array


def velocity(d: Array, d_dot: Array) -> Array:
    """Swimming velocity ``dX/dt`` along x (Golestanian & Ajdari 2008, as in Xu & Zhu).

    ``(1/6) [ (d2_dot - d1_dot) / (d1 + d2) + 2 (d1_dot / d2 - d2_dot / d1) ]``
    """
    d1, d2 = d[0], d[1]
    r1, r2 = d_dot[0], d_dot[1]
    return ((r2 - r1) / (d1 + d2) + 2.0 * (r1 / d2 - r2 / d1)) / 6.0


def arm_move_displacement(d1a: float, d1b: float, d2a: float, d2b: float) -> float:
    """Closed-form X displacement of a move that changes one arm at a time.

    Exactly one of the two arms may change (``d1a -> d1b`` with ``d2a == d2b``, or the reverse).
    Integrating the velocity along the straight path gives logarithms and ratios only.
    """
    if d2a == d2b:
        d2 = d2a
        return (-math.log((d1b + d2) / (d1a + d2)) + 2.0 * (d1b - d1a) / d2) / 6.0
    if d1a == d1b:
        d1 = d1a
        return (math.log((d1 + d2b) / (d1 + d2a)) - 2.0 * (d2b - d2a) / d1) / 6.0
    raise ValueError("only one arm may change in a move")


def square_cycle_displacement(d_min: float, d_max: float) -> float:
    """Net displacement of the square gait (d1 up, d2 up, d1 down, d2 down) per cycle."""
    m, big = d_min, d_max
    dl = big - m
    return (2.0 * dl**2 / (m * big) - math.log(1.0 + dl**2 / (4.0 * m * big))) / 3.0
