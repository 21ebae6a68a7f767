"""Point-force mobility of spheres in the vertical plane y = 0: unbounded fluid or above a wall.

Units: lengths in the swimmer's sphere radius ``a`` and forces such that a free sphere of radius
``a`` has unit mobility, ``1 / (6 pi mu a) = 1`` (the units of :mod:`jswim.swimmers.nsphere`).
All centres lie in the plane y = 0 and all forces act in it, so by the mirror symmetry y -> -y
every velocity lies in it too: each pair block is the (x, z) part, 2 x 2, of the 3-D tensor.

Pair blocks (sphere ``i`` moved by a point force on sphere ``j``):

* unbounded fluid: the Oseen tensor ``(1 / 8 pi mu) (I / r + r r / r^3)``, i.e.
  ``(3 / 4) (I / r + r r / r^3)`` in these units;
* no-slip plane wall at z = 0: Blake's image system (J. R. Blake, Proc. Camb. Phil. Soc. 70, 303,
  1971): the Stokeslet at ``x_j`` (height ``h = z_j``), minus a Stokeslet at the mirror point
  ``(x_j, -h)``, plus a Stokeslet doublet and a source doublet there,

  ``8 pi mu G_ik = S_ik(r) - S_ik(R) + 2 h m_k d/dR_k [h R_i / R^3 - delta_i3 / R - R_i R_3 / R^3]``

  with ``S(r) = I / r + r r / r^3``, ``r = x_i - x_j``, ``R = x_i - (x_j, -h)``, ``k`` the force
  component, ``m = (1, 1, -1)`` and no sum over ``k``. The derivative is written out in
  :func:`blake`. It vanishes for a field point on the wall and is symmetric under exchanging the
  two points together with the two indices (the tests check both).

Self blocks (a sphere of radius ``b`` moved by its own force): the Stokes mobility ``a / b``;
above the wall times the wall corrections of Faxen (parallel) and Lorentz/Brenner (normal) to
fifth order in ``b / h`` as used in the Rotne-Prager-Blake self-mobility (Swan & Brady, Phys.
Fluids 19, 113306, 2007):

  parallel ``1 - (9/16) e + (1/8) e^3 - (1/16) e^5``, normal ``1 - (9/8) e + (1/2) e^3 - (1/8) e^5``,
  ``e = b / h``.

Their first-order terms are exactly the point-force image of the sphere's own force (a check in
the tests). The pair blocks are point forces (no Faxen/Rotne-Prager size terms): the model of
Golestanian & Ajdari for the three-sphere swimmer and of Zargar, Najafi & Miri (Phys. Rev. E 80,
026308, 2009) near a wall; accurate to first order in ``a / d`` between spheres ``d`` apart.
"""

from __future__ import annotations

import jax.numpy as jnp
from jax import Array

#: Mobility of a point force's far field in units of 1 / (6 pi mu a): 6 pi a / (8 pi) = 3/4.
OSEEN_PREFACTOR = 0.75


def stokeslet(rx: Array, rz: Array) -> tuple[Array, Array, Array]:
    """``S = I / r + r r / r^3`` in the (x, z) plane, as its three distinct entries
    ``(S_xx, S_xz, S_zz)``; elementwise over any shape. ``r`` must be non-zero."""
    r2 = rx * rx + rz * rz
    inv = 1.0 / jnp.sqrt(r2)
    inv3 = inv / r2
    return inv + rx * rx * inv3, rx * rz * inv3, inv + rz * rz * inv3


def blake(rx: Array, zi: Array, zj: Array) -> Array:
    """Blake's tensor as ``(..., 2, 2)`` (see :func:`blake_entries`)."""
    gxx, gxz, gzx, gzz = blake_entries(rx, zi, zj)
    return jnp.stack([jnp.stack([gxx, gxz], -1), jnp.stack([gzx, gzz], -1)], -2)


