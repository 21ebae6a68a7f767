"""Force- and torque-free motion of sphere swimmers with prescribed arm rates, among fixed spheres.

``S`` swimmers of ``n`` spheres each (radius ``a = 1``) lie on straight axes in the vertical
plane y = 0; swimmer ``s`` has its reference sphere (index ``n_dof // 2``, the middle sphere of
the three-sphere swimmer) at ``c_s = (x_s, z_s)`` and its axis along ``e_s = (cos t_s, sin t_s)``
(``t_s`` the tilt from the wall plane, positive nose up; the nose is the last sphere). Sphere
``i`` sits at ``c_s + q_i e_s`` with ``q`` the cumulative arm lengths measured from the reference
sphere. ``O`` obstacles are spheres of given radius held fixed.

Unknowns: the forces on all spheres ``F`` (2 per sphere) and each swimmer's rigid motion
``xi_s = (U_x, U_z, Omega)`` (``Omega = d t_s / dt``). Equations, with ``M`` the grand mobility
([`jswim.swimmers.mobility.mobility_matrix`][jswim.swimmers.mobility.mobility_matrix]):

* ``M F = K xi + v``: a swimmer sphere moves rigidly with its swimmer plus its prescribed axial
  velocity ``v_i = qdot_i e_s``; an obstacle does not move (zero rows of ``K`` and ``v``);
* ``K^T F = 0``: each swimmer feels zero total force and zero torque (about ``c_s``).

Eliminating ``F = M^-1 (K xi + v)`` leaves ``(K^T M^-1 K) xi = -K^T M^-1 v``, a ``3S x 3S``
symmetric positive-definite system; ``M`` is factorised once (Cholesky) per call.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.swimmers.mobility import (
    mobility_matrix,
    pair_entries,
    swimmer_blocks,
    sphere_self_factors,
    transposed_blocks,
)


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
    return cum - cum[..., m : m + 1]


def sphere_centres(centre: Array, tilt: Array, arms: Array) -> Array:
    """Centres ``(S, n, 2)`` of every swimmer sphere from centres ``(S, 2)``, tilts ``(S,)``, arms
    ``(S, n_dof)``."""
    q = axial_offsets(arms)
    e = jnp.stack([jnp.cos(tilt), jnp.sin(tilt)], -1)
    return centre[:, None, :] + q[..., None] * e[:, None, :]


def solve(
    centre: Array,
    tilt: Array,
    arms: Array,
    arm_rates: Array,
    obstacles: Array,
    wall: bool,
    mobility: str = "point",
    self_mobility: str = "rpb",
) -> RigidMotion:
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
    mobility : str
        Static: ``"point"`` or ``"rpy"`` pair blocks ([`jswim.swimmers.mobility.pair_entries`][jswim.swimmers.mobility.pair_entries]).
    self_mobility : str
        Static: the spheres' self-mobility above the wall, ``"rpb"`` or ``"exact"``
        ([`jswim.swimmers.mobility.wall_self_factors`][jswim.swimmers.mobility.wall_self_factors]).

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
    mob = mobility_matrix(pos, radii, wall, mobility, self_mobility)
    # K: (N, 2, S, 3): rigid velocity of sphere i per unit (U_x, U_z, Omega) of swimmer s.
    rel = pos_sw - centre[:, None, :]  # (S, n, 2)
    one = jnp.ones((S, n), dtype)
    zero = jnp.zeros((S, n), dtype)
    k_own = jnp.stack(
        [jnp.stack([one, zero, -rel[..., 1]], -1), jnp.stack([zero, one, rel[..., 0]], -1)], -2
    )  # (S, n, 2, 3)
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


#: Largest system (2 N rows) that [`rigid_motion`][jswim.swimmers.forcefree.rigid_motion] solves by unrolled elimination.
UNROLLED_MAX_ROWS = 6


def rigid_motion(
    centre: Array,
    tilt: Array,
    arms: Array,
    arm_rates: Array,
    obstacles: Array,
    wall: bool,
    mobility: str = "point",
    self_mobility: str = "rpb",
) -> RigidMotion:
    """[`solve`][jswim.swimmers.forcefree.solve], by unrolled elimination for small scenes (``2 N <=``
    `UNROLLED_MAX_ROWS`: one or two swimmers, or one swimmer and up to three obstacles),
    else through LAPACK. The two agree to rounding (a test checks it)."""
    n_rows = 2 * (arms.shape[0] * (arms.shape[1] + 1) + obstacles.shape[0])
    if n_rows <= UNROLLED_MAX_ROWS:
        return solve_unrolled(
            centre, tilt, arms, arm_rates, obstacles, wall, None, mobility, self_mobility
        )
    return solve(centre, tilt, arms, arm_rates, obstacles, wall, mobility, self_mobility)


def solve_unrolled(
    centre: Array,
    tilt: Array,
    arms: Array,
    arm_rates: Array,
    obstacles: Array,
    wall: bool,
    background: Array | None = None,
    mobility: str = "point",
    self_mobility: str = "rpb",
) -> RigidMotion:
    """[`solve`][jswim.swimmers.forcefree.solve] written entry by entry (Cholesky of ``M``, then of the ``3S x 3S`` Schur
    complement), so that under ``vmap`` every operation is elementwise over the batch and XLA
    fuses the whole solve; the sizes are static, the loops below run at trace time over matrix
    entries. Same arguments and result as [`solve`][jswim.swimmers.forcefree.solve]; ``background`` ``(S, n, 2)``, if given,
    is an imposed flow velocity at each swimmer sphere (the spheres then move at
    ``K xi + v = M F + background``)."""

    S, nd = arms.shape
    n = nd + 1
    O = obstacles.shape[0]
    pos_sw = sphere_centres(centre, tilt, arms)  # (S, n, 2)
    e = jnp.stack([jnp.cos(tilt), jnp.sin(tilt)], -1)
    qdot = axial_offsets(arm_rates)
    xs = [pos_sw[s, i, 0] for s in range(S) for i in range(n)] + [obstacles[o, 0] for o in range(O)]
    zs = [pos_sw[s, i, 1] for s in range(S) for i in range(n)] + [obstacles[o, 1] for o in range(O)]
    rad = [None] * (S * n) + [obstacles[o, 2] for o in range(O)]  # None: radius a = 1
    N = len(xs)
    if wall:
        zs = [jnp.maximum(z, 1.0 if r is None else r) for z, r in zip(zs, rad)]
    m = [[None] * (2 * N) for _ in range(2 * N)]
    for i in range(N):
        if wall:
            par, nor = sphere_self_factors(1.0 if rad[i] is None else rad[i], zs[i], self_mobility)
        else:
            par = nor = 1.0
        inv_r = 1.0 if rad[i] is None else 1.0 / rad[i]
        m[2 * i][2 * i] = par * inv_r + 0.0 * zs[i]
        m[2 * i + 1][2 * i + 1] = nor * inv_r + 0.0 * zs[i]
        m[2 * i + 1][2 * i] = 0.0 * zs[i]
        for j in range(i):
            mxx, mxz, mzx, mzz = pair_entries(
                xs[i] - xs[j],
                zs[i],
                zs[j],
                wall,
                mobility,
                1.0 if rad[i] is None else rad[i],
                1.0 if rad[j] is None else rad[j],
            )
            m[2 * i][2 * j], m[2 * i][2 * j + 1] = mxx, mxz
            m[2 * i + 1][2 * j], m[2 * i + 1][2 * j + 1] = mzx, mzz
    chol, inv_diag = unrolled_cholesky(m)
    # Right-hand sides: the rigid modes K (3 per swimmer) and the prescribed velocities v.
    zero = 0.0 * xs[0]
    cols = []
    for s in range(S):
        cx, cz = centre[s, 0], centre[s, 1]
        kx = [zero] * (2 * N)
        kz = [zero] * (2 * N)
        kr = [zero] * (2 * N)
        for i in range(n):
            p = s * n + i
            kx[2 * p] = 1.0 + zero
            kz[2 * p + 1] = 1.0 + zero
            kr[2 * p] = -(pos_sw[s, i, 1] - cz)
            kr[2 * p + 1] = pos_sw[s, i, 0] - cx
        cols += [kx, kz, kr]
    v = [zero] * (2 * N)
    for s in range(S):
        for i in range(n):
            p = s * n + i
            v[2 * p] = qdot[s, i] * e[s, 0]
            v[2 * p + 1] = qdot[s, i] * e[s, 1]
            if background is not None:
                v[2 * p] = v[2 * p] - background[s, i, 0]
                v[2 * p + 1] = v[2 * p + 1] - background[s, i, 1]
    sols = [unrolled_cholesky_solve(chol, inv_diag, c) for c in cols]
    sol_v = unrolled_cholesky_solve(chol, inv_diag, v)
    k3 = 3 * S
    schur = [
        [sum(cols[a][p] * sols[b][p] for p in range(2 * N)) for b in range(k3)] for a in range(k3)
    ]
    rhs = [-sum(cols[a][p] * sol_v[p] for p in range(2 * N)) for a in range(k3)]
    sc, sd = unrolled_cholesky(schur)
    xi = unrolled_cholesky_solve(sc, sd, rhs)
    forces = [sum(sols[b][p] * xi[b] for b in range(k3)) + sol_v[p] for p in range(2 * N)]
    xi_arr = jnp.stack(xi).reshape(S, 3)
    return RigidMotion(xi_arr[:, :2], xi_arr[:, 2], jnp.stack(forces).reshape(N, 2))


def solve_by_swimmer(
    centre: Array,
    tilt: Array,
    arms: Array,
    arm_rates: Array,
    wall: bool,
    forces: Array,
    mobility: str = "point",
    self_mobility: str = "rpb",
) -> RigidMotion:
    """One block Gauss-Seidel sweep of the coupled solve of ``S >= 2`` swimmers (no obstacles).

    The swimmers are solved in two colours, the even ones then the odd ones ([`red_black`][jswim.swimmers.forcefree.red_black]; a
    pair: swimmer 0, then swimmer 1), each colour at once (its one-swimmer solves vmapped: one
    traced solve whatever ``S``). Each swimmer is solved alone ([`solve_unrolled`][jswim.swimmers.forcefree.solve_unrolled], force- and torque-free exactly)
    in the flow that the other swimmers' forces make at its spheres, taking the forces of the
    swimmers already solved in this sweep and ``forces`` for the others. Repeated, it converges to
    [`solve`][jswim.swimmers.forcefree.solve]: by the swimmers' far field, ~2e-3 per sweep at D = 30 a and ~1e-5 at 60 a
    (measured for coaxial NG swimmers, free fluid and wall). The collocation's Picard sweeps
    (`jswim.scenes.collocation`) carry the forces from sweep to sweep, so the two iterations
    converge together at the cost of ``S`` one-swimmer solves per node.

    Parameters
    ----------
    centre, tilt, arms, arm_rates, wall
        As in [`solve`][jswim.swimmers.forcefree.solve].
    forces : Array (S n, 2)
        The forces of the previous sweep (zeros at the start), ordered as [`solve`][jswim.swimmers.forcefree.solve]'s.

    Returns
    -------
    RigidMotion
        With the new forces.
    """

    S, nd = arms.shape
    n = nd + 1
    pos = sphere_centres(centre, tilt, arms)  # (S, n, 2)
    if wall:
        pos = pos.at[..., 1].set(jnp.maximum(pos[..., 1], 1.0))
    no_obstacles = jnp.zeros((0, 3), arms.dtype)
    alone = jax.vmap(
        lambda c, t, a, r, bg: solve_unrolled(
            c[None],
            t[None],
            a[None],
            r[None],
            no_obstacles,
            wall,
            bg[None],
            mobility,
            self_mobility,
        )
    )

    def colour(c: int, flow: Array) -> tuple[Array, tuple[Array, Array, Array]]:
        r = alone(centre[c::2], tilt[c::2], arms[c::2], arm_rates[c::2], flow)
        f = r.forces.astype(forces.dtype)
        return f, (f, r.velocity[:, 0], r.omega[:, 0])

    f, vel, om = red_black(pos, forces.reshape(S, n, 2), colour, wall, mobility)
    return RigidMotion(vel, om, f.reshape(S * n, 2))


def red_black(pos: Array, lab: Array, colour: Any, wall: bool, mobility: str = "point") -> Any:
    """One red-black block Gauss-Seidel sweep over ``S >= 2`` swimmers: the even ones (0, 2, ...)
    at once in the others' flow, then the odd ones in the even ones' new flow (a pair: swimmer 0,
    then swimmer 1). Neighbours in a line or side by side have different colours, so the strongest
    couplings are updated as in a sweep one swimmer after the other; within a colour everything is
    arrays over its swimmers (no loop over swimmers).

    Parameters
    ----------
    pos : Array (S, n, 2)
        Sphere centres.
    lab : Array (S, n, 2)
        Lab-frame sphere forces of the previous sweep.
    colour : callable
        ``colour(c, flow) -> (new lab forces, outputs)`` solves the swimmers ``c::2`` (static
        ``c`` in 0, 1) in the flow ``(S_c, n, 2)`` at their spheres; ``outputs`` a tuple of arrays
        with a leading axis over those swimmers.
    wall, mobility
        Static: the pair blocks ([`jswim.swimmers.mobility.swimmer_blocks`][jswim.swimmers.mobility.swimmer_blocks]).

    Returns
    -------
    tuple
        ``outputs`` of both colours, in swimmer order.
    """
    S = pos.shape[0]
    pe, po = pos[0::2], pos[1::2]

    def flow(blocks: Array, f: Array) -> Array:
        if wall:  # as sums: XLA fuses them into the (unrolled, elementwise) solves that read them
            return jnp.sum(blocks * f[None, :, None, :, None, :], axis=(1, 3, 5))
        if blocks.shape[:2] == (
            1,
            1,
        ):  # one swimmer per colour (a pair): no swimmer axes in the product
            return jnp.einsum("ijab,jb->ia", blocks[0, 0], f[0])[None]
        return jnp.einsum("soijab,ojb->sia", blocks, f)

    b_eo = swimmer_blocks(pe, po, wall, mobility)  # each pair of colours once
    flow_e = flow(b_eo, lab[1::2])
    if pe.shape[0] > 1:
        flow_e = flow_e + flow(swimmer_blocks(pe, pe, wall, mobility, same=True), lab[0::2])
    new_e, out_e = colour(0, flow_e)
    flow_o = flow(transposed_blocks(b_eo), new_e)
    if po.shape[0] > 1:
        flow_o = flow_o + flow(swimmer_blocks(po, po, wall, mobility, same=True), lab[1::2])
    _, out_o = colour(1, flow_o)
    # back to swimmer order: a static permutation (none for a pair)
    order = np.argsort(np.concatenate([np.arange(0, S, 2), np.arange(1, S, 2)]), kind="stable")
    both = [jnp.concatenate([a, b], 0) for a, b in zip(out_e, out_o)]
    return tuple(v if S <= 2 else v[order] for v in both)


def is_structural_zero(v: object) -> bool:
    """A structural zero of the unrolled solves: a Python zero (not a traced value), which the
    entry-by-entry arithmetic drops instead of multiplying through."""
    return isinstance(v, float) and v == 0.0


def unrolled_cholesky(m: list) -> tuple[list, list]:
    """Lower Cholesky factor of a symmetric matrix given by its lower triangle (lists of
    scalars), with the reciprocals of its diagonal. Python zeros in ``m`` stay Python zeros where
    the factor keeps them (no fill-in), so a block-structured matrix costs what its blocks cost."""
    size = len(m)
    low = [[None] * size for _ in range(size)]
    inv_diag = [None] * size
    for p in range(size):
        for q in range(p + 1):
            acc = m[p][q]
            for k in range(q):
                if not (is_structural_zero(low[p][k]) or is_structural_zero(low[q][k])):
                    acc = acc - low[p][k] * low[q][k]
            if p == q:
                inv_diag[p] = jax.lax.rsqrt(jnp.asarray(acc))
                low[p][p] = acc * inv_diag[p]
            else:
                low[p][q] = 0.0 if is_structural_zero(acc) else acc * inv_diag[q]
    return low, inv_diag


def unrolled_cholesky_solve(low: list, inv_diag: list, b: list) -> list:
    """``x`` with ``L L^T x = b`` (forward then back substitution, lists of scalars; Python zeros
    in ``L`` and ``b`` are skipped)."""
    size = len(b)
    y = [None] * size
    for p in range(size):
        acc = b[p]
        for k in range(p):
            if not (is_structural_zero(low[p][k]) or is_structural_zero(y[k])):
                acc = acc - low[p][k] * y[k]
        y[p] = 0.0 if is_structural_zero(acc) else acc * inv_diag[p]
    x = [None] * size
    for p in reversed(range(size)):
        acc = y[p]
        for k in range(p + 1, size):
            if not (is_structural_zero(low[k][p]) or is_structural_zero(x[k])):
                acc = acc - low[k][p] * x[k]
        x[p] = 0.0 if is_structural_zero(acc) else acc * inv_diag[p]
    return x
