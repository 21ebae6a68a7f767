"""A spending cap for a study: calls reserve their worst cost before they go out.

A study run with ``--max-cost USD`` holds one [`Budget`][jswim.llm.budget.Budget]: each request reserves its bound
([`call_bound`][jswim.llm.budget.call_bound]), the answer replaces it with the call's cost, and the first reservation past
the cap (spent, reserved and unanswered together) raises [`BudgetExhausted`][jswim.errors.BudgetExhausted], as every later
one does. ``spent_usd`` starts at what earlier sessions paid. docs/paid-apis.md (*Cap*) describes
the rule, and why unanswered requests count.
"""

from __future__ import annotations

import math
from typing import Any
from collections.abc import Mapping

from jswim.errors import BudgetExhausted, ConfigError
from jswim.llm.tokens import estimate_prompt_tokens
from jswim.llm.usage import PriceTable


def call_bound(
    payload: Mapping[str, Any], prices: PriceTable, model: str, default_max_tokens: int = 256
) -> float:
    """USD bound of one request: estimated prompt tokens plus ``max_tokens`` of completion."""
    p_in, p_out = prices.lookup(model)
    prompt = estimate_prompt_tokens(payload.get("messages") or [])
    completion = (
        payload.get("max_tokens") or payload.get("max_completion_tokens") or default_max_tokens
    )
    return (prompt * p_in + int(completion) * p_out) / 1e6


class Budget:
    """Spent and reserved USD against a cap.

    Parameters
    ----------
    cap_usd : float or None
        The cap (``None``: no cap; reservations are still tracked).
    spent_usd : float
        Already spent (earlier sessions).
    unanswered_usd : float
        Bounds of earlier sessions' requests that got no answer (docs/paid-apis.md).

    Raises
    ------
    ConfigError
        For a negative or non-finite cap.
    """

    def __init__(
        self, cap_usd: float | None, spent_usd: float = 0.0, unanswered_usd: float = 0.0
    ) -> None:
        if cap_usd is not None and not (math.isfinite(cap_usd) and cap_usd >= 0):
            raise ConfigError(f"the cost cap must be a number >= 0, got {cap_usd}")
        self.cap_usd = cap_usd
        self.spent_usd = float(spent_usd)
        self.unanswered_usd = float(unanswered_usd)
        self.reserved_usd = 0.0
        self.exhausted = False  # set by the first refusal; every later reservation is refused

    @property
    def remaining_usd(self) -> float | None:
        """Cap minus spent, unanswered and reserved (``None`` without a cap)."""
        if self.cap_usd is None:
            return None
        return self.cap_usd - self.spent_usd - self.unanswered_usd - self.reserved_usd

    def reserve(self, usd: float) -> float:
        """Reserve ``usd`` for a call about to go out; returns the amount to settle later.

        Raises
        ------
        BudgetExhausted
            When the cap would be passed (or was reached before).
        """
        if self.cap_usd is not None and (
            self.exhausted
            or self.spent_usd + self.unanswered_usd + self.reserved_usd + usd > self.cap_usd
        ):
            self.exhausted = True
            unanswered = (
                f", at most ${self.unanswered_usd:.4f} for requests that got no answer"
                if self.unanswered_usd
                else ""
            )
            raise BudgetExhausted(
                f"stopped at the cost cap: ${self.spent_usd:.4f} spent{unanswered}, ${self.reserved_usd:.4f} in flight, "
                f"cap ${self.cap_usd:.4f}; rerun with a higher --max-cost to continue"
            )
        self.reserved_usd += usd
        return usd

    def settle(self, reserved: float, actual_usd: float) -> None:
        """Replace a reservation by the call's actual cost."""
        self.reserved_usd = max(0.0, self.reserved_usd - reserved)
        self.spent_usd += actual_usd

    def release(self, reserved: float) -> None:
        """Drop a reservation whose call was not billed (failed attempt)."""
        self.reserved_usd = max(0.0, self.reserved_usd - reserved)

    def unanswered(self, reserved: float) -> None:
        """Keep a reservation whose request went out and got no answer: the server may bill it."""
        self.reserved_usd = max(0.0, self.reserved_usd - reserved)
        self.unanswered_usd += reserved
