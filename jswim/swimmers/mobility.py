"""Point-force mobility of spheres in the vertical plane y = 0: unbounded fluid or above a wall.

Units: lengths in the swimmer's sphere radius ``a`` and forces such that a free sphere of radius
``a`` has unit mobility, ``1 / (6 pi mu a) = 1`` (the units of [`jswim.swimmers.nsphere`][jswim.swimmers.nsphere]).
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
  [`blake`][jswim.swimmers.mobility.blake]. It vanishes for a field point on the wall and is symmetric under exchanging the
  two points together with the two indices (the tests check both).

Self blocks (a sphere of radius ``b`` moved by its own force): the Stokes mobility ``a / b``;
above the wall times the factors of [`wall_self_factors`][jswim.swimmers.mobility.wall_self_factors]:
``"rpb"``, the Rotne-Prager-Blake self terms (Swan & Brady, Phys. Fluids 19, 113306, 2007: the
Faxen operator applied twice to Blake's image part at the sphere's own centre),

  parallel ``1 - (9/16) e + (1/8) e^3 - (1/16) e^5``, normal ``1 - (9/8) e + (1/2) e^3 - (1/8) e^5``,
  ``e = b / h``,

a series in ``e`` (Faxen's parallel ``-(45/256) e^4`` is absent, and the normal factor leaves
Brenner's exact series beyond third order: 3.2 times Brenner's at h = 1.1 a); or ``"exact"``,
Brenner's series normal to the wall and near-contact asymptotics joined to Faxen's series
parallel to it (the scenes' default). Their first-order terms are exactly the point-force image
of the sphere's own force (a check in the tests). The default pair blocks are point forces (no
Faxen/Rotne-Prager size terms): the model of Golestanian & Ajdari for the three-sphere swimmer
and of Zargar, Najafi & Miri (Phys. Rev. E 80, 026308, 2009) near a wall; accurate to first
order in ``a / d`` between spheres ``d`` apart. ``mobility="rpy"`` gives finite-size pair
blocks ([`rpy_entries`][jswim.swimmers.mobility.rpy_entries], [`rpb_entries`][jswim.swimmers.mobility.rpb_entries]), consistent with the "rpb" self terms.
"""

from __future__ import annotations

import jax.numpy as jnp
import numpy as np
from jax import Array

#: Mobility of a point force's far field in units of 1 / (6 pi mu a): 6 pi a / (8 pi) = 3/4.
OSEEN_PREFACTOR = 0.75

#: Pair mobilities: ``"point"`` (point forces: Oseen / Blake, the default) or ``"rpy"``
#: (finite-size spheres: Rotne-Prager-Yamakawa / Rotne-Prager-Blake).
MOBILITIES = ("point", "rpy")


def rpy_entries(
    rx: Array, rz: Array, ai: Array = 1.0, aj: Array = 1.0
) -> tuple[Array, Array, Array]:
    """Rotne-Prager-Yamakawa pair mobility of non-overlapping spheres of radii ``ai``, ``aj``
    (units of ``a``) in the unbounded fluid, ``(M_xx, M_xz, M_zz)`` in units of ``1 / (6 pi mu a)``.

    ``M = (1 + ai^2/6 lap_i)(1 + aj^2/6 lap_j) G`` for the Oseen tensor ``G`` (Rotne & Prager, J.
    Chem. Phys. 50, 4831, 1969; Yamakawa, ibid. 53, 436, 1970): since ``lap lap G = 0``,
    ``(3/4) / r [(1 + s/(3 r^2)) I + (1 - s/r^2) r r / r^2]`` with ``s = ai^2 + aj^2``, for
    ``r >= ai + aj`` (the scenes refuse closer approaches). Elementwise; ``r`` non-zero.
    """
    r2 = rx * rx + rz * rz
    inv = 1.0 / jnp.sqrt(r2)
    s = ai * ai + aj * aj
    iso = OSEEN_PREFACTOR * inv * (1.0 + s / (3.0 * r2))
    rr = OSEEN_PREFACTOR * inv * (1.0 - s / r2) / r2
    return iso + rr * rx * rx, rr * rx * rz, iso + rr * rz * rz


