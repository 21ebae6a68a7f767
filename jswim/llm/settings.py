"""What an [`LLMClient`][jswim.llm.client.LLMClient] sends and how: [`ClientSettings`][jswim.llm.settings.ClientSettings] and the
checks of the values it carries (temperature, ``--max-tokens``, extra request fields)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any
from collections.abc import Iterable, Mapping

from jswim.errors import ConfigError, check_choice
from jswim.llm import constrain
from jswim.llm.credentials import mask_fields
from jswim.llm.reasoning import REASONING_MAX_TOKENS, check_mode
from jswim.llm.rejection import REQUIRED_FIELDS
from jswim.llm.urls import is_local_host, normalize_base_url, safe_url
from jswim.llm.usage import PriceTable, price_table


def check_temperature(value: float, name: str = "temperature") -> float:
    """``value`` if it is a sampling temperature in [0, 2] (the OpenAI API's range); ``name`` is
    how the message names it (``"--temperatures"``).

    Raises
    ------
    ConfigError
        Otherwise.
    """
    if not 0.0 <= value <= 2.0:  # also rejects NaN
        raise ConfigError(f"{name} must lie in [0, 2], got {value}")
    return value


#: Longest reply a request may ask for (``--max-tokens``; a reasoning budget has its own range).
MAX_TOKENS = 100_000


def check_max_tokens(value: int | None) -> int | None:
    """``value`` if it is ``None`` (the default) or a reply length limit in 1..`MAX_TOKENS`."""
    if value is not None and not 1 <= value <= MAX_TOKENS:
        raise ConfigError(f"--max-tokens must be between 1 and {MAX_TOKENS}, got {value}")
    return value


#: Request fields jswim itself sets, and the option that sets each: an extra field (a models
#: file's ``extra``, ``--extra-field``) naming one is refused, since it would change what is sent
#: behind the cost reservation, the study's identity and the record of what was sent.
CORE_FIELDS = {
    "model": "--model",
    "messages": "--prompt-file (the prompt template)",
    "max_tokens": "--max-tokens",
    "max_completion_tokens": "--max-tokens (with --reasoning on)",
    "temperature": "--temperature",
    "stream": 'nothing: jswim always sends "stream": false (--omit-field stream leaves it out)',
    "response_format": "--constrain",
    "grammar": "--constrain",
    "reasoning_effort": "--reasoning-effort",
}


def check_extra_fields(fields: Iterable[tuple[str, Any]], option: str = "--extra-field") -> None:
    """Refuse an extra request field that jswim sets itself (`CORE_FIELDS`).

    Raises
    ------
    ConfigError
        One line naming the field and the option that sets it.
    """
    import json

    for name, value in fields:
        if name in CORE_FIELDS:
            raise ConfigError(
                f"{option} {name}=...: jswim sets {name!r} itself; use {CORE_FIELDS[name]}"
            )
        try:  # what the request body will carry: strict JSON (no NaN or Infinity)
            json.dumps(value, allow_nan=False)
        except (TypeError, ValueError):
            raise ConfigError(
                f"{option} {name}=...: not a JSON value a server can read (NaN, Infinity?); "
                "give a number, text, true/false or JSON"
            ) from None


@dataclass(frozen=True)
class ClientSettings:
    """Connection and request settings.

    Attributes
    ----------
    base_url : str
        Server root including the API prefix, e.g. ``https://api.openai.com/v1``. Common other
        shapes are accepted and normalized (see `jswim.llm.urls.normalize_base_url`).
    model : str
        Model name sent with each request (also keys the cache and the price table).
    api_key_env : str
        Name of the environment variable holding the API key (unset: no ``Authorization``).
    timeout_s : float
        Per-attempt timeout (connect, read, write, pool). A request that times out is a transient
        failure like a 5xx: sent again within the retry budget (``max_retries``, ``retry_for_s``,
        whose clock runs from when the first failed attempt went out, so the waits for answers
        that never came count); when the budget is spent on timeouts the call fails with
        [`LLMTimeoutError`][jswim.errors.LLMTimeoutError], saying the server is slow.
    max_concurrency : int
        Requests in flight at once.
    max_retries : int
        Retries after the first attempt before giving up (``--retries``).
    retry_for_s : float or None
        Longest time a call keeps retrying, from its first failure (``--retry-for``); the call
        gives up when either budget is spent. ``None``: no time limit. The defaults (20 retries,
        120 s) ride out a server that is down or rate-limiting for a minute or more.
    backoff_base_s, backoff_max_s : float
        Backoff before retry ``k`` is ``min(max, base * 2**k)`` scaled by a jitter in [0.5, 1]
        (the last wait is shortened to end at the ``retry_for_s`` deadline).
    max_retry_after_s : float
        Longest ``Retry-After`` wait honoured (longer ones are shortened to this).
    temperature : float
        Sampling temperature (0, the paper's setting, makes requests cacheable).
    max_tokens : int or None
        Reply length limit.
    seed : int or None
        Sent when given (some servers use it for sampling at temperature > 0).
    constrain : {"auto", "grammar", "json_schema", "json_object", "none"}
        Constrained decoding; see `jswim.llm.constrain`.
    server_kind : str
        The server's family (`jswim.llm.constrain.SERVER_KINDS`, told by
        `jswim.llm.probe.probe`); resolves ``constrain="auto"``.
    cache_dir : str or None
        Directory of the response cache; ``None`` disables it.
    prices : mapping or None
        USD per 1M tokens by model name, applied on any host; ``None`` uses
        `jswim.llm.usage.DEFAULT_PRICES` where they apply ([`jswim.llm.usage.price_table`][jswim.llm.usage.price_table]:
        not on this machine or the LAN, not for a model the server does not list, not for a reply
        whose ``model`` field names another model).
    price_local : bool
        Price calls at the list prices even on a local or LAN server (a local gateway that
        forwards to a paid API); default False: a local server's calls cost nothing.
    listed_models : tuple of str or None
        The models the server's ``/v1/models`` listed at preflight (``None``: not known).
    fast_transport : bool
        For ``http://`` servers on loopback, use `jswim.llm.transport.LoopbackTransport`
        (asyncio streams) instead of httpx's default transport (anyio). Default True.
    omit_fields : tuple of str
        Optional request fields never sent (``"seed"``, ``"max_tokens"``, ``"stream"``, ...),
        for servers that reject them.
    reasoning : {"auto", "on", "off"}
        Reasoning models (`jswim.llm.reasoning`): switch to ``max_completion_tokens`` and the
        temperature the model accepts when the server's 400 asks for them (auto), use the
        reasoning budget from the start (on), or never switch (off).
    reasoning_max_tokens : int
        The reply budget once reasoning is on (default
        `jswim.llm.reasoning.REASONING_MAX_TOKENS`).
    reasoning_effort : str or None
        Sent as ``reasoning_effort`` when given (``minimal``, ``low``, ``medium``, ``high``).
    extra_fields : tuple of (name, value)
        More fields of every request body (a models file's ``extra``, ``--extra-field``); a field
        jswim sets itself (`CORE_FIELDS`: ``model``, ``messages``, ``max_tokens``,
        ``temperature``, ``stream``, ...) is refused with [`ConfigError`][jswim.errors.ConfigError].
    sampling : tuple of (str, float)
        Sampling fields every request carries (``(("repeat_penalty", 1.0), ...)``;
        `jswim.llm.sampling.sampling_fields`), before ``omit_fields`` are removed.
    """

    base_url: str = "https://api.openai.com/v1"
    model: str = "gpt-4"
    api_key_env: str = "OPENAI_API_KEY"
    timeout_s: float = 60.0
    max_concurrency: int = 16
    max_retries: int = 20
    retry_for_s: float | None = 120.0
    backoff_base_s: float = 0.5
    backoff_max_s: float = 30.0
    max_retry_after_s: float = 120.0
    temperature: float = 0.0
    max_tokens: int | None = 32
    seed: int | None = None
    constrain: str = "auto"
    server_kind: str = "generic"
    cache_dir: str | None = None
    prices: Mapping[str, tuple[float, float]] | None = field(default=None, compare=False)
    price_local: bool = field(default=False, compare=False)
    listed_models: tuple[str, ...] | None = field(default=None, compare=False)
    fast_transport: bool = field(default=True, compare=False)
    omit_fields: tuple[str, ...] = ()
    reasoning: str = "auto"
    reasoning_max_tokens: int = REASONING_MAX_TOKENS
    reasoning_effort: str | None = None
    extra_fields: tuple[tuple[str, Any], ...] = ()
    sampling: tuple[tuple[str, float], ...] = ()

    def __post_init__(self) -> None:
        check_mode(self.reasoning, self.reasoning_effort)
        object.__setattr__(self, "base_url", normalize_base_url(self.base_url))
        object.__setattr__(
            self, "sampling", tuple((str(k), v) for k, v in dict(self.sampling).items())
        )
        object.__setattr__(self, "omit_fields", tuple(sorted(set(self.omit_fields))))
        required = sorted(set(self.omit_fields) & set(REQUIRED_FIELDS))
        if required:
            raise ConfigError(
                f"cannot leave out the request field(s) {', '.join(required)}: every request needs them"
            )
        check_choice(self.constrain, constrain.MODES, "constrain")
        check_choice(self.server_kind, constrain.SERVER_KINDS, "server_kind")
        if (
            self.max_concurrency < 1
            or self.max_retries < 0
            or not (math.isfinite(self.timeout_s) and self.timeout_s > 0)
        ):
            raise ConfigError(
                "need max_concurrency >= 1, max_retries >= 0 and a finite timeout_s > 0"
            )
        if self.retry_for_s is not None and not (self.retry_for_s >= 0):  # also NaN
            raise ConfigError(f"retry_for_s must be >= 0 seconds, got {self.retry_for_s}")
        check_temperature(self.temperature)
        check_extra_fields(self.extra_fields)
        mask_fields(dict(self.extra_fields))  # registers each credential for scrub

    def price_table(self) -> tuple[PriceTable, str | None]:
        """The table these calls are priced by, and why it is empty when it is.

        The one pricing rule of the client and of its dry run
        ([`jswim.llm.usage.price_table`][jswim.llm.usage.price_table] on this host, model and list).
        """
        return price_table(
            self.prices,
            self.model,
            local_host=is_local_host(self.base_url),
            listed=self.listed_models,
            price_local=self.price_local,
        )

    def metadata(self) -> dict[str, Any]:
        """Settings worth recording with a run (no secrets: only the key's variable name)."""
        plain = (
            "model",
            "temperature",
            "max_tokens",
            "seed",
            "constrain",
            "server_kind",
            "max_retries",
            "retry_for_s",
            "timeout_s",
            "omit_fields",
            "reasoning",
            "reasoning_max_tokens",
            "reasoning_effort",
            "extra_fields",
            "sampling",
        )
        out = {"base_url": safe_url(self.base_url)} | {name: getattr(self, name) for name in plain}
        # The tuple-valued fields as JSON shapes (keys keep their places: update only replaces).
        out.update(
            omit_fields=list(self.omit_fields),
            extra_fields=mask_fields(dict(self.extra_fields)),  # a credential never written
            sampling=dict(self.sampling),
        )
        return out
