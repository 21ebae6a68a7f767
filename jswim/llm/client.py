"""Async client for OpenAI-compatible chat-completions servers, over httpx.

One :class:`LLMClient` serves a whole study: many requests in flight at once (bounded by a
semaphore), retries with exponential backoff and jitter on transient failures (connection errors,
timeouts, 408, 409, 429, 5xx, unreadable bodies) within one budget per call (``max_retries``,
``retry_for_s``), ``Retry-After`` honoured, requests that got no answer counted as possibly
billed, a disk cache and in-flight de-duplication for deterministic (temperature 0) requests,
and usage/cost per call.

Real servers differ in ordinary ways and the client absorbs them (see :mod:`jswim.llm.reply`):
every request says ``"stream": false`` and a stream that comes anyway is assembled; reasoning
(``<think>`` blocks, ``reasoning_content``) is split from the answer; null or list content is
read; base URLs are accepted in their common shapes (:mod:`jswim.llm.urls`). A rejection names
the server's own message, the URL tried and the setting that avoids it.

The API key is read from an environment variable whose *name* is a setting; the key itself is
only ever put in the ``Authorization`` header, never in logs, cache keys, results or errors.

Example
-------
>>> async def main():
...     async with LLMClient(ClientSettings(base_url="http://127.0.0.1:8080/v1", model="local")) as c:
...         r = await c.chat([{"role": "user", "content": "Say [1, 1]"}], replies=["[1, 1]"])
...         return r.text
"""

from __future__ import annotations

import asyncio
import email.utils
import json
import math
import os
import random
import ssl
import time
import zlib
from dataclasses import dataclass, field, replace
from typing import Any, Callable, Iterable, Mapping, Sequence

import httpx

from jswim.errors import ConfigError
from jswim.llm import constrain, credentials
from jswim.llm.budget import Budget, call_bound
from jswim.llm.cache import ResponseCache, request_key
from jswim.llm.errors import (LLMRequestError, LLMResponseError, LLMServerError, LLMSetupError, LLMTimeoutError,
                              no_answer)
from jswim.llm.pacing import Pacer
from jswim.llm.reasoning import REASONING_MAX_TOKENS, ReasoningState, check_mode
from jswim.llm.rejection import REQUIRED_FIELDS, rejection, server_text, validation_error
from jswim.llm.reply import Completion, MalformedReply, assemble_sse, looks_like_sse, read_completion
from jswim.llm.tokens import estimate_prompt_tokens
from jswim.llm.transport import LoopbackTransport
from jswim.llm.urls import endpoint, is_local_host, is_loopback, normalize_base_url, safe_url
from jswim.llm.usage import Usage, price_table

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
    """``value`` if it is ``None`` (the default) or a reply length limit in 1..:data:`MAX_TOKENS`."""
    if value is not None and not 1 <= value <= MAX_TOKENS:
        raise ConfigError(f"--max-tokens must be between 1 and {MAX_TOKENS}, got {value}")
    return value


#: Same-host 307/308 redirects a request follows before it fails.
MAX_REDIRECTS = 5

#: HTTP statuses worth retrying: timeout, conflict, rate limit (5xx are added in code).
RETRY_STATUSES = frozenset({408, 409, 429})




#: Request fields jswim itself sets, and the option that sets each: an extra field (a models
#: file's ``extra``, ``--extra-field``) naming one is refused, since it would change what is sent
#: behind the cost reservation, the study's identity and the record of what was sent.
CORE_FIELDS = {
    "model": "--model", "messages": "--prompt-file (the prompt template)", "max_tokens": "--max-tokens",
    "max_completion_tokens": "--max-tokens (with --reasoning on)", "temperature": "--temperature",
    "stream": "nothing: jswim always sends \"stream\": false (--omit-field stream leaves it out)",
    "response_format": "--constrain",
    "grammar": "--constrain", "reasoning_effort": "--reasoning-effort",
}


def check_extra_fields(fields: Iterable[tuple[str, Any]], option: str = "--extra-field") -> None:
    """Refuse an extra request field that jswim sets itself (:data:`CORE_FIELDS`).

    Raises
    ------
    ConfigError
        One line naming the field and the option that sets it.
    """
    for name, _ in fields:
        if name in CORE_FIELDS:
            raise ConfigError(f"{option} {name}=...: jswim sets {name!r} itself; use {CORE_FIELDS[name]}")


