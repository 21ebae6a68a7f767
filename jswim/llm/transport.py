"""A plain-asyncio httpx transport for servers on this machine.

httpx reaches the network through httpcore, whose default backend on asyncio goes through anyio:
cancel scopes and checkpoints around every read and write. Against a server on loopback (the
embedded model, a local vLLM or llama.cpp) that bookkeeping is a visible share of each request's
CPU time, and in a lockstep round of many requests it is paid before the next round can start.
`LoopbackTransport` keeps httpcore's HTTP/1.1 connection handling and swaps only the byte
streams for asyncio's own. It is used for ``http://`` URLs on a loopback address; everything else
(TLS, proxies) keeps httpx's default transport.
"""

from __future__ import annotations

import asyncio
import contextlib
import socket
import ssl
from typing import Any
from collections.abc import AsyncIterator, Iterable

import httpcore
import httpx


def _to_httpx(exc: Exception, request: httpx.Request) -> httpx.TransportError:
    # httpcore and httpx name their exception classes alike (ReadTimeout, ConnectError, ...).
    cls = getattr(httpx, type(exc).__name__, None)
    if not (isinstance(cls, type) and issubclass(cls, httpx.TransportError)):
        cls = httpx.TransportError
    return cls(str(exc) or type(exc).__name__, request=request)


@contextlib.asynccontextmanager
async def _deadline(
    timeout: float | None, error: type[Exception], what: str
) -> AsyncIterator[None]:
    if timeout is None:
        yield
        return
    try:
        async with asyncio.timeout(timeout):
            yield
    except TimeoutError:
        raise error(f"{what} timed out after {timeout} s") from None


class _Stream(httpcore.AsyncNetworkStream):
    """One TCP connection as an asyncio reader/writer pair."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self._reader = reader
        self._writer = writer

    async def read(self, max_bytes: int, timeout: float | None = None) -> bytes:
        try:
            async with _deadline(timeout, httpcore.ReadTimeout, "read"):
                return await self._reader.read(max_bytes)
        except OSError as exc:
            raise httpcore.ReadError(str(exc) or type(exc).__name__) from None

    async def write(self, buffer: bytes, timeout: float | None = None) -> None:
        if not buffer:
            return
        try:
            self._writer.write(buffer)
            async with _deadline(timeout, httpcore.WriteTimeout, "write"):
                await self._writer.drain()
        except OSError as exc:
            raise httpcore.WriteError(str(exc) or type(exc).__name__) from None

    async def aclose(self) -> None:
        self._writer.close()
        with contextlib.suppress(OSError):
            await self._writer.wait_closed()

    async def start_tls(
        self,
        ssl_context: ssl.SSLContext,
        server_hostname: str | None = None,
        timeout: float | None = None,
    ) -> httpcore.AsyncNetworkStream:
        raise httpcore.ConnectError("LoopbackTransport serves plain http only")

    def get_extra_info(self, info: str) -> Any:
        # httpcore asks "is_readable" of an idle keep-alive connection: readable means the server
        # closed it (or sent something unasked), so the connection must not be reused.
        if info == "is_readable":
            return self._reader.at_eof() or len(self._reader._buffer) > 0
        if info in ("socket", "peername", "sockname"):
            return self._writer.get_extra_info(info)
        return None


class _Backend(httpcore.AsyncNetworkBackend):
    async def connect_tcp(
        self,
        host: str,
        port: int,
        timeout: float | None = None,
        local_address: str | None = None,
        socket_options: Iterable[Any] | None = None,
    ) -> httpcore.AsyncNetworkStream:
        try:
            async with _deadline(timeout, httpcore.ConnectTimeout, "connect"):
                reader, writer = await asyncio.open_connection(
                    host, port, local_addr=(local_address, 0) if local_address else None
                )
        except OSError as exc:
            raise httpcore.ConnectError(str(exc) or type(exc).__name__) from None
        sock = writer.get_extra_info("socket")
        if sock is not None:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
            for option in socket_options or ():
                sock.setsockopt(*option)
        return _Stream(reader, writer)

    async def sleep(self, seconds: float) -> None:
        await asyncio.sleep(seconds)


class _ResponseBody(httpx.AsyncByteStream):
    def __init__(self, response: httpcore.Response, request: httpx.Request) -> None:
        self._response = response
        self._request = request

    async def __aiter__(self) -> AsyncIterator[bytes]:
        try:
            async for chunk in self._response.aiter_stream():
                yield chunk
        except (httpcore.NetworkError, httpcore.TimeoutException, httpcore.ProtocolError) as exc:
            raise _to_httpx(exc, self._request) from None

    async def aclose(self) -> None:
        await self._response.aclose()


class LoopbackTransport(httpx.AsyncBaseTransport):
    """httpx transport over plain asyncio streams, for ``http://`` servers on loopback.

    Parameters
    ----------
    limits : httpx.Limits
        Connection limits, as for `httpx.AsyncHTTPTransport`.
    """

    def __init__(self, limits: httpx.Limits = httpx.Limits()) -> None:
        self._pool = httpcore.AsyncConnectionPool(
            max_connections=limits.max_connections,
            max_keepalive_connections=limits.max_keepalive_connections,
            keepalive_expiry=limits.keepalive_expiry,
            network_backend=_Backend(),
        )

    async def handle_async_request(self, request: httpx.Request) -> httpx.Response:
        if request.url.scheme != "http":
            raise httpx.UnsupportedProtocol(
                "LoopbackTransport serves plain http only", request=request
            )
        core = httpcore.Request(
            method=request.method,
            url=httpcore.URL(
                scheme=request.url.raw_scheme,
                host=request.url.raw_host,
                port=request.url.port,
                target=request.url.raw_path,
            ),
            headers=request.headers.raw,
            content=request.stream,
            extensions=request.extensions,
        )
        try:
            response = await self._pool.handle_async_request(core)
        except (
            httpcore.NetworkError,
            httpcore.TimeoutException,
            httpcore.ProtocolError,
            httpcore.UnsupportedProtocol,
        ) as exc:
            raise _to_httpx(exc, request) from None
        return httpx.Response(
            status_code=response.status,
            headers=response.headers,
            stream=_ResponseBody(response, request),
            extensions=response.extensions,
        )

    async def aclose(self) -> None:
        await self._pool.aclose()
