"""A fake OpenAI-compatible chat-completions server for tests and benchmarks.

Real HTTP on 127.0.0.1 (a threading ``http.server``), so the client's whole network path runs.
Replies are scripted, latency can be added, and faults injected:

>>> with FakeServer(reply=lambda body: "[1, -1]", latency=0.01) as srv:   # doctest: +SKIP
...     srv.add_faults(Fault.rate_limit("0.05"), Fault.server_error(), None, Fault.drop())
...     ...  # point a client at srv.url; srv.n_requests counts what arrived

Faults queued with :meth:`FakeServer.add_faults` apply to the next requests in arrival order
(``None`` = answer normally). A ``reply`` callable may also return a :class:`Fault` to fail
requests by content. Independent of jswim, so benchmarks can import it too; run it standalone
with ``python -m tests.fakeserver --latency 0.1``.
"""

from __future__ import annotations

import argparse
import json
import threading
import time
from collections import deque
from dataclasses import dataclass
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any, Callable, Iterable


@dataclass(frozen=True)
class Fault:
    """One injected failure.

    kind : ``"status"`` (HTTP ``status``, optional ``Retry-After``), ``"drop"`` (close the
    connection without answering), ``"delay"`` (answer normally after ``seconds``: a client
    timeout), ``"malformed"`` (200 with a body that is not JSON). ``message`` is the error text of
    a status fault.
    """

    kind: str
    status: int = 500
    retry_after: str | None = None
    seconds: float = 0.0
    message: str = "injected fault"

    @classmethod
    def rate_limit(cls, retry_after: str | None = "0") -> "Fault":
        return cls("status", 429, retry_after)

    @classmethod
    def server_error(cls, status: int = 500, message: str = "injected fault") -> "Fault":
        return cls("status", status, message=message)

    @classmethod
    def drop(cls) -> "Fault":
        return cls("drop")

    @classmethod
    def delay(cls, seconds: float) -> "Fault":
        return cls("delay", seconds=seconds)

    @classmethod
    def malformed(cls) -> "Fault":
        return cls("malformed")


Reply = Callable[[dict[str, Any]], "str | Fault"]


def count_words(text: str) -> int:
    """Crude token count used for the fake ``usage`` field."""
    return len(text.split())