def rpb_wall_coefficients(
    ez: Array, t: Array, ir: Array, ir3: Array, ir5: Array
) -> tuple[Array, Array, Array, Array, Array]:
    """Swan & Brady's wall coefficients ``(A, B, C, D, E)`` of the Rotne-Prager-Blake mobility of
    two unit spheres (Phys. Fluids 19, 113306, 2007, appendix), in units of ``1 / (6 pi mu a)``.

    The wall part of the mobility of sphere ``i`` per force on sphere ``j`` is
    ``W_ab = A d_ab + B e_a e_b + C e_a d_b3 + D d_a3 e_b + E d_a3 d_b3``, with ``e`` the unit
    image vector ``R = x_i - (x_j, -z_j)`` and ``d_a3`` the wall normal. ``A`` and ``B`` are
    symmetric in the two spheres; ``C``, ``D``, ``E`` are the paper's for the swapped pair
    (``t -> 1 - t``). Used by [`rpb_entries`][jswim.swimmers.mobility.rpb_entries] (the plane)
    and `jswim.swimmers.purcell_beads.rpb_wall_blocks` (3-D).

    Parameters
    ----------
    ez : Array
        The image vector's normal component ``(z_i + z_j) / R``.
    t : Array
        ``z_i / (z_i + z_j)``.
    ir, ir3, ir5 : Array
        ``1 / R``, ``1 / R^3``, ``1 / R^5``. Given by the caller: each rounds ``1 / R^5`` its own
        way, and keeps its numbers.

    Returns
    -------
    tuple of Array
        ``(A, B, C, D, E)``, elementwise.
    """
    ez2 = ez * ez
    tt = t * (1.0 - t)
    u = 1.0 - t  # the swapped pair's t
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
    return a_, b_, c_, d_, e_


def rpb_entries(rx: Array, zi: Array, zj: Array) -> tuple[Array, Array, Array, Array]:
    """Rotne-Prager-Blake pair mobility of two unit spheres (radius ``a``) above the no-slip wall
    at z = 0, ``(M_xx, M_xz, M_zx, M_zz)`` of sphere ``i`` at height ``zi`` per unit force on
    sphere ``j`` at height ``zj``, ``rx = x_i - x_j``; units of ``1 / (6 pi mu a)``.

    Blake's tensor with the Faxen operators of both spheres applied,
    ``(1 + a^2/6 lap_i)(1 + a^2/6 lap_j) G_Blake`` (Swan & Brady, Phys. Fluids 19, 113306, 2007,
    appendix): the unbounded Rotne-Prager-Yamakawa tensor ([`rpy_entries`][jswim.swimmers.mobility.rpy_entries]) plus the
    wall part of [`rpb_wall_coefficients`][jswim.swimmers.mobility.rpb_wall_coefficients] in the
    image vector ``R = x_i - (x_j, -z_j)`` (direction ``(e_x, e_z)``). Non-overlapping spheres
    not touching the wall. A test checks it against the Faxen operators applied numerically to
    Blake's image system.
    """
    Rz = zi + zj
    R2 = rx * rx + Rz * Rz
    iR = 1.0 / jnp.sqrt(R2)
    iR3 = iR / R2
    ex, ez = rx * iR, Rz * iR
    ez2 = ez * ez
    a_, b_, c_, d_, e_ = rpb_wall_coefficients(ez, zi / Rz, iR, iR3, iR3 / R2)
    fxx, fxz, fzz = rpy_entries(rx, zi - zj)
    return (
        fxx + a_ + b_ * ex * ex,
        fxz + b_ * ex * ez + c_ * ex,
        fxz + b_ * ex * ez + d_ * ex,
        fzz + a_ + b_ * ez2 + (c_ + d_) * ez + e_,
    )


def stokeslet(rx: Array, rz: Array) -> tuple[Array, Array, Array]:
    """``S = I / r + r r / r^3`` in the (x, z) plane, as its three distinct entries
    ``(S_xx, S_xz, S_zz)``; elementwise over any shape. ``r`` must be non-zero."""
    r2 = rx * rx + rz * rz
    inv = 1.0 / jnp.sqrt(r2)
    inv3 = inv / r2
    return inv + rx * rx * inv3, rx * rz * inv3, inv + rz * rz * inv3


def blake(rx: Array, zi: Array, zj: Array) -> Array:
    """Blake's tensor as ``(..., 2, 2)`` (see [`blake_entries`][jswim.swimmers.mobility.blake_entries])."""
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
        return (
            h * (dik * iR3 - 3.0 * ri * rk * iR5)
            + di3 * rk * iR3
            - (dik * Rz + ri * d3k) * iR3
            + 3.0 * ri * Rz * rk * iR5
        )

    # 2 h m_k d_k f_i, m = (+1 for x, -1 for z).
    dxx = 2.0 * h * df(rx, rx, 1.0, 0.0, 0.0)
    dzx = 2.0 * h * df(Rz, rx, 0.0, 1.0, 0.0)
    dxz = -2.0 * h * df(rx, Rz, 0.0, 0.0, 1.0)
    dzz = -2.0 * h * df(Rz, Rz, 1.0, 1.0, 1.0)
    return sxx - ixx + dxx, sxz - ixz + dxz, sxz - ixz + dzx, szz - izz + dzz


