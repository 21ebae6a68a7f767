"""Action sets: which ``(DOF, ROC)`` actions an agent is offered (environment layer, no JAX).

One name for the concept everywhere (``action_set``): the LLM's S5 and grammar, the Q-learner's
and the random policy's choices, study grids and the command line all take one of
:data:`ACTION_SETS`. Kept apart from :mod:`jswim.env` so the text layers can read it without
importing JAX.
"""

from __future__ import annotations

from jswim.errors import ConfigError

#: ``"all"``: every (DOF, ROC) pair (the paper's setting); ``"shape-changing"``: only the moves
#: that change the shape from the current one (ROC +1 below ``hi``, ROC -1 above ``lo``).
ACTION_SETS = ("all", "shape-changing")


def check_action_set(name: str) -> str:
    """``name`` if it is one of :data:`ACTION_SETS`.

    Raises
    ------
    ConfigError
        For any other name.
    """
    if name not in ACTION_SETS:
        raise ConfigError(f"action set must be one of {', '.join(ACTION_SETS)}, got {name!r}")
    return name
