"""A fake OpenAI-compatible chat-completions server for tests and benchmarks.

Real HTTP/1.1 with keep-alive on 127.0.0.1, served by an asyncio event loop on a background
thread, so the client's whole network path runs and hundreds of requests can wait out their
latency at once without a thread each. Replies are scripted, latency can be added, and faults
injected:

>>> with FakeServer(reply=lambda body: "[1, -1]", latency=0.01) as srv:   # doctest: +SKIP
...     srv.add_faults(Fault.rate_limit("0.05"), Fault.server_error(), None, Fault.drop())
...     ...  # point a client at srv.url; srv.n_requests counts what arrived

Faults queued with :meth:`FakeServer.add_faults` apply to the next requests in arrival order
(``None`` = answer normally). A ``reply`` callable may also return a :class:`Fault` to fail
requests by content, or an :class:`Answer` to shape the message (null or list content,
reasoning fields, ``finish_reason``). ``latency`` may also be a callable of the request body, e.g.
:func:`lognormal_latency`: heavy-tailed delays drawn per request from a hash of its messages,
so each (run, step) of a study gets its own reproducible delay and a benchmark can recompute
every delay from the prompts it sent. ``tokens`` counts usage (default: words) and ``headers``
adds response headers (rate-limit headers, for instance). Independent of jswim, so benchmarks
can import it too; run it standalone with ``python -m tests.fakeserver --latency 0.1`` (it
prints its base URL).

Real servers misbehave in ordinary ways; :data:`MODES` names one scripted server per behaviour
(reasoning blocks, null content, streams sent unasked, rejected fields, a context-length 400 at
step 3, a cold start, ...), each usable as ``FakeServer(**MODES[name])`` or
``python -m tests.fakeserver --mode NAME``.
"""

from __future__ import annotations

import argparse
import asyncio
import hashlib
import json
import urllib.parse
import math
import random
import re
import threading
import time
import zlib
from collections import deque
from dataclasses import dataclass
from http import HTTPStatus
from typing import Any
from collections.abc import Callable, Iterable, Sequence


@dataclass(frozen=True)
class Fault:
    """One injected failure.

    kind : ``"status"`` (HTTP ``status``, optional ``Retry-After``), ``"drop"`` (close the
    connection without answering), ``"delay"`` (answer normally after ``seconds``: a client
    timeout), ``"malformed"`` (200 with a body that is not JSON), ``"endless"`` (200 and a stream
    that never ends, a piece every ``seconds``, until ``hold_s``). ``message`` is the error text of
    a status fault; ``body``, when given, is its whole JSON body instead (e.g. FastAPI's
    ``{"detail": [...]}``).
    """

    kind: str
    status: int = 500
    retry_after: str | None = None
    seconds: float = 0.0
    message: str = "injected fault"
    body: Any = None

    @classmethod
    def rate_limit(cls, retry_after: str | None = "0") -> Fault:
        return cls("status", 429, retry_after)

    @classmethod
    def server_error(cls, status: int = 500, message: str = "injected fault") -> Fault:
        return cls("status", status, message=message)

    @classmethod
    def drop(cls) -> Fault:
        return cls("drop")

    @classmethod
    def delay(cls, seconds: float) -> Fault:
        return cls("delay", seconds=seconds)

    @classmethod
    def malformed(cls) -> Fault:
        return cls("malformed")

    @classmethod
    def endless(cls, every: float = 0.05) -> Fault:
        """200 and an SSE stream that never ends: a content piece every ``every`` seconds."""
        return cls("endless", seconds=every)


@dataclass(frozen=True)
class Answer:
    """A scripted assistant message, for replies that are more than plain text.

    content : the ``content`` field as sent: a string, ``None`` (JSON null) or a list of parts.
    finish_reason : ``"stop"``, ``"length"``, ...
    fields : more message fields, e.g. ``{"reasoning_content": "..."}``.
    """

    content: Any = ""
    finish_reason: str = "stop"
    fields: tuple[tuple[str, Any], ...] = ()
    usage: tuple[
        tuple[str, Any], ...
    ] = ()  # fields of ``usage`` set as given (e.g. reasoning tokens)

    def message(self) -> dict[str, Any]:
        return {"role": "assistant", "content": self.content, **dict(self.fields)}


Reply = Callable[[dict[str, Any]], "str | Fault | Answer"]

#: Moves of the two-DOF square gait; :func:`hash_reply` picks among them.
GAIT_MOVES = ("[1, -1]", "[2, -1]", "[1, 1]", "[2, 1]")


def hash_reply(body: dict[str, Any]) -> str:
    """A deterministic, prompt-dependent valid two-DOF move (varied, so runs wander)."""
    last = str(body.get("messages", [{}])[-1].get("content", ""))
    return GAIT_MOVES[zlib.crc32(last.encode()) % len(GAIT_MOVES)]


