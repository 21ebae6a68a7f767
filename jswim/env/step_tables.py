"""Exact step tables, built once per model in float64.

The corner table holds the paper's discrete world: every corner-to-corner one-DOF move.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.env.table_cache import cached, model_key
from jswim.env.state import corner_values
from jswim.integrate import centroid, integrate_stroke
from jswim.swimmers.models import SwimmerModel

#: Chebyshev degree used to build the step table (error ~1e-15 relative, see tests).
TABLE_DEGREE = 32


@functools.lru_cache(maxsize=64)
def step_table(model: SwimmerModel) -> tuple[np.ndarray, np.ndarray]:
    """Exact body-frame step increments of ``model`` (float64, built once per model).

    Returns
    -------
    increments : ndarray, shape (2**n_dof, n_dof, 3)
        For the corner with levels ``l`` (index ``sum_k l_k 2**k``) and a move of DOF ``k`` to the
        opposite level: centroid displacement ``(dx, dy)`` in the body frame at the start of the
        step, and the change of orientation.
    offsets : ndarray, shape (2**n_dof, 2)
        Centroid minus reference point, body frame, per corner.
    """
    n = model.n_dof
    out = cached(
        "corner",
        model_key(model),
        lambda: dict(zip(("inc", "offs"), _build_step_table(model))),
        {"inc": (2**n, n, 3), "offs": (2**n, 2)},
    )
    return out["inc"], out["offs"]


def _build_step_table(model: SwimmerModel) -> tuple[np.ndarray, np.ndarray]:
    n = model.n_dof
    corners = np.array([[(c >> k) & 1 for k in range(n)] for c in range(2**n)], np.float64)
    # Evaluate now even when first called while tracing a step (the table is a constant).
    with jax.ensure_compile_time_eval(), jax.enable_x64(True):
        lv = jnp.asarray(np.repeat(corners, n, axis=0))  # (2**n * n, n)
        dof = jnp.tile(jnp.arange(n), 2**n)
        sign = 1.0 - 2.0 * lv[jnp.arange(lv.shape[0]), dof]  # lo -> +1, hi -> -1
        rate = jax.nn.one_hot(dof, n, dtype=jnp.float64) * sign[:, None]
        d0 = corner_values(model, lv)
        d1 = d0 + rate * model.duration

        def one(a: Array, r: Array, b: Array) -> Array:
            pose = integrate_stroke(model, a, r, model.duration, n_sub=TABLE_DEGREE)
            disp = centroid(model, b, pose) - centroid(model, a, jnp.zeros(3))
            return jnp.concatenate([disp, pose[2:]])

        inc = jax.jit(jax.vmap(one))(d0, rate, d1)
        offs = jax.vmap(model.centroid_offset)(corner_values(model, jnp.asarray(corners)))
        return np.asarray(inc).reshape(2**n, n, 3), np.asarray(offs)


def corner_index(levels: Array) -> Array:
    """The corner of the DOF cube at ``levels`` (0/1 per DOF, last axis) as a binary number, DOF 1
    the lowest bit: the corner table's row block (int32)."""
    return jnp.sum(
        levels * (2 ** jnp.arange(levels.shape[-1], dtype=jnp.int32)), axis=-1, dtype=jnp.int32
    )


@functools.lru_cache(maxsize=64)
def _flat_table(model: SwimmerModel) -> np.ndarray:
    """Step table as rows ``(dx, dy, dtheta, cos dtheta, sin dtheta)`` indexed by corner*n + dof."""
    inc = step_table(model)[0].reshape(-1, 3)
    return np.concatenate([inc, np.cos(inc[:, 2:]), np.sin(inc[:, 2:])], axis=1)


@functools.lru_cache(maxsize=64)
def step_rows(model: SwimmerModel) -> np.ndarray:
    """The corner table as rows ``(dx, dy, dtheta, cos dtheta, sin dtheta)`` (float64), indexed by
    ``corner * n_dof + dof``, plus a last row for a step that moves nothing (`still_row`)."""
    return np.concatenate([_flat_table(model), [[0.0, 0.0, 0.0, 1.0, 0.0]]])


