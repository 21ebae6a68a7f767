"""Scene actions: ``(swimmer, dof, roc)``, and their integer codes for discrete agents.

A step takes ``action = (swimmer, dof, roc)``: ``swimmer`` (int, 0-based), ``dof`` (int, 0 = d1,
1 = d2) and ``roc`` (float in [-1, 1]: the fraction of the arm range ``d_max - d_min`` to move
it by). With K = ``params.roc_levels``, integer code
``c = (swimmer * 2 + dof) * (2K + 1) + (k + K)`` means ROC ``k / K``, ``k`` in ``-K..K``; for one
swimmer and K = 1 these are the environment's codes ``(dof - 1) * 3 + roc + 1``.
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
from jax import Array

from jswim.action_codes import decode_action, encode_action


def encode_scene_action(swimmer: Any, dof: Any, k: Any, roc_levels: int = 1) -> Any:
    """Integer code of swimmer ``swimmer`` (0-based), ``dof`` (0-based) at ROC ``k / K``."""
    return encode_action(swimmer * 2 + dof + 1, k, roc_levels)


def decode_scene_action(code: Array, roc_levels: int = 1) -> tuple[Array, Array, Array]:
    """``(swimmer, dof, roc)`` of integer codes (jit-friendly; roc as a float ``k / K``)."""
    joint, k = decode_action(jnp.asarray(code, jnp.int32), roc_levels)
    return (joint - 1) // 2, (joint - 1) % 2, k.astype(jnp.result_type(float)) / roc_levels


def split_action(action: Any) -> tuple[Array, Array, Array]:
    """``(swimmer, dof, roc)`` from a 3-tuple of arrays or an array ``(..., 3)``."""
    if isinstance(action, (tuple, list)):
        sw, dof, roc = action
        return jnp.asarray(sw, jnp.int32), jnp.asarray(dof, jnp.int32), jnp.asarray(roc)
    a = jnp.asarray(action)
    if a.shape[-1:] != (3,):
        raise ValueError(f"a scene action is (swimmer, dof, roc), got shape {a.shape}")
    return a[..., 0].astype(jnp.int32), a[..., 1].astype(jnp.int32), a[..., 2]
