"""Purcell's swimmer above a plane wall, non-local: each link a rigid chain of beads.

Every link (length ``l = 1``, the unit of length) is ``m`` beads of radius ``b`` at the midpoints
of ``m`` equal pieces of it. All ``3 m`` beads are coupled by the Rotne-Prager-Yamakawa mobility
(Rotne & Prager, J. Chem. Phys. 50, 4831, 1969, with their form for overlapping beads,
``r < 2 b``) plus Swan & Brady's wall part
(Phys. Fluids 19, 113306, 2007, appendix: the Faxen operators of both beads applied to Blake's
image system, as :func:`jswim.swimmers.mobility.rpb_entries` writes it, here in 3-D). Each bead's
self term has the Rotne-Prager-Blake factors (:func:`jswim.swimmers.mobility.wall_self_factors`,
``"rpb"``, the terms consistent with the pair blocks). Every link's flow and every link's image
enter one force- and torque-free solve of the whole swimmer, in all six rigid modes: the in-plane
motion ``(U_x, U_y, Omega_z)`` and the motion out of the plane ``(U_z, Omega_x, Omega_y)``
(heave, roll and pitch), which local resistive force theory cannot give.

As ``m`` grows at fixed ``b`` the chain converges to a slender body whose drag is set by ``b``
(the bead spacing ``1/m`` below ``b`` is converged to ~1e-3; docs/scenes.md gives the table).
Its drag ratio ``xi_perp / xi_par`` is that of a body of finite slenderness (about 1.6 at
``l / b = 100`` in the bulk, not local RFT's 2), so its bulk stroke differs from the paper's
0.19124724 l per cycle: a different swimmer, compared with itself near the wall and far from it.

Range: lengths ``b << l``; heights with every bead clear of the wall (``h > b``; the RPB blocks
are a far-field series in ``b / h`` and need ``h`` a few ``b``). The swimmer's plane is held
parallel to the wall; the out-of-plane rates are computed, not integrated (their per-cycle sums
are the leading drift out of the plane).
"""

from __future__ import annotations

import functools
import math

import jax
import jax.numpy as jnp
from jax import Array

from jswim.swimmers import nlink
from jswim.swimmers.mobility import OSEEN_PREFACTOR, wall_self_factors

#: Default bead radius (link lengths): local RFT's link radius (jswim.swimmers.wall_rft).
BEAD_RADIUS = 0.01

#: Default beads per link: spacing 1/m = b at the default radius.
BEADS_PER_LINK = 100


def bead_frame(d: Array, d_dot: Array, m: int) -> tuple[Array, Array]:
    """Bead positions ``(3 m, 2)`` in the plane (middle link's centre at the origin, along x) and
    their shape velocities ``(3 m, 2)`` (the middle link held still) for hinge angles ``d`` (2,)
    and rates ``d_dot`` (2,) (:mod:`jswim.swimmers.nlink`'s conventions)."""
    phi = nlink.link_angles(d, 0.0)
    phi_dot = nlink.link_angles(d_dot, 0.0)
    t = jnp.stack([jnp.cos(phi), jnp.sin(phi)], -1)  # (3, 2)
    nrm = jnp.stack([-t[:, 1], t[:, 0]], -1)
    centres = nlink.link_centres(d, 0.0)
    hinge_v = 0.5 * (phi_dot[:-1, None] * nrm[:-1] + phi_dot[1:, None] * nrm[1:])
    cum = jnp.concatenate([jnp.zeros((1, 2), t.dtype), jnp.cumsum(hinge_v, 0)])
    centre_v = cum - cum[1]
    s = (jnp.arange(m, dtype=t.dtype) + 0.5) / m - 0.5  # (m,) along each link
    pos = centres[:, None, :] + s[None, :, None] * t[:, None, :]
    vel = centre_v[:, None, :] + (phi_dot[:, None] * s[None, :])[..., None] * nrm[:, None, :]
    return pos.reshape(-1, 2), vel.reshape(-1, 2)


def rpy_blocks(r: Array, b: float) -> Array:
    """Unbounded RPY mobility ``(..., 3, 3)`` of two beads of radius ``b`` ``r`` (..., 3) apart,
    units of ``1 / (6 pi mu)`` (lengths in ``l``); overlapping beads included (``r < 2 b``:
    ``(1/b) [(1 - 9 r / (32 b)) I + (3 r / (32 b)) rr/r^2]``, Rotne & Prager 1969). ``r != 0``."""
    rn = jnp.sqrt(jnp.sum(r * r, -1))[..., None, None]
    rr = r[..., :, None] * r[..., None, :] / rn**2
    eye = jnp.eye(3, dtype=r.dtype)
    s = 2.0 * b * b
    far = OSEEN_PREFACTOR / rn * ((1.0 + s / (3.0 * rn**2)) * eye + (1.0 - s / rn**2) * rr)
    near = ((1.0 - 9.0 * rn / (32.0 * b)) * eye + (3.0 * rn / (32.0 * b)) * rr) / b
    return jnp.where(rn >= 2.0 * b, far, near)


