"""Work per step: the energy a step's stroke dissipates in the fluid, and its exact tables.

A step lasts one time unit ``tau`` whatever its ROC: the DOF moves at ``|d_dot| = |ROC| (hi -
lo) / tau`` until it has moved ``ROC x (hi - lo)`` or reaches a limit (the motors' path of
[`jswim.env.stepping`][jswim.env.stepping]), then holds still. The work of the step is the
integral of the power ([`jswim.swimmers.dissipation.power`][jswim.swimmers.dissipation.power])
over that path, computed with the integrator that computes the step's motion: Clenshaw-Curtis
quadrature on the Chebyshev-Lobatto nodes of [`jswim.integrate.chebyshev_rule`][jswim.integrate.chebyshev_rule]
(the last row of its running-integral matrix), spectrally accurate for the smooth integrand.

Because the power is quadratic in the rate and the time a move takes is inversely proportional
to it, a move along a given path costs ``|ROC|`` times what it costs at ``|ROC| = 1``: halving
the rate halves the work. A reciprocal stroke (a move and its reverse) costs twice the move, not
zero: dissipation is even under time reversal.

Units: work in ``xi_par a^3 / tau`` (link swimmers; ``xi_par`` of the bulk fluid, ``a`` the link
length) or ``6 pi mu a^3 / tau`` (sphere swimmers, ``a`` the sphere radius), ``tau`` the duration
of one step.

Tables, like the step tables of `jswim.env.step_tables` and indexed the same way:
[`corner_work_table`][jswim.env.work.corner_work_table] (the paper's world, K = 1) and
[`lattice_work_table`][jswim.env.work.lattice_work_table] (the K lattice).
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.env.table_cache import cached, model_key
from jswim.env.state import corner_values
from jswim.env.step_tables import TABLE_DEGREE, lattice_moves, lattice_rows
from jswim.integrate import chebyshev_rule
from jswim.swimmers.dissipation import power
from jswim.swimmers.models import SwimmerModel


def stroke_work(
    model: SwimmerModel, d0: Array, d_dot: Array, duration: Array | float, n_sub: int = TABLE_DEGREE
) -> Array:
    """Work of the straight stroke from shape ``d0`` at constant rate ``d_dot`` for ``duration``.

    Parameters
    ----------
    model : SwimmerModel
    d0, d_dot : Array, shape (n_dof,)
        Start shape and constant rate (per time unit ``t``).
    duration : float
        Time of the stroke, in ``t``.
    n_sub : int
        Degree of the Chebyshev-Lobatto rule (``n_sub + 1`` power evaluations); the default, the
        tables' degree, is exact to rounding for the paper's swimmers.

    Returns
    -------
    Array, shape ()
        ``int_0^duration power(d0 + d_dot s, d_dot) ds``, in ``xi_par a^3 / t`` (links) or
        ``6 pi mu a^3 / t`` (spheres); dtype of ``d0``. Works under ``jit`` and ``vmap``.
    """
    d0 = jnp.asarray(d0)
    d_dot = jnp.asarray(d_dot, d0.dtype)
    nodes, running = chebyshev_rule(n_sub)
    duration = jnp.asarray(duration, d0.dtype)
    t = jnp.asarray(nodes, d0.dtype) * duration
    p = jax.vmap(lambda tk: power(model, d0 + d_dot * tk, d_dot))(t)
    # Products and sums, not a dot: the same numbers, and no mixed-precision dot under x64.
    return jnp.sum(jnp.asarray(running[-1], d0.dtype) * p) * duration


def step_work(model: SwimmerModel, s0: Array, rocs: Array, n_sub: int = TABLE_DEGREE) -> Array:
    """Work of one step of ROC vector ``rocs`` from shape fractions ``s0`` (in ``xi_par a^3 /
    tau`` or ``6 pi mu a^3 / tau``).

    The path is the motors' ``clip(s0 + rocs t, 0, 1)``, ``t`` in ``[0, 1]`` (units of ``tau``):
    straight until a DOF reaches its limit, then bent (one straight piece per DOF). Several
    non-zero ROCs make a diagonal stroke; a one-DOF step has one non-zero entry.

    Parameters
    ----------
    model : SwimmerModel
    s0 : Array, shape (n_dof,)
        Start shape as fractions of the range, in [0, 1].
    rocs : Array, shape (n_dof,)
        ROC of each DOF, in [-1, 1].

    Returns
    -------
    Array, shape ()
        The step's work; 0 for a step that moves nothing (ROC 0, or a push at a limit).
    """
    s0 = jnp.asarray(s0)
    rocs = jnp.asarray(rocs, s0.dtype)
    span = model.hi - model.lo
    room = jnp.where(rocs > 0, 1.0 - s0, s0)
    hit = jnp.where(
        rocs != 0, jnp.clip(room / jnp.where(rocs != 0, jnp.abs(rocs), 1.0), 0.0, 1.0), 1.0
    )
    times = jnp.concatenate([jnp.zeros(1, s0.dtype), jnp.sort(hit)])
    total = jnp.zeros((), s0.dtype)
    for i in range(model.n_dof):  # one straight piece between consecutive limit times
        ta, tb = times[i], times[i + 1]
        rate = jnp.where(hit >= tb, rocs, 0.0) * span
        start = jnp.clip(s0 + rocs * ta, 0.0, 1.0)
        total = total + stroke_work(model, corner_values(model, start), rate, tb - ta, n_sub)
    return total


@functools.lru_cache(maxsize=64)
def corner_work_table(model: SwimmerModel) -> np.ndarray:
    """Work of every step of the paper's world (K = 1), float64, ``xi_par a^3 / tau`` or ``6 pi
    mu a^3 / tau``.

    Row ``c n + k`` (``c = sum_m l_m 2^m`` the corner, ``k`` the DOF moved to its other level,
    the rows of the corner step table) and a last row 0 for a step that moves nothing: the
    indexing of the stepping's corner rows, so ``corner_work_table(model)[row]`` is the step's
    work.

    Returns
    -------
    ndarray, shape (2**n_dof * n_dof + 1,)
    """
    n = model.n_dof
    rows = lattice_work_table(model, 1).reshape(2**n, n, 2)
    corners = np.array([[(c >> k) & 1 for k in range(n)] for c in range(2**n)])
    # The lattice row of the move of DOF k from level l_k goes to level 1 - l_k.
    flipped = np.take_along_axis(rows, (1 - corners)[:, :, None], axis=2)[:, :, 0]
    return np.concatenate([flipped.reshape(-1), [0.0]])


@functools.lru_cache(maxsize=64)
def lattice_work_table(model: SwimmerModel, roc_levels: int) -> np.ndarray:
    """Work of every one-DOF move on the K lattice at the ROC that lands on its end, float64.

    Row ``(i n + k)(K + 1) + j'`` (``i = sum_m j_m (K+1)^m`` the start shape, ``k`` the DOF,
    ``j'`` its new lattice value) as in `jswim.env.step_tables.lattice_table`:
    the move ``j_k -> j'`` at ``|ROC| = |j' - j_k| / K``, which takes the whole step. A push
    clipped at a limit (requested ``|ROC| = |q| / K`` larger than ``|j' - j_k| / K``) moves faster
    and stops early: its work is the row times ``|q| / |j' - j_k|``
    ([`lattice_step_work`][jswim.env.work.lattice_step_work]). Rows with ``j' = j_k`` are 0.

    Returns
    -------
    ndarray, shape (lattice_rows(model, K),)
    """
    return cached(
        "work",
        f"{model_key(model)}|K={roc_levels}|deg={TABLE_DEGREE}",
        lambda: {"rows": _build_lattice_work(model, roc_levels)},
        {"rows": (lattice_rows(model, roc_levels),)},
    )["rows"]


def _build_lattice_work(model: SwimmerModel, roc_levels: int) -> np.ndarray:
    big_k = roc_levels
    start, end = lattice_moves(model.n_dof, roc_levels)
    span = model.hi - model.lo
    with jax.ensure_compile_time_eval(), jax.enable_x64(True):

        def one(a: Array, b: Array) -> Array:
            return stroke_work(model, corner_values(model, a), (b - a) * span, 1.0)

        rows = jax.jit(jax.vmap(one))(jnp.asarray(start / big_k), jnp.asarray(end / big_k))
        return np.asarray(rows, np.float64)


def lattice_step_work(
    model: SwimmerModel, roc_levels: int, levels: Array, dof: Array, k: Array
) -> Array:
    """Work of the lattice step ``(dof, ROC k / K)`` from lattice shape ``levels``, read from
    [`lattice_work_table`][jswim.env.work.lattice_work_table] (float64; call under
    ``jax.enable_x64`` to keep it so). Works under ``jit`` and ``vmap``.

    Parameters
    ----------
    model : SwimmerModel
    roc_levels : int
        K (static).
    levels : int Array, shape (n_dof,)
        Lattice values ``j`` in ``0..K`` of the start shape.
    dof : int Array, shape ()
        The DOF moved (0-based).
    k : int Array, shape ()
        Requested ROC in lattice units, in ``-K..K``.
    """
    n, big_k = model.n_dof, roc_levels
    levels = jnp.asarray(levels, jnp.int32)
    onehot = jnp.arange(n, dtype=jnp.int32) == dof
    j = jnp.sum(jnp.where(onehot, levels, 0))
    j_end = jnp.clip(j + k, 0, big_k)
    shape = jnp.sum(levels * (big_k + 1) ** jnp.arange(n, dtype=jnp.int32))
    row = (shape * n + dof) * (big_k + 1) + j_end
    moved = jnp.abs(j_end - j)
    table = jnp.asarray(lattice_work_table(model, big_k))
    scale = jnp.abs(k) / jnp.maximum(moved, 1)
    return jnp.where(moved > 0, table[row] * scale, 0.0)


def lighthill_efficiency(displacement: float, work: float, steps: int, bodies: int) -> float:
    """Lighthill's efficiency of a run: ``C X^2 / (N W)``.

    The power of towing the rigid, straight swimmer at the run's mean speed ``U = X / (N tau)``
    is ``C U^2``; the strokes spent ``W / (N tau)`` on average; their ratio is the efficiency
    (Lighthill 1975; Tam & Hosoi, Phys. Rev. Lett. 98, 068105, 2007, for Purcell's swimmer).
    ``C`` is the straight swimmer's axial drag: ``bodies x xi_par a`` for straight links,
    ``bodies x 6 pi mu a`` for isolated spheres, so in the units of
    [`jswim.env.work`][jswim.env.work] it is ``bodies``. One square-gait cycle (``N = 4``)
    gives the page's ``3 dX^2 / (4 W)`` (docs/physics.md, *Energy and turning*).

    Parameters
    ----------
    displacement : float
        X, the run's displacement (a).
    work : float
        W, its total work (``xi_par a^3 / tau`` or ``6 pi mu a^3 / tau``); must be > 0.
    steps : int
        N, its number of steps (each lasts ``tau``).
    bodies : int
        Links or spheres of the swimmer (``n_dof + 1`` for a chain or a collinear sphere
        swimmer).

    Raises
    ------
    ValueError
        If ``work <= 0`` or ``steps < 1``.
    """
    if not work > 0 or steps < 1:
        raise ValueError(f"efficiency needs work > 0 and steps >= 1, got {work} and {steps}")
    return bodies * displacement**2 / (steps * work)
