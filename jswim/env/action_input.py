"""Actions: a DOF and a rate of change ROC in [-1, 1].

Two encodings reach [`jswim.env.step`][jswim.env.stepping.step] (docs/continuous.md, "Actions"): an **integer code**
``(dof - 1) (2K + 1) + (k + K)`` (``K = params.roc_levels``; DOF ``dof`` 1-based, ROC ``k / K``;
K = 1 gives the paper's codes), or a **float ROC vector** ``(n_dof,)``, entry ``i`` DOF ``i + 1``'s
ROC (at most one non-zero unless ``params.diagonal``). The *action sets* offered to agents
(``"all"`` / ``"shape-changing"``) live in [`jswim.action_codes`][jswim.action_codes].
"""

from __future__ import annotations

from typing import Any

import numpy as np

from jswim.action_codes import decode_action, encode_action, n_actions  # noqa: F401  (the one codec, JAX-free)
from jswim.errors import ConfigError

#: Rates of change an action may carry in the paper's discrete world (K = 1).
ROCS = (-1, 0, 1)


def roc_vector(dof: int, roc: float, n_dof: int) -> np.ndarray:
    """Float ROC vector (float64, shape ``(n_dof,)``) moving DOF ``dof`` (1-based) at ``roc``."""
    out = np.zeros(n_dof)
    out[dof - 1] = roc
    return out


def validate_actions(actions: Any, n_dof: int) -> np.ndarray:
    """Check ``(dof, roc)`` pairs (last axis of size 2) of the paper's discrete world and return
    their action codes (K = 1)."""
    arr = np.asarray(actions)
    if arr.ndim < 1 or arr.shape[-1] != 2 or not np.issubdtype(arr.dtype, np.number):
        raise ConfigError("actions must be (dof, roc) pairs, shape (steps, 2) or (batch, steps, 2)")
    if not np.all(arr == np.round(arr)):
        raise ConfigError("actions must be integers: dof in 1..n_dof, roc in {-1, 0, 1}")
    dof, roc = arr[..., 0].astype(int), arr[..., 1].astype(int)
    _check_dofs(dof, n_dof)
    if np.any(np.abs(roc) > 1):
        raise ConfigError(
            f"action roc must be -1, 0 or 1, got {sorted(set(roc[np.abs(roc) > 1].tolist()))}"
        )
    return encode_action(dof, roc).astype(np.int32)


def validate_moves(actions: Any, n_dof: int) -> np.ndarray | None:
    """Check ``(dof, roc)`` pairs with real ROCs and return them as float64 ROC vectors.

    Returns
    -------
    ndarray (..., n_dof) float64, or None
        ``None`` when every ROC is -1, 0 or 1 (the discrete world:
        use [`validate_actions`][jswim.env.action_input.validate_actions]); otherwise one ROC vector per pair.

    Raises
    ------
    ConfigError
        Not pairs, a DOF outside ``1..n_dof``, or a ROC that is not a finite number in [-1, 1].
    """
    try:
        arr = np.asarray(actions, np.float64)
    except (TypeError, ValueError):
        raise ConfigError("actions must be (dof, roc) pairs of numbers") from None
    if arr.ndim < 1 or arr.shape[-1] != 2:
        raise ConfigError("actions must be (dof, roc) pairs, shape (steps, 2) or (batch, steps, 2)")
    dof_f, roc = arr[..., 0], arr[..., 1]
    if not np.all(np.isfinite(arr)) or not np.all(dof_f == np.round(dof_f)):
        raise ConfigError(
            f"actions must be (dof, roc) pairs: dof one of the integers 1..{n_dof}, roc a finite number in [-1, 1]"
        )
    dof = dof_f.astype(int)
    _check_dofs(dof, n_dof)
    bad = np.abs(roc) > 1
    if np.any(bad):
        raise ConfigError(f"action roc must lie in [-1, 1], got {sorted(set(roc[bad].tolist()))}")
    if np.all(np.isin(roc, (-1.0, 0.0, 1.0))):
        return None
    return np.eye(n_dof)[dof - 1] * roc[..., None]


def _check_dofs(dof: np.ndarray, n_dof: int) -> None:
    bad = (dof < 1) | (dof > n_dof)
    if np.any(bad):
        raise ConfigError(f"action dof must be in 1..{n_dof}, got {sorted(set(dof[bad].tolist()))}")
