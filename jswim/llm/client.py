"""Async client for OpenAI-compatible chat-completions servers, over httpx.

One [`LLMClient`][jswim.llm.client.LLMClient] serves a whole study: many requests in flight at once (bounded by a
semaphore), retries with backoff and jitter within one budget per call (``max_retries``,
``retry_for_s``), requests that got no answer counted as possibly billed, a disk cache and
in-flight de-duplication for temperature-0 requests, and usage/cost per call. How it absorbs real
servers' differences (streams, reasoning, content shapes, base URLs: `jswim.llm.server_response`,
`jswim.llm.urls`), what it retries and what a rejection says are in docs/servers.md; how the
API key is kept (only in the ``Authorization`` header) in docs/studies.md (*Secrets*).

Example
-------
>>> async def main():
...     async with LLMClient(ClientSettings(base_url="http://127.0.0.1:8080/v1", model="local")) as c:
...         r = await c.chat([{"role": "user", "content": "Say [1, 1]"}], replies=["[1, 1]"])
...         return r.text
"""

from __future__ import annotations

import asyncio
import json
import math
import random
import ssl
import time
from dataclasses import replace
from typing import Any
from collections.abc import Callable, Mapping, Sequence

import httpx

from jswim.llm import constrain, credentials
from jswim.llm.budget import Budget, Hold, call_bound
from jswim.llm.response_cache import ResponseCache, request_key
from jswim.errors import (
    LLMRequestError,
    LLMResponseError,
    LLMServerError,
    LLMSetupError,
    LLMTimeoutError,
)
from jswim.llm.http_errors import no_answer
from jswim.llm.pacing import Pacer
from jswim.llm.reasoning import ReasoningState
from jswim.llm.rejection import REQUIRED_FIELDS, rejection, server_text, validation_error
from jswim.llm.server_response import (
    Completion,
    MalformedReply,
    assemble_sse,
    decode_body,
    looks_like_sse,
    parse_retry_after,
    read_completion,
)
from jswim.llm.result import FAULT_KINDS, ChatResult, LiveCounts  # noqa: F401  (also read from here)
from jswim.llm.settings import (  # noqa: F401
    CORE_FIELDS,
    MAX_TOKENS,
    ClientSettings,
    check_extra_fields,
    check_max_tokens,
    check_temperature,
)
from jswim.llm.tokens import estimate_prompt_tokens
from jswim.llm.transport import LoopbackTransport
from jswim.llm.urls import endpoint, is_loopback, safe_url
from jswim.llm.usage import Usage

#: The key and URL credentials taken out of a text, in any encoding.
_scrub = credentials.scrub

#: Same-host 307/308 redirects a request follows before it fails.
MAX_REDIRECTS = 5

#: HTTP statuses worth retrying: timeout, conflict, rate limit (5xx are added in code).
RETRY_STATUSES = frozenset({408, 409, 429})

#: The largest response body read; a longer one is a bad body (billed at its reservation).
MAX_BODY_BYTES = 8 << 20

#: What is kept of a reply's text, raw content and reasoning: this many characters per token of
#: ``max_tokens`` plus `KEEP_BASE` (no tokenizer's token is longer than a few dozen
#: characters, so an honest reply is never cut; a server that sends a megabyte under
#: ``max_tokens`` 10 fills no folder).
KEEP_PER_TOKEN = 32
KEEP_BASE = 1024


def kept(text: str, max_tokens: int) -> str:
    """``text`` cut to ``KEEP_BASE + KEEP_PER_TOKEN * max_tokens`` characters, the cut said."""
    limit = KEEP_BASE + KEEP_PER_TOKEN * max(0, max_tokens)
    if len(text) <= limit:
        return text
    return text[:limit] + f" [jswim: {len(text) - limit} more characters not kept]"


class _Failure(Exception):
    """A retryable attempt failure (internal); ``kind`` is one of `FAULT_KINDS`."""

    def __init__(
        self,
        what: str,
        retry_after: float | None = None,
        bad_body: bool = False,
        timeout: bool = False,
        kind: str = "connection",
        unanswered: bool = False,
    ) -> None:
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


