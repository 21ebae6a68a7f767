"""Force- and torque-free motion of sphere swimmers with prescribed arm rates, among fixed spheres.

``S`` swimmers of ``n`` spheres each (radius ``a = 1``) lie on straight axes in the vertical
plane y = 0; swimmer ``s`` has its reference sphere (index ``n_dof // 2``, the middle sphere of
the three-sphere swimmer) at ``c_s = (x_s, z_s)`` and its axis along ``e_s = (cos t_s, sin t_s)``
(``t_s`` the tilt from the wall plane, positive nose up; the nose is the last sphere). Sphere
``i`` sits at ``c_s + q_i e_s`` with ``q`` the cumulative arm lengths measured from the reference
sphere. ``O`` obstacles are spheres of given radius held fixed.

Unknowns: the forces on all spheres ``F`` (2 per sphere) and each swimmer's rigid motion
``xi_s = (U_x, U_z, Omega)`` (``Omega = d t_s / dt``). Equations, with ``M`` the grand mobility
(:func:`jswim.swimmers.mobility.mobility_matrix`):

* ``M F = K xi + v``: a swimmer sphere moves rigidly with its swimmer plus its prescribed axial
  velocity ``v_i = qdot_i e_s``; an obstacle does not move (zero rows of ``K`` and ``v``);
* ``K^T F = 0``: each swimmer feels zero total force and zero torque (about ``c_s``).

Eliminating ``F = M^-1 (K xi + v)`` leaves ``(K^T M^-1 K) xi = -K^T M^-1 v``, a ``3S x 3S``
symmetric positive-definite system; ``M`` is factorised once (Cholesky) per call.
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
from jax import Array

from jswim.swimmers.mobility import mobility_matrix


class RigidMotion(NamedTuple):
    """Solution of one force-free solve."""

    velocity: Array  # (S, 2) dc_s / dt of each reference sphere (lab frame)
    omega: Array  # (S,) d tilt / dt
    forces: Array  # (N, 2) force on every sphere, swimmers' spheres first, then obstacles


def axial_offsets(arms: Array) -> Array:
    """Positions ``q`` of the spheres along the axis from the reference sphere, ``(..., n_dof + 1)``."""
    zero = jnp.zeros(arms.shape[:-1] + (1,), arms.dtype)
    cum = jnp.concatenate([zero, jnp.cumsum(arms, axis=-1)], axis=-1)
    m = arms.shape[-1] // 2
    return cum - cum[..., m:m + 1]


def sphere_centres(centre: Array, tilt: Array, arms: Array) -> Array:
    """Centres ``(S, n, 2)`` of every swimmer sphere from centres ``(S, 2)``, tilts ``(S,)``, arms
    ``(S, n_dof)``."""
    q = axial_offsets(arms)
    e = jnp.stack([jnp.cos(tilt), jnp.sin(tilt)], -1)
    return centre[:, None, :] + q[..., None] * e[:, None, :]


def solve(centre: Array, tilt: Array, arms: Array, arm_rates: Array, obstacles: Array,
          wall: bool) -> RigidMotion:
    """Rigid motion of every swimmer for given arm rates.

    Parameters
    ----------
    centre : Array (S, 2)
        Reference-sphere centres ``(x, z)``, units of ``a``.
    tilt : Array (S,)
        Axis angle from the x axis, rad.
    arms : Array (S, n_dof)
        Arm lengths (centre-to-centre distances of neighbouring spheres), units of ``a``.
    arm_rates : Array (S, n_dof)
        ``d arms / dt``.
    obstacles : Array (O, 3)
        Fixed spheres ``(x, z, radius)``; ``O`` may be 0.
    wall : bool
        Static: a no-slip wall at z = 0 (Blake) or the unbounded fluid (Oseen).

    Returns
    -------
    RigidMotion
        Velocities in units of ``a`` per unit time (an arm at unit rate changes by ``a`` per unit
        time), forces in units of ``6 pi mu a^2`` per unit time. Works under ``jit`` and ``vmap``.
    """
    S, nd = arms.shape
    n = nd + 1
    dtype = arms.dtype
    pos_sw = sphere_centres(centre, tilt, arms)  # (S, n, 2)
    e = jnp.stack([jnp.cos(tilt), jnp.sin(tilt)], -1)
    qdot = axial_offsets(arm_rates)  # (S, n)
    v_sw = qdot[..., None] * e[:, None, :]  # (S, n, 2)
    O = obstacles.shape[0]
    pos = jnp.concatenate([pos_sw.reshape(S * n, 2), obstacles[:, :2]], 0)
    radii = jnp.concatenate([jnp.ones((S * n,), dtype), obstacles[:, 2]], 0)
    N = S * n + O
    if wall:
        # Keep the solve finite for a sphere pushed into the wall (the scene refuses such steps
        # by their surface gap; the point-force model is not valid that close anyway).
        pos = pos.at[:, 1].set(jnp.maximum(pos[:, 1], radii))
    mob = mobility_matrix(pos, radii, wall)
    # K: (N, 2, S, 3): rigid velocity of sphere i per unit (U_x, U_z, Omega) of swimmer s.
    rel = pos_sw - centre[:, None, :]  # (S, n, 2)
    one = jnp.ones((S, n), dtype)
    zero = jnp.zeros((S, n), dtype)
    k_own = jnp.stack([jnp.stack([one, zero, -rel[..., 1]], -1),
                       jnp.stack([zero, one, rel[..., 0]], -1)], -2)  # (S, n, 2, 3)
    owner = jnp.eye(S, dtype=dtype)  # (S, S)
    k_sw = k_own[:, :, :, None, :] * owner[:, None, None, :, None]  # (S, n, 2, S, 3)
    k_mat = jnp.concatenate([k_sw.reshape(S * n * 2, 3 * S), jnp.zeros((2 * O, 3 * S), dtype)], 0)
    v = jnp.concatenate([v_sw.reshape(-1), jnp.zeros((2 * O,), dtype)])
    chol = jax.scipy.linalg.cho_factor(mob, lower=True)
    rhs = jnp.concatenate([k_mat, v[:, None]], 1)
    sol = jax.scipy.linalg.cho_solve(chol, rhs)  # M^-1 [K | v]
    a_mat, b_vec = sol[:, :-1], sol[:, -1]
    schur = k_mat.T @ a_mat
    xi = jnp.linalg.solve(schur, -(k_mat.T @ b_vec))
    forces = a_mat @ xi + b_vec
    xi = xi.reshape(S, 3)
    return RigidMotion(xi[:, :2], xi[:, 2], forces.reshape(N, 2))
