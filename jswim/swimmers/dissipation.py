"""Dissipation: the rate at which a swimmer's stroke does work on the fluid.

At zero Reynolds number all the work the body does on the fluid is dissipated, and the power is
``P = -sum (force of the fluid on the body) . (velocity of the body)`` at every instant. The
body velocities come from the same formulas the stepping uses (``model.body_velocity``), so the
power belongs to the motion the swimmer actually makes.

**Links (resistive force theory).** A link of length ``l`` with unit tangent ``t`` and normal
``n``, centre velocity ``a`` and angular velocity ``w``, moves at ``u(s) = a + s w n`` for
``s`` in ``[-l/2, l/2]``. Resistive force theory (Gray & Hancock, J. Exp. Biol. 32, 802, 1955;
Lighthill, *Mathematical Biofluiddynamics*, SIAM 1975, ch. 3; the form used for Purcell's
swimmer by Becker, Koehler & Stone, J. Fluid Mech. 490, 15, 2003, section 2) puts the force
density ``f(s) = -(xi_par (u.t) t + xi_perp (u.n) n)`` on the link, so the link's power is

``P_link = int xi_par (u.t)^2 + xi_perp (u.n)^2 ds``
``       = l [xi_par (a.t)^2 + xi_perp (a.n)^2] + xi_perp w^2 l^3 / 12``            (D1)

exactly: ``u.t`` is constant along the link and ``u.n`` is linear in ``s``, and the cross term
integrates to zero on the symmetric interval. The swimmer's power is the sum over links.

**Spheres (Stokes drag with point-force interactions).** Sphere ``i`` (radius ``a``) moves at
``V_i``; with the drag of an isolated sphere ``6 pi mu a = 1`` and the point-force (Oseen)
interaction of Golestanian & Ajdari (Phys. Rev. E 77, 036308, 2008, section II), along the
swimmer's line ``V = M F`` with ``M_ii = 1`` and ``M_ij = (3/2) a / |x_i - x_j|``, so

``P = sum_i F_i V_i = V^T M^{-1} V``                                                 (D2)

The sphere velocities are the reference velocity the stepping uses (the paper's NG formula, or
the first-order N-sphere model) plus each sphere's velocity relative to the mean sphere position
(fixed by the arm rates). Because the force-free motion minimises ``V^T M^{-1} V`` over rigid
translations (Helmholtz's minimum-dissipation theorem), a reference velocity that is off by
``dU`` changes ``P`` by ``O(dU^2)`` only. The N-sphere model's velocity is force-free to first
order in ``a / d``: its power is within 2e-4 of the exactly force-free point-force solve over
arms in [6, 10] (measured, tests). The paper's NG formula differs from the mean sphere
velocity by ``(1/6) d/dt ln(d2 / d1)`` ([`nsphere`][jswim.swimmers.nsphere]), a first-order
term, so NG's power is within 0.4 % of that solve (second order in ``a / d``, measured). The
point-force model itself holds to first order in ``a / d``.

**The quadratic form.** All velocities are linear in the shape rates, so ``P = d_dot^T Q(d)
d_dot`` with ``Q`` symmetric and positive semi-definite ([`dissipation_matrix`][jswim.swimmers.dissipation.dissipation_matrix]): power is
never negative, vanishes exactly when the shape is still (rigid motion of a force-free body
costs nothing) and is even under time reversal ``d_dot -> -d_dot``.

Units: the link swimmers' power is in ``xi_par a^3 / t^2`` (``xi_par`` the bulk drag per unit
length along a link, ``a`` the link length, ``t`` the time unit of ``d_dot``); the sphere
swimmers' in ``6 pi mu a^3 / t^2`` (``a`` the sphere radius).
"""

from __future__ import annotations

import jax
import jax.numpy as jnp
from jax import Array

from jswim.swimmers import nlink, nsphere
from jswim.swimmers.models import SwimmerModel

#: Pair mobility of two spheres on a line, point forces, in ``a / r`` and units of
#: ``1 / (6 pi mu a)``: the Oseen tensor's longitudinal part, ``(3/4) (1 + 1) a / r``.
LONGITUDINAL_OSEEN = 1.5


def link_power(
    centre_velocity: Array,
    omega: Array,
    tangent: Array,
    xi_par: float = 1.0,
    xi_perp: float = 2.0,
    length: float = 1.0,
) -> Array:
    """Power each link does on the fluid, equation (D1) of the module docstring.

    Parameters
    ----------
    centre_velocity : Array, shape (..., 2)
        Velocity ``a`` of the link's centre.
    omega : Array, shape (...)
        The link's angular velocity ``w``.
    tangent : Array, shape (..., 2)
        Unit tangent ``t``.
    xi_par, xi_perp : float
        Drag per unit length along and across the link.
    length : float
        Link length ``l`` (1: lengths in link lengths).

    Returns
    -------
    Array, shape (...)
        ``l [xi_par (a.t)^2 + xi_perp (a.n)^2] + xi_perp w^2 l^3 / 12``; same dtype as the inputs.
    """
    normal = jnp.stack([-tangent[..., 1], tangent[..., 0]], axis=-1)
    along = jnp.sum(centre_velocity * tangent, axis=-1)
    across = jnp.sum(centre_velocity * normal, axis=-1)
    return length * (xi_par * along**2 + xi_perp * across**2) + xi_perp * omega**2 * length**3 / 12


