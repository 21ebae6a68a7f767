"""Pacing requests to a provider's rate limits before the 429s come.

[`Pacer`][jswim.llm.pacing.Pacer] uses two sources together: the user's limits, ``rpm`` and ``tpm``, enforced with
`aiolimiter.AsyncLimiter` leaky buckets (a request counts its estimated prompt tokens plus
``max_tokens``, as OpenAI counts them against TPM), and the provider's own ``x-ratelimit-*`` and
``retry-after`` headers on every response. docs/paid-apis.md (*Pacing*) says how each is applied.
"""

from __future__ import annotations

import asyncio
import re
import time
from collections.abc import Callable, Mapping

from aiolimiter import AsyncLimiter

from jswim.errors import ConfigError

_DURATION = re.compile(r"(\d+(?:\.\d+)?)(ms|h|m|s)")


def parse_duration(text: str | None) -> float | None:
    """Seconds in a rate-limit reset header: ``"1s"``, ``"6m0s"``, ``"20ms"``, ``"1h2m"`` or ``"0.5"``.

    Returns ``None`` for a missing or unreadable value.
    """
    if not text:
        return None
    text = text.strip().lower()
    try:
        return max(0.0, float(text))
    except ValueError:
        pass
    parts = _DURATION.findall(text)
    if not parts or "".join(n + u for n, u in parts) != text.replace(" ", ""):
        return None
    scale = {"ms": 1e-3, "s": 1.0, "m": 60.0, "h": 3600.0}
    return sum(float(n) * scale[u] for n, u in parts)


def _number(headers: Mapping[str, str], name: str) -> float | None:
    value = headers.get(name)
    if value is None:
        return None
    try:
        return float(value)
    except ValueError:
        return None


class Pacer:
    """Holds requests back to stay within ``rpm``/``tpm`` and the provider's signalled limits.

    Parameters
    ----------
    rpm : float or None
        Requests per minute (``None``: no limit of our own).
    tpm : float or None
        Tokens per minute, prompt plus ``max_tokens`` (``None``: no limit of our own).
    margin : int
        Requests that may be on their way before a response's headers are read (the client's
        concurrency): new requests wait while the provider's remaining requests are below it,
        or its remaining tokens below ``margin`` times the last request's tokens.
    max_pause_s : float
        Longest single wait a header can cause.
    clock : callable
        Monotonic seconds (tests may replace it).

    Attributes
    ----------
    paused_s : float
        Total time new requests were held by the provider's headers (for reports).
    """

    def __init__(
        self,
        rpm: float | None = None,
        tpm: float | None = None,
        *,
        margin: int = 1,
        max_pause_s: float = 60.0,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if (rpm is not None and rpm <= 0) or (tpm is not None and tpm <= 0):
            raise ConfigError("rpm and tpm must be > 0")
        self.rpm, self.tpm = rpm, tpm
        self._requests = AsyncLimiter(1, 60.0 / rpm) if rpm else None
        self._tokens = AsyncLimiter(tpm / 6.0, 10.0) if tpm else None
        self.margin = max(1, int(margin))
        self.max_pause_s = max_pause_s
        self._clock = clock
        self._until = 0.0
        self._last_tokens = 0
        self.paused_s = 0.0

    async def wait(self, tokens: int) -> None:
        """Return when a request of ``tokens`` (prompt + ``max_tokens``) may go out."""
        self._last_tokens = tokens
        while True:
            delay = self._until - self._clock()
            if delay <= 0:
                break
            self.paused_s += delay
            await asyncio.sleep(delay)
        if self._requests is not None:
            await self._requests.acquire(1)
        if self._tokens is not None:
            await self._tokens.acquire(min(float(tokens), self._tokens.max_rate))

    def hold(self, seconds: float) -> None:
        """Hold every new request for ``seconds`` from now (bounded by ``max_pause_s``)."""
        if seconds > 0:
            self._until = max(self._until, self._clock() + min(seconds, self.max_pause_s))

    def observe(self, headers: Mapping[str, str]) -> None:
        """Read a response's rate-limit headers and slow down if the limits are close."""
        ms = _number(headers, "retry-after-ms")
        after = ms / 1000.0 if ms is not None else _number(headers, "retry-after")
        if after is not None:
            self.hold(after)
        self._check(headers, "requests", self.margin)
        self._check(headers, "tokens", self.margin * max(self._last_tokens, 1))

    def _check(self, headers: Mapping[str, str], kind: str, margin: float) -> None:
        remaining = _number(headers, f"x-ratelimit-remaining-{kind}")
        if remaining is None or remaining >= margin:
            return
        reset = parse_duration(headers.get(f"x-ratelimit-reset-{kind}"))
        if reset is None:
            reset = 1.0  # a provider that says "nearly out" but not when: back off a little
        limit = _number(headers, f"x-ratelimit-limit-{kind}")
        if limit is not None and limit > remaining and reset > 0:
            # The window refills at (limit - remaining) / reset; wait until `margin` is back.
            rate = (limit - remaining) / reset
            self.hold(min(reset, (margin - remaining) / rate))
        else:
            self.hold(reset)
