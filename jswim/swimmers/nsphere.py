"""N-sphere swimmer: N spheres of unit radius on a line, N - 1 extensible arms.

Force-free motion with point-force (Oseen) interactions, kept to first order in ``a/d``. In units
where a sphere's Stokes drag is 1, sphere ``i`` moves at ``v_i = F_i + (3/2) sum_j F_j / r_ij``.
Expanding the force-free solution in the interaction, the zeroth-order forces are the free-sphere
velocities ``v0`` (zero sum, differences equal to the arm rates), and the mean sphere position
moves at ``(3 / 2N) sum_i sum_{j != i} v0_j / r_ij``. For N = 3 this differs from the paper's NG
formula by the exact derivative ``d/dt ln(d2 / d1)`` (a different reference point), so both give
the same displacement over any closed stroke cycle.
"""

from __future__ import annotations

import jax.numpy as jnp
from jax import Array


def free_velocities(d_dot: Array) -> Array:
    """Velocities of non-interacting spheres: zero total force, arm rates ``d_dot``."""
    cum = jnp.concatenate([jnp.zeros((1,), d_dot.dtype), jnp.cumsum(d_dot)])
    return cum - jnp.mean(cum)


def positions(d: Array) -> Array:
    """Sphere centres relative to their mean, shape ``(N,)``."""
    cum = jnp.concatenate([jnp.zeros((1,), d.dtype), jnp.cumsum(d)])
    return cum - jnp.mean(cum)


def velocity(d: Array, d_dot: Array) -> Array:
    """Velocity of the mean sphere position along the line, to first order in ``a/d``."""
    d = jnp.asarray(d)
    v0 = free_velocities(jnp.asarray(d_dot))
    x = positions(d)
    n = x.shape[0]
    r = jnp.abs(x[:, None] - x[None, :])
    inv = jnp.where(jnp.eye(n, dtype=bool), 0.0, 1.0 / jnp.where(r == 0, 1.0, r))
    return 1.5 * jnp.sum(inv @ v0) / n