def blake_entries(rx: Array, zi: Array, zj: Array) -> tuple[Array, Array, Array, Array]:
    """Blake's wall Green function ``8 pi mu G`` for a force at height ``zj`` and a field point at
    height ``zi``, ``rx = x_i - x_j`` apart along x; (x, z) components.

    Parameters
    ----------
    rx, zi, zj : arrays of one shape (...)
        Field minus source x; field and source heights above the wall (> 0 for the source).

    Returns
    -------
    (G_xx, G_xz, G_zx, G_zz), each of shape (...)
        ``G_ik``: velocity component ``i`` per unit force component ``k``, times ``8 pi mu``
        (units of 1 / length). The field point must differ from the source.
    """
    h = zj
    rz = zi - zj
    Rz = zi + zj  # field minus mirror point (x_j, -h)
    sxx, sxz, szz = stokeslet(rx, rz)
    ixx, ixz, izz = stokeslet(rx, Rz)
    R2 = rx * rx + Rz * Rz
    iR = 1.0 / jnp.sqrt(R2)
    iR3 = iR / R2
    iR5 = iR3 / R2
    # d_k f_i with f_i = h R_i / R^3 - delta_i3 / R - R_i R_3 / R^3 (R_3 = Rz):
    #   h (delta_ik / R^3 - 3 R_i R_k / R^5) + delta_i3 R_k / R^3
    #   - (delta_ik R_3 + R_i delta_3k) / R^3 + 3 R_i R_3 R_k / R^5
    def df(ri: Array, rk: Array, dik: float, di3: float, d3k: float) -> Array:
        return (h * (dik * iR3 - 3.0 * ri * rk * iR5) + di3 * rk * iR3
                - (dik * Rz + ri * d3k) * iR3 + 3.0 * ri * Rz * rk * iR5)

    # 2 h m_k d_k f_i, m = (+1 for x, -1 for z).
    dxx = 2.0 * h * df(rx, rx, 1.0, 0.0, 0.0)
    dzx = 2.0 * h * df(Rz, rx, 0.0, 1.0, 0.0)
    dxz = -2.0 * h * df(rx, Rz, 0.0, 0.0, 1.0)
    dzz = -2.0 * h * df(Rz, Rz, 1.0, 1.0, 1.0)
    return sxx - ixx + dxx, sxz - ixz + dxz, sxz - ixz + dzx, szz - izz + dzz


def pair_entries(rx: Array, zi: Array, zj: Array, wall: bool) -> tuple[Array, Array, Array, Array]:
    """Mobility ``(M_xx, M_xz, M_zx, M_zz)`` of sphere ``i`` per unit point force on sphere ``j``
    (units of ``1 / (6 pi mu a)``): Blake's tensor above the wall, else the Oseen tensor, times
    :data:`OSEEN_PREFACTOR`; ``rx = x_i - x_j``, heights ``zi``, ``zj``; elementwise."""
    if wall:
        gxx, gxz, gzx, gzz = blake_entries(rx, zi, zj)
    else:
        gxx, gxz, gzz = stokeslet(rx, zi - zj)
        gzx = gxz
    c = OSEEN_PREFACTOR
    return c * gxx, c * gxz, c * gzx, c * gzz


def oseen(rx: Array, rz: Array) -> Array:
    """``8 pi mu`` times the Oseen tensor in the (x, z) plane, ``(..., 2, 2)``."""
    sxx, sxz, szz = stokeslet(rx, rz)
    return jnp.stack([jnp.stack([sxx, sxz], -1), jnp.stack([sxz, szz], -1)], -2)


def wall_self_factors(e: Array) -> tuple[Array, Array]:
    """Wall corrections to a sphere's self-mobility, parallel and normal to the wall, at
    ``e = radius / height`` (Faxen; Lorentz/Brenner; fifth order as in Swan & Brady 2007)."""
    e3 = e * e * e
    e5 = e3 * e * e
    return 1.0 - 0.5625 * e + 0.125 * e3 - 0.0625 * e5, 1.0 - 1.125 * e + 0.5 * e3 - 0.125 * e5


def mobility_matrix(pos: Array, radii: Array, wall: bool) -> Array:
    """Grand mobility of ``N`` spheres in the plane y = 0.

    Parameters
    ----------
    pos : Array (N, 2)
        Centres ``(x, z)`` in units of ``a`` (above the wall, z > radius, when ``wall``).
    radii : Array (N,)
        Radii in units of ``a``.
    wall : bool
        Static: Blake's no-slip wall at z = 0, or the unbounded fluid.

    Returns
    -------
    Array (2N, 2N)
        ``M`` with ``v = M F``, rows and columns ordered ``(x_0, z_0, x_1, z_1, ...)``, in units of
        ``1 / (6 pi mu a)``. Symmetric.
    """
    n = pos.shape[0]
    x, z = pos[:, 0], pos[:, 1]
    eye = jnp.eye(n, dtype=bool)
    rx = x[:, None] - x[None, :]
    zi = jnp.broadcast_to(z[:, None], (n, n))
    zj = jnp.broadcast_to(z[None, :], (n, n))
    # A dummy separation on the diagonal keeps the pair formula finite there (then replaced).
    rx_safe = jnp.where(eye, 1.0, rx)
    if wall:
        pair = blake(rx_safe, zi, zj)
        par, nor = wall_self_factors(radii / z)
    else:
        pair = oseen(rx_safe, zi - zj)
        par = nor = jnp.ones_like(radii)
    pair = OSEEN_PREFACTOR * pair
    selfs = jnp.stack([jnp.stack([par, 0.0 * par], -1), jnp.stack([0.0 * nor, nor], -1)], -2)
    selfs = selfs / radii[:, None, None]
    blocks = jnp.where(eye[:, :, None, None], selfs[:, None], pair)  # (n, n, 2, 2)
    return blocks.transpose(0, 2, 1, 3).reshape(2 * n, 2 * n)
