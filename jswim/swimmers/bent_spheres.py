"""A three-sphere swimmer with a hinge: two extensible arms at an angle, which can turn.

Three spheres of unit radius in a plane; arm ``L1`` joins sphere 0 to the middle sphere 1, arm
``L2`` joins sphere 1 to sphere 2, and the hinge at the middle sphere bends arm 2 by ``beta``
from the line of arm 1 (``beta = 0``: the straight, collinear swimmer; ``beta > 0``: bent
counter-clockwise). The shape is ``d = (L1, L2, beta)``. In the body frame (middle sphere at the
origin, arm 1 along +x) the centres are ``x0 = (-L1, 0)``, ``x1 = 0``, ``x2 = L2 (cos beta,
sin beta)``.

The motion is force- and torque-free in an unbounded fluid: with ``M`` the point-force grand
mobility of the spheres ([`mobility_matrix`][jswim.swimmers.mobility.mobility_matrix], the model
of Golestanian & Ajdari for the collinear swimmer; ``mobility="rpy"`` for finite-size pair
terms), the unknown forces ``F`` and the rigid motion ``(U, Omega)`` of the body frame satisfy

``M F = U + Omega z x x_i + w_i`` (each sphere moves with the frame plus its shape velocity),
``sum_i F_i = 0`` and ``sum_i x_i x F_i = 0``,

a 9 x 9 linear system. Bent (``beta != 0``), the swimmer loses the collinear swimmer's mirror
symmetry, so a stroke cycle of the arms at a fixed bend rotates it: it swims on a circle, the
circle swimmer of Ledesma-Aguilar, Loewen & Yeomans (Eur. Phys. J. E 35, 70, 2012); this module
takes their geometry with the bend as a third DOF, which lets a controller choose to turn or go
straight. Units: lengths in sphere radii ``a``, forces in ``6 pi mu a`` times velocity, the
power in ``6 pi mu a^3 / t^2``. Point forces hold to first order in ``a / L``.
"""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
from jax import Array

from jswim.swimmers.mobility import mobility_matrix


class BentMotion(NamedTuple):
    """Force-free motion of the bent three-sphere swimmer, body frame."""

    velocity: Array  # (2,) velocity of the middle sphere
    omega: Array  # () angular velocity of the body frame (of arm 1)
    forces: Array  # (3, 2) force each sphere exerts on the fluid


def positions(d: Array) -> Array:
    """Sphere centres ``(3, 2)`` in the body frame for the shape ``d = (L1, L2, beta)``."""
    d = jnp.asarray(d)
    zero = jnp.zeros((), d.dtype)
    return jnp.stack(
        [
            jnp.stack([-d[0], zero]),
            jnp.stack([zero, zero]),
            d[1] * jnp.stack([jnp.cos(d[2]), jnp.sin(d[2])]),
        ]
    )


def shape_velocities(d: Array, d_dot: Array) -> Array:
    """Sphere velocities ``(3, 2)`` from the shape change alone (frame held still)."""
    d = jnp.asarray(d)
    d_dot = jnp.asarray(d_dot, d.dtype)
    zero = jnp.zeros((), d.dtype)
    c, s = jnp.cos(d[2]), jnp.sin(d[2])
    return jnp.stack(
        [
            jnp.stack([-d_dot[0], zero]),
            jnp.stack([zero, zero]),
            jnp.stack([d_dot[1] * c - d[1] * d_dot[2] * s, d_dot[1] * s + d[1] * d_dot[2] * c]),
        ]
    )


def solve(d: Array, d_dot: Array, mobility: str = "point") -> BentMotion:
    """The force- and torque-free motion for shape ``d`` and shape rate ``d_dot`` (both (3,)).

    Works under ``jit`` and ``vmap``; ``mobility`` is static.
    """
    d = jnp.asarray(d)
    x = positions(d)
    w = shape_velocities(d, d_dot)
    m = mobility_matrix(x, jnp.ones(3, d.dtype), False, mobility)  # (6, 6)
    # Rigid part: K (6, 3) maps (U_x, U_y, Omega) to the spheres' velocities.
    eye2 = jnp.eye(2, dtype=d.dtype)
    rot = jnp.stack([-x[:, 1], x[:, 0]], -1)  # z x x_i
    k = jnp.concatenate([jnp.tile(eye2, (3, 1)), rot.reshape(6, 1)], axis=1)
    top = jnp.concatenate([m, -k], axis=1)  # M F - K q = w
    bottom = jnp.concatenate([k.T, jnp.zeros((3, 3), d.dtype)], axis=1)  # K^T F = 0
    rhs = jnp.concatenate([w.reshape(6), jnp.zeros(3, d.dtype)])
    sol = jnp.linalg.solve(jnp.concatenate([top, bottom], axis=0), rhs)
    return BentMotion(sol[6:8], sol[8], sol[:6].reshape(3, 2))


def body_velocity(d: Array, d_dot: Array, mobility: str = "point") -> Array:
    """``(u, v, omega)`` of the middle sphere in the body frame: the contract of
    [`SwimmerModel.body_velocity`][jswim.swimmers.models.SwimmerModel.body_velocity]."""
    motion = solve(d, d_dot, mobility)
    return jnp.concatenate([motion.velocity, motion.omega[None]])


def power(d: Array, d_dot: Array, mobility: str = "point") -> Array:
    """Rate of work on the fluid, ``sum_i F_i . V_i`` (``6 pi mu a^3 / t^2``); non-negative."""
    d = jnp.asarray(d)
    motion = solve(d, d_dot, mobility)
    x = positions(d)
    v = (
        motion.velocity
        + motion.omega * jnp.stack([-x[:, 1], x[:, 0]], -1)
        + shape_velocities(d, d_dot)
    )
    return jnp.sum(motion.forces * v)
