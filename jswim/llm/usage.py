"""Token usage and cost accounting.

Prices are USD per million tokens, ``(prompt, completion)``, looked up by model name (exact, then
the longest known prefix); models not in the table cost 0. [`price_table`][jswim.llm.usage.price_table] applies the list
prices only where they can be right, and [`cap_refusal`][jswim.llm.usage.cap_refusal] says why a capped study's calls could
not be priced: both rules are in docs/paid-apis.md.
"""

from __future__ import annotations

from dataclasses import dataclass
from collections.abc import Iterable, Mapping, Sequence

#: When `DEFAULT_PRICES` was read off the providers' list prices (standard tier, no batch
#: or cached-input discounts). Printed with every estimate.
PRICES_AS_OF = "2025-04"

#: USD per 1M tokens (prompt, completion). Check the provider's price page before trusting it.
DEFAULT_PRICES: dict[str, tuple[float, float]] = {
    "gpt-4": (30.0, 60.0),  # the paper's model
    "gpt-4-32k": (60.0, 120.0),
    "gpt-4-turbo": (10.0, 30.0),
    "gpt-4o": (2.5, 10.0),
    "gpt-4o-mini": (0.15, 0.6),
    "gpt-4.1": (2.0, 8.0),
    "gpt-4.1-mini": (0.4, 1.6),
    "gpt-4.1-nano": (0.1, 0.4),
    "gpt-3.5-turbo": (0.5, 1.5),
}


@dataclass(frozen=True)
class Usage:
    """Tokens of one call, from the response's ``usage`` field."""

    prompt_tokens: int = 0
    completion_tokens: int = 0
    cached_tokens: int = 0  # prompt tokens the server served from its prefix cache, if reported
    reasoning_tokens: int = 0  # of the completion tokens, those spent reasoning, if reported

    @property
    def total_tokens(self) -> int:
        return self.prompt_tokens + self.completion_tokens

    @classmethod
    def from_response(cls, usage: Mapping | None) -> Usage:
        """Read an OpenAI-style ``usage`` object. A count that is missing, or is not a
        non-negative whole number (``"n/a"``, ``[3]``, ``-1``, ``1.5``, NaN), counts as 0, as when
        a server sends no usage at all: the answer is still read."""
        if not isinstance(usage, Mapping):
            return cls()
        details = usage.get("prompt_tokens_details") or {}
        cached = details.get("cached_tokens", 0) if isinstance(details, Mapping) else 0
        out = usage.get("completion_tokens_details") or {}
        thought = _count(out.get("reasoning_tokens") if isinstance(out, Mapping) else 0)
        completion = _count(usage.get("completion_tokens"))
        # OpenAI counts reasoning inside completion_tokens; a server that reports more reasoning
        # than completion tokens counted them apart, and both are billed as output.
        if thought > completion:
            completion += thought
        return cls(_count(usage.get("prompt_tokens")), completion, _count(cached), thought)

    @staticmethod
    def priceable(usage: object) -> bool:
        """Whether a response's ``usage`` can price its call: an object whose ``prompt_tokens``
        is a whole number above 0 (every request has a prompt) and whose ``completion_tokens``
        is a whole number >= 0. No usage, a negative, NaN or text count cannot."""
        if not isinstance(usage, Mapping):
            return False
        prompt, completion = usage.get("prompt_tokens"), usage.get("completion_tokens")
        return _valid(prompt) and _count(prompt) > 0 and _valid(completion)


def _valid(value: object) -> bool:
    """Whether ``value`` is a token count as servers send it (0 included)."""
    return _count(value) > 0 or (value == 0 and not isinstance(value, bool)) or value == "0"


def _count(value: object) -> int:
    """A token count as servers send it (an int, an integral float, a digit string), else 0."""
    if isinstance(value, bool):
        return 0
    if isinstance(value, int):
        return value if value >= 0 else 0
    if isinstance(value, float):
        return (
            int(value) if value.is_integer() and 0 <= value < 2**53 else 0
        )  # NaN and inf are not integers
    if isinstance(value, str) and value.strip().isascii() and value.strip().isdigit():
        return int(value.strip())
    return 0


class PriceTable:
    """Model name -> USD per 1M tokens ``(prompt, completion)``."""

    def __init__(self, prices: Mapping[str, tuple[float, float]] | None = None) -> None:
        self.prices = dict(DEFAULT_PRICES if prices is None else prices)

    def entry(self, model: str) -> str | None:
        """The table's name that prices ``model``: the exact name, else the longest matching
        prefix, else ``None`` (free)."""
        if model in self.prices:
            return model
        return max((k for k in self.prices if model.startswith(k)), key=len, default=None)

    def lookup(self, model: str) -> tuple[float, float]:
        """Price of ``model``: exact name, else longest matching prefix, else free."""
        name = self.entry(model)
        return self.prices[name] if name is not None else (0.0, 0.0)

    def agrees(self, model: str, replied: str | None) -> bool:
        """Whether a reply that says it came from ``replied`` is priced as ``model`` is: the
        same table entry (``gpt-4-0613`` for ``gpt-4``), or no ``model`` field in the reply."""
        return not replied or self.entry(replied) == self.entry(model)

    def cost(self, model: str, usage: Usage) -> float:
        """USD for one call."""
        p_in, p_out = self.lookup(model)
        return (usage.prompt_tokens * p_in + usage.completion_tokens * p_out) / 1e6