def hangs_for(seconds: float, reply: Reply = hash_reply) -> Reply:
    """A server that hangs: every request arriving within ``seconds`` of the first one is read and
    never answered (a wedged worker, a proxy that lost its upstream; the client times out), and
    later ones are answered by ``reply``. Use as ``FakeServer(reply=hangs_for(2.0))``."""
    state: dict[str, float] = {}

    def answer(body: dict[str, Any]) -> str | Answer | Fault:
        t0 = state.setdefault("t0", time.monotonic())
        if time.monotonic() - t0 < seconds:
            return Fault.delay(3600.0)  # until the server stops (its tasks are cancelled then)
        return reply(body)

    return answer


_ROC_RANGE = re.compile(r"The ROC is a whole number from -(\d+) to (\d+)")


def lattice_reply(body: dict[str, Any]) -> str:
    """A deterministic, prompt-dependent move on the prompt's ROC lattice (``--roc-levels K``):
    ``[dof, k]`` with ``k`` in ``-K..K`` read from S5 (K = 1 when S5 names no range); a first
    attempt at K > 1 sometimes answers a ROC past the range, as a model may, to be asked again."""
    last = str(body.get("messages", [{}])[-1].get("content", ""))
    first = str(body.get("messages", [{}])[0].get("content", ""))
    prompt = last if len(body.get("messages", [])) <= 2 else first + last
    m = _ROC_RANGE.search(
        "\n".join(str(msg.get("content", "")) for msg in body.get("messages", []))
    )
    k = int(m.group(1)) if m else 1
    h = zlib.crc32(prompt.encode())
    if k > 1 and h % 7 == 0 and "names no valid action" not in last:
        return (
            f"[1, {k + 1}]"  # outside the lattice: the parser refuses it and the driver asks again
        )
    roc = h // 7 % (2 * k + 1) - k
    return f"[{1 + h % 2}, {roc}]"


_DOF_CHOICES = re.compile(r"the changed DOF ([0-9, or]+?) and the ROC")


def scene_reply(body: dict[str, Any]) -> str:
    """A deterministic, prompt-dependent move over the DOFs S5 offers (four for a pair of NG
    swimmers: D3 and D4 are swimmer 2's). A first attempt sometimes names a DOF one past the last,
    as a model may that miscounts the swimmers' arms, to be asked again."""
    msgs = body.get("messages", [])
    last = str(msgs[-1].get("content", "")) if msgs else ""
    text = "\n".join(str(m.get("content", "")) for m in msgs)
    m = _DOF_CHOICES.search(text)
    n = max(int(v) for v in re.findall(r"[0-9]+", m.group(1))) if m else 2
    h = zlib.crc32(last.encode())
    if h % 5 == 0 and "names no valid action" not in last:
        return f"[{n + 1}, 1]"  # no such DOF: refused by the parser, asked again
    return f"[{1 + h % n}, {h // n % 2 * 2 - 1}]"


def count_words(text: str) -> int:
    """Crude token count used for the fake ``usage`` field."""
    return len(text.split())


Latency = Callable[[dict[str, Any]], float]


def request_digest(body: dict[str, Any]) -> bytes:
    """Digest of a request's messages (what identifies a run's step)."""
    text = json.dumps(body.get("messages", []), sort_keys=True, ensure_ascii=False)
    return hashlib.blake2b(text.encode(), digest_size=16).digest()


def lognormal_latency(median: float, sigma: float, seed: int = 0) -> Latency:
    """Delays ``median * exp(sigma * N(0, 1))``, the normal draw seeded by ``seed`` and the messages.

    The same request always gets the same delay, so the delays of a study are fixed by its
    prompts: with noisy runs every (run, step) sends its own prompt and gets its own draw.
    """

    def delay(body: dict[str, Any]) -> float:
        rng = random.Random(int.from_bytes(request_digest(body), "little") ^ seed)
        return median * math.exp(sigma * rng.gauss(0.0, 1.0))

    return delay


