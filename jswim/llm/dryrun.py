"""A stand-in client for ``--dry-run``: every call answered at once, nothing sent.

The driver runs a study's LLM runs against `EstimatingClient` exactly as against a server,
so the prompts are those of a real study; usage is estimated from the text (`jswim.llm.tokens`)
and priced. What the estimate leaves out (parse retries; replies longer than the bare action:
`Estimate.cost_max_usd`) and how a reasoning model's thinking is estimated
(`jswim.llm.reasoning.ESTIMATE_SHARE`, an assumption) are in docs/paid-apis.md.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass
from typing import Any
from collections.abc import Mapping, Sequence

from jswim.llm.result import ChatResult, LiveCounts
from jswim.llm.settings import ClientSettings
from jswim.llm.reasoning import ESTIMATE_SHARE, dry_run_budget, dry_run_warning
from jswim.llm.tokens import estimate_prompt_tokens, estimate_tokens
from jswim.llm.usage import PRICES_AS_OF, Usage


class EstimatingClient:
    """Answers chat calls without a server (docs/paid-apis.md); use like an LLMClient."""

    def __init__(self, settings: ClientSettings) -> None:
        self.settings = settings
        self._prices, self.unpriced = settings.price_table()
        self.counts = LiveCounts()
        self.n_requests = 0
        self.max_completion_tokens = 0  # sum over calls of the max_tokens each was sent with
        self.max_tokens_seen: set[int] = set()
        self.pacer = self.budget = None
        #: The reasoning budget every call will carry (None: a plain model), and the tokens each
        #: call is estimated to think (jswim.llm.reasoning.ESTIMATE_SHARE of it).
        self.reasoning_budget = dry_run_budget(
            settings.model, settings.reasoning, settings.reasoning_max_tokens
        )
        self.reasoning_per_call = (
            round(self.reasoning_budget * ESTIMATE_SHARE.get(settings.reasoning_effort, 0.25))
            if self.reasoning_budget
            else 0
        )
        self.reasoning_warning = dry_run_warning(settings.model, settings.reasoning)

    async def __aenter__(self) -> EstimatingClient:
        return self

    async def __aexit__(self, *exc: object) -> None:
        return None

    async def aclose(self) -> None:
        return None

    async def chat(
        self,
        messages: Sequence[Mapping[str, str]],
        *,
        replies: Sequence[str] | None = None,
        max_tokens: int | None = None,
        **_: Any,
    ) -> ChatResult:
        """An immediate answer: a valid reply and estimated usage (no request is sent)."""
        mt = max_tokens if max_tokens is not None else self.settings.max_tokens
        if self.reasoning_budget and mt:  # the budget replaces max_tokens (jswim.llm.reasoning)
            mt = self.reasoning_budget
        if mt:
            self.max_completion_tokens += mt
            self.max_tokens_seen.add(mt)
        last = str(messages[-1].get("content", "")) if messages else ""
        options = list(replies) if replies else ["[1, 1]"]
        text = options[zlib.crc32(last.encode()) % len(options)]
        thought = self.reasoning_per_call
        usage = Usage(estimate_prompt_tokens(messages), estimate_tokens(text) + thought, 0, thought)
        cost = self._prices.cost(self.settings.model, usage)
        self.n_requests += 1
        self.counts.tokens += usage.total_tokens
        self.counts.cost_usd += cost
        return ChatResult(
            text=text,
            usage=usage,
            latency_s=0.0,
            cache_hit=False,
            shared=False,
            retries=0,
            cost_usd=cost,
            constraint="none",
            finish_reason="stop",
            raw=text,
        )


@dataclass(frozen=True)
class Estimate:
    """What a study's LLM runs would cost.

    Attributes
    ----------
    model : str
    calls : int
        Requests (one per step; parse retries not included).
    prompt_tokens, completion_tokens : int
        Estimated totals (completion: the bare action per call, plus the reasoning tokens).
    price_in, price_out : float
        USD per 1M tokens from the price table (0 for unknown models).
    cost_usd : float
        Estimated cost.
    cost_max_usd : float
        Cost if every reply ran to the ``max_tokens`` it was sent with.
    max_tokens : str or None
        Those limits (``"10"``, or ``"10-20"`` when they differ by swimmer).
    prices_as_of : str
        Date of the price table.
    unpriced : str or None
        Why a model of the price table is not priced here (a local server), if it is not.
    reasoning_tokens : int
        Of the completion tokens, those estimated for thinking (0 for a plain model).
    reasoning_budget : int or None
        The reasoning budget each call carries (``max_completion_tokens``), if any.
    reasoning_share : float or None
        The share of the budget each call is estimated to think.
    reasoning_warning : str or None
        An open reasoning model that ``--reasoning auto`` would cut while thinking.
    cap_refusal : str or None
        The line the run would refuse its ``--max-cost`` with (calls it could not price).
    models_unasked : str or None
        Why the server's ``/v1/models`` could not be asked (then the model is priced as if listed).
    """

    model: str
    calls: int
    prompt_tokens: int
    completion_tokens: int
    price_in: float
    price_out: float
    cost_usd: float
    cost_max_usd: float
    max_tokens: str | None
    prices_as_of: str = PRICES_AS_OF
    unpriced: str | None = None
    reasoning_tokens: int = 0
    reasoning_budget: int | None = None
    reasoning_share: float | None = None
    reasoning_warning: str | None = None
    cap_refusal: str | None = None
    models_unasked: str | None = None

    def as_dict(self) -> dict[str, Any]:
        return dict(vars(self))

    def lines(self) -> list[str]:
        """A short human-readable report (what ``--dry-run`` prints)."""
        per_call = (self.prompt_tokens + self.completion_tokens) / max(self.calls, 1)
        out = [
            f"dry run: {self.calls} calls to {self.model} (one per step; no request sent)",
            f"  tokens: {self.prompt_tokens:,} prompt + {self.completion_tokens:,} completion "
            f"(~{per_call:.0f} per call, estimated from the rendered prompts)",
        ]
        if self.reasoning_budget:
            out.append(
                f"  reasoning: {self.reasoning_tokens:,} of the completion tokens are thinking, estimated as "
                f"{self.reasoning_share:g} of the budget max_completion_tokens={self.reasoning_budget} per call "
                "(an assumption, not a measurement; priced as output)"
            )
        limit = (
            f"used its whole reasoning budget ({self.reasoning_budget} tokens)"
            if self.reasoning_budget
            else f"ran to max_tokens={self.max_tokens}"
        )
        if self.price_in or self.price_out:
            out.append(
                f"  cost: ${self.cost_usd:.2f} at ${self.price_in:g} / ${self.price_out:g} per 1M tokens "
                f"(price table of {self.prices_as_of}"
                + ("; reasoning tokens included" if self.reasoning_budget else "")
                + f"); at most ${self.cost_max_usd:.2f} if every reply {limit}"
            )
        elif self.unpriced:
            out.append(f"  cost: $0 ({self.unpriced})")
        else:
            out.append(
                f"  cost: not priced: no price for {self.model!r} in the price table of {self.prices_as_of} "
                "(free or unknown); --prices FILE prices it"
            )
        if self.models_unasked:
            out.append(f"  note: {self.models_unasked}; priced as if it lists {self.model!r}")
        if self.cap_refusal:
            out.append(f"  --max-cost: the run would send nothing and stop: {self.cap_refusal}")
        if self.reasoning_warning:
            out.append(f"  warning: {self.reasoning_warning}")
        out.append(
            "  not counted: parse retries after off-format replies"
            + (
                ""
                if self.reasoning_budget
                else "; a reasoning model's thinking is counted only where the dry run knows "
                "it reasons (--reasoning on, or OpenAI's o1/o3/o4/gpt-5 models by name)"
            )
        )
        return out


def estimate(
    client: EstimatingClient, calls: int, prompt_tokens: int, completion_tokens: int
) -> Estimate:
    """Totals of a dry run priced by ``client``'s price table (``completion_tokens`` with the
    reasoning tokens the client estimated; the worst case at its reasoning budget per call)."""
    s = client.settings
    p_in, p_out = client._prices.lookup(s.model)
    cost = (prompt_tokens * p_in + completion_tokens * p_out) / 1e6
    most = max(client.max_completion_tokens, completion_tokens)
    cost_max = (prompt_tokens * p_in + most * p_out) / 1e6
    seen = sorted(client.max_tokens_seen)
    mt = None if not seen else str(seen[0]) if len(seen) == 1 else f"{seen[0]}-{seen[-1]}"
    budget = client.reasoning_budget
    return Estimate(
        s.model,
        calls,
        prompt_tokens,
        completion_tokens,
        p_in,
        p_out,
        cost,
        cost_max,
        mt,
        unpriced=client.unpriced,
        reasoning_tokens=client.reasoning_per_call * calls,
        reasoning_budget=budget,
        reasoning_share=ESTIMATE_SHARE.get(s.reasoning_effort, 0.25) if budget else None,
        reasoning_warning=client.reasoning_warning,
    )