def rpb_wall_blocks(rho: Array, zi: Array, zj: Array, b: float) -> Array:
    """Swan & Brady's wall part ``(..., 3, 3)`` of the RPB mobility of bead ``i`` at height ``zi``
    per force on bead ``j`` at ``zj``, in-plane offset ``rho = x_i - x_j`` (..., 2); units of
    ``1 / (6 pi mu)``. :func:`jswim.swimmers.mobility.rpb_entries`'s ``A .. E`` in 3-D:
    ``W = A I + B e e + C e z + D z e + E z z`` (``e`` the unit image vector, ``z`` the wall
    normal), for unit beads at lengths divided by ``b``, then divided by ``b``."""
    rx, ry = rho[..., 0] / b, rho[..., 1] / b
    zi, zj = zi / b, zj / b
    rz = zi + zj
    r2 = rx * rx + ry * ry + rz * rz
    ir = 1.0 / jnp.sqrt(r2)
    ir3, ir5 = ir / r2, ir / (r2 * r2)
    ex, ey, ez = rx * ir, ry * ir, rz * ir
    ez2 = ez * ez
    t = zi / rz
    tt = t * (1.0 - t)
    u = 1.0 - t
    a_ = -0.25 * (
        3.0 * (1.0 + 2.0 * tt * ez2) * ir
        + 2.0 * (1.0 - 3.0 * ez2) * ir3
        - 2.0 * (1.0 - 5.0 * ez2) * ir5
    )
    b_ = -0.25 * (
        3.0 * (1.0 - 6.0 * tt * ez2) * ir
        - 6.0 * (1.0 - 5.0 * ez2) * ir3
        + 10.0 * (1.0 - 7.0 * ez2) * ir5
    )
    c_ = (
        0.5
        * ez
        * (
            3.0 * u * (1.0 - 6.0 * t * ez2) * ir
            - 6.0 * (1.0 - 5.0 * ez2) * ir3
            + 10.0 * (2.0 - 7.0 * ez2) * ir5
        )
    )
    d_ = 0.5 * ez * (3.0 * u * ir - 10.0 * ir5)
    e_ = -(3.0 * u * u * ez2 * ir + 3.0 * ez2 * ir3 + (2.0 - 15.0 * ez2) * ir5)
    ev = jnp.stack([ex, ey, ez], -1)
    zhat = jnp.zeros_like(ev).at[..., 2].set(1.0)
    eye = jnp.eye(3, dtype=ev.dtype)
    out = (
        a_[..., None, None] * eye
        + b_[..., None, None] * ev[..., :, None] * ev[..., None, :]
        + c_[..., None, None] * ev[..., :, None] * zhat[..., None, :]
        + d_[..., None, None] * zhat[..., :, None] * ev[..., None, :]
        + e_[..., None, None] * zhat[..., :, None] * zhat[..., None, :]
    )
    return out / b


def grand_mobility(pos: Array, height: Array, b: float, wall: bool) -> Array:
    """``(3 N, 3 N)`` mobility of ``N`` beads at in-plane positions ``pos`` (N, 2), all at
    ``height`` above the wall (``wall``) or in the unbounded fluid; units of ``1 / (6 pi mu)``."""
    n = pos.shape[0]
    rho = pos[:, None, :] - pos[None, :, :]
    eye = jnp.eye(n, dtype=bool)
    r3 = jnp.concatenate([rho, jnp.zeros(rho.shape[:-1] + (1,), rho.dtype)], -1)
    r3 = jnp.where(eye[..., None], jnp.array([1.0, 0.0, 0.0], rho.dtype), r3)  # finite stand-in
    blocks = rpy_blocks(r3, b)
    self_par, self_nor = 1.0 / b, 1.0 / b
    if wall:
        hh = jnp.full((n, n), height, rho.dtype)
        wpart = rpb_wall_blocks(rho, hh, hh, b)
        blocks = blocks + jnp.where(eye[..., None, None], 0.0, wpart)
        par, nor = wall_self_factors(b / height, "rpb")
        self_par, self_nor = par / b, nor / b
    diag = jnp.diag(jnp.stack([self_par, self_par, self_nor]).astype(rho.dtype))
    blocks = jnp.where(eye[..., None, None], diag, blocks)
    return blocks.transpose(0, 2, 1, 3).reshape(3 * n, 3 * n)


