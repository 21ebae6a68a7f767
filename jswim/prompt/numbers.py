"""The numbers of a prompt: an [`Action`][jswim.prompt.Action] (DOF, ROC), the integer encoding of the position
X (the paper's ``(X - X_min) * 1000``, truncated) and a DOF value as the prompt shows it."""

from __future__ import annotations

import math
from decimal import ROUND_DOWN, Decimal
from typing import NamedTuple

from jswim.errors import ConfigError


class Action(NamedTuple):
    """One action: the changed DOF (1-based) and its rate of change."""

    dof: int
    roc: int

    def text(self) -> str:
        """The reply form, ``[dof, roc]``."""
        return f"[{self.dof}, {self.roc}]"


def _decimal(value: float) -> Decimal:
    # repr gives the shortest exact-looking form, so 1.001 stays 1.001 (not 1.000999...).
    return Decimal(repr(float(value)))


def encode_position(x: float, x_min: float = -2.5) -> int:
    """``(X/a)_LLM = (X/a - X_min/a) * 1000`` as an integer.

    ``X`` is truncated (toward zero, not rounded) to three decimals first, as in the paper.
    ``X_min`` is chosen so that values stay positive; a position below it gives a negative
    number, which is sent as it is (the authors' code does the same; a run is never stopped
    for it; the driver warns once and records the step).

    Raises
    ------
    ConfigError
        When ``x`` is not finite.
    """
    if not math.isfinite(x):
        raise ConfigError(f"position X must be finite, got {x!r}")
    x3 = _decimal(x).quantize(Decimal("0.001"), rounding=ROUND_DOWN)
    shifted = (x3 - _decimal(x_min)) * 1000
    return int(shifted.to_integral_value(rounding=ROUND_DOWN))


def format_dof(value: float, decimals: int) -> str:
    """A DOF value rounded to ``decimals`` (angles: 3, sphere arms: 0), without ``-0``."""
    r = round(float(value), decimals) + 0.0  # + 0.0 turns -0.0 into 0.0
    return f"{r:.{decimals}f}"