class FakeServer:
    """Scripted chat-completions server on a free loopback port.

    Parameters
    ----------
    reply : callable, optional
        Request body -> reply text (or a :class:`Fault`); default always ``"[1, 1]"``.
    latency : float
        Seconds added before every answer.
    faults : iterable of Fault or None, optional
        Initial fault queue.
    """

    def __init__(self, reply: Reply | None = None, latency: float = 0.0, faults: Iterable[Fault | None] = ()) -> None:
        self.reply: Reply = reply or (lambda body: "[1, 1]")
        self.latency = latency
        self._faults: deque[Fault | None] = deque(faults)
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self.requests: list[dict[str, Any]] = []  # bodies of chat requests, in arrival order
        self.auth_headers: list[str | None] = []
        self.n_requests = 0  # chat requests received (faulty ones included)
        self.n_answered = 0  # chat requests answered with a completion
        self.in_flight = 0
        self.max_in_flight = 0  # most chat requests handled at once
        self._httpd: ThreadingHTTPServer | None = None
        self._thread: threading.Thread | None = None

    # -- lifecycle ---------------------------------------------------------------------------

    def start(self) -> "FakeServer":
        handler = type("Handler", (_Handler,), {"fake": self})
        self._httpd = _QuietServer(("127.0.0.1", 0), handler)
        self._thread = threading.Thread(target=self._httpd.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._stop.set()  # wake handlers sleeping in latency or delay faults
        if self._httpd is not None:
            self._httpd.shutdown()
            self._httpd.server_close()
            self._httpd = None

    def __enter__(self) -> "FakeServer":
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    @property
    def port(self) -> int:
        assert self._httpd is not None, "server not started"
        return self._httpd.server_address[1]

    @property
    def url(self) -> str:
        """Base URL to give a client: ``http://127.0.0.1:<port>/v1``."""
        return f"http://127.0.0.1:{self.port}/v1"

    # -- scripting ---------------------------------------------------------------------------

    def add_faults(self, *faults: Fault | None) -> None:
        with self._lock:
            self._faults.extend(faults)

    def reset_counts(self) -> None:
        with self._lock:
            self.requests.clear()
            self.auth_headers.clear()
            self.n_requests = self.n_answered = self.max_in_flight = 0

    def _next_fault(self, body: dict[str, Any], auth: str | None) -> Fault | None:
        with self._lock:
            self.n_requests += 1
            self.requests.append(body)
            self.auth_headers.append(auth)
            return self._faults.popleft() if self._faults else None

    def completion(self, body: dict[str, Any], text: str) -> dict[str, Any]:
        prompt = sum(count_words(str(m.get("content", ""))) for m in body.get("messages", []))
        done = count_words(text)
        return {
            "id": f"fake-{self.n_requests}",
            "object": "chat.completion",
            "created": int(time.time()),
            "model": body.get("model", "fake"),
            "choices": [{"index": 0, "message": {"role": "assistant", "content": text}, "finish_reason": "stop"}],
            "usage": {"prompt_tokens": prompt, "completion_tokens": done, "total_tokens": prompt + done},
        }


class _QuietServer(ThreadingHTTPServer):
    daemon_threads = True  # never join handlers stuck in a delay fault
    request_queue_size = 256  # a benchmark opens many connections at once

    def handle_error(self, request: Any, client_address: Any) -> None:
        pass  # clients that gave up (timeouts) make writes fail; that is expected here


class _Handler(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"  # keep-alive, as real servers
    fake: FakeServer

    def log_message(self, format: str, *args: Any) -> None:  # quiet
        pass

    def _send(self, status: int, payload: bytes, headers: dict[str, str] | None = None) -> None:
        self.send_response(status)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(payload)))
        for k, v in (headers or {}).items():
            self.send_header(k, v)
        self.end_headers()
        self.wfile.write(payload)

    def do_GET(self) -> None:
        if self.path.rstrip("/") in ("/health", "/v1/health"):
            self._send(200, b'{"status":"ok"}')
        elif self.path.rstrip("/") == "/v1/models":
            self._send(200, b'{"object":"list","data":[{"id":"fake","object":"model"}]}')
        else:
            self._send(404, b'{"error":"not found"}')

    def do_POST(self) -> None:
        fake = self.fake
        raw = self.rfile.read(int(self.headers.get("Content-Length") or 0))
        if self.path.rstrip("/") != "/v1/chat/completions":
            self._send(404, b'{"error":"not found"}')
            return
        try:
            body = json.loads(raw)
        except ValueError:
            self._send(400, b'{"error":{"message":"request body is not JSON"}}')
            return
        fault = fake._next_fault(body, self.headers.get("Authorization"))
        with fake._lock:
            fake.in_flight += 1
            fake.max_in_flight = max(fake.max_in_flight, fake.in_flight)
        try:
            self._answer(fake, body, fault)
        finally:
            with fake._lock:
                fake.in_flight -= 1

    def _answer(self, fake: FakeServer, body: dict[str, Any], fault: Fault | None) -> None:
        text: str | Fault | None = None
        if fault is None:
            text = fake.reply(body)
            if isinstance(text, Fault):
                fault, text = text, None
        if fake.latency and fake._stop.wait(fake.latency):
            return
        if fault is not None:
            if fault.kind == "drop":
                self.close_connection = True
                return
            if fault.kind == "status":
                extra = {"Retry-After": fault.retry_after} if fault.retry_after is not None else {}
                err = json.dumps({"error": {"message": fault.message}}).encode()
                self._send(fault.status, err, extra)
                return
            if fault.kind == "malformed":
                self._send(200, b'{"choices": [ {"message": ')
                return
            if fault.kind == "delay":
                if fake._stop.wait(fault.seconds):
                    return
                text = fake.reply(body)
                text = text if isinstance(text, str) else ""
        with fake._lock:
            fake.n_answered += 1
        self._send(200, json.dumps(fake.completion(body, text or "")).encode())


def main() -> None:
    ap = argparse.ArgumentParser(description="Fake chat-completions server answering '[1, 1]'.")
    ap.add_argument("--latency", type=float, default=0.0)
    args = ap.parse_args()
    with FakeServer(latency=args.latency) as srv:
        print(srv.url, flush=True)
        try:
            while True:
                time.sleep(3600)
        except KeyboardInterrupt:
            pass


if __name__ == "__main__":
    main()
