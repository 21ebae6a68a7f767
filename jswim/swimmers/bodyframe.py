"""A swimmer's force-free response in the unbounded fluid, in its own frame: a function of the
arms alone, so one factorisation serves every pose and every sweep of a step.

In the frame of swimmer ``s`` (axis ``e = (cos t, sin t)``, normal ``n = (-sin t, cos t)``) its
spheres sit at ``q_i e`` (``q`` the cumulative arm lengths from the reference sphere), and the
rigid modes and prescribed velocities of [`jswim.swimmers.forcefree`][jswim.swimmers.forcefree] depend on the arms only:

* ``K'``: sphere ``i`` moves by ``(U_e, U_n + q_i Omega)`` for a rigid motion ``xi' = (U_e, U_n, Omega)``;
* ``v'``: sphere ``i`` moves by ``(qdot_i, 0)`` for the arm rates.

So does the swimmer's own mobility ``M'``: its spheres are collinear, and the Oseen block of two
spheres ``r`` apart along ``e`` is ``(3/4)(I + e e) / r``, i.e. ``(3/4) diag(2, 1) / r`` in this
frame. With ``b'`` the flow that the other swimmers' forces make at its spheres, the swimmer alone
obeys ``M' F' = K' xi' + w'``, ``K'^T F' = 0``, ``w' = v' - b'``; eliminating ``F'``,

    ``F' = P w'``, ``xi' = Q w'``,  ``G = M'^-1 K'``, ``S = K'^T G``, ``Q = -S^-1 G^T``, ``P = M'^-1 + G Q``

(``K'^T P = 0``: every ``F' = P w'`` is force- and torque-free exactly). [`response`][jswim.swimmers.bodyframe.response] builds
``(P, Q)`` from the arms (per collocation node); [`sweep`][jswim.swimmers.bodyframe.sweep] then solves the swimmers one after
the other in each other's flow (block Gauss-Seidel) for the cost of that flow and two small
products per swimmer. Above a wall ``M'`` depends on the height and tilt too, so wall scenes solve
afresh at every pose ([`jswim.swimmers.forcefree.solve_by_swimmer`][jswim.swimmers.forcefree.solve_by_swimmer]).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
from jax import Array

from jswim.swimmers.forcefree import (
    unrolled_cholesky_solve,
    unrolled_cholesky,
    is_structural_zero,
    axial_offsets,
    red_black,
    sphere_centres,
)
from jswim.swimmers.mobility import OSEEN_PREFACTOR


class Response(NamedTuple):
    """``F' = P w'``, ``xi' = Q w'`` for swimmers of ``n`` spheres (body frame, see the module)."""

    p: Array  # (..., 2n, 2n) rows and columns (e_0, n_0, e_1, n_1, ...), symmetric
    q: Array  # (..., 3, 2n) rows (U_e, U_n, Omega)


def response(arms: Array, mobility: str = "point") -> Response:
    """``(P, Q)`` of every swimmer alone in the unbounded fluid.

    Parameters
    ----------
    arms : Array (S, n_dof)
        Arm lengths, units of ``a``.
    mobility : str
        Static: ``"point"`` (Oseen) or ``"rpy"`` (Rotne-Prager-Yamakawa) blocks between the spheres.

    Returns
    -------
    Response
        ``p`` ``(S, 2n, 2n)``, ``q`` ``(S, 3, 2n)`` (``n = n_dof + 1``) in the dtype of ``arms``,
        in units of ``6 pi mu a`` (forces per velocity) and of ``1`` and ``1 / a`` (rigid motion
        per velocity). Works under ``jit`` and ``vmap`` (mapped over the swimmers here).
    """
    p, q = jax.vmap(lambda a: _one_response(a, mobility))(arms)
    return Response(p, q)


def sweep(
    centre: Array,
    tilt: Array,
    arms: Array,
    arm_rates: Array,
    resp: Response,
    forces: Array,
    mobility: str = "point",
) -> tuple[Array, Array]:
    """One block Gauss-Seidel sweep over the swimmers in the unbounded fluid (no obstacles).

    The swimmers are solved in two colours ([`jswim.swimmers.forcefree.red_black`][jswim.swimmers.forcefree.red_black]), the even
    ones (0, 2, ...) then the odd ones, each colour at once (arrays over its swimmers): each
    swimmer alone, exactly, in the flow that the other swimmers' forces make at its spheres, the
    odd ones taking the even ones' new forces (a pair: swimmer 0, then swimmer 1 in swimmer 0's
    new flow). Repeated, it converges to the coupled
    solve ([`jswim.swimmers.forcefree.solve`][jswim.swimmers.forcefree.solve]) by the far field: ~2e-3 per sweep at D = 30 a.
    One swimmer: one sweep is its exact solve.

    Parameters
    ----------
    centre, tilt, arms, arm_rates : Array (S, 2), (S,), (S, n_dof), (S, n_dof)
        Reference-sphere centres and axis angles (units of ``a``, rad), arms and arm rates.
    resp : Response
        [`response`][jswim.swimmers.bodyframe.response] of these arms.
    forces : Array (S, n, 2)
        Body-frame sphere forces ``F'`` of the previous sweep (zeros at the start).
    mobility : str
        Static: the pair blocks between the swimmers, as for [`response`][jswim.swimmers.bodyframe.response].

    Returns
    -------
    (forces, xi)
        The new ``F'`` ``(S, n, 2)`` and the rigid motions ``xi'`` ``(S, 3)``: velocity along the
        axis and normal to it, and ``d tilt / dt``.
    """
    S = arms.shape[0]
    pos = sphere_centres(centre, tilt, arms)  # (S, n, 2)
    e = jnp.stack([jnp.cos(tilt), jnp.sin(tilt)], -1)  # (S, 2) axis
    nrm = jnp.stack([-e[:, 1], e[:, 0]], -1)  # (S, 2) normal
    qdot = axial_offsets(arm_rates)
    if S == 1:  # alone: no flow from others (static)
        w = jnp.stack([qdot[0], jnp.zeros_like(qdot[0])], -1).reshape(-1)
        f = (resp.p[0] @ w).reshape(-1, 2)
        return f[None].astype(forces.dtype), (resp.q[0] @ w)[None].astype(forces.dtype)

    def colour(c: int, flow: Array) -> tuple[Array, tuple[Array, Array]]:
        ec, nc = e[c::2, None, :], nrm[c::2, None, :]
        along, normal = (
            jnp.einsum("sia,sa->si", flow, e[c::2]),
            jnp.einsum("sia,sa->si", flow, nrm[c::2]),
        )
        w = jnp.stack([qdot[c::2] - along, -normal], -1).reshape(flow.shape[0], -1)  # v' - b'

        # The products are dots, which XLA:CPU keeps unfused: written as sums they fuse with
        # everything before them, and each force of the next colour recomputes this colour's
        # whole solve (measured ~40x slower for the P products, 2x for the flow's projections).
        f = jnp.einsum("spq,sq->sp", resp.p[c::2], w).reshape(w.shape[0], -1, 2)
        xi = jnp.einsum("saq,sq->sa", resp.q[c::2], w)
        return f[..., :1] * ec + f[..., 1:] * nc, (f.astype(forces.dtype), xi.astype(forces.dtype))

    lab = forces[..., :1] * e[:, None, :] + forces[..., 1:] * nrm[:, None, :]  # (S, n, 2)
    return red_black(pos, lab, colour, False, mobility)


def _one_response(arms: Array, mobility: str = "point") -> tuple[Array, Array]:
    """``(P, Q)`` of one swimmer, ``(2n, 2n)`` and ``(3, 2n)``, entry by entry: the exact zeros of
    ``M'`` (axis and normal do not couple) are Python zeros, which the elimination skips."""
    nd = arms.shape[0]
    n = nd + 1
    q = axial_offsets(arms)
    qs = [0.0 if i == nd // 2 else q[i] for i in range(n)]  # the reference sphere is at q = 0
    size = 2 * n
    m = [[None] * size for _ in range(size)]  # lower triangle of M'
    for i in range(n):
        m[2 * i][2 * i], m[2 * i + 1][2 * i], m[2 * i + 1][2 * i + 1] = 1.0, 0.0, 1.0
        for j in range(i):
            inv_r = 1.0 / (q[i] - q[j])
            axial, normal = 2.0 * OSEEN_PREFACTOR * inv_r, OSEEN_PREFACTOR * inv_r
            if (
                mobility == "rpy"
            ):  # collinear unit spheres: (3/4)/r [(1 + 2/(3r^2)) I + (1 - 2/r^2) e e]
                inv_r3 = inv_r * inv_r * inv_r
                axial, normal = axial - inv_r3, normal + 0.5 * inv_r3
            m[2 * i][2 * j], m[2 * i][2 * j + 1] = axial, 0.0
            m[2 * i + 1][2 * j], m[2 * i + 1][2 * j + 1] = 0.0, normal
    low, inv_diag = unrolled_cholesky(m)
    minv = [
        unrolled_cholesky_solve(low, inv_diag, [1.0 if r == col else 0.0 for r in range(size)])
        for col in range(size)
    ]
    # G = M'^-1 K' (size x 3): the columns of K' are sums of unit columns (and q_i times them)
    g = [
        [
            _sum(minv[2 * i][p] for i in range(n)),
            _sum(minv[2 * i + 1][p] for i in range(n)),
            _sum(_mul(qs[i], minv[2 * i + 1][p]) for i in range(n)),
        ]
        for p in range(size)
    ]
    k_rows = [[1.0, 0.0, 0.0] if p % 2 == 0 else [0.0, 1.0, qs[p // 2]] for p in range(size)]
    schur = [
        [_sum(_mul(k_rows[p][a], g[p][b]) for p in range(size)) for b in range(3)] for a in range(3)
    ]
    sl, sd = unrolled_cholesky(schur)
    h = [
        unrolled_cholesky_solve(sl, sd, g[p]) for p in range(size)
    ]  # h[p] = S^-1 G^T e_p, so Q[:, p] = -h[p]
    p_mat = [
        [
            _plus(minv[col][row], _sum(-_mul(g[row][a], h[col][a]) for a in range(3)))
            for col in range(size)
        ]
        for row in range(size)
    ]
    q_mat = [
        [0.0 if is_structural_zero(h[col][a]) else -h[col][a] for col in range(size)]
        for a in range(3)
    ]
    zero = jnp.zeros((), arms.dtype)
    as_array = lambda rows: jnp.stack([jnp.stack([zero + v for v in r]) for r in rows]).astype(
        arms.dtype
    )
    return as_array(p_mat), as_array(q_mat)


def _mul(a, b):
    return 0.0 if is_structural_zero(a) or is_structural_zero(b) else a * b


def _plus(a, b):
    return b if is_structural_zero(a) else (a if is_structural_zero(b) else a + b)


def _sum(values) -> object:
    acc = 0.0
    for v in values:
        acc = _plus(acc, v)
    return acc