@dataclass(frozen=True)
class ClientSettings:
    """Connection and request settings.

    Attributes
    ----------
    base_url : str
        Server root including the API prefix, e.g. ``https://api.openai.com/v1``. Common other
        shapes are accepted and normalized (see :func:`jswim.llm.urls.normalize_base_url`).
    model : str
        Model name sent with each request (also keys the cache and the price table).
    api_key_env : str
        Name of the environment variable holding the API key (unset: no ``Authorization``).
    timeout_s : float
        Per-attempt timeout (connect, read, write, pool). A request that times out is a transient
        failure like a 5xx: sent again within the retry budget (``max_retries``, ``retry_for_s``,
        whose clock runs from when the first failed attempt went out, so the waits for answers
        that never came count); when the budget is spent on timeouts the call fails with
        :class:`~jswim.llm.errors.LLMTimeoutError`, saying the server is slow.
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
        Constrained decoding; see :mod:`jswim.llm.constrain`.
    server_kind : str
        The server's family (:data:`jswim.llm.constrain.SERVER_KINDS`, told by
        :func:`jswim.llm.probe.probe`); resolves ``constrain="auto"``.
    cache_dir : str or None
        Directory of the response cache; ``None`` disables it.
    prices : mapping or None
        USD per 1M tokens by model name, applied on any host; ``None`` uses
        :data:`jswim.llm.usage.DEFAULT_PRICES` where they apply (:func:`jswim.llm.usage.price_table`:
        not on this machine or the LAN, not for a model the server does not list, not for a reply
        whose ``model`` field names another model).
    price_local : bool
        Price calls at the list prices even on a local or LAN server (a local gateway that
        forwards to a paid API); default False: a local server's calls cost nothing.
    listed_models : tuple of str or None
        The models the server's ``/v1/models`` listed at preflight (``None``: not known).
    fast_transport : bool
        For ``http://`` servers on loopback, use :class:`jswim.llm.transport.LoopbackTransport`
        (asyncio streams) instead of httpx's default transport (anyio). Default True.
    omit_fields : tuple of str
        Optional request fields never sent (``"seed"``, ``"max_tokens"``, ``"stream"``, ...),
        for servers that reject them.
    reasoning : {"auto", "on", "off"}
        Reasoning models (:mod:`jswim.llm.reasoning`): switch to ``max_completion_tokens`` and the
        temperature the model accepts when the server's 400 asks for them (auto), use the
        reasoning budget from the start (on), or never switch (off).
    reasoning_max_tokens : int
        The reply budget once reasoning is on (default
        :data:`jswim.llm.reasoning.REASONING_MAX_TOKENS`).
    reasoning_effort : str or None
        Sent as ``reasoning_effort`` when given (``minimal``, ``low``, ``medium``, ``high``).
    extra_fields : tuple of (name, value)
        More fields of every request body (a models file's ``extra``, ``--extra-field``); a field
        jswim sets itself (:data:`CORE_FIELDS`: ``model``, ``messages``, ``max_tokens``,
        ``temperature``, ``stream``, ...) is refused with :class:`~jswim.errors.ConfigError`.
    sampling : tuple of (str, float)
        Sampling fields every request carries (``(("repeat_penalty", 1.0), ...)``;
        :func:`jswim.llm.sampling.sampling_fields`), before ``omit_fields`` are removed.
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
        object.__setattr__(self, "sampling", tuple((str(k), v) for k, v in dict(self.sampling).items()))
        object.__setattr__(self, "omit_fields", tuple(sorted(set(self.omit_fields))))
        required = sorted(set(self.omit_fields) & set(REQUIRED_FIELDS))
        if required:
            raise ConfigError(f"cannot leave out the request field(s) {', '.join(required)}: every request needs them")
        if self.constrain not in constrain.MODES:
            raise ConfigError(f"constrain must be one of {constrain.MODES}, got {self.constrain!r}")
        if self.server_kind not in constrain.SERVER_KINDS:
            raise ConfigError(f"server_kind must be one of {constrain.SERVER_KINDS}, got {self.server_kind!r}")
        if self.max_concurrency < 1 or self.max_retries < 0 or not (math.isfinite(self.timeout_s) and self.timeout_s > 0):
            raise ConfigError("need max_concurrency >= 1, max_retries >= 0 and a finite timeout_s > 0")
        if self.retry_for_s is not None and not (self.retry_for_s >= 0):  # also NaN
            raise ConfigError(f"retry_for_s must be >= 0 seconds, got {self.retry_for_s}")
        check_temperature(self.temperature)
        check_extra_fields(self.extra_fields)

    def metadata(self) -> dict[str, Any]:
        """Settings worth recording with a run (no secrets: only the key's variable name)."""
        return {
            "base_url": safe_url(self.base_url),
            "model": self.model,
            "temperature": self.temperature,
            "max_tokens": self.max_tokens,
            "seed": self.seed,
            "constrain": self.constrain,
            "server_kind": self.server_kind,
            "max_retries": self.max_retries,
            "retry_for_s": self.retry_for_s,
            "timeout_s": self.timeout_s,
            "omit_fields": list(self.omit_fields),
            "reasoning": self.reasoning,
            "reasoning_max_tokens": self.reasoning_max_tokens,
            "reasoning_effort": self.reasoning_effort,
            "extra_fields": dict(self.extra_fields),
            "sampling": dict(self.sampling),
        }


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
    temperature_sent: float | None = None  # what the request carried (a reasoning model may refuse ours)

    @property
    def truncated(self) -> bool:
        """The reply was cut off at ``max_tokens`` (``finish_reason == "length"``): no answer."""
        return self.finish_reason == "length"

    @property
    def cut_while_thinking(self) -> bool:
        """Cut off before any answer while the model was still reasoning (reasoning text or
        reasoning tokens, no answer text): the budget left no room to think."""
        return self.truncated and not self.text.strip() and bool(self.reasoning or self.usage.reasoning_tokens)

    def as_dict(self) -> dict[str, Any]:
        """A transcript record (the raw content only when it differs from ``text``)."""
        extra: dict[str, Any] = {}
        if self.reasoning:
            extra["reasoning"] = self.reasoning
        if self.raw != self.text:
            extra["raw"] = self.raw
        return {
            "text": self.text,
            "prompt_tokens": self.usage.prompt_tokens,
            "completion_tokens": self.usage.completion_tokens,
            "latency_s": round(self.latency_s, 6),
            "cache_hit": self.cache_hit,
            "shared": self.shared,
            "retries": self.retries,
            "cost_usd": self.cost_usd,
            "constraint": self.constraint,
            "finish_reason": self.finish_reason,
            **({"reasoning_tokens": self.usage.reasoning_tokens} if self.usage.reasoning_tokens else {}),
            **({"temperature_sent": self.temperature_sent} if self.temperature_sent is not None else {}),
            **extra,
        }


def decode_body(raw: bytes, content_encoding: str) -> bytes:
    """The body ``raw`` undone from its ``Content-Encoding`` (gzip, deflate, identity).

    A header that lies (a plain JSON body labelled ``gzip`` by a misconfigured proxy) or names
    an encoding we did not ask for leaves the body as it came: whether it is a completion is then
    decided by reading it, never by a decoding traceback.
    """
    out = raw
    for name in reversed([t.strip().lower() for t in content_encoding.split(",") if t.strip()]):
        try:
            if name in ("gzip", "x-gzip"):
                out = zlib.decompress(out, 16 + zlib.MAX_WBITS)
            elif name == "deflate":
                try:
                    out = zlib.decompress(out)
                except zlib.error:  # raw deflate, as some servers send it
                    out = zlib.decompress(out, -zlib.MAX_WBITS)
            elif name != "identity":
                return raw
        except zlib.error:
            return raw
    return out


def parse_retry_after(headers: httpx.Headers, now: float | None = None) -> float | None:
    """Seconds to wait from ``retry-after-ms``, or ``Retry-After`` (seconds or an HTTP date)."""
    ms = headers.get("retry-after-ms")
    if ms:
        try:
            return max(0.0, float(ms) / 1000.0)
        except ValueError:
            pass
    value = headers.get("retry-after")
    if not value:
        return None
    try:
        return max(0.0, float(value))
    except ValueError:
        pass
    try:
        when = email.utils.parsedate_to_datetime(value)
    except (TypeError, ValueError, IndexError):
        return None
    now = time.time() if now is None else now
    return max(0.0, when.timestamp() - now)


#: Kinds of transient failure, as counted in :attr:`LiveCounts.faults` (and a study's summary).
FAULT_KINDS = ("429", "5xx", "408/409", "connection", "timeout", "bad body")


class _Failure(Exception):
    """A retryable attempt failure (internal); ``kind`` is one of :data:`FAULT_KINDS`."""

    def __init__(self, what: str, retry_after: float | None = None, bad_body: bool = False,
                 timeout: bool = False, kind: str = "connection", unanswered: bool = False) -> None:
        super().__init__(what)
        self.what = what
        self.retry_after = retry_after
        self.bad_body = bad_body
        self.timeout = timeout
        #: The request went out whole and no answer came back (a read timeout, a connection cut
        #: while waiting): the server may have run, and billed, it.
        self.unanswered = unanswered
        self.kind = "bad body" if bad_body else "timeout" if timeout else kind


class _Adapted(Exception):
    """The server refused a field and said what it wants instead (internal; not billed)."""


class _Slot:
    """A permit to have one request in flight, with its own keep-alive connection."""

    __slots__ = ("http",)

    def __init__(self) -> None:
        self.http: httpx.AsyncClient | None = None


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


class LLMClient:
    """Async chat-completions client; use as ``async with LLMClient(settings) as client``.

    The client binds to the running event loop on first use; create one per ``asyncio.run``.
    ``pacer`` (:class:`jswim.llm.pacing.Pacer`) holds requests back to rate limits; ``budget``
    (:class:`jswim.llm.budget.Budget`) reserves each request's cost bound before it goes out and
    raises :class:`jswim.llm.budget.BudgetExhausted` past the cap.
    """

    def __init__(
        self, settings: ClientSettings, *, rng: random.Random | None = None, pacer: Pacer | None = None,
        budget: Budget | None = None,
    ) -> None:
        self.pacer = pacer
        self.budget = budget
        self.settings = settings
        self._key = credentials.read_api_key(settings.api_key_env)
        # User info of the base URL goes as HTTP Basic auth unless an API key is set (the key wins:
        # one Authorization header); either way it never stays in a URL a library could print.
        self._url, self._basic = credentials.split_userinfo(endpoint(settings.base_url))
        self._where = safe_url(settings.base_url)
        self._prices, self.unpriced = price_table(settings.prices, settings.model,
                                                  local_host=is_local_host(settings.base_url),
                                                  listed=settings.listed_models, price_local=settings.price_local)
        #: What a reasoning model must be sent, amended by the server's 400s (jswim.llm.reasoning).
        self.reasoning = ReasoningState(settings.reasoning, settings.reasoning_max_tokens, settings.reasoning_effort,
                                        openai="api.openai.com" in settings.base_url)
        self._cache: ResponseCache | None = None
        self._rng = rng or random.Random()
        self._inflight: dict[str, asyncio.Future] = {}
        self._slots: asyncio.LifoQueue[_Slot] | None = None
        self._all_slots: list[_Slot] = []
        self._ssl: ssl.SSLContext | None = None
        self.n_requests = 0  # HTTP attempts made
        self.counts = LiveCounts()
        self._auto_form: str | None = None  # under constrain="auto": the form the server took
        self._forms_tried: set[str] = set()
        #: Constrained-decoding forms the server rejected under ``"auto"`` (in order) and why.
        self.fallbacks: list[dict[str, str]] = []

    def __repr__(self) -> str:  # never show the key
        return f"LLMClient(base_url={self._where!r}, model={self.settings.model!r})"

    # -- lifecycle ---------------------------------------------------------------------------

    async def __aenter__(self) -> "LLMClient":
        self._open()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.aclose()

    def _open(self) -> None:
        if self._slots is not None:
            return
        if self.settings.cache_dir and self._cache is None:
            self._cache = ResponseCache(self.settings.cache_dir)
        # One single-connection httpx client per concurrency slot. httpcore's shared pool scans
        # every connection for every queued request (quadratic in the connections in use); with
        # one connection per client that bookkeeping is trivial. LIFO reuses warm connections.
        self._slots = asyncio.LifoQueue()
        self._all_slots = [_Slot() for _ in range(self.settings.max_concurrency)]
        for slot in self._all_slots:
            self._slots.put_nowait(slot)

    def _http_client(self) -> httpx.AsyncClient:
        s = self.settings
        if self._ssl is None:
            # Built once and shared: httpx builds a context per client even for plain http, and
            # loading the CA files takes ~15 ms, which for 64 slots was a second of every study.
            self._ssl = httpx.create_ssl_context()
        limits = httpx.Limits(max_connections=1, max_keepalive_connections=1)
        loopback = is_loopback(s.base_url)
        # Plain http on this machine: asyncio streams instead of anyio's (see transport.py);
        # about 8% less wall time per lockstep round against a fast server.
        fast = loopback and s.base_url.startswith("http://") and s.fast_transport
        return httpx.AsyncClient(
            timeout=httpx.Timeout(s.timeout_s),
            limits=limits,
            verify=self._ssl,
            transport=LoopbackTransport(limits) if fast else None,
            # Proxy variables must not divert loopback traffic (the embedded server).
            trust_env=not loopback,
        )

    async def aclose(self) -> None:
        slots, self._all_slots, self._slots = self._all_slots, [], None
        for slot in slots:
            if slot.http is not None:
                await slot.http.aclose()
        if self._cache is not None:
            self._cache.close()
            self._cache = None

    # -- requests ----------------------------------------------------------------------------

    def build_payload(
        self,
        messages: Sequence[Mapping[str, str]],
        *,
        replies: Sequence[str] | None = None,
        temperature: float | None = None,
        max_tokens: int | None = None,
        seed: int | None = None,
        constrain_mode: str | None = None,
    ) -> tuple[dict[str, Any], str]:
        """Request body and the resolved constraint mode.

        The body always says ``"stream": false`` (some servers stream unless told not to),
        then every field in ``omit_fields`` is removed.
        """
        s = self.settings
        payload: dict[str, Any] = {
            "model": s.model,
            "messages": [dict(m) for m in messages],
            "temperature": s.temperature if temperature is None else temperature,
            "stream": False,
        }
        mt = s.max_tokens if max_tokens is None else max_tokens
        if mt is not None:
            payload["max_tokens"] = mt
        sd = s.seed if seed is None else seed
        if sd is not None:
            payload["seed"] = sd
        payload.update(s.sampling)
        asked = constrain_mode or s.constrain
        if asked == "auto" and self._auto_form is not None:  # the server rejected auto's first form(s)
            asked = self._auto_form
        mode = constrain.resolve_mode(asked, s.server_kind, bool(replies))
        constrain.apply(payload, mode, replies)
        for name, value in s.extra_fields:
            if name not in REQUIRED_FIELDS:
                payload[name] = value
        payload = self.reasoning.apply(payload)
        for name in s.omit_fields:
            payload.pop(name, None)
        if "grammar" not in payload and "response_format" not in payload:
            mode = "none"
        return payload, mode

    async def chat(
        self,
        messages: Sequence[Mapping[str, str]],
        *,
        replies: Sequence[str] | None = None,
        temperature: float | None = None,
        max_tokens: int | None = None,
        seed: int | None = None,
        constrain_mode: str | None = None,
        use_cache: bool = True,
        cache_scope: str | None = None,
        cache_if: Callable[[ChatResult], bool] | None = None,
    ) -> ChatResult:
        """Send one chat completion and return its result.

        Parameters
        ----------
        messages : sequence of mapping
            OpenAI chat messages.
        replies : sequence of str, optional
            The valid replies; used for constrained decoding (grammar or JSON schema).
        temperature, max_tokens, seed, constrain_mode : optional
            Override the settings for this call.
        use_cache : bool
            Allow the disk cache and in-flight sharing (only deterministic requests use them).
        cache_scope : str, optional
            Part of the cache key besides the request: a call with a scope is only ever answered
            by an earlier call with the same scope and request (never shared with other scopes),
            e.g. ``"<run id>/<step>/<attempt>"`` so a run resumes from its own replies only.
        cache_if : callable, optional
            Put a reply in the disk cache only when this returns True (e.g. "it names a valid
            action"), so a failure is never replayed to a later run. Replies cut off at
            ``max_tokens`` and replies without an answer are never cached.

        Raises
        ------
        LLMServerError
            The server stayed unreachable or kept failing through every retry
            (:class:`~jswim.llm.errors.LLMTimeoutError` when it kept timing out).
        LLMRequestError
            The server rejected the request (e.g. 400: context too long);
            :class:`~jswim.llm.errors.LLMSetupError` when no request can succeed as configured
            (404, 401/403, a rejected field). The message names the server's own error.
        LLMResponseError
            The server kept sending bodies that are not chat completions.
        """
        self._open()
        while True:
            payload, mode = self.build_payload(
                messages, replies=replies, temperature=temperature, max_tokens=max_tokens, seed=seed,
                constrain_mode=constrain_mode,
            )
            try:
                return await self._chat(payload, mode, use_cache, cache_scope, cache_if)
            except LLMSetupError as exc:
                auto = (constrain_mode or self.settings.constrain) == "auto"
                if not (auto and mode != "none" and self._fall_back(mode, exc)):
                    raise

    def _fall_back(self, mode: str, exc: LLMSetupError) -> bool:
        """Under ``constrain="auto"``: after the server rejected the form ``mode``, move to the next
        form (:data:`jswim.llm.constrain.FALLBACK`); False when the error is not about the form
        or no form is left."""
        if exc.field not in ("grammar", "response_format"):
            return False
        self._forms_tried.add(mode)
        if self._auto_form is not None and self._auto_form != mode:
            return True  # another call already moved on: just send again
        nxt = constrain.next_form(self._forms_tried)
        if nxt is None:
            return False
        self.fallbacks.append({"rejected": mode, "server": exc.server_message, "next": nxt})
        self._auto_form = nxt
        return True

    async def _chat(self, payload: dict[str, Any], mode: str, use_cache: bool, cache_scope: str | None,
                    cache_if: Callable[[ChatResult], bool] | None) -> ChatResult:
        t0 = time.perf_counter()
        deterministic = use_cache and payload.get("temperature", 0) == 0
        if not deterministic:
            return await self._send(payload, mode, t0)
        key = request_key(payload if cache_scope is None else {**payload, "jswim_cache_scope": cache_scope})
        if self._cache is not None:
            hit = self._cache.get(key)
            if hit is not None:
                self.counts.cache_hits += 1
                return self._from_cache(hit, mode, time.perf_counter() - t0)
        pending = self._inflight.get(key)
        if pending is not None:
            self.counts.shared += 1
            res = await asyncio.shield(pending)
            return replace(res, shared=True, retries=0, latency_s=time.perf_counter() - t0)
        fut = asyncio.get_running_loop().create_future()
        self._inflight[key] = fut
        try:
            res = await self._send(payload, mode, t0)
        except BaseException as exc:
            if not isinstance(exc, Exception):  # cancelled: waiters get an error, not a cancel
                exc = LLMServerError(f"{self._where}: request cancelled")
            fut.set_exception(exc)
            fut.exception()  # mark retrieved: nobody may be waiting
            raise
        else:
            fut.set_result(res)
            if self._cache is not None and self._cacheable(res, cache_if):
                self._cache.put(key, self._to_cache(res))
            return res
        finally:
            self._inflight.pop(key, None)

    @staticmethod
    def _cacheable(res: ChatResult, cache_if: Callable[[ChatResult], bool] | None) -> bool:
        if res.truncated or not res.text.strip() or res.temperature_sent:  # sampled after all: never cached
            return False
        return cache_if is None or bool(cache_if(res))

    def _to_cache(self, res: ChatResult) -> dict[str, Any]:
        u = res.usage
        return {
            "raw": res.raw,
            "reasoning": res.reasoning,
            "text": res.text,
            "finish_reason": res.finish_reason,
            "usage": [u.prompt_tokens, u.completion_tokens, u.cached_tokens, u.reasoning_tokens],
        }

    def _from_cache(self, value: dict[str, Any], mode: str, latency: float) -> ChatResult:
        usage = Usage(*value["usage"])
        return ChatResult(
            text=value["text"], usage=usage, latency_s=latency, cache_hit=True,
            shared=False, retries=0, cost_usd=self._prices.cost(self.settings.model, usage),
            constraint=mode, finish_reason=value.get("finish_reason"), raw=value["raw"],
            reasoning=value.get("reasoning", ""),
        )

    def _scrub(self, text: str) -> str:
        return credentials.scrub(text)  # the key and URL credentials, in any encoding

    def _headers(self) -> dict[str, str]:
        if self._key:
            return {"Authorization": f"Bearer {self._key}"}
        return {"Authorization": self._basic} if self._basic else {}

    def _backoff(self, retry: int) -> float:
        s = self.settings
        return min(s.backoff_max_s, s.backoff_base_s * 2.0**retry) * (0.5 + 0.5 * self._rng.random())

    async def _send(self, payload: dict[str, Any], mode: str, t0: float) -> ChatResult:
        s = self.settings
        slots = self._slots
        assert slots is not None
        retries = 0
        adaptations = 0
        first_failure: float | None = None  # when the first failed attempt went out
        while True:
            tokens = estimate_prompt_tokens(payload["messages"]) + int(
                payload.get("max_tokens") or payload.get("max_completion_tokens") or 0)
            if self.pacer is not None:
                await self.pacer.wait(tokens)
            slot = await slots.get()
            held = 0.0
            try:
                if self.budget is not None:  # reserved while in flight, settled by the answer
                    held = self.budget.reserve(call_bound(payload, self._prices, s.model))
                if slot.http is None:
                    slot.http = self._http_client()
                self.n_requests += 1
                self.counts.requests += 1
                self.counts.retries += retries > 0
                self.counts.in_flight += 1
                sent_at = time.perf_counter()
                try:
                    got = await self._attempt(slot.http, payload)
                except _Adapted:
                    if self.budget is not None:
                        self.budget.release(held)
                    adaptations += 1
                    if adaptations > 3:  # a server that keeps refusing what it asked for
                        raise self._rejection(400, "the server kept refusing the amended request", payload) from None
                    payload = self._amend(payload)
                    continue
                except BaseException as exc:
                    # Sent and never answered (a timeout, a cut, a Ctrl-C while waiting): the server
                    # may bill it, so its bound stays counted against the cap; anything else was
                    # refused or never arrived and costs nothing.
                    if isinstance(exc, _Failure) and exc.unanswered or isinstance(exc, asyncio.CancelledError):
                        bound = call_bound(payload, self._prices, s.model)
                        self.counts.unanswered += 1
                        self.counts.unanswered_usd += bound
                        if self.budget is not None:
                            self.budget.unanswered(held)
                    elif self.budget is not None:
                        self.budget.release(held)
                    if isinstance(exc, _Failure) and first_failure is None:
                        first_failure = sent_at
                    raise
                finally:
                    self.counts.in_flight -= 1
                res = self._attempt_result(got, mode, t0, retries, payload)
                if self.budget is not None:
                    self.budget.settle(held, res.cost_usd)
                self.counts.tokens += res.usage.prompt_tokens + res.usage.completion_tokens
                self.counts.cost_usd += res.cost_usd
                return res
            except _Failure as fail:
                self.counts.faults[fail.kind] = self.counts.faults.get(fail.kind, 0) + 1
                now = time.perf_counter()
                first_failure = now if first_failure is None else first_failure
                left = math.inf if s.retry_for_s is None else s.retry_for_s - (now - first_failure)
                if retries >= s.max_retries or left <= 0:
                    spent = f"{retries} retries over {now - first_failure:.0f} s"
                    budget = (f"the budget is --retries {s.max_retries}, "
                              f"--retry-for {s.retry_for_s if s.retry_for_s is not None else 'none'}")
                    if fail.timeout:  # the last straw was a timeout: say slow, and what to raise
                        raise LLMTimeoutError(self._scrub(
                            f"{self._where}: the server is slow: no answer within {s.timeout_s:g} s; gave up after "
                            f"{retries + 1} attempts ({spent}; {budget}); a cold local server may still be loading "
                            f"its model: wait for it or raise --timeout (now {s.timeout_s:g} s)"
                        )) from None
                    msg = f"{self._where}: {fail.what}; gave up after {retries + 1} attempts ({spent}; {budget})"
                    raise (LLMResponseError if fail.bad_body else LLMServerError)(self._scrub(msg)) from None
                # A timed-out request already waited a whole timeout: send it again at once.
                wait = 0.0 if fail.timeout else self._backoff(retries)
                if fail.retry_after is not None:
                    wait = min(fail.retry_after, s.max_retry_after_s)
                wait = min(wait, left)  # the last attempt goes out at the deadline, not after it
                retries += 1
            finally:
                slots.put_nowait(slot)  # free the slot before any backoff wait
            await asyncio.sleep(wait)

    async def _attempt(self, http: httpx.AsyncClient, payload: dict[str, Any]) -> Completion:
        s = self.settings
        try:
            resp = await self._post(http, payload)
        except httpx.TransportError as exc:
            kind, unanswered = no_answer(exc)
            if kind == "connect":
                raise _Failure(f"could not connect within {s.timeout_s:g} s", kind="connection") from None
            if kind == "timeout":
                raise _Failure(f"no answer within {s.timeout_s:g} s (timeout)", timeout=True,
                               unanswered=unanswered) from None
            detail = self._scrub(str(exc)) or "no detail"
            raise _Failure(f"connection failed ({type(exc).__name__}: {detail})", unanswered=unanswered) from None
        if self.pacer is not None:
            self.pacer.observe(resp.headers)
        status = resp.status_code
        if status in RETRY_STATUSES or status >= 500:
            # A 5xx whose body is a request-validation error is the server refusing the request.
            invalid = validation_error(resp) if status not in (408, 429) else None
            if invalid is not None:
                raise self._rejection(status, invalid, payload, invalid=True)
            detail = server_text(resp)
            raise _Failure(f"HTTP {status}" + (f": {detail}" if detail else ""),
                           retry_after=parse_retry_after(resp.headers),
                           kind="429" if status == 429 else "5xx" if status >= 500 else "408/409")
        if status != 200:
            said = server_text(resp)
            if status == 400 and self.reasoning.adapt(said, payload, s.model):
                raise _Adapted()  # the server said what it wants: send the request again as amended
            raise self._rejection(status, said, payload, invalid=validation_error(resp) is not None)
        text = resp.text
        ctype = resp.headers.get("content-type", "")
        try:
            if looks_like_sse(ctype, text):  # streamed although "stream": false was sent
                return read_completion(assemble_sse(text), streamed=True)
            return read_completion(json.loads(text))
        except MalformedReply as exc:
            raise _Failure(f"the response is not a chat completion ({exc})", bad_body=True) from None
        except ValueError:
            snippet = " ".join(text.split())[:80] or "empty"
            raise _Failure(
                f"the response is not a chat completion (malformed body, {ctype or 'no content type'}: {snippet})",
                bad_body=True,
            ) from None

    async def _post(self, http: httpx.AsyncClient, payload: dict[str, Any]) -> httpx.Response:
        """POST ``payload`` and read the body as it was sent (see :func:`decode_body`).

        A 307 or 308 to the same scheme, host and port is followed (at most
        :data:`MAX_REDIRECTS`, the body and the key sent again); one to another host is refused
        (:class:`~jswim.llm.errors.LLMSetupError`): the key never goes to a host nobody named."""
        headers = {**self._headers(), "Accept-Encoding": "gzip, deflate"}  # what decode_body reads
        url = httpx.URL(self._url)
        for _ in range(MAX_REDIRECTS + 1):
            async with http.stream("POST", url, json=payload, headers=headers) as resp:
                raw = b"".join([chunk async for chunk in resp.aiter_raw()])
            if resp.status_code not in (307, 308) or "location" not in resp.headers:
                break
            try:
                nxt = url.join(resp.headers["location"])
            except (httpx.InvalidURL, ValueError):
                raise LLMSetupError(self._scrub(f"{self._where}: HTTP {resp.status_code} to an address that does "
                                                "not parse; give --base-url the server's address"),
                                    resp.status_code, "") from None
            if (nxt.scheme, nxt.host, nxt.port) != (url.scheme, url.host, url.port):
                raise LLMSetupError(self._scrub(
                    f"{self._where}: HTTP {resp.status_code} redirects to another host ({safe_url(str(nxt.copy_with(query=None)))}); "
                    "not followed, so the API key is not sent there: give --base-url that address if you trust it"),
                    resp.status_code, "")
            url = nxt
        else:
            raise LLMSetupError(self._scrub(f"{self._where}: more than {MAX_REDIRECTS} redirects; give --base-url "
                                            "the address they lead to"), resp.status_code, "")
        kept = [(k, v) for k, v in resp.headers.multi_items() if k.lower() not in ("content-encoding", "content-length")]
        return httpx.Response(resp.status_code, headers=kept, request=resp.request,
                              content=decode_body(raw, resp.headers.get("content-encoding", "")))

    def _rejection(self, status: int, server: str, payload: Mapping[str, Any], invalid: bool = False) -> LLMRequestError:
        s = self.settings
        err = rejection(status, server, payload, where=self._where, url=safe_url(self._url), model=s.model,
                        api_key_env=s.api_key_env, invalid=invalid)
        err.args = (self._scrub(str(err)),)
        err.server_message = self._scrub(err.server_message)
        return err

    def _cost(self, usage: Usage, replied: str | None) -> float:
        """What a call cost: nothing when the reply says another model ran than the one priced
        (a server that echoes any requested name), unless the user gave the prices."""
        s = self.settings
        if s.prices is None and not self._prices.agrees(s.model, replied):
            if self.budget is not None and self.budget.cap_usd is not None:
                # Under --max-cost a $0 call would let the cap lapse: priced as requested, and said.
                if self.unpriced is None:
                    self.unpriced = (f"the server says it ran {replied!r}, not {s.model!r}; priced at {s.model}'s "
                                     "price anyway, because --max-cost needs a price (--prices FILE gives yours)")
                return self._prices.cost(s.model, usage)
            if self.unpriced is None:
                self.unpriced = (f"the server says it ran {replied!r}, not {s.model!r}: its calls are not priced at "
                                 f"{s.model}'s list price; --prices FILE gives your own prices, applied as given")
            return 0.0
        return self._prices.cost(s.model, usage)

    def _amend(self, payload: dict[str, Any]) -> dict[str, Any]:
        """``payload`` as the reasoning state now sends it (omitted fields stay omitted)."""
        out = self.reasoning.apply(payload)
        for name in self.settings.omit_fields:
            out.pop(name, None)
        return out

    def _attempt_result(self, got: Completion, mode: str, t0: float, retries: int,
                        payload: Mapping[str, Any] | None = None) -> ChatResult:
        usage = Usage.from_response(got.usage)
        # A reply may echo a credential (a proxy quoting the request's headers): scrubbed by the
        # registry the error messages use, before the journal, the cache or a transcript see it.
        clean = self._scrub
        return ChatResult(
            text=clean(constrain.reply_text(mode, got.answer)), usage=usage, latency_s=time.perf_counter() - t0,
            cache_hit=False, shared=False, retries=retries,
            cost_usd=self._cost(usage, got.model), constraint=mode,
            finish_reason=got.finish_reason, raw=clean(got.content), reasoning=clean(got.reasoning),
            temperature_sent=(payload or {}).get("temperature"),
        )

