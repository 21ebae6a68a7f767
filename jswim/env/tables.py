"""Exact step tables, built once per model in float64.

The corner table holds the paper's discrete world: every corner-to-corner one-DOF move.
"""

from __future__ import annotations

import functools

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

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


def _corner_index(levels: Array) -> Array:
    return jnp.sum(levels * (2 ** jnp.arange(levels.shape[-1], dtype=jnp.int32)), axis=-1, dtype=jnp.int32)


@functools.lru_cache(maxsize=64)
def _flat_table(model: SwimmerModel) -> np.ndarray:
    """Step table as rows ``(dx, dy, dtheta, cos dtheta, sin dtheta)`` indexed by corner*n + dof."""
    inc = step_table(model)[0].reshape(-1, 3)
    return np.concatenate([inc, np.cos(inc[:, 2:]), np.sin(inc[:, 2:])], axis=1)


@functools.lru_cache(maxsize=64)
def _step_rows(model: SwimmerModel) -> np.ndarray:
    """:func:`_flat_table` (float64) plus a last row for a step that moves nothing."""
    return np.concatenate([_flat_table(model), [[0.0, 0.0, 0.0, 1.0, 0.0]]])


def _still_row(model: SwimmerModel) -> int:
    return 2**model.n_dof * model.n_dof