def pair_entries(
    rx: Array,
    zi: Array,
    zj: Array,
    wall: bool,
    mobility: str = "point",
    ai: Array = 1.0,
    aj: Array = 1.0,
) -> tuple[Array, Array, Array, Array]:
    """Mobility ``(M_xx, M_xz, M_zx, M_zz)`` of sphere ``i`` per unit force on sphere ``j``
    (units of ``1 / (6 pi mu a)``); ``rx = x_i - x_j``, heights ``zi``, ``zj``; elementwise.

    ``mobility`` (static): ``"point"``: Blake's tensor above the wall, else the Oseen tensor, times
    `OSEEN_PREFACTOR` (the radii do not enter); ``"rpy"``: [`rpb_entries`][jswim.swimmers.mobility.rpb_entries] above the
    wall (unit spheres only), else [`rpy_entries`][jswim.swimmers.mobility.rpy_entries] with radii ``ai``, ``aj``."""
    if mobility == "rpy":
        if wall:
            return rpb_entries(rx, zi, zj)
        mxx, mxz, mzz = rpy_entries(rx, zi - zj, ai, aj)
        return mxx, mxz, mxz, mzz
    if wall:
        gxx, gxz, gzx, gzz = blake_entries(rx, zi, zj)
    else:
        gxx, gxz, gzz = stokeslet(rx, zi - zj)
        gzx = gxz
    c = OSEEN_PREFACTOR
    return c * gxx, c * gxz, c * gzx, c * gzz


def swimmer_blocks(
    pa: Array, pb: Array, wall: bool, mobility: str = "point", same: bool = False
) -> Array:
    """The pair blocks between two groups of swimmers' spheres, ``(A, B, n, n, 2, 2)``.

    Entry ``[s, o, i, j]`` is the mobility ``[[M_xx, M_xz], [M_zx, M_zz]]`` of sphere ``i`` of
    swimmer ``s`` of ``pa`` ``(A, n, 2)`` per force on sphere ``j`` of swimmer ``o`` of ``pb``
    ``(B, n, 2)`` ([`pair_entries`][jswim.swimmers.mobility.pair_entries], unit spheres). ``same`` (static): ``pa`` and ``pb`` are
    one group, and a swimmer's blocks with itself are zero (its own spheres are solved with it).
    """
    rx = pa[:, None, :, None, 0] - pb[None, :, None, :, 0]  # (A, B, n, n)
    zi = jnp.broadcast_to(pa[:, None, :, None, 1], rx.shape)
    zj = jnp.broadcast_to(pb[None, :, None, :, 1], rx.shape)
    if same:
        own = np.eye(pa.shape[0], dtype=bool)[:, :, None, None]
        rx, zj = (
            jnp.where(own, 1.0, rx),
            jnp.where(own, zi + 1.0, zj),
        )  # finite stand-ins, zeroed below
    mxx, mxz, mzx, mzz = pair_entries(rx, zi, zj, wall, mobility)
    blk = jnp.stack([jnp.stack([mxx, mxz], -1), jnp.stack([mzx, mzz], -1)], -2)
    return jnp.where(own[..., None, None], 0.0, blk) if same else blk


def transposed_blocks(blocks: Array) -> Array:
    """[`swimmer_blocks`][jswim.swimmers.mobility.swimmer_blocks] of ``(pb, pa)`` from that of ``(pa, pb)``: ``M_(o j, s i) = M_(s i, o j)^T``."""
    return jnp.transpose(blocks, (1, 0, 3, 2, 5, 4))


def oseen(rx: Array, rz: Array) -> Array:
    """``8 pi mu`` times the Oseen tensor in the (x, z) plane, ``(..., 2, 2)``."""
    sxx, sxz, szz = stokeslet(rx, rz)
    return jnp.stack([jnp.stack([sxx, sxz], -1), jnp.stack([sxz, szz], -1)], -2)


