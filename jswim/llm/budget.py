"""A spending cap for a study: calls reserve their worst cost before they go out.

A study run with ``--max-cost USD`` holds one [`Budget`][jswim.llm.budget.Budget]: each request reserves its bound
([`call_bound`][jswim.llm.budget.call_bound], scaled by the largest bill-to-bound ratio the provider has shown), the answer
replaces it with the call's cost, and the first reservation past the cap (spent, reserved and
unanswered together) raises [`BudgetExhausted`][jswim.errors.BudgetExhausted], as every later one does. With a ledger
([`jswim.llm.ledger.RequestLedger`][jswim.llm.ledger.RequestLedger]) every reservation is written down before its request
goes out, and the totals start from what the ledger recomputes. docs/paid-apis.md (*Cap*) states
what the cap guarantees, and why unanswered requests count.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any
from collections.abc import Mapping

from jswim.errors import BudgetExhausted, ConfigError
from jswim.llm.ledger import RequestLedger
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


@dataclass(frozen=True)
class Hold:
    """One request's reservation: ``usd`` held against the cap, ``bound_usd`` its unscaled bound,
    ``n`` its ledger line (``None`` without a ledger)."""

    usd: float
    bound_usd: float
    n: int | None = None


class Budget:
    """Spent and reserved USD against a cap.

    Parameters
    ----------
    cap_usd : float or None
        The cap (``None``: no cap; reservations are still tracked).
    spent_usd : float
        Already spent (earlier sessions); with a ledger, at least what the ledger recomputes.
    unanswered_usd : float
        Bounds of earlier sessions' requests that got no answer (docs/paid-apis.md); with a
        ledger, at least what the ledger recomputes.
    ledger : RequestLedger, optional
        Where each request is written down before it goes out, and each outcome after.

    Raises
    ------
    ConfigError
        For a negative or non-finite cap.
    """

    def __init__(
        self,
        cap_usd: float | None,
        spent_usd: float = 0.0,
        unanswered_usd: float = 0.0,
        ledger: RequestLedger | None = None,
    ) -> None:
        if cap_usd is not None and not (
            isinstance(cap_usd, (int, float))
            and not isinstance(cap_usd, bool)
            and math.isfinite(cap_usd)
            and cap_usd >= 0
        ):
            raise ConfigError(f"the cost cap must be a number >= 0, got {cap_usd!r}")
        self.cap_usd = cap_usd
        self.ledger = ledger
        self.spent_usd = _usd(spent_usd)
        self.unanswered_usd = _usd(unanswered_usd)
        #: Later reservations are the bound times this: the largest bill-to-bound ratio seen.
        self.ratio = 1.0
        if ledger is not None:
            self.spent_usd = max(self.spent_usd, ledger.spent_usd)
            self.unanswered_usd = max(self.unanswered_usd, ledger.unanswered_usd)
            self.ratio = max(1.0, ledger.ratio)
        self.reserved_usd = 0.0
        self.exhausted = False  # set by the first refusal; every later reservation is refused

    @property
    def remaining_usd(self) -> float | None:
        """Cap minus spent, unanswered and reserved (``None`` without a cap)."""
        if self.cap_usd is None:
            return None
        return self.cap_usd - self.spent_usd - self.unanswered_usd - self.reserved_usd

    def reserve(self, bound_usd: float, retry: bool = False) -> Hold:
        """Reserve a request's bound (times `ratio`) before it goes out, and write it down
        (``retry``: the request is a retry, as the ledger counts them).

        Raises
        ------
        BudgetExhausted
            When the cap would be passed (or was reached before).
        StudyFolderError
            The ledger cannot be written: the request must not be sent.
        """
        usd = bound_usd * self.ratio
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
        n = self.ledger.sent(usd, retry) if self.ledger is not None else None
        self.reserved_usd += usd
        return Hold(usd, bound_usd, n)

    def _drop(self, hold: Hold) -> None:
        self.reserved_usd = max(0.0, self.reserved_usd - hold.usd)

    def settle(self, hold: Hold, actual_usd: float, fault: str | None = None) -> None:
        """Replace a reservation by the call's actual cost; a bill above the bound raises the
        ratio later reservations are scaled by (``fault``: the transient fault that came with
        the bill, ``"bad body"``, for the ledger)."""
        self._drop(hold)
        self.spent_usd += actual_usd
        if hold.bound_usd > 0:
            self.ratio = max(self.ratio, actual_usd / hold.bound_usd)
        if self.ledger is not None and hold.n is not None:
            self.ledger.billed(hold.n, actual_usd, fault)

    def release(self, hold: Hold, fault: str | None = None) -> None:
        """Drop a reservation whose call was not billed (refused, or never delivered;
        ``fault``: the transient fault's kind, for the ledger)."""
        self._drop(hold)
        if self.ledger is not None and hold.n is not None:
            self.ledger.released(hold.n, fault)

    def unanswered(self, hold: Hold, fault: str | None = None) -> None:
        """Keep a reservation whose request went out and got no answer: the server may bill it
        (the ledger already says so: a sent line with no outcome; ``fault``, the timeout or cut
        that left it unanswered, is noted there; an interrupt notes nothing)."""
        self._drop(hold)
        self.unanswered_usd += hold.usd
        if self.ledger is not None and hold.n is not None and fault is not None:
            self.ledger.no_answer(hold.n, fault)


def _usd(v: Any) -> float:
    """A ledger amount as given: a finite number >= 0 (anything else is a damaged ledger)."""
    if isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v >= 0:
        return float(v)
    raise ConfigError(f"a spent or unanswered amount must be a number >= 0, got {v!r}")
