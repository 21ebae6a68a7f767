"""What one chat call returned ([`ChatResult`][jswim.llm.result.ChatResult]) and a client's running totals
([`LiveCounts`][jswim.llm.result.LiveCounts], its transient failures by `FAULT_KINDS`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from jswim.llm.usage import Usage


@dataclass(frozen=True)
class ChatResult:
    """One chat completion.

    Attributes
    ----------
    text : str
        The reply (unwrapped from JSON in ``json_schema`` mode).
    usage : Usage
        Tokens reported by the server for the call that produced the reply.
    latency_s : float
        Wall time of this call, including retries and waits.
    cache_hit : bool
        Served from the disk cache.
    shared : bool
        Shared the answer of an identical request already in flight.
    retries : int
        Retries this call needed (0 for cache hits and shared calls).
    cost_usd : float
        Price of the producing call (0 for free or unknown models).
    constraint : str
        Constrained-decoding mode used: ``"grammar"``, ``"json_schema"``, ``"json_object"`` or ``"none"``.
    finish_reason : str or None
        As reported by the server.
    raw : str
        The message content as sent (reasoning blocks included), before unwrapping.
    reasoning : str
        The model's reasoning (reasoning fields and inline blocks), for transcripts only.
    """

    text: str
    usage: Usage
    latency_s: float
    cache_hit: bool
    shared: bool
    retries: int
    cost_usd: float
    constraint: str
    finish_reason: str | None = None
    raw: str = ""
    reasoning: str = ""
    temperature_sent: float | None = (
        None  # what the request carried (a reasoning model may refuse ours)
    )

    @property
    def truncated(self) -> bool:
        """The reply was cut off at ``max_tokens`` (``finish_reason == "length"``): no answer."""
        return self.finish_reason == "length"

    @property
    def cut_while_thinking(self) -> bool:
        """Cut off before any answer while the model was still reasoning (reasoning text or
        reasoning tokens, no answer text): the budget left no room to think."""
        return (
            self.truncated
            and not self.text.strip()
            and bool(self.reasoning or self.usage.reasoning_tokens)
        )

    def as_dict(self) -> dict[str, Any]:
        """A transcript record (the raw content only when it differs from ``text``)."""
        u = self.usage
        out = {
            "text": self.text,
            "prompt_tokens": u.prompt_tokens,
            "completion_tokens": u.completion_tokens,
            "latency_s": round(self.latency_s, 6),
        }
        plain = ("cache_hit", "shared", "retries", "cost_usd", "constraint", "finish_reason")
        out |= {k: getattr(self, k) for k in plain}
        optional = {
            "reasoning_tokens": u.reasoning_tokens or None,
            "temperature_sent": self.temperature_sent,
            "reasoning": self.reasoning or None,
            "raw": None if self.raw == self.text else self.raw,
        }
        return out | {k: v for k, v in optional.items() if v is not None}


#: Kinds of transient failure, as counted in `LiveCounts.faults` (and a study's summary).
FAULT_KINDS = ("429", "5xx", "408/409", "connection", "timeout", "bad body")


@dataclass
class LiveCounts:
    """Running totals of one client, for progress displays."""

    in_flight: int = 0  # HTTP requests sent and not yet answered
    tokens: int = 0  # prompt + completion tokens the server reported
    cache_hits: int = 0  # calls answered from the disk cache
    shared: int = 0  # calls that waited on an identical request already in flight
    cost_usd: float = 0.0  # what the answered calls cost
    requests: int = 0  # HTTP requests sent (first attempts and retries): what the server counts
    retries: int = 0  # of those, retries after a transient failure
    faults: dict[str, int] = field(default_factory=dict)  # transient failures by kind (FAULT_KINDS)
    # Requests sent whole that got no answer (timed out, cut while waiting, cancelled in flight by
    # an interruption): a server may still have run and billed them. ``unanswered_usd`` is what
    # they could have cost at most (their call bound; 0 where calls are not priced).
    unanswered: int = 0
    unanswered_usd: float = 0.0