def link_motion(d: Array, d_dot: Array, body_velocity: Array) -> tuple[Array, Array, Array]:
    """Every link's tangent, centre velocity and angular velocity, in the body frame.

    Parameters
    ----------
    d, d_dot : Array, shape (N - 1,)
        Hinge angles and their rates (the sign convention of [`nlink`][jswim.swimmers.nlink]).
    body_velocity : Array, shape (3,)
        ``(U_x, U_y, Omega)`` of the reference (middle) link's centre, body frame (orientation 0).

    Returns
    -------
    tangent : Array, shape (N, 2)
    centre_velocity : Array, shape (N, 2)
    omega : Array, shape (N,)
    """
    phi = nlink.link_angles(d, 0.0)
    spin = nlink.link_angles(d_dot, 0.0)  # each link's angular velocity relative to the reference
    tangent = jnp.stack([jnp.cos(phi), jnp.sin(phi)], axis=-1)
    normal = jnp.stack([-tangent[:, 1], tangent[:, 0]], axis=-1)
    centres = nlink.link_centres(d, 0.0)
    m = (phi.shape[0] - 1) // 2
    # c_(i+1) - c_i = (t_i + t_(i+1)) / 2, so its rate is (spin_i n_i + spin_(i+1) n_(i+1)) / 2.
    steps = 0.5 * (spin[:-1, None] * normal[:-1] + spin[1:, None] * normal[1:])
    cum = jnp.concatenate([jnp.zeros((1, 2), steps.dtype), jnp.cumsum(steps, axis=0)])
    shape_velocity = cum - cum[m]
    u, omega = body_velocity[:2], body_velocity[2]
    rigid = u + omega * jnp.stack([-centres[:, 1], centres[:, 0]], axis=-1)
    return tangent, rigid + shape_velocity, omega + spin


def sphere_velocities(d: Array, d_dot: Array, reference_velocity: Array) -> Array:
    """Velocities of the spheres along the line: the reference velocity (of the mean sphere
    position) plus each sphere's velocity relative to it, shape ``(N,)``."""
    return reference_velocity + nsphere.free_velocities(d_dot)


def sphere_mobility(d: Array) -> Array:
    """Point-force mobility ``M`` of the spheres along their line, shape ``(N, N)``, units
    ``1 / (6 pi mu a)``: 1 on the diagonal, ``(3/2) a / |x_i - x_j|`` off it (equation (D2))."""
    x = nsphere.positions(jnp.asarray(d))
    n = x.shape[0]
    eye = jnp.eye(n, dtype=bool)
    r = jnp.abs(x[:, None] - x[None, :])
    return jnp.where(eye, 1.0, LONGITUDINAL_OSEEN / jnp.where(eye, 1.0, r))


def sphere_forces(d: Array, velocities: Array) -> Array:
    """Forces ``F = M^{-1} V`` the spheres exert on the fluid, shape ``(N,)``, units ``6 pi mu a``
    times the velocity unit."""
    return jnp.linalg.solve(sphere_mobility(d), velocities)


def power(model: SwimmerModel, d: Array, d_dot: Array) -> Array:
    """Instantaneous power the swimmer does on the fluid (= the rate of dissipation).

    Parameters
    ----------
    model : SwimmerModel
        Any swimmer (links: equation (D1) summed over links, with ``xi_par`` and ``xi_perp`` of
        the model, ``(1, xi_ratio)`` unless it carries its own, as above a wall; spheres:
        equation (D2)).
    d, d_dot : Array, shape (n_dof,)
        Shape and shape rate (radians or sphere radii, per time unit).

    Returns
    -------
    Array, shape ()
        ``xi_par a^3 / t^2`` (links; ``xi_par`` of the bulk fluid) or ``6 pi mu a^3 / t^2``
        (spheres). Non-negative.
    """
    d = jnp.asarray(d)
    d_dot = jnp.asarray(d_dot, d.dtype)
    body = model.body_velocity(d, d_dot)
    if model.planar:
        xi_par = getattr(model, "xi_par", 1.0)
        xi_perp = getattr(model, "xi_perp", model.xi_ratio * xi_par)
        tangent, centre_velocity, omega = link_motion(d, d_dot, body)
        return jnp.sum(link_power(centre_velocity, omega, tangent, xi_par, xi_perp))
    v = sphere_velocities(d, d_dot, body[0])
    return jnp.dot(sphere_forces(d, v), v)


def dissipation_matrix(model: SwimmerModel, d: Array) -> Array:
    """The symmetric matrix ``Q(d)`` with ``power(model, d, d_dot) = d_dot^T Q d_dot``.

    Shape ``(n_dof, n_dof)``, units of [`power`][jswim.swimmers.dissipation.power] per squared rate. Built from the power at the
    unit rates and their pairwise sums (polarisation), so it is exact for the quadratic form.
    """
    d = jnp.asarray(d)
    n = d.shape[0]
    eye = jnp.eye(n, dtype=d.dtype)
    diag = jax.vmap(lambda e: power(model, d, e))(eye)
    pair = jax.vmap(lambda e: jax.vmap(lambda f: power(model, d, e + f))(eye))(eye)
    # Q_ij = (P(e_i + e_j) - P(e_i) - P(e_j)) / 2; on the diagonal P(2 e_i) = 4 P(e_i) gives Q_ii.
    return 0.5 * (pair - diag[:, None] - diag[None, :])