#: What a user passes to price a local server's calls at the list prices (a gateway on this
#: machine or the LAN that forwards to a paid API).
PRICE_LOCAL_OPTION = "--price-local"


def price_table(
    prices: Mapping[str, tuple[float, float]] | None,
    model: str,
    *,
    local_host: bool,
    listed: Sequence[str] | None = None,
    price_local: bool = False,
) -> tuple[PriceTable, str | None]:
    """The table to price ``model``'s calls by, and why it is empty when it is.

    Parameters
    ----------
    prices : mapping or None
        The user's table (always applied, on any host), or ``None`` for `DEFAULT_PRICES`.
    model : str
        The model name requests carry.
    local_host : bool
        The server is on this machine or the LAN (`jswim.llm.urls.is_local_host`).
    price_local : bool
        Price a local server's calls at the list prices anyway (a local gateway to a paid API);
        a model the server's ``/v1/models`` does not list stays unpriced.
    listed : sequence of str, optional
        The models the server's ``/v1/models`` lists (``None``: not known).

    Returns
    -------
    (PriceTable, str or None)
        An empty table (every call free) and the reason, when cloud list prices do not apply.
    """
    if prices is not None:
        return PriceTable(prices), None
    table = PriceTable()
    if table.entry(model) is None:
        return table, None  # not a priced model anyway
    if local_host and not price_local:
        return PriceTable({}), (
            f"{model!r} on a local or LAN server is not priced at a cloud list price; "
            f"{PRICE_LOCAL_OPTION} prices it (a local gateway to a paid API)"
        )
    if (
        listed is not None and model not in listed
    ):  # also with --price-local: a server may answer any name
        return PriceTable({}), (
            f"the server does not list {model!r}, so its calls are not priced at "
            f"{model}'s list price; --prices FILE gives your own prices, applied as given"
        )
    return table, None


def cap_refusal(
    prices: Mapping[str, tuple[float, float]] | None,
    model: str,
    cap_usd: float | None,
    *,
    local_host: bool,
    listed: Sequence[str] | None = None,
    price_local: bool = False,
) -> str | None:
    """Why a cost cap could not hold for ``model``'s calls (one line naming ``--prices``), or ``None``.

    A cap holds when the calls have a price: from the user's table, or the list price where
    [`price_table`][jswim.llm.usage.price_table] applies it. A server on this machine or the LAN without
    ``--price-local`` and with no list price for the model is free, and the cap has nothing to
    bound. Anything else priced at $0 would let the cap lapse: every call would be sent.
    """
    if cap_usd is None:
        return None
    table, why = price_table(
        prices, model, local_host=local_host, listed=listed, price_local=price_local
    )
    head = f"--max-cost {cap_usd:g} cannot hold, since the calls to {model!r} would cost $0"
    if why is not None:
        also = "" if "--prices" in why else "; or --prices FILE with your own prices"
        return f"{head}: {why}{also}; nothing was sent"
    if table.entry(model) is not None:
        return None
    if prices is not None:
        return f"{head}: --prices has no price for {model!r}; add one to the file; nothing was sent"
    if local_host and not price_local:
        return None  # a local server's own model: free, nothing to cap
    return (
        f"{head}: the built-in table of {PRICES_AS_OF} has no price for {model!r}; give --prices FILE "
        f"with its price; nothing was sent"
    )


@dataclass
class UsageTotals:
    """Sums over many calls (a run, a study). Only billed calls add tokens and cost.

    A call is billed when it reached the server: disk-cache hits and calls that shared an
    identical in-flight request are counted in ``calls`` but add nothing else.
    """

    calls: int = 0
    billed_calls: int = 0
    cache_hits: int = 0
    shared: int = 0
    retries: int = 0
    prompt_tokens: int = 0
    completion_tokens: int = 0
    cached_tokens: int = 0  # of the prompt tokens, those the server took from its prefix cache
    reasoning_tokens: int = 0  # of the completion tokens, those spent reasoning (priced as output)
    cost_usd: float = 0.0
    latency_s: float = 0.0

    def add(self, result: object) -> None:
        """Add one [`jswim.llm.client.ChatResult`][jswim.llm.result.ChatResult]."""
        self.calls += 1
        self.retries += result.retries
        self.latency_s += result.latency_s
        if result.cache_hit:
            self.cache_hits += 1
        elif result.shared:
            self.shared += 1
        else:
            self.billed_calls += 1
            self.prompt_tokens += result.usage.prompt_tokens
            self.completion_tokens += result.usage.completion_tokens
            self.cached_tokens += result.usage.cached_tokens
            self.reasoning_tokens += result.usage.reasoning_tokens
            self.cost_usd += result.cost_usd

    def merge(self, others: Iterable[UsageTotals]) -> UsageTotals:
        """Sum of ``self`` and ``others`` (e.g. runs into a study), as a new object."""
        out = UsageTotals(**vars(self))
        for o in others:
            for k, v in vars(o).items():
                setattr(out, k, getattr(out, k) + v)
        return out

    def as_dict(self) -> dict[str, float]:
        return dict(vars(self))