#: Self-mobility models above the wall ([`wall_self_factors`][jswim.swimmers.mobility.wall_self_factors]): ``"rpb"`` (the
#: Rotne-Prager-Blake self terms, a series in a/h) and ``"exact"`` (Brenner's bipolar series normal
#: to the wall; near-contact lubrication joined to Faxen's series parallel to it).
SELF_MOBILITIES = ("rpb", "exact")

#: Terms kept of Brenner's series: at the smallest gap it is summed for (`LUBRICATION_GAP`,
#: alpha = 0.0447) the last term is below 1e-13 of the sum.
BRENNER_TERMS = 400

#: Gap (h - a)/a below which the normal factor is Cox & Brenner's lubrication asymptote instead of
#: Brenner's series (there they differ by 2e-6 relative).
LUBRICATION_GAP = 1e-3

#: Gap (h - a)/a at which the parallel factor switches from Goldman, Cox & Brenner's near-contact
#: asymptote to Faxen's series: where the two are equal (0.0321).
PARALLEL_JOIN_GAP = 0.0321239069

#: Smallest gap (h - a)/a the factors are evaluated at; closer heights are clamped to it.
MIN_GAP = 1e-6

#: Smallest gap (units of the radius) at which the solves evaluate the exact self-mobility
#: ([`sphere_self_factors`][jswim.swimmers.mobility.sphere_self_factors]). The scenes refuse a step whose spheres come within 0.1 a of the
#: wall, but a refused step's trial poses may go closer: there the exact normal factor (~gap)
#: falls below the far-field pair blocks and the grand mobility stops being positive definite
#: (measured: a lying swimmer's smallest eigenvalue is +0.003 at a gap of 0.005 a, -0.001 at
#: 0.001 a). Above this floor every pose keeps it positive definite; below, refused anyway.
SOLVE_MIN_GAP = 0.01


def wall_self_factors(e: Array, model: str = "rpb") -> tuple[Array, Array]:
    """Wall corrections ``(parallel, normal)`` to a torque-free sphere's self-mobility: its
    translational mobility along and normal to a no-slip plane wall, over the bulk ``1/(6 pi mu a)``.

    Parameters
    ----------
    e : float or Array (...)
        ``a / h``, radius over the centre's height above the wall, in ``[0, 1)``.
    model : str
        Static. ``"rpb"``: the Rotne-Prager-Blake self terms (Swan & Brady, Phys. Fluids 19,
        113306, 2007, eqs. (A1)-(A2) as this module's docstring writes them),
        ``1 - (9/16) e + (1/8) e^3 - (1/16) e^5`` and ``1 - (9/8) e + (1/2) e^3 - (1/8) e^5``: a
        series in ``e``, within 1 % of the exact normal factor for h >= 3.2 a, 22 % high at 1.5 a,
        3.2 times too high at 1.1 a, and not zero at contact. ``"exact"``: see
        [`exact_normal_factor`][jswim.swimmers.mobility.exact_normal_factor] and [`exact_parallel_factor`][jswim.swimmers.mobility.exact_parallel_factor].

    Returns
    -------
    (parallel, normal) : Arrays of the shape of ``e``
        Dimensionless, in (0, 1]; 1 at ``e = 0``.

    Raises
    ------
    ValueError
        An unknown ``model``.
    """
    if model == "rpb":
        e3 = e * e * e
        e5 = e3 * e * e
        return 1.0 - 0.5625 * e + 0.125 * e3 - 0.0625 * e5, 1.0 - 1.125 * e + 0.5 * e3 - 0.125 * e5
    if model == "exact":
        return exact_parallel_factor(e), exact_normal_factor(e)
    raise ValueError(
        f"wall self-mobility model must be one of {', '.join(SELF_MOBILITIES)}, got {model!r}"
    )


def sphere_self_factors(radius: Array, z: Array, model: str = "rpb") -> tuple[Array, Array]:
    """[`wall_self_factors`][jswim.swimmers.mobility.wall_self_factors] of a sphere of ``radius`` centred ``z`` above the wall, as the
    force-free solves take them: for ``"exact"`` the height is floored at
    ``radius (1 +`` `SOLVE_MIN_GAP` ``)`` (``"rpb"`` as it is)."""
    if model == "exact":
        z = jnp.maximum(z, radius * (1.0 + SOLVE_MIN_GAP))
    return wall_self_factors(radius / z, model)


def _gap(e: Array) -> Array:
    """``(h - a)/a = 1/e - 1`` from ``e = a/h``, clamped to `MIN_GAP` (``e = 0`` gives inf)."""
    e = jnp.asarray(e)
    inv = jnp.where(e > 0, 1.0 / jnp.where(e > 0, e, 1.0), jnp.inf)
    return jnp.maximum(inv - 1.0, MIN_GAP)


