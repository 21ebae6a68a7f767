"""Purcell's swimmer above a plane wall, non-local: each link a rigid chain of beads.

Every link (length ``l = 1``, the unit of length) is ``m`` beads of radius ``b`` at the midpoints
of ``m`` equal pieces of it. All ``3 m`` beads are coupled by the Rotne-Prager-Yamakawa mobility
(Rotne & Prager, J. Chem. Phys. 50, 4831, 1969, with their form for overlapping beads,
``r < 2 b``) plus Swan & Brady's wall part
(Phys. Fluids 19, 113306, 2007, appendix: the Faxen operators of both beads applied to Blake's
image system, as [`rpb_entries`][jswim.swimmers.mobility.rpb_entries] writes it, here in 3-D). Each bead's
self term has the Rotne-Prager-Blake factors ([`wall_self_factors`][jswim.swimmers.mobility.wall_self_factors],
``"rpb"``, the terms consistent with the pair blocks). Every link's flow and every link's image
enter one force- and torque-free solve of the whole swimmer, in all six rigid modes: the in-plane
motion ``(U_x, U_y, Omega_z)`` and the motion out of the plane ``(U_z, Omega_x, Omega_y)``
(heave, roll and pitch), which local resistive force theory cannot give.

As ``m`` grows at fixed ``b`` the chain converges (as ``1/m^2`` once ``1/m < b``) to a slender body whose drag is
set by ``b`` (docs/scenes.md gives the table). Its drag ratio ``xi_perp / xi_par`` is that of a
body of finite slenderness (below local RFT's 2 at ``l / b = 50``), and the links' flows act on
each other, so its bulk stroke differs from the paper's 0.19124724 l per cycle: a different
swimmer, compared with itself near the wall and far from it.

Range: lengths ``b << l``; heights with every bead clear of the wall (``h > b``; the RPB blocks
are a far-field series in ``b / h`` and need ``h`` a few ``b``). The swimmer's plane is held
parallel to the wall; the out-of-plane rates are computed, not integrated (their per-cycle sums
are the leading drift out of the plane).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Any

import jax
import jax.numpy as jnp
from jax import Array

from jswim.errors import ConfigError
from jswim.swimmers import nlink
from jswim.swimmers.mobility import OSEEN_PREFACTOR, rpb_wall_coefficients, wall_self_factors
from jswim.swimmers.models import SwimmerModel, make_model

#: Default bead radius (link lengths): l / b = 50.
BEAD_RADIUS = 0.02

#: Default beads per link: spacing 1/m = 0.78 b; the bulk stroke is then 1.0 % below the
#: converged value (the error falls as 1/m^2; docs/scenes.md gives the table).
BEADS_PER_LINK = 64


def bead_frame(d: Array, d_dot: Array, m: int) -> tuple[Array, Array]:
    """Bead positions ``(3 m, 2)`` in the plane (middle link's centre at the origin, along x) and
    their shape velocities ``(3 m, 2)`` (the middle link held still) for hinge angles ``d`` (2,)
    and rates ``d_dot`` (2,) ([`jswim.swimmers.nlink`][jswim.swimmers.nlink]'s conventions)."""
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
    ``1 / (6 pi mu)``: [`rpb_wall_coefficients`][jswim.swimmers.mobility.rpb_wall_coefficients] in 3-D,
    ``W = A I + B e e + C e z + D z e + E z z`` (``e`` the unit image vector, ``z`` the wall
    normal), for unit beads at lengths divided by ``b``, then divided by ``b``."""
    rx, ry = rho[..., 0] / b, rho[..., 1] / b
    zi, zj = zi / b, zj / b
    rz = zi + zj
    r2 = rx * rx + ry * ry + rz * rz
    ir = 1.0 / jnp.sqrt(r2)
    ex, ey, ez = rx * ir, ry * ir, rz * ir
    a_, b_, c_, d_, e_ = rpb_wall_coefficients(ez, zi / rz, ir, ir / r2, ir / (r2 * r2))
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
    Cholesky of ``M`` and the 6 x 6 Schur complement (as [`solve`][jswim.swimmers.forcefree.solve]).
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

    The body rates depend on the hinge angles alone (not on the pose), so they are solved once
    at each of the ``2 steps + 1`` RK4 nodes of a side ([`body_rates`][jswim.swimmers.purcell_beads.body_rates], one solve at a
    time), and the pose is then integrated from them.

    Returns
    -------
    Array (6,)
        ``(X, Y, Theta, Z, A_x, A_y)``: the middle link's lab displacement and rotation in the
        plane over one cycle, and the cycle's integrals of the body-frame heave ``U_z`` and of
        the roll and pitch rates (the leading drift out of the plane per cycle).
    """
    dtype = jnp.result_type(height)
    dm = d_max
    dt = 2.0 * dm / steps
    rates = jnp.array([[0.0, -1.0], [-1.0, 0.0], [0.0, 1.0], [1.0, 0.0]], dtype)
    starts = jnp.array([[dm, dm], [dm, -dm], [-dm, -dm], [-dm, dm]], dtype)
    frac = jnp.arange(2 * steps + 1, dtype=dtype) * (0.5 * dt)  # node times along a side
    d_nodes = starts[:, None, :] + rates[:, None, :] * frac[None, :, None]  # (4, 2 s + 1, 2)
    r_nodes = jnp.broadcast_to(rates[:, None, :], d_nodes.shape)
    q = jax.lax.map(
        lambda a: body_rates(a[0], a[1], height, m, b, wall),
        jnp.stack([d_nodes, r_nodes], 2).reshape(-1, 2, 2),
    ).reshape(4, 2 * steps + 1, 6)

    def rate(p: Array, qn: Array) -> Array:
        c, s = jnp.cos(p[2]), jnp.sin(p[2])
        return jnp.stack([c * qn[0] - s * qn[1], s * qn[0] + c * qn[1], qn[2], qn[3], qn[4], qn[5]])

    def body(p: Array, j: Array) -> tuple[Array, None]:
        side, i = j // steps, j % steps
        q0, qh, q1 = q[side, 2 * i], q[side, 2 * i + 1], q[side, 2 * i + 2]
        k1 = rate(p, q0)
        k2 = rate(p + 0.5 * dt * k1, qh)
        k3 = rate(p + 0.5 * dt * k2, qh)
        k4 = rate(p + dt * k3, q1)
        return p + dt / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4), None

    return jax.lax.scan(body, jnp.zeros(6, dtype), jnp.arange(4 * steps))[0]


def _planar(d: Array, d_dot: Array, height: float, m: int, b: float) -> Array:
    """``(U_x, U_y, Omega_z)`` of [`body_rates`][jswim.swimmers.purcell_beads.body_rates]; under ``vmap`` one solve at a time
    (``lax.map``), so a batch of poses holds one grand mobility, not one per pose."""

    @jax.custom_batching.custom_vmap
    def one(d: Array, d_dot: Array) -> Array:
        return body_rates(d, d_dot, height, m, b, True)[:3]

    @one.def_vmap
    def _batched(axis_size: int, in_batched: Any, d: Array, d_dot: Array) -> Any:
        d = d if in_batched[0] else jnp.broadcast_to(d, (axis_size, *d.shape))
        d_dot = d_dot if in_batched[1] else jnp.broadcast_to(d_dot, (axis_size, *d_dot.shape))
        return jax.lax.map(lambda a: one(a[0], a[1]), (d, d_dot)), True

    return one(d, d_dot)


@dataclasses.dataclass(frozen=True)
class BeadPurcellModel(SwimmerModel):
    """Purcell's swimmer of bead-chain links, its plane held ``height`` link lengths above the
    wall: a [`SwimmerModel`][jswim.swimmers.models.SwimmerModel] of kind ``"purcell"`` whose in-plane
    body velocity is [`body_rates`][jswim.swimmers.purcell_beads.body_rates]' ``(U_x, U_y, Omega_z)``. Its heave, roll and pitch are
    left out (the plane is held; [`square_cycle`][jswim.swimmers.purcell_beads.square_cycle] reports them). ``beads`` per link of radius
    ``link_radius`` (link lengths)."""

    height: float = math.inf
    link_radius: float = BEAD_RADIUS
    beads: int = BEADS_PER_LINK

    def body_velocity(self, d: Array, d_dot: Array) -> Array:
        return _planar(d, d_dot, self.height, self.beads, self.link_radius)


def wall_model(
    height: float,
    link_radius: float = BEAD_RADIUS,
    beads: int = BEADS_PER_LINK,
    *,
    d_max: float | None = None,
) -> BeadPurcellModel:
    """The bead model of Purcell's swimmer with its plane ``height`` link lengths above the wall.

    Raises
    ------
    ConfigError
        ``link_radius`` outside (0, 0.1], ``beads`` outside 4..256, or a height that does not
        clear the beads by one radius (``height > 2 link_radius``), in one line.
    """
    try:
        b, h = float(link_radius), float(height)
    except (TypeError, ValueError):
        raise ConfigError(
            f"height and link_radius must be numbers, got {height!r}, {link_radius!r}"
        ) from None
    if not 0.0 < b <= 0.1:
        raise ConfigError(f"link_radius must lie in (0, 0.1] link lengths, got {link_radius!r}")
    if isinstance(beads, bool) or not isinstance(beads, int) or not 4 <= beads <= 256:
        raise ConfigError(f"beads must be an integer in 4..256 per link, got {beads!r}")
    if not (math.isfinite(h) and h > 2.0 * b):
        raise ConfigError(
            f"the bead model needs the plane more than 2 bead radii ({2 * b:g} l) above the wall, got {height!r}"
        )
    base = make_model("purcell", d_max=d_max)
    return BeadPurcellModel("purcell", base.n_dof, base.lo, base.hi, base.xi_ratio, h, b, beads)