class LLMClient:
    """Async chat-completions client; use as ``async with LLMClient(settings) as client``.

    The client binds to the running event loop on first use; create one per ``asyncio.run``.
    ``pacer`` ([`jswim.llm.pacing.Pacer`][jswim.llm.pacing.Pacer]) holds requests back to rate limits; ``budget``
    ([`jswim.llm.budget.Budget`][jswim.llm.budget.Budget]) reserves each request's cost bound before it goes out and
    raises [`jswim.llm.budget.BudgetExhausted`][jswim.errors.BudgetExhausted] past the cap.
    """

    def __init__(
        self,
        settings: ClientSettings,
        *,
        rng: random.Random | None = None,
        pacer: Pacer | None = None,
        budget: Budget | None = None,
    ) -> None:
        self.pacer = pacer
        self.budget = budget
        self.settings = settings
        if pacer is not None and settings.retry_for_s is not None:
            # A Retry-After longer than the retry time is no reason to wait past it.
            pacer.max_pause_s = min(pacer.max_pause_s, max(settings.retry_for_s, 0.0))
        self._key = credentials.read_api_key(settings.api_key_env)
        # User info of the base URL goes as HTTP Basic auth unless an API key is set (the key wins:
        # one Authorization header); either way it never stays in a URL a library could print.
        self._url, self._basic = credentials.split_userinfo(endpoint(settings.base_url))
        self._where = safe_url(settings.base_url)
        self._prices, self.unpriced = settings.price_table()
        #: What a reasoning model must be sent, amended by the server's 400s (jswim.llm.reasoning).
        self.reasoning = ReasoningState(
            settings.reasoning,
            settings.reasoning_max_tokens,
            settings.reasoning_effort,
            openai="api.openai.com" in settings.base_url,
        )
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

    async def __aenter__(self) -> LLMClient:
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
        given = {
            "max_tokens": s.max_tokens if max_tokens is None else max_tokens,
            "seed": s.seed if seed is None else seed,
        }
        payload.update({k: v for k, v in given.items() if v is not None})
        payload.update(s.sampling)
        asked = constrain_mode or s.constrain
        if (
            asked == "auto" and self._auto_form is not None
        ):  # the server rejected auto's first form(s)
            asked = self._auto_form
        mode = constrain.resolve_mode(asked, s.server_kind, bool(replies))
        constrain.apply(payload, mode, replies)
        for name, value in s.extra_fields:
            if name not in REQUIRED_FIELDS:
                payload[name] = value
        payload = self._amend(payload)
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
            ([`LLMTimeoutError`][jswim.errors.LLMTimeoutError] when it kept timing out).
        LLMRequestError
            The server rejected the request (e.g. 400: context too long);
            [`LLMSetupError`][jswim.errors.LLMSetupError] when no request can succeed as configured
            (404, 401/403, a rejected field). The message names the server's own error.
        LLMResponseError
            The server kept sending bodies that are not chat completions.
        """
        self._open()
        while True:
            payload, mode = self.build_payload(
                messages,
                replies=replies,
                temperature=temperature,
                max_tokens=max_tokens,
                seed=seed,
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
        form (`jswim.llm.constrain.FALLBACK`); False when the error is not about the form
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

    async def _chat(
        self,
        payload: dict[str, Any],
        mode: str,
        use_cache: bool,
        cache_scope: str | None,
        cache_if: Callable[[ChatResult], bool] | None,
    ) -> ChatResult:
        t0 = time.perf_counter()
        deterministic = use_cache and payload.get("temperature", 0) == 0
        if not deterministic:
            return await self._send(payload, mode, t0)
        key = request_key(
            payload if cache_scope is None else {**payload, "jswim_cache_scope": cache_scope}
        )
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
        if (
            res.truncated or not res.text.strip() or res.temperature_sent
        ):  # sampled after all: never cached
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
            text=value["text"],
            usage=usage,
            latency_s=latency,
            cache_hit=True,
            shared=False,
            retries=0,
            cost_usd=self._prices.cost(self.settings.model, usage),
            constraint=mode,
            finish_reason=value.get("finish_reason"),
            raw=value["raw"],
            reasoning=value.get("reasoning", ""),
        )

    def _headers(self) -> dict[str, str]:
        if self._key:
            return {"Authorization": f"Bearer {self._key}"}
        return {"Authorization": self._basic} if self._basic else {}

    def _backoff(self, retry: int) -> float:
        s = self.settings
        return min(s.backoff_max_s, s.backoff_base_s * 2.0**retry) * (
            0.5 + 0.5 * self._rng.random()
        )

    async def _send(self, payload: dict[str, Any], mode: str, t0: float) -> ChatResult:
        s = self.settings
        slots = self._slots
        assert slots is not None
        retries = 0
        adaptations = 0
        first_failure: float | None = None  # when the first failed attempt went out
        while True:
            tokens = estimate_prompt_tokens(payload["messages"]) + int(
                payload.get("max_tokens") or payload.get("max_completion_tokens") or 0
            )
            if self.pacer is not None:
                await self.pacer.wait(tokens)
            slot = await slots.get()
            held: Hold | None = None
            try:
                if self.budget is not None:  # reserved while in flight, settled by the answer
                    held = self.budget.reserve(
                        call_bound(payload, self._prices, s.model), retry=retries > 0
                    )
                if slot.http is None:
                    slot.http = self._http_client()
                self.n_requests += 1
                self.counts.requests += 1
                self.counts.retries += retries > 0
                self.counts.in_flight += 1
                sent_at = time.perf_counter()
                try:
                    try:
                        async with asyncio.timeout(self._attempt_limit()):
                            got = await self._attempt(slot.http, payload)
                    except TimeoutError:
                        # A reply that keeps coming (a stream that never ends): it is being
                        # generated, so it may be billed.
                        raise _Failure(
                            f"no whole answer within {self._attempt_limit():g} s (the reply kept "
                            "coming; --timeout and --retry-for bound one attempt)",
                            kind="timeout",
                            unanswered=True,
                        ) from None
                except _Adapted:
                    if held is not None:
                        self.budget.release(held)
                    adaptations += 1
                    if adaptations > 3:  # a server that keeps refusing what it asked for
                        raise self._rejection(
                            400, "the server kept refusing the amended request", payload
                        ) from None
                    payload = self._amend(payload)
                    continue
                except BaseException as exc:
                    # Sent and never answered (a timeout, a cut, a Ctrl-C while waiting): the server
                    # may bill it, so its bound stays counted against the cap; anything else was
                    # refused or never arrived and costs nothing.
                    bound = held.usd if held is not None else self._bound(payload)
                    fault = exc.kind if isinstance(exc, _Failure) else None  # for the ledger
                    if (isinstance(exc, _Failure) and exc.unanswered) or isinstance(
                        exc, asyncio.CancelledError
                    ):
                        self.counts.unanswered += 1
                        self.counts.unanswered_usd += bound
                        if held is not None:
                            self.budget.unanswered(held, fault)
                    elif isinstance(exc, _Failure) and exc.bad_body:
                        # Answered 200 with a body that is no chat completion: the server ran
                        # the request and may bill it, so it is spent, at its reservation.
                        self.counts.cost_usd += bound
                        if held is not None:
                            self.budget.settle(held, bound, fault)
                    elif held is not None:
                        self.budget.release(held, fault)
                    if isinstance(exc, _Failure) and first_failure is None:
                        first_failure = sent_at
                    raise
                finally:
                    self.counts.in_flight -= 1
                res = self._attempt_result(
                    got,
                    mode,
                    t0,
                    retries,
                    payload,
                    reserved=held.usd if held is not None else self._bound(payload),
                )
                if held is not None:
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
                    budget = (
                        f"the budget is --retries {s.max_retries}, "
                        f"--retry-for {s.retry_for_s if s.retry_for_s is not None else 'none'}"
                    )
                    if fail.timeout:  # the last straw was a timeout: say slow, and what to raise
                        raise LLMTimeoutError(
                            _scrub(
                                f"{self._where}: the server is slow: no answer within {s.timeout_s:g} s; gave up after "
                                f"{retries + 1} attempts ({spent}; {budget}); a cold local server may still be loading "
                                f"its model: wait for it or raise --timeout (now {s.timeout_s:g} s)"
                            )
                        ) from None
                    msg = f"{self._where}: {fail.what}; gave up after {retries + 1} attempts ({spent}; {budget})"
                    raise (LLMResponseError if fail.bad_body else LLMServerError)(
                        _scrub(msg)
                    ) from None
                # A timed-out request already waited a whole timeout: send it again at once.
                wait = 0.0 if fail.timeout else self._backoff(retries)
                if fail.retry_after is not None:
                    wait = min(fail.retry_after, s.max_retry_after_s)
                wait = min(wait, left)  # the last attempt goes out at the deadline, not after it
                retries += 1
            finally:
                slots.put_nowait(slot)  # free the slot before any backoff wait
            await asyncio.sleep(wait)

    def _bound(self, payload: Mapping[str, Any]) -> float:
        """A request's cost bound at this client's prices, scaled as the budget scales it."""
        ratio = self.budget.ratio if self.budget is not None else 1.0
        return call_bound(payload, self._prices, self.settings.model) * ratio

    def _attempt_limit(self) -> float:
        """Longest wall time of one attempt, first byte to last: --timeout or --retry-for,
        whichever is longer (ten times --timeout without a retry time); a reply streamed for
        ever is cut there."""
        s = self.settings
        return max(s.timeout_s, 10 * s.timeout_s if s.retry_for_s is None else s.retry_for_s)

    async def _attempt(self, http: httpx.AsyncClient, payload: dict[str, Any]) -> Completion:
        s = self.settings
        try:
            resp = await self._post(http, payload)
        except httpx.TransportError as exc:
            kind, unanswered = no_answer(exc)
            if kind == "connect":
                raise _Failure(
                    f"could not connect within {s.timeout_s:g} s", kind="connection"
                ) from None
            if kind == "timeout":
                raise _Failure(
                    f"no answer within {s.timeout_s:g} s (timeout)",
                    timeout=True,
                    unanswered=unanswered,
                ) from None
            detail = _scrub(str(exc)) or "no detail"
            raise _Failure(
                f"connection failed ({type(exc).__name__}: {detail})", unanswered=unanswered
            ) from None
        if self.pacer is not None:
            self.pacer.observe(resp.headers)
        status = resp.status_code
        if status in RETRY_STATUSES or status >= 500:
            # A 5xx whose body is a request-validation error is the server refusing the request.
            invalid = validation_error(resp) if status not in (408, 429) else None
            if invalid is not None:
                raise self._rejection(status, invalid, payload, invalid=True)
            detail = server_text(resp)
            raise _Failure(
                f"HTTP {status}" + (f": {detail}" if detail else ""),
                retry_after=parse_retry_after(resp.headers),
                kind="429" if status == 429 else "5xx" if status >= 500 else "408/409",
            )
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
            raise _Failure(
                f"the response is not a chat completion ({exc})", bad_body=True
            ) from None
        except ValueError:
            snippet = " ".join(text.split())[:80] or "empty"
            raise _Failure(
                f"the response is not a chat completion (malformed body, {ctype or 'no content type'}: {snippet})",
                bad_body=True,
            ) from None

    async def _post(self, http: httpx.AsyncClient, payload: dict[str, Any]) -> httpx.Response:
        """POST ``payload`` and read the body as it was sent (see `decode_body`).

        A 307 or 308 to the same scheme, host and port is followed (at most
        `MAX_REDIRECTS`, the body and the key sent again); one to another host is refused
        ([`LLMSetupError`][jswim.errors.LLMSetupError]): the key never goes to a host nobody named."""
        headers = {**self._headers(), "Accept-Encoding": "gzip, deflate"}  # what decode_body reads
        url = httpx.URL(self._url)
        for _ in range(MAX_REDIRECTS + 1):
            async with http.stream("POST", url, json=payload, headers=headers) as resp:
                parts, size = [], 0
                async for chunk in resp.aiter_raw():
                    size += len(chunk)
                    if size > MAX_BODY_BYTES:
                        # A 200 this large was run (and may be billed): a bad body; an error
                        # status this large is a failure like any other of its status.
                        raise _Failure(
                            f"HTTP {resp.status_code}: the response is larger than "
                            f"{MAX_BODY_BYTES >> 20} MiB, not a chat completion",
                            bad_body=resp.status_code == 200,
                            kind="5xx" if resp.status_code >= 500 else "connection",
                        )
                    parts.append(chunk)
                raw = b"".join(parts)
            if resp.status_code not in (307, 308) or "location" not in resp.headers:
                break
            try:
                nxt = url.join(resp.headers["location"])
            except (httpx.InvalidURL, ValueError):
                raise LLMSetupError(
                    _scrub(
                        f"{self._where}: HTTP {resp.status_code} to an address that does "
                        "not parse; give --base-url the server's address"
                    ),
                    resp.status_code,
                    "",
                ) from None
            if (nxt.scheme, nxt.host, nxt.port) != (url.scheme, url.host, url.port):
                raise LLMSetupError(
                    _scrub(
                        f"{self._where}: HTTP {resp.status_code} redirects to another host ({safe_url(str(nxt.copy_with(query=None)))}); "
                        "not followed, so the API key is not sent there: give --base-url that address if you trust it"
                    ),
                    resp.status_code,
                    "",
                )
            url = nxt
        else:
            raise LLMSetupError(
                _scrub(
                    f"{self._where}: more than {MAX_REDIRECTS} redirects; give --base-url "
                    "the address they lead to"
                ),
                resp.status_code,
                "",
            )
        kept = [
            (k, v)
            for k, v in resp.headers.multi_items()
            if k.lower() not in ("content-encoding", "content-length")
        ]
        return httpx.Response(
            resp.status_code,
            headers=kept,
            request=resp.request,
            content=decode_body(raw, resp.headers.get("content-encoding", "")),
        )

    def _rejection(
        self, status: int, server: str, payload: Mapping[str, Any], invalid: bool = False
    ) -> LLMRequestError:
        s = self.settings
        err = rejection(
            status,
            server,
            payload,
            where=self._where,
            url=safe_url(self._url),
            model=s.model,
            api_key_env=s.api_key_env,
            invalid=invalid,
        )
        err.args = (_scrub(str(err)),)
        err.server_message = _scrub(err.server_message)
        return err

    def _cost(self, usage: Usage, replied: str | None) -> float:
        """What a call cost: nothing when the reply says another model ran than the one priced
        (a server that echoes any requested name), unless the user gave the prices."""
        s = self.settings
        if s.prices is None and not self._prices.agrees(s.model, replied):
            if self.budget is not None and self.budget.cap_usd is not None:
                # Under --max-cost a $0 call would let the cap lapse: priced as requested, and said.
                if self.unpriced is None:
                    self.unpriced = (
                        f"the server says it ran {replied!r}, not {s.model!r}; priced at {s.model}'s "
                        "price anyway, because --max-cost needs a price (--prices FILE gives yours)"
                    )
                return self._prices.cost(s.model, usage)
            if self.unpriced is None:
                self.unpriced = (
                    f"the server says it ran {replied!r}, not {s.model!r}: its calls are not priced at "
                    f"{s.model}'s list price; --prices FILE gives your own prices, applied as given"
                )
            return 0.0
        return self._prices.cost(s.model, usage)

    def _amend(self, payload: dict[str, Any]) -> dict[str, Any]:
        """``payload`` as the reasoning state now sends it (omitted fields stay omitted)."""
        out = self.reasoning.apply(payload)
        for name in self.settings.omit_fields:
            out.pop(name, None)
        return out

    def _attempt_result(
        self,
        got: Completion,
        mode: str,
        t0: float,
        retries: int,
        payload: Mapping[str, Any] | None = None,
        reserved: float = 0.0,
    ) -> ChatResult:
        usage = Usage.from_response(got.usage)
        cost = self._cost(usage, got.model)
        if not Usage.priceable(got.usage):
            # No usage, or counts that are no token counts (negative, NaN, text): the call is
            # priced at its reservation, the most it was allowed to cost, never at $0.
            cost = max(cost, reserved)
            if reserved > 0 and self.unpriced is None:
                self.unpriced = (
                    "the server sent no usable token counts; each such call is priced at its "
                    "reservation (prompt estimate plus max_tokens), the most it could cost"
                )
        p = payload or {}
        room = int(p.get("max_tokens") or p.get("max_completion_tokens") or 4096)
        # A reply may echo a credential (a proxy quoting the request's headers): scrubbed by the
        # registry the error messages use, before the journal, the cache or a transcript see it;
        # and cut to what max_tokens can honestly produce ([`kept`][jswim.llm.client.kept]).
        return ChatResult(
            text=kept(_scrub(constrain.reply_text(mode, got.answer)), room),
            usage=usage,
            latency_s=time.perf_counter() - t0,
            cache_hit=False,
            shared=False,
            retries=retries,
            cost_usd=cost,
            constraint=mode,
            finish_reason=got.finish_reason,
            raw=kept(_scrub(got.content), room),
            reasoning=kept(_scrub(got.reasoning), room),
            temperature_sent=(payload or {}).get("temperature"),
        )