def brenner_drag(gap: Array, terms: int = BRENNER_TERMS) -> Array:
    """Brenner's drag factor ``lambda = F / (6 pi mu a U)`` of a sphere moving normal to a no-slip
    plane wall, at centre height ``h = a (1 + gap)`` (Brenner, Chem. Eng. Sci. 16, 242, 1961; the
    series as Happel & Brenner, *Low Reynolds number hydrodynamics*, 1965, give it)::

        lambda = (4/3) sinh(alpha) sum_{n>=1} n (n+1) / ((2n-1)(2n+3)) [
            (2 sinh((2n+1) alpha) + (2n+1) sinh(2 alpha))
            / (4 sinh^2((n+1/2) alpha) - (2n+1)^2 sinh^2(alpha)) - 1 ],   cosh(alpha) = h / a.

    Each bracket is evaluated divided through by ``exp((2n+1) alpha)``, so no term overflows
    (float32 included). ``terms`` terms (static). The bracket's denominator cancels to
    ``O(alpha^4)`` near contact: in float32 the factor is good to 2e-4 down to a gap of 0.01 a
    and loses digits below (0.5 % at 1e-3 a); float64 holds 1e-9 throughout.
    """
    gap = jnp.asarray(gap)
    alpha = jnp.arccosh(1.0 + gap)
    n = jnp.arange(1, terms + 1, dtype=alpha.dtype)
    al = alpha[..., None]
    k = 2.0 * n + 1.0
    q = jnp.exp(-k * al)  # exp(-(2n+1) alpha)
    sh = jnp.sinh(al)
    num = 1.0 - q * q + k * jnp.sinh(2.0 * al) * q  # (2 sinh x + k sinh 2a) e^-x
    den = 1.0 + q * q - 2.0 * q - k * k * sh * sh * q  # (4 sinh^2(x/2) - k^2 sinh^2 a) e^-x
    coef = n * (n + 1.0) / ((2.0 * n - 1.0) * (2.0 * n + 3.0))
    bracket = (num - den) / den
    return (4.0 / 3.0) * jnp.sinh(alpha) * jnp.sum(coef * bracket, -1)


def lubrication_normal_drag(gap: Array) -> Array:
    """Cox & Brenner's near-contact drag factor normal to the wall (Chem. Eng. Sci. 22, 1753,
    1967): ``lambda = 1/gap + (1/5) ln(1/gap) + 0.971264`` at ``gap = (h - a)/a -> 0``."""
    gap = jnp.asarray(gap)
    return 1.0 / gap + 0.2 * jnp.log(1.0 / gap) + 0.971264


def exact_normal_factor(e: Array) -> Array:
    """Normal self-mobility factor ``1 / lambda`` from Brenner's series ([`brenner_drag`][jswim.swimmers.mobility.brenner_drag],
    `BRENNER_TERMS` terms) for gaps above `LUBRICATION_GAP`, Cox & Brenner's
    asymptote below ([`lubrication_normal_drag`][jswim.swimmers.mobility.lubrication_normal_drag]; ~ ``gap`` at contact, so a sphere never
    touches the wall in finite time under a finite force), and ``1 - (9/8) e + (1/2) e^3`` for
    ``e < 1e-3`` (the series' far-field expansion, Lorentz 1907 and Brenner 1961; the next term,
    ``O(e^4)``, is below 1e-12 there). ``e = a/h``; shape kept."""
    e = jnp.asarray(e)
    gap = _gap(e)
    far = e < 1e-3
    near = gap < LUBRICATION_GAP
    mid_gap = jnp.where(far | near, 1.0, gap)  # a safe stand-in where the series is not used
    series = 1.0 / brenner_drag(mid_gap)
    lub = 1.0 / lubrication_normal_drag(jnp.minimum(gap, LUBRICATION_GAP))
    ef = jnp.where(far, e, 0.0)
    return jnp.where(far, 1.0 - 1.125 * ef + 0.5 * ef**3, jnp.where(near, lub, series))


def faxen_parallel_factor(e: Array) -> Array:
    """Faxen's series for the parallel self-mobility, ``1 - (9/16) e + (1/8) e^3 - (45/256) e^4
    - (1/16) e^5`` (Faxen 1923, as Happel & Brenner 1965 give it; a torque-free sphere: its
    rotation changes the translation only at ``O(e^8)``)."""
    e = jnp.asarray(e)
    return 1.0 - 0.5625 * e + 0.125 * e**3 - 0.17578125 * e**4 - 0.0625 * e**5


