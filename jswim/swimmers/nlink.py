"""General N-link swimmer in resistive force theory (Purcell's swimmer is N = 3).

``N`` straight links of unit length joined by ``N - 1`` planar hinges. Hinge ``j`` (1-based)
joins links ``j - 1`` and ``j``; its angle is ``d_j = phi_j - phi_{j-1}`` (this sign convention
reproduces the paper's closed form for N = 3). The reference link is the middle one,
``m = (N - 1) // 2``; its centre is the reference point and its angle the orientation.

Velocities follow from zero total force and zero total torque. Because the link velocity is
affine in the unknowns ``q = (U_x, U_y, Omega)``, the residual ``R(q) = M q + b`` is built by
evaluating it at ``q = 0`` and the three unit vectors, then a 3x3 solve gives ``q``.
"""

from __future__ import annotations

import jax.numpy as jnp
from jax import Array


def link_angles(d: Array, theta: Array | float = 0.0) -> Array:
    """Absolute link angles ``phi_i`` for hinge angles ``d`` and reference orientation ``theta``."""
    n = d.shape[0] + 1
    m = (n - 1) // 2
    # phi_j - phi_{j-1} = d_j  =>  phi_i = theta + (d_1 + .. + d_i) - (d_1 + .. + d_m).
    cum = jnp.concatenate([jnp.zeros((1,), d.dtype), jnp.cumsum(d)])
    return theta + cum - cum[m]


def link_centres(d: Array, theta: Array | float = 0.0) -> Array:
    """Centres of the links relative to the reference link's centre, shape ``(N, 2)``."""
    phi = link_angles(d, theta)
    t = jnp.stack([jnp.cos(phi), jnp.sin(phi)], axis=-1)
    n = phi.shape[0]
    m = (n - 1) // 2
    # Consecutive centres are half a link plus half a link apart along the two tangents.
    steps = 0.5 * (t[:-1] + t[1:])  # c_{i+1} - c_i
    cum = jnp.concatenate([jnp.zeros((1, 2), t.dtype), jnp.cumsum(steps, axis=0)])
    return cum - cum[m]


def centroid_offset(d: Array) -> Array:
    """Geometric centroid minus reference point, in the body frame (``theta = 0``)."""
    return jnp.mean(link_centres(d, 0.0), axis=0)


def _cross(a: Array, b: Array) -> Array:
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def velocity(
    d: Array, d_dot: Array, theta: Array | float = 0.0, xi_ratio: float = 2.0, xi_par: float = 1.0
) -> Array:
    """Reference-link velocity ``(U_x, U_y, Omega)`` of the N-link swimmer in the lab frame.

    Parameters
    ----------
    d, d_dot : Array, shape (N - 1,)
        Hinge angles and their rates.
    theta : float
        Orientation of the reference (middle) link.
    xi_ratio : float
        ``xi_perp / xi_par``; 2 is the slender-body limit used by the paper, 1 is isotropic drag
        (no propulsion at all). With ``xi_par`` given: ``xi_perp`` itself.
    xi_par : float
        Drag along a link (default 1, the unit of ``xi_ratio``); the velocities depend only on
        ``xi_ratio / xi_par`` ([`jswim.swimmers.wall_rft`][jswim.swimmers.wall_rft] passes both).
    """
    d = jnp.asarray(d)
    d_dot = jnp.asarray(d_dot)
    phi = link_angles(d, theta)
    phi_dot_rel = link_angles(d_dot, 0.0)  # shape-driven angular velocity of each link
    n = phi.shape[0]
    m = (n - 1) // 2
    t = jnp.stack([jnp.cos(phi), jnp.sin(phi)], axis=-1)
    nrm = jnp.stack([-t[:, 1], t[:, 0]], axis=-1)
    centres = link_centres(d, theta)
    # Shape-driven velocity of each centre with the reference link held still.
    hinge_v = 0.5 * (phi_dot_rel[:-1, None] * nrm[:-1] + phi_dot_rel[1:, None] * nrm[1:])
    cum = jnp.concatenate([jnp.zeros((1, 2), t.dtype), jnp.cumsum(hinge_v, axis=0)])
    shape_v = cum - cum[m]
    xi_perp = xi_ratio

    def residual(q: Array) -> Array:
        u, omega = q[:2], q[2]
        rigid = u + omega * jnp.stack([-centres[:, 1], centres[:, 0]], axis=-1)
        a = rigid + shape_v  # velocity of each link centre
        a_par = jnp.sum(a * t, axis=-1, keepdims=True) * t
        ka = xi_par * a_par + xi_perp * (a - a_par)  # drag tensor applied to the centre velocity
        force = -jnp.sum(ka, axis=0)
        # Torque about the reference point: centre term plus the link's own rotation (s^2/12).
        spin = omega + phi_dot_rel
        torque = -jnp.sum(_cross(centres, ka)) - jnp.sum(xi_perp * spin / 12.0)
        return jnp.concatenate([force, torque[None]])

    eye = jnp.eye(3, dtype=t.dtype)
    b = residual(jnp.zeros(3, t.dtype))
    mat = jnp.stack([residual(eye[k]) - b for k in range(3)], axis=1)
    return jnp.linalg.solve(mat, -b)