def body_rates(
    d: Array,
    d_dot: Array,
    height: Array,
    m: int = BEADS_PER_LINK,
    b: float = BEAD_RADIUS,
    wall: bool = True,
) -> Array:
    """Rigid motion of the middle link's frame, ``(U_x, U_y, Omega_z, U_z, Omega_x, Omega_y)`` in
    that frame (middle link along x, its centre the reference point), for hinge angles ``d`` and
    rates ``d_dot`` at ``height`` (link lengths) above the wall; force- and torque-free.

    ``M F = K xi + v`` (beads move rigidly plus their shape velocity), ``K^T F = 0``; solved by
    Cholesky of ``M`` and the 6 x 6 Schur complement (as :func:`jswim.swimmers.forcefree.solve`).
    ``m``, ``b``, ``wall`` static. Units: link lengths per unit time of the hinge rates.
    """
    pos, vel = bead_frame(d, d_dot, m)
    n = pos.shape[0]
    dtype = pos.dtype
    mob = grand_mobility(pos, jnp.asarray(height, dtype), b, wall)
    x, y = pos[:, 0], pos[:, 1]
    one, zero = jnp.ones(n, dtype), jnp.zeros(n, dtype)
    # columns: U_x, U_y, Omega_z, U_z, Omega_x, Omega_y; rows bead (vx, vy, vz); r = (x, y, 0)
    # Omega x r = (-Om_z y, Om_z x, Om_x y - Om_y x)
    k = jnp.stack(
        [
            jnp.stack([one, zero, -y, zero, zero, zero], -1),
            jnp.stack([zero, one, x, zero, zero, zero], -1),
            jnp.stack([zero, zero, zero, one, y, -x], -1),
        ],
        1,
    ).reshape(3 * n, 6)
    v = jnp.concatenate([vel, jnp.zeros((n, 1), dtype)], -1).reshape(-1)
    chol = jax.scipy.linalg.cho_factor(mob, lower=True)
    sol = jax.scipy.linalg.cho_solve(chol, jnp.concatenate([k, v[:, None]], 1))
    schur = k.T @ sol[:, :-1]
    return jnp.linalg.solve(schur, -(k.T @ sol[:, -1]))


@functools.partial(jax.jit, static_argnames=("m", "b", "wall", "steps"))
def square_cycle(
    height: Array,
    m: int = BEADS_PER_LINK,
    b: float = BEAD_RADIUS,
    wall: bool = True,
    steps: int = 32,
    d_max: float = math.pi / 3,
) -> Array:
    """Purcell's square stroke from ``(d_max, d_max)``: D2 down, D1 down, D2 up, D1 up, each
    side by ``steps`` RK4 steps, the plane held at ``height``.

    Returns
    -------
    Array (6,)
        ``(X, Y, Theta, Z, A_x, A_y)``: the middle link's lab displacement and rotation in the
        plane over one cycle, and the cycle's integrals of the body-frame heave ``U_z`` and of
        the roll and pitch rates (the leading drift out of the plane per cycle).
    """
    dm = d_max
    dt = 2.0 * dm / steps
    rates = jnp.array([[0.0, -1.0], [-1.0, 0.0], [0.0, 1.0], [1.0, 0.0]])

    def rate(p: Array, d: Array, r: Array) -> Array:
        q = body_rates(d, r, height, m, b, wall)
        c, s = jnp.cos(p[2]), jnp.sin(p[2])
        return jnp.stack([c * q[0] - s * q[1], s * q[0] + c * q[1], q[2], q[3], q[4], q[5]])

    def body(j: Array, p: Array) -> Array:
        side = j // steps
        r = rates[side]
        d0 = jnp.array([dm, dm]) + 2.0 * dm * jnp.sum(
            jnp.where(jnp.arange(4)[:, None] < side, rates, 0.0), 0
        )
        t = (j % steps) * dt
        k1 = rate(p, d0 + r * t, r)
        k2 = rate(p + 0.5 * dt * k1, d0 + r * (t + 0.5 * dt), r)
        k3 = rate(p + 0.5 * dt * k2, d0 + r * (t + 0.5 * dt), r)
        k4 = rate(p + dt * k3, d0 + r * (t + dt), r)
        return p + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4)

    return jax.lax.fori_loop(0, 4 * steps, body, jnp.zeros(6, jnp.result_type(height)))
