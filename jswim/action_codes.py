"""Action sets and the action codec (environment layer, no JAX): which ``(DOF, ROC)`` actions an
agent is offered, and the integer codes every world reads ([`encode_action`][jswim.action_codes.encode_action]).

One name for the concept everywhere (``action_set``): the LLM's S5 and grammar, the Q-learner's
and the random policy's choices, study grids and the command line all take one of
`ACTION_SETS`. Kept apart from `jswim.env` so the text layers can read it without
importing JAX.
"""

from __future__ import annotations

import numbers
from typing import Any

from jswim.errors import ConfigError, check_choice

__all__ = [
    "ACTION_SETS",
    "MAX_ROC_LEVELS",
    "check_action_set",
    "check_roc_levels",
    "decode_action",
    "encode_action",
    "n_actions",
    "offered_rocs",
]

#: Largest number of ROC levels K (``--roc-levels``, ``make_params(roc_levels=K)``).
MAX_ROC_LEVELS = 1000

#: ``"all"``: every (DOF, ROC) pair (the paper's setting); ``"shape-changing"``: only the moves
#: that change the shape from the current one (ROC +1 below ``hi``, ROC -1 above ``lo``).
ACTION_SETS = ("all", "shape-changing")


def check_action_set(name: str) -> str:
    """``name`` if it is one of `ACTION_SETS`.

    Raises
    ------
    ConfigError
        For any other name.
    """
    return check_choice(name, ACTION_SETS, "action set")


def check_roc_levels(k: Any, name: str = "--roc-levels") -> int:
    """``k`` as an int if it is a valid number of ROC levels K (an integer in
    1..`MAX_ROC_LEVELS`; ROC ``k`` in ``-K..K`` moves a DOF by ``k/K`` of its range).

    The one rule for K, shared by the CLI, the agents and the environment; ``name`` is what the
    message calls it (``--roc-levels`` on the command line, ``roc_levels`` in Python).

    Raises
    ------
    ConfigError
        For anything else (the message names ``name``).
    """
    if isinstance(k, bool) or not hasattr(k, "__index__") or not 1 <= int(k) <= MAX_ROC_LEVELS:
        raise ConfigError(f"{name} (K) must be an integer from 1 to {MAX_ROC_LEVELS}, got {k!r}")
    return int(k)


# -- the integer action codec of every world ---------------------------------------------------


def offered_rocs(n_dof: int, roc_levels: int = 1) -> tuple[int, ...]:
    """ROCs ``k`` offered to an agent: the paper's {-1, 0, 1} for two DOFs, {-1, 1} for more (the
    published four-DOF setting). With ``roc_levels = K`` (an extension): every integer of
    ``-K..K`` (ROC ``k`` moves the DOF by ``k/K`` of its range), 0 left out for more than two DOFs."""
    k = check_roc_levels(roc_levels)
    return tuple(r for r in range(-k, k + 1) if r != 0 or n_dof == 2)


def n_actions(n_dof: int, roc_levels: int = 1) -> int:
    """Number of integer codes: ``n_dof (2K + 1)`` (``K = 1``: the paper's ``3 n_dof``)."""
    return n_dof * (2 * roc_levels + 1)


def encode_action(dof: Any, roc: Any, roc_levels: int = 1) -> Any:
    """Integer code of ``(dof, roc)``: ``dof`` 1-based as in the prompt, ``roc`` the integer
    ``k`` in ``-K..K`` (ROC ``k / K``; with K = 1 the paper's -1, 0, 1). The one codec of every
    world (a scene's joint DOF ``2 s + j`` of swimmer ``s`` is ``dof``); ints, NumPy or JAX arrays."""
    return (dof - 1) * (2 * roc_levels + 1) + (roc + roc_levels)


def decode_action(action: Any, roc_levels: int = 1) -> tuple[Any, Any]:
    """``(dof, k)`` of integer codes (ROC ``k / K``, ``dof`` 1-based); Python ints for an integer
    code, arrays (NumPy or JAX, jit-friendly) for arrays."""
    if isinstance(action, numbers.Integral):  # NumPy's integers too, without importing NumPy
        action = int(action)
    width = 2 * roc_levels + 1
    return action // width + 1, action % width - roc_levels