class FakeServer:
    """Scripted chat-completions server on a free loopback port.

    Parameters
    ----------
    reply : callable, optional
        Request body -> reply text (or a :class:`Fault`); default always ``"[1, 1]"``.
    latency : float or callable
        Seconds added before every answer, or request body -> seconds (:func:`lognormal_latency`).
    tokens : callable, optional
        Text -> token count for the ``usage`` field (default :func:`count_words`).
    headers : callable, optional
        Request body -> extra headers of a completion (e.g. ``x-ratelimit-remaining-requests``).
    faults : iterable of Fault or None, optional
        Initial fault queue.
    stream : {"never", "default", "always"}
        Answer as an SSE stream: never; unless the request says ``"stream": false`` (servers
        whose default is to stream); or always, whatever the request says.
    reject_fields : mapping of str to str, optional
        Request field -> error message: a request carrying the field gets HTTP 400 with it.
    cold_start : float
        Seconds from the first chat request during which requests wait: a server that loads its
        model on first use (Ollama does), or is still loading it.
    models : sequence of str or None
        The ids ``GET /v1/models`` lists (``None``: that endpoint answers 404).
    served_model : str or None
        The ``model`` field of every completion (``None``: the requested name echoed back, as
        servers that accept any name do).
    hold : callable, optional
        Request body -> bool: while it returns ``True`` the request's answer waits (checked every
        5 ms, for at most ``hold_s`` seconds). Tests script the order of answers with it (answer
        run A's call only after run B's three calls arrived) instead of relying on timing.
    hold_s : float
        Longest hold of one request; then it is answered anyway (a test that deadlocks fails on
        its assertions instead of hanging).
    owned_by : str or None
        The ``owned_by`` of each ``/v1/models`` entry (a server family's tell).
    props : dict or None
        The JSON ``GET /props`` answers (llama.cpp's server); ``None``: 404 there.
    api_key : str or None
        The only key accepted: every request without ``Authorization: Bearer <api_key>`` (the
        preflight's ``/v1/models`` too) gets HTTP 401.

    Attributes
    ----------
    n_requests : int
        Chat requests received (faulty ones included).
    n_answered : int
        Chat requests answered with a completion.
    requests : list of dict
        Bodies of the chat requests, in arrival order.
    auth_headers : list of str or None
        Their ``Authorization`` headers.
    max_in_flight : int
        Most chat requests being handled at once.
    """

    def __init__(
        self,
        reply: Reply | None = None,
        latency: float | Latency = 0.0,
        faults: Iterable[Fault | None] = (),
        tokens: Callable[[str], int] = count_words,
        headers: Callable[[dict[str, Any]], dict[str, str]] | None = None,
        stream: str = "never",
        reject_fields: dict[str, str] | None = None,
        cold_start: float = 0.0,
        models: Sequence[str] | None = ("fake",),
        served_model: str | None = None,
        hold: Callable[[dict[str, Any]], bool] | None = None,
        hold_s: float = 30.0,
        owned_by: str | None = None,
        props: dict[str, Any] | None = None,
        api_key: str | None = None,
        usage: Callable[[dict[str, Any]], Any] | None = None,
        redirects: dict[str, tuple[int, str]] | None = None,
    ) -> None:
        if stream not in ("never", "default", "always"):
            raise ValueError(f"stream must be never, default or always, got {stream!r}")
        self.reply: Reply = reply or (lambda body: "[1, 1]")
        self.latency = latency
        self.tokens = tokens
        self.headers = headers
        self.arrivals: list[float] = []  # time.monotonic() of each chat request's arrival
        self.stream = stream
        self.reject_fields = dict(reject_fields or {})
        self.cold_start = cold_start
        self.models = None if models is None else tuple(models)
        self.served_model = served_model
        self.hold = hold
        self.hold_s = hold_s
        self.owned_by = owned_by
        self.props = props
        self.api_key = api_key
        self.n_preflight = 0  # GET requests (models, props)
        self.usage = (
            usage  # replaces the usage object of every completion (servers that send odd ones)
        )
        # POST path -> (status, Location): a moved endpoint; the chat endpoint also answers where
        # a redirect leads.
        self.redirects = dict(redirects or {})
        self.redirected: list[
            str | None
        ] = []  # the Authorization header of each redirected request
        self._warm_at: float | None = None
        self._faults: deque[Fault | None] = deque(faults)
        self._lock = threading.Lock()
        self.requests: list[dict[str, Any]] = []
        self.auth_headers: list[str | None] = []
        self.n_requests = 0
        self.n_answered = 0
        self.n_connections = 0  # TCP connections accepted (keep-alive reuse shows here)
        self.in_flight = 0
        self._held = 0  # of those in flight, held on purpose by a delay fault (a hang)
        self.max_in_flight = 0
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._port: int | None = None

    # -- lifecycle ---------------------------------------------------------------------------

    def start(self) -> FakeServer:
        ready = threading.Event()
        self._thread = threading.Thread(
            target=self._serve, args=(ready,), daemon=True, name="fakeserver"
        )
        self._thread.start()
        if not ready.wait(10) or self._port is None:
            raise RuntimeError("fake server did not start")
        return self

    def _serve(self, ready: threading.Event) -> None:
        loop = asyncio.new_event_loop()
        asyncio.set_event_loop(loop)
        self._loop = loop
        server = loop.run_until_complete(
            asyncio.start_server(self._connection, "127.0.0.1", 0, backlog=1024)
        )
        self._port = server.sockets[0].getsockname()[1]
        ready.set()
        try:
            loop.run_forever()
        finally:
            server.close()
            tasks = asyncio.all_tasks(loop)
            for t in tasks:  # handlers sleeping in latency or delay faults
                t.cancel()
            loop.run_until_complete(asyncio.gather(*tasks, return_exceptions=True))
            loop.close()

    def stop(self) -> None:
        if self._loop is not None and self._thread is not None:
            self._loop.call_soon_threadsafe(self._loop.stop)
            self._thread.join(10)
            self._loop = self._thread = None

    def __enter__(self) -> FakeServer:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    @property
    def port(self) -> int:
        assert self._port is not None, "server not started"
        return self._port

    @property
    def url(self) -> str:
        """Base URL to give a client: ``http://127.0.0.1:<port>/v1``."""
        return f"http://127.0.0.1:{self.port}/v1"

    # -- scripting ---------------------------------------------------------------------------

    def add_faults(self, *faults: Fault | None) -> None:
        with self._lock:
            self._faults.extend(faults)

    def backend(self, model: str = "fake") -> Any:
        """A :class:`jswim.studies.Backend` pointed at this server, with no API key set."""
        from jswim.studies import Backend

        return Backend(base_url=self.url, model=model, api_key_env="JSWIM_TEST_NO_KEY")

    def settle(self, quiet: float = 0.3, limit: float = 20.0) -> int:
        """``n_requests`` once every request already on the wire has been read.

        A client that stopped (a full disk, a signal, a spent budget) may leave a request sent
        but not yet read by this server's thread; counting before it is read would charge it to
        the next session. Waits until nothing is in flight and the count holds for ``quiet``
        seconds (at most ``limit``); a wait, never an assertion on time.
        """
        last, end = -1, time.monotonic() + limit
        while time.monotonic() < end:
            with self._lock:
                # a request held by a delay fault has been read and counted: no need to wait for
                # it (a hang of an hour would otherwise hold every settle to its limit)
                n, busy = self.n_requests, self.in_flight - self._held
            if n == last and not busy:
                return n
            last = n
            time.sleep(quiet)
        return self.n_requests

    def reset_counts(self) -> None:
        with self._lock:
            self.requests.clear()
            self.auth_headers.clear()
            self.arrivals.clear()
            self.n_requests = self.n_answered = self.max_in_flight = 0

    def completion(self, body: dict[str, Any], text: str | Answer) -> dict[str, Any]:
        """The chat.completion object answering ``body`` with ``text``."""
        answer = text if isinstance(text, Answer) else Answer(text)
        prompt = sum(self.tokens(str(m.get("content", ""))) for m in body.get("messages", []))
        parts = [answer.content if isinstance(answer.content, str) else json.dumps(answer.content)]
        parts += [str(v) for _, v in answer.fields]
        done = sum(self.tokens(p) for p in parts)
        return {
            "id": f"fake-{self.n_requests}",
            "object": "chat.completion",
            "created": int(time.time()),
            "model": self.served_model or body.get("model", "fake"),
            "choices": [
                {"index": 0, "message": answer.message(), "finish_reason": answer.finish_reason}
            ],
            "usage": {
                "prompt_tokens": prompt,
                "completion_tokens": done,
                "total_tokens": prompt + done,
                **dict(answer.usage),
            }
            if self.usage is None
            else self.usage(body),
        }

    def chunks(self, body: dict[str, Any], text: str | Answer) -> list[dict[str, Any]]:
        """The chat.completion.chunk events of a streamed answer (content in small pieces)."""
        full = self.completion(body, text)
        choice = full["choices"][0]
        msg = choice["message"]
        head = {k: full[k] for k in ("id", "created", "model")} | {
            "object": "chat.completion.chunk"
        }

        def event(delta: dict[str, Any], finish: str | None = None) -> dict[str, Any]:
            return {**head, "choices": [{"index": 0, "delta": delta, "finish_reason": finish}]}

        out = [event({"role": "assistant", "content": ""})]
        for key, value in msg.items():
            if key in ("role", "content") or not isinstance(value, str):
                continue
            out += [event({key: value[i : i + 5]}) for i in range(0, len(value), 5)]
        content = msg.get("content")
        if isinstance(content, str):
            out += [event({"content": content[i : i + 3]}) for i in range(0, len(content), 3)]
        elif content is not None:
            out.append(event({"content": content}))
        out.append(event({}, choice["finish_reason"]))
        out.append({**head, "choices": [], "usage": full["usage"]})
        return out

    # -- HTTP --------------------------------------------------------------------------------

    async def _connection(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        self.n_connections += 1
        try:
            while True:
                head = await reader.readuntil(b"\r\n\r\n")
                lines = head.decode("latin-1").split("\r\n")
                method, path = lines[0].split(" ")[:2]
                headers = {}
                for line in lines[1:]:
                    key, sep, value = line.partition(":")
                    if sep:
                        headers[key.strip().lower()] = value.strip()
                size = int(headers.get("content-length") or 0)
                raw = await reader.readexactly(size) if size else b""
                keep = await self._dispatch(method, path.rstrip("/"), headers, raw, writer)
                if not keep or headers.get("connection", "").lower() == "close":
                    break
        except (
            asyncio.IncompleteReadError,
            asyncio.LimitOverrunError,
            ConnectionError,
            ValueError,
        ):
            pass  # the client went away or sent garbage
        except asyncio.CancelledError:
            pass  # the server stops while an answer still waits (hangs_for): no noise in the log
        finally:
            writer.close()

    @staticmethod
    async def _send(
        writer: asyncio.StreamWriter,
        status: int,
        payload: bytes,
        extra: dict[str, str] | None = None,
    ) -> bool:
        head = [
            f"HTTP/1.1 {status} {HTTPStatus(status).phrase}",
            "Content-Type: application/json",
            f"Content-Length: {len(payload)}",
        ]
        head += [f"{k}: {v}" for k, v in (extra or {}).items()]
        writer.write(("\r\n".join(head) + "\r\n\r\n").encode("latin-1") + payload)
        await writer.drain()
        return True

    async def _dispatch(
        self,
        method: str,
        path: str,
        headers: dict[str, str],
        raw: bytes,
        writer: asyncio.StreamWriter,
    ) -> bool:
        if method == "GET" and path in ("/health", "/v1/health"):
            return await self._send(writer, 200, b'{"status":"ok"}')
        if method == "GET":
            self.n_preflight += 1
        if self.api_key is not None and headers.get("authorization") != f"Bearer {self.api_key}":
            if method == "POST":
                with self._lock:
                    self.n_requests += 1
            msg = {
                "error": {
                    "message": "Incorrect API key provided",
                    "type": "invalid_request_error",
                    "code": "invalid_api_key",
                }
            }
            return await self._send(writer, 401, json.dumps(msg).encode())
        if method == "GET" and path == "/v1/models" and self.models is not None:
            data = [
                {
                    "id": m,
                    "object": "model",
                    **({"owned_by": self.owned_by} if self.owned_by else {}),
                }
                for m in self.models
            ]
            return await self._send(
                writer, 200, json.dumps({"object": "list", "data": data}).encode()
            )
        if method == "GET" and path == "/props" and self.props is not None:
            return await self._send(writer, 200, json.dumps(self.props).encode())
        if method == "POST" and path in self.redirects:
            status, location = self.redirects[path]
            with self._lock:
                self.redirected.append(headers.get("authorization"))
            return await self._send(writer, status, b"", {"Location": location})
        # The chat endpoint answers at /v1/chat/completions and where a redirect leads, nowhere
        # else: a wrong base URL must still get the 404 real servers send.
        targets = {"/v1/chat/completions"} | {
            urllib.parse.urlsplit(loc).path for _, loc in self.redirects.values()
        }
        if method != "POST" or path not in targets:
            msg = json.dumps(
                {"error": {"message": f"File Not Found: {path}", "code": 404}}
            ).encode()
            return await self._send(writer, 404, msg)
        try:
            body = json.loads(raw)
        except ValueError:
            return await self._send(
                writer, 400, b'{"error":{"message":"request body is not JSON"}}'
            )
        with self._lock:
            self.n_requests += 1
            self.requests.append(body)
            self.arrivals.append(time.monotonic())
            self.auth_headers.append(headers.get("authorization"))
            fault = self._faults.popleft() if self._faults else None
            self.in_flight += 1
            self.max_in_flight = max(self.max_in_flight, self.in_flight)
        try:
            return await self._answer(body, fault, writer)
        finally:
            with self._lock:
                self.in_flight -= 1

    async def _answer(
        self, body: dict[str, Any], fault: Fault | None, writer: asyncio.StreamWriter
    ) -> bool:
        text: str | Answer | Fault | None = None
        if self._warm_at is None:
            self._warm_at = time.monotonic() + self.cold_start
        cold = self._warm_at - time.monotonic()
        if cold > 0:  # still "loading the model"
            await asyncio.sleep(cold)
        if self.hold is not None:
            give_up = time.monotonic() + self.hold_s
            while self.hold(body) and time.monotonic() < give_up:
                await asyncio.sleep(0.005)
        for name, message in self.reject_fields.items():
            if name in body and fault is None:
                fault = Fault("status", 400, message=message)
        if fault is None:
            text = self.reply(body)
            if isinstance(text, Fault):
                fault, text = text, None
        delay = self.latency(body) if callable(self.latency) else self.latency
        if delay:
            await asyncio.sleep(delay)
        if fault is not None:
            if fault.kind == "drop":
                return False  # close without a response
            if fault.kind == "status":
                extra = {"Retry-After": fault.retry_after} if fault.retry_after is not None else {}
                err = json.dumps(
                    fault.body if fault.body is not None else {"error": {"message": fault.message}}
                ).encode()
                return await self._send(writer, fault.status, err, extra)
            if fault.kind == "malformed":
                return await self._send(writer, 200, b'{"choices": [ {"message": ')
            if fault.kind == "endless":
                head = "HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nTransfer-Encoding: chunked\r\n\r\n"
                writer.write(head.encode("latin-1"))
                event = {"choices": [{"index": 0, "delta": {"content": "[1, "}}]}
                piece = f"data: {json.dumps(event)}\n\n".encode()
                give_up = time.monotonic() + self.hold_s  # a test that hangs fails instead
                while time.monotonic() < give_up:  # or until the client goes away
                    writer.write(f"{len(piece):x}\r\n".encode() + piece + b"\r\n")
                    await writer.drain()
                    await asyncio.sleep(fault.seconds)
                writer.write(b"0\r\n\r\n")
                await writer.drain()
                return False
            if fault.kind == "delay":
                with self._lock:
                    self._held += 1
                try:
                    await asyncio.sleep(fault.seconds)
                finally:
                    with self._lock:
                        self._held -= 1
                got = self.reply(body)
                text = got if isinstance(got, (str, Answer)) else ""
        with self._lock:
            self.n_answered += 1
        if text is None:
            text = ""
        if self.stream == "always" or (
            self.stream == "default" and body.get("stream") is not False
        ):
            return await self._send_stream(writer, self.chunks(body, text))
        extra = self.headers(body) if self.headers is not None else None
        return await self._send(
            writer, 200, json.dumps(self.completion(body, text)).encode(), extra
        )

    @staticmethod
    async def _send_stream(writer: asyncio.StreamWriter, events: list[dict[str, Any]]) -> bool:
        head = [
            "HTTP/1.1 200 OK",
            "Content-Type: text/event-stream; charset=utf-8",
            "Cache-Control: no-cache",
            "Transfer-Encoding: chunked",
        ]
        writer.write(("\r\n".join(head) + "\r\n\r\n").encode("latin-1"))
        for data in [json.dumps(e) for e in events] + ["[DONE]"]:
            piece = f"data: {data}\n\n".encode()
            writer.write(f"{len(piece):x}\r\n".encode() + piece + b"\r\n")
            await writer.drain()
        writer.write(b"0\r\n\r\n")
        await writer.drain()
        return True


# -- modes: one scripted server per ordinary real-server behaviour ---------------------------------

#: Reasoning that names a move the answer then rejects: parsing it would execute [1, 1].
THOUGHT = "The last move was [1, 1] and X did not grow; not [1, 1] again, try the other joint."


def history_records(body: dict[str, Any]) -> int:
    """History lines (``3: (...) [1, 1] -> ...``) in the request's first user message."""
    first = next((m for m in body.get("messages", []) if m.get("role") == "user"), {})
    return len(re.findall(r"^\d+: \(", str(first.get("content", "")), re.M))


def is_follow_up(body: dict[str, Any]) -> bool:
    """Whether the request continues a conversation (it carries an earlier assistant reply)."""
    return any(m.get("role") == "assistant" for m in body.get("messages", []))


def _context_400(body: dict[str, Any]) -> str | Fault:
    # The prompt outgrows a small context once it shows two history records: from step 3 on.
    if history_records(body) >= 2:
        return Fault(
            "status",
            400,
            message=(
                "This model's maximum context length is 64 tokens. However, you requested 97 tokens "
                "(65 in the messages, 32 in the completion). Please reduce the length of the messages or completion."
            ),
        )
    return "[2, -1]"


def _think_then_follow_up(body: dict[str, Any]) -> str | Answer:
    # Thinks past max_tokens on a first request; answers a follow-up (a longer conversation).
    if is_follow_up(body):
        return "[2, -1]"
    return Answer("<think>" + THOUGHT, "length")


#: Reasoning tokens the fake reasoning model spends before each answer.
REASONING_TOKENS = 300


def reasoning_model(answer: Reply | None = None, think: int = REASONING_TOKENS) -> Reply:
    """A reply function behaving as OpenAI's reasoning models (o-series, gpt-5) do:

    - HTTP 400 on ``max_tokens`` ("Use 'max_completion_tokens' instead");
    - HTTP 400 on any ``temperature`` but 1 ("Only the default (1) value is supported");
    - with ``max_completion_tokens`` below ``think`` plus a few tokens of answer: empty content,
      ``finish_reason`` "length", every completion token a reasoning token (it was still thinking);
    - otherwise ``answer(body)`` (default ``[2, -1]``) after ``think`` reasoning tokens, reported in
      ``usage.completion_tokens_details.reasoning_tokens`` and counted in ``completion_tokens``.
    """
    answer = answer or (lambda body: "[2, -1]")

    def reply(body: dict[str, Any]) -> str | Fault | Answer:
        if "max_tokens" in body:
            return Fault(
                "status",
                400,
                message="Unsupported parameter: 'max_tokens' is not supported with this "
                "model. Use 'max_completion_tokens' instead.",
            )
        t = body.get("temperature", 1)
        if t != 1:
            return Fault(
                "status",
                400,
                message=f"Unsupported value: 'temperature' does not support {t:g} with "
                "this model. Only the default (1) value is supported.",
            )
        limit = body.get("max_completion_tokens")
        if limit is not None and limit < think + 8:
            return Answer(
                "",
                "length",
                usage=(
                    ("completion_tokens", limit),
                    ("completion_tokens_details", {"reasoning_tokens": limit}),
                ),
            )
        text = answer(body)
        if not isinstance(text, str):
            return text
        n = think + count_words(text)
        return Answer(
            text,
            usage=(
                ("completion_tokens", n),
                ("completion_tokens_details", {"reasoning_tokens": think}),
            ),
        )

    return reply


#: llama-cpp-python's server (0.3.x) answering ``response_format`` ``json_schema``: HTTP 500 whose
#: message is pydantic's validation error followed by the server's traceback (with its paths).
VALIDATION_500 = (
    "1 validation error for CreateChatCompletionRequest\nresponse_format.type\n"
    "  Input should be 'text' or 'json_object' [type=literal_error, input_value='json_schema', input_type=str]\n"
    "    For further information visit https://errors.pydantic.dev/2.11/v/literal_error\n"
    "Traceback (most recent call last):\n"
    '  File "/opt/venv/lib/python3.11/site-packages/llama_cpp/server/errors.py", line 173, in custom_route_handler\n'
    "    response = await original_route_handler(request)\n"
    '  File "/opt/venv/lib/python3.11/site-packages/fastapi/routing.py", line 301, in app\n'
    "    raise validation_error\n"
    "fastapi.exceptions.RequestValidationError: 1 validation error"
)

#: What a GGUF-serving server lists at /v1/models: the file it loaded.
GGUF_ID = "/models/SmolLM2-135M-Instruct.Q4_1.gguf"


def _takes_json_object(body: dict[str, Any]) -> str | Fault:
    # llama-cpp-python: json_schema is a 500 validation error; json_object with a schema is honoured.
    form = (body.get("response_format") or {}).get("type")
    if form == "json_schema":
        return Fault("status", 500, message=VALIDATION_500)
    if form == "json_object":
        return '{"action": "[2, -1]"}'
    return "[2, -1]"


def _repeat_penalty_default(body: dict[str, Any]) -> str:
    # A server whose default repeat_penalty (1.1, llama-cpp-python's) turns the greedy reply into
    # another one unless the request says repeat_penalty 1 (as the real server did with SmolLM2).
    return "[2, -1]" if body.get("repeat_penalty", 1.1) == 1.0 else "[1, 0]"


#: llama.cpp's ``/props`` (abridged): two slots and its sampling defaults.
LLAMACPP_PROPS = {
    "total_slots": 2,
    "default_generation_settings": {
        "n_ctx": 2048,
        "params": {
            "temperature": 0.8,
            "top_k": 40,
            "top_p": 0.95,
            "min_p": 0.05,
            "repeat_penalty": 1.0,
            "repeat_last_n": 64,
            "presence_penalty": 0.0,
            "frequency_penalty": 0.0,
            "dry_multiplier": 0.0,
            "samplers": ["top_k", "top_p"],
        },
    },
    "model_path": GGUF_ID,
}

#: name -> FakeServer keyword arguments. The comments give what a correct client executes.
MODES: dict[str, dict[str, Any]] = {
    "plain": {"reply": lambda body: "[2, -1]"},  # -> [2, -1]; base-URL shape cases use it
    "think": {"reply": lambda body: f"<think>{THOUGHT}</think>\n[2, -1]"},  # -> [2, -1]
    "think-no-open-tag": {"reply": lambda body: f"{THOUGHT}</think>\n\n[2, -1]"},  # -> [2, -1]
    "reasoning-field": {
        "reply": lambda body: Answer("[2, -1]", fields=(("reasoning_content", THOUGHT),))
    },
    "parts": {
        "reply": lambda body: Answer(
            [{"type": "thinking", "thinking": THOUGHT}, {"type": "text", "text": "[2, -1]"}]
        )
    },  # -> [2, -1]
    # Cut off while thinking: no answer; the follow-up (a different request) answers.
    "null-length": {
        "reply": lambda body: (
            "[2, -1]"
            if is_follow_up(body)
            else Answer(None, "length", (("reasoning_content", THOUGHT),))
        )
    },
    "empty-length": {
        "reply": lambda body: "[2, -1]" if is_follow_up(body) else Answer("", "length")
    },
    "think-length": {"reply": _think_then_follow_up},
    # Never answers within max_tokens: every step fails (no-op), each reply counted as cut off.
    "always-length": {
        "reply": lambda body: Answer(None, "length", (("reasoning_content", THOUGHT),))
    },
    "stream-default": {"reply": lambda body: "[2, -1]", "stream": "default"},  # -> [2, -1]
    "stream-always": {
        "reply": lambda body: Answer("[2, -1]", fields=(("reasoning_content", THOUGHT),)),
        "stream": "always",
    },  # -> [2, -1]
    "reject-grammar": {
        "reply": lambda body: "[2, -1]",
        "reject_fields": {"grammar": "Unrecognized request argument supplied: grammar"},
    },
    "reject-seed": {
        "reply": lambda body: "[2, -1]",
        "reject_fields": {
            "seed": "Unsupported parameter: 'seed' is not supported with this model."
        },
    },
    "reject-max-tokens": {
        "reply": lambda body: "[2, -1]",
        "reject_fields": {
            "max_tokens": (
                "Unsupported parameter: 'max_tokens' is not supported with this model. Use 'max_completion_tokens' instead."
            )
        },
    },
    "context-400": {"reply": _context_400},  # steps 1-2 fine, then HTTP 400 (context length)
    "bare-pair": {"reply": lambda body: "2, -1"},  # -> [2, -1]
    "negated": {"reply": lambda body: "not [1, 1]; answer [2, -1]"},  # -> [2, -1]
    "cold": {"reply": lambda body: "[2, -1]", "cold_start": 1.5},  # first answers after 1.5 s
    # OpenAI's reasoning models: 400 on max_tokens and on temperature != 1, cut while thinking
    # below 308 max_completion_tokens, reasoning tokens in usage (see reasoning_model) -> [2, -1]
    "openai-reasoning": {"reply": reasoning_model()},
    # llama-cpp-python-like: --constrain json_schema is a 500 validation error (a rejection, not
    # retried); json_object with a schema works (what --constrain auto falls back to).
    "validation-500": {"reply": _takes_json_object, "models": (GGUF_ID,), "owned_by": "me"},
    # Runs its one model under any requested name, and lists only its file.
    "echo-any-model": {"reply": lambda body: "[2, -1]", "models": (GGUF_ID,), "owned_by": "me"},
    # Default repeat_penalty 1.1: [1, 0] unless the request sends repeat_penalty 1 -> [2, -1].
    "repeat-penalty": {"reply": _repeat_penalty_default, "models": (GGUF_ID,), "owned_by": "me"},
    # 401 for a missing or wrong key, at the preflight's GET /v1/models too.
    "auth-401": {"reply": lambda body: "[2, -1]", "api_key": "sk-right-key"},
    # llama.cpp's server: /props with total_slots 2 and its sampling defaults; grammar honoured.
    "props-slots": {
        "reply": lambda body: "[2, -1]",
        "models": (GGUF_ID,),
        "owned_by": "llamacpp",
        "props": LLAMACPP_PROPS,
        "latency": 0.05,
    },
    # Says "Content-Encoding: gzip" over a plain JSON body (a misconfigured proxy): -> [2, -1]
    "lying-encoding": {
        "reply": lambda body: "[2, -1]",
        "headers": lambda body: {"Content-Encoding": "gzip"},
    },
    # Token counts that are not numbers: read as missing (0), the answer still -> [2, -1]
    "usage-not-numbers": {
        "reply": lambda body: "[2, -1]",
        "usage": lambda body: {
            "prompt_tokens": "n/a",
            "completion_tokens": [3],
            "total_tokens": -1,
            "prompt_tokens_details": {"cached_tokens": "lots"},
        },
    },
    # Fullwidth brackets, comma, digits and minus (an East Asian input mode): -> [2, -1]
    "fullwidth": {"reply": lambda body: "\uff3b\uff12\uff0c\uff0d\uff11\uff3d"},
    # Arabic-Indic digits: not read as an answer (no action; the step fails to a no-op)
    "arabic-digits": {"reply": lambda body: "[\u0662, -\u0661]"},
}


def main() -> None:
    ap = argparse.ArgumentParser(description="Fake chat-completions server; prints its base URL.")
    ap.add_argument("--latency", type=float, default=0.0, help="seconds added to every answer")
    ap.add_argument(
        "--lognormal",
        type=float,
        nargs=2,
        default=None,
        metavar=("MEDIAN", "SIGMA"),
        help="heavy-tailed latency per request instead (see lognormal_latency)",
    )
    ap.add_argument("--latency-seed", type=int, default=0, help="seed of the lognormal delays")
    ap.add_argument(
        "--reply",
        choices=("fixed", "hash"),
        default="hash",
        help="'[1, 1]' always, or a prompt-dependent square-gait move (default)",
    )
    ap.add_argument(
        "--mode",
        choices=sorted(MODES),
        default=None,
        help="behave like a real server in one ordinary way (overrides --reply)",
    )
    args = ap.parse_args()
    reply = hash_reply if args.reply == "hash" else None
    latency = (
        lognormal_latency(*args.lognormal, seed=args.latency_seed)
        if args.lognormal
        else args.latency
    )
    options = {"reply": reply, **MODES.get(args.mode, {})}
    with FakeServer(latency=latency, **options) as srv:
        print(srv.url, flush=True)
        try:
            while True:
                time.sleep(3600)
        except KeyboardInterrupt:
            pass


if __name__ == "__main__":
    main()


#: What a gateway lists at /v1/models: the paid models under its own names (never plain ``gpt-4``).
GATEWAY_MODELS = ("openai/gpt-4", "openai/gpt-4o", "meta-llama/llama-3-70b")


def as_remote(monkeypatch: Any) -> None:
    """Make jswim take the fake server (on loopback) for a remote host: a gateway off this
    machine, where the list prices apply (:func:`jswim.llm.urls.is_local_host` answers False)."""
    import jswim.llm.settings
    import jswim.llm.urls
    import jswim.studies.session

    for module in (jswim.llm.urls, jswim.llm.settings, jswim.studies.session):
        monkeypatch.setattr(module, "is_local_host", lambda url: False)
