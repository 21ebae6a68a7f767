"""What an httpx exception means, written once: `no_answer` (what a request that got no HTTP
answer met, read by the client's retries) and `unreachable` (the preflight's one-line error). The
LLM layer's error classes live in [`jswim.errors`][jswim.errors], under the one root ``JswimError``.
"""

from __future__ import annotations

import httpx

from jswim.errors import LLMServerError, LLMTimeoutError

__all__ = ["no_answer", "unreachable"]


def no_answer(exc: httpx.HTTPError) -> tuple[str, bool]:
    """What a request that got no HTTP answer met: ``(kind, unanswered)``.

    ``kind`` is ``"connect"`` (no connection within the timeout), ``"timeout"`` (connected, no
    answer in time: read, write or pool), ``"cut"`` (the connection failed while the answer was
    awaited), ``"transport"`` (any other connection failure) or ``"http"`` (another httpx error).
    ``unanswered``: the request went out whole, so a provider may bill it (a read timeout, a cut).
    """
    if isinstance(exc, httpx.ConnectTimeout):
        return "connect", False
    if isinstance(exc, httpx.TimeoutException):
        return "timeout", isinstance(exc, httpx.ReadTimeout)
    if isinstance(exc, (httpx.ReadError, httpx.RemoteProtocolError)):
        return "cut", True
    return ("transport" if isinstance(exc, httpx.TransportError) else "http"), False


def unreachable(exc: httpx.HTTPError, where: str, url: str, timeout_s: float) -> LLMServerError:
    """The one-line error of a preflight request (``url``, shown safe) to the server ``where`` that
    got no answer: [`LLMTimeoutError`][jswim.errors.LLMTimeoutError] when it connected but took longer than ``timeout_s``."""
    kind, _ = no_answer(exc)
    if kind == "connect":
        return LLMServerError(
            f"cannot reach {where} (no connection within {timeout_s:g} s); "
            "check --base-url or start the server"
        )
    if kind == "timeout":
        return LLMTimeoutError(
            f"{url} did not answer within {timeout_s:g} s: the server is slow or still loading "
            "its model; wait for it or raise --timeout"
        )
    return LLMServerError(
        f"cannot reach {where} ({type(exc).__name__}); check --base-url or start the server"
    )