def contact_parallel_factor(gap: Array) -> Array:
    """Near-contact parallel self-mobility of a torque-free sphere, from Goldman, Cox & Brenner's
    asymptotic resistances (Chem. Eng. Sci. 22, 637, 1967), ``L = ln(gap)``::

        F^t = (8/15) L - 0.9588,  T^t = -(1/10) L - 0.1895,
        F^r = (4/3) T^t (reciprocity),  T^r = (2/5) L - 0.3817,

    the force ``6 pi mu a (U F^t + a Omega F^r)`` and torque ``8 pi mu a^2 (U T^t + a Omega T^r)``
    on a sphere translating at ``U`` and rotating at ``Omega``. Torque-free:
    ``a Omega = -U T^t / T^r``, so the factor is ``-1 / (F^t - F^r T^t / T^r)``, which tends to
    ``-2 / ln(gap)`` at contact. Valid as ``gap -> 0`` (error O(gap ln gap))."""
    lg = jnp.log(jnp.asarray(gap))
    f_t = (8.0 / 15.0) * lg - 0.9588
    t_t = -0.1 * lg - 0.1895
    t_r = 0.4 * lg - 0.3817
    return -1.0 / (f_t - (4.0 / 3.0) * t_t * t_t / t_r)


def exact_parallel_factor(e: Array) -> Array:
    """Parallel self-mobility factor: [`contact_parallel_factor`][jswim.swimmers.mobility.contact_parallel_factor] below the gap
    `PARALLEL_JOIN_GAP` (0.0321 a, where the two curves cross, so the factor is
    continuous), [`faxen_parallel_factor`][jswim.swimmers.mobility.faxen_parallel_factor] above. Not an exact solution: O'Neill's (1964)
    bipolar solution is not implemented; both asymptotes are least accurate near the join, where
    they differ in slope and bracket the exact value within a few per cent (docs/scenes.md gives
    the table). ``e = a/h``; shape kept."""
    e = jnp.asarray(e)
    gap = _gap(e)
    near = gap < PARALLEL_JOIN_GAP
    return jnp.where(
        near, contact_parallel_factor(jnp.minimum(gap, PARALLEL_JOIN_GAP)), faxen_parallel_factor(e)
    )


def mobility_matrix(
    pos: Array, radii: Array, wall: bool, mobility: str = "point", self_mobility: str = "rpb"
) -> Array:
    """Grand mobility of ``N`` spheres in the plane y = 0.

    Parameters
    ----------
    pos : Array (N, 2)
        Centres ``(x, z)`` in units of ``a`` (above the wall, z > radius, when ``wall``).
    radii : Array (N,)
        Radii in units of ``a``.
    wall : bool
        Static: Blake's no-slip wall at z = 0, or the unbounded fluid.
    mobility : str
        Static: ``"point"`` (point-force pair blocks) or ``"rpy"`` (Rotne-Prager-Yamakawa /
        -Blake, [`pair_entries`][jswim.swimmers.mobility.pair_entries]; above the wall unit radii only).
    self_mobility : str
        Static: the self blocks above the wall, [`wall_self_factors`][jswim.swimmers.mobility.wall_self_factors]'s ``model``
        (``"rpb"`` or ``"exact"``).

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
    if mobility == "rpy":
        ai = jnp.broadcast_to(radii[:, None], (n, n))
        aj = jnp.broadcast_to(radii[None, :], (n, n))
        gxx, gxz, gzx, gzz = pair_entries(rx_safe, zi, zj, wall, "rpy", ai, aj)
        pair = jnp.stack([jnp.stack([gxx, gxz], -1), jnp.stack([gzx, gzz], -1)], -2)
    elif wall:
        pair = OSEEN_PREFACTOR * blake(rx_safe, zi, zj)
    else:
        pair = OSEEN_PREFACTOR * oseen(rx_safe, zi - zj)
    if wall:
        par, nor = sphere_self_factors(radii, z, self_mobility)
    else:
        par = nor = jnp.ones_like(radii)
    selfs = jnp.stack([jnp.stack([par, 0.0 * par], -1), jnp.stack([0.0 * nor, nor], -1)], -2)
    selfs = selfs / radii[:, None, None]
    blocks = jnp.where(eye[:, :, None, None], selfs[:, None], pair)  # (n, n, 2, 2)
    return blocks.transpose(0, 2, 1, 3).reshape(2 * n, 2 * n)