def still_row(model: SwimmerModel) -> int:
    """The index of `step_rows`' last row, the step that moves nothing (``2**n_dof * n_dof``)."""
    return 2**model.n_dof * model.n_dof


#: Largest lattice table built (rows); beyond it lattice steps go through the integrator.
MAX_LATTICE_ROWS = 200_000


def lattice_rows(model: SwimmerModel, roc_levels: int) -> int:
    """Rows of the lattice table of ``model`` at K = ``roc_levels``: ``(K+1)^n n (K+1)``."""
    return (roc_levels + 1) ** model.n_dof * model.n_dof * (roc_levels + 1)


@functools.lru_cache(maxsize=64)
def lattice_table(model: SwimmerModel, roc_levels: int) -> np.ndarray:
    """Exact body-frame rows of every one-DOF move on the K lattice (float64, built once).

    The K lattice holds the shapes whose DOFs sit at ``lo + (j / K)(hi - lo)``, ``j`` in
    ``0..K``. Row ``(i n + k)(K + 1) + j'`` (``i = sum_m j_m (K+1)^m`` the start shape, ``k`` the
    DOF, ``j'`` its new lattice value) holds ``(dx, dy, dtheta, cos dtheta, sin dtheta)`` of the
    centroid in the body frame at the start, like the corner table (`step_table`; the
    lattice table at K = 1 holds the same moves). Rows for ``j' = j_k`` are the identity.

    Returns
    -------
    ndarray, shape (lattice_rows(model, K), 5)
    """
    return cached(
        "lattice",
        f"{model_key(model)}|K={roc_levels}|deg={TABLE_DEGREE}",
        lambda: {"rows": _build_lattice_table(model, roc_levels)},
        {"rows": (lattice_rows(model, roc_levels), 5)},
    )["rows"]


def lattice_moves(n_dof: int, roc_levels: int) -> tuple[np.ndarray, np.ndarray]:
    """Every move of the K lattice in table-row order: its start and end levels.

    Row ``(i (n_dof (K + 1)) + dof (K + 1) + j)`` moves DOF ``dof`` of lattice point ``i`` to
    level ``j``; point ``i`` has level ``j_m`` of DOF ``m`` at digit ``m`` of ``i`` in base
    ``K + 1`` (``i = sum_m j_m (K + 1)^m``).

    Returns
    -------
    start, end : int ndarrays, shape (lattice_rows, n_dof)
        Levels ``0..K`` before and after the move.
    """
    n, big_k = n_dof, roc_levels
    shapes = np.stack(np.meshgrid(*[np.arange(big_k + 1)] * n, indexing="ij"), -1)[
        ..., ::-1
    ].reshape(-1, n)
    start = np.repeat(shapes, n * (big_k + 1), axis=0)
    dof = np.tile(np.repeat(np.arange(n), big_k + 1), len(shapes))
    end = start.copy()
    end[np.arange(len(end)), dof] = np.tile(np.arange(big_k + 1), len(shapes) * n)
    return start, end


def _build_lattice_table(model: SwimmerModel, roc_levels: int) -> np.ndarray:
    big_k = roc_levels
    start, end = lattice_moves(model.n_dof, roc_levels)
    span = model.hi - model.lo
    with jax.ensure_compile_time_eval(), jax.enable_x64(True):

        def one(a: Array, b: Array) -> Array:
            d0, d1 = corner_values(model, a), corner_values(model, b)
            pose = integrate_stroke(model, d0, (b - a) * span, 1.0, n_sub=TABLE_DEGREE)
            disp = centroid(model, d1, pose) - centroid(model, d0, jnp.zeros(3))
            return jnp.stack([disp[0], disp[1], pose[2], jnp.cos(pose[2]), jnp.sin(pose[2])])

        rows = jax.jit(jax.vmap(one))(jnp.asarray(start / big_k), jnp.asarray(end / big_k))
        return np.asarray(rows)
