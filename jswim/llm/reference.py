"""A prompt-only reference agent behind an OpenAI-compatible server (``jswim serve reference``).

It is not a language model and is never presented as one: a plain rule ([`decide`][jswim.llm.reference.decide]) that reads
the rendered prompt text it receives, nothing else, and answers one action. Its purpose, the rule
step by step, what it reads of the prompt and what it measured are in docs/bench.md (*The
reference agent*).
"""

from __future__ import annotations

import json
import math
import re
import threading
import time
from dataclasses import dataclass
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any
from collections.abc import Sequence

from jswim.llm.tokens import estimate_prompt_tokens, estimate_tokens

#: The model name the server answers with (and lists at /v1/models).
MODEL = "reference-rule"

_RECORD = re.compile(
    r"^\s*\d+:\s*\(([^)]*)\)\s*\[\s*(\d+)\s*,\s*(-?\d+)\s*\]\s*->\s*\(([^)]*)\),\s*X\s*(-?\d+)\s*->\s*(-?\d+)"
    r"(?:,\s*stuck\s*(yes|no))?",
    re.M,
)
_PAIR = re.compile(r"\[\s*(\d+)\s*,\s*(-?\d+)\s*\]")
_RANGE = re.compile(r"stays? in \[\s*(-?[\d.]+)\s*,\s*(-?[\d.]+)\s*\]", re.I)
_SPLIT = re.compile(r"the changed DOF ([\d ,or]+?) and the ROC ([-\d ,or]+)", re.I)


@dataclass(frozen=True)
class Record:
    """One history record as read from the prompt text."""

    before: str
    action: tuple[int, int]
    after: str
    progress: int  # X after - X before, toward the target (thousandths of a)
    stuck: bool


def _shape(text: str) -> str:
    return ",".join(v.strip() for v in text.split(","))


def read_prompt(text: str) -> tuple[int, list[Record], list[tuple[int, int]]]:
    """``(direction, records, offered actions)`` read from a rendered prompt."""
    direction = -1 if re.search(r"negative x", text, re.I) else 1
    records = []
    for m in _RECORD.finditer(text):
        dx = (int(m.group(6)) - int(m.group(5))) * direction
        records.append(
            Record(
                _shape(m.group(1)),
                (int(m.group(2)), int(m.group(3))),
                _shape(m.group(4)),
                dx,
                m.group(7) == "yes",
            )
        )
    tail = text[max((m.end() for m in _RECORD.finditer(text)), default=0) :]
    split = _SPLIT.search(tail)
    if split:
        dofs = [int(v) for v in re.findall(r"\d+", split.group(1))]
        rocs = [int(v) for v in re.findall(r"-?\d+", split.group(2))]
        offered = [(d, r) for d in dofs for r in rocs]
    else:
        offered = [(int(a), int(b)) for a, b in _PAIR.findall(tail)]
    return direction, records, offered or [(1, -1), (1, 1), (2, -1), (2, 1)]


def _order(action: tuple[int, int]) -> tuple[int, int, int]:
    dof, roc = action
    return (roc == 0, dof, roc)  # moves before holds, DOFs in order, -1 before +1


def _blocked(action: tuple[int, int], here: str | None, text: str) -> bool:
    """Whether S2's range says ``action`` cannot change shape ``here`` (a hold at a limit)."""
    dof, roc = action
    m = _RANGE.search(text)
    if roc == 0 or here is None or m is None:
        return roc == 0
    try:
        value = float(here.split(",")[dof - 1])
    except (IndexError, ValueError):
        return False
    lo, hi = float(m.group(1)), float(m.group(2))
    return (roc < 0 and value <= lo) or (roc > 0 and value >= hi)


# -- navigation (an extension; docs/navigation.md) -------------------------------------------------

_TARGET = re.compile(r"\(X, Y\) = \((-?\d+), (-?\d+)\)")
_NAV_RECORD = re.compile(
    r"^\s*\d+:\s*\(([^)]*)\)\s*\[\s*(\d+)\s*,\s*(-?\d+)\s*\]\s*->\s*\(([^)]*)\),\s*X\s*(-?\d+)\s*->\s*"
    r"(-?\d+),\s*Y\s*(-?\d+)\s*->\s*(-?\d+),\s*heading\s*(-?[\d.]+)\s*->\s*(-?[\d.]+)",
    re.M,
)
_LEVELS = re.compile(r"k/(\d+) of its range")

#: |bearing| (rad) under which the navigation rule swims straight: twice the quarter loop's
#: rotation per cycle for Purcell's swimmer at d_max = pi/3 (0.0584 rad, jswim.env.loops), so one
#: turning cycle cannot carry the bearing from one side of the dead band to the other.
NAV_TOLERANCE = 0.117


def _nav_cycles(k: int) -> list[tuple[tuple[int, int], ...]]:
    """The rule's cycles on the K lattice as closed vertex lists, each from its hub ``(K, K)``
    or ``(0, 0)``: the square gait's halves forward and backward, and the quarter loops that
    touch it, both ways (the steering controller's cycles, jswim.swimmers.turning)."""
    m = k // 2
    hi, lo = (k, k), (0, 0)
    return [
        (hi, (k, 0), lo),  # forward half from (K, K)
        (lo, (0, k), hi),  # forward half from (0, 0)
        (hi, (0, k), lo),  # backward half from (K, K)
        (lo, (k, 0), hi),  # backward half from (0, 0)
        (hi, (k, m), (m, m), (m, k), hi),  # upper quarter loop: left while moving forward
        (hi, (m, k), (m, m), (k, m), hi),  # its reverse: right while moving backward
        (lo, (0, m), (m, m), (m, 0), lo),  # lower quarter loop: right while moving forward
        (lo, (m, 0), (m, m), (0, m), lo),  # its reverse: left while moving backward
    ]


def _wrap(angle: float) -> float:
    return math.pi - (math.pi - angle) % (2 * math.pi)


#: Hysteresis (rad) of the choice between swimming forward and backward: a swimmer that came
#: backward keeps on backward until the target is this much inside 90 degrees of its heading
#: (and forward likewise), so that a target near 90 degrees does not set it swimming half a gait
#: forward, half back, which undoes itself (the scallop theorem).
NAV_HYSTERESIS = 0.35


def _nav_choice(k: int, hub: tuple[int, int], bearing: float, was_back: bool) -> tuple[int, int]:
    """The next vertex from ``hub`` for a target at ``bearing`` (rad, from the heading): straight
    (half the square gait) within `NAV_TOLERANCE`, else the quarter loop that turns toward the
    target if it starts here, else half the gait to the other hub, where it does. A target more
    than 90 degrees off is approached swimming backward (the reversed gait), with
    `NAV_HYSTERESIS` about 90 degrees (``was_back``: the last cycle ran backward)."""
    cycles = _nav_cycles(k)
    back = abs(bearing) > math.pi / 2 + (-NAV_HYSTERESIS if was_back else NAV_HYSTERESIS)
    b = _wrap(bearing - math.pi) if back else bearing
    half = cycles[(2 if back else 0) + (hub != (k, k))]
    if abs(b) <= NAV_TOLERANCE:
        return half[1]
    left = b > 0
    loop = cycles[(7 if left else 5) if back else (4 if left else 6)]
    return loop[1] if loop[0] == hub else half[1]


def nav_decide(text: str) -> tuple[int, int] | None:
    """The navigation rule's action for a navigation prompt, ``None`` for any other prompt.

    It steers as the steering controller does, from the prompt alone: the target's (X, Y) from
    S1, the latest record's X, Y, heading and DOFs, K from S2 (K = 1 has no quarter loop: the
    square gait only, toward +x of the body). On a hub of the square gait, ``(hi, hi)`` or
    ``(lo, lo)``, it chooses the next cycle from the target's bearing (`_nav_choice`); between
    hubs it plays on the cycle its last move belongs to (every move of the eight cycles is in
    one cycle only); off the cycles (another agent's shape) it moves each DOF to ``hi``.
    """
    target = _TARGET.search(text)
    if target is None or "heading" not in text:
        return None
    records = list(_NAV_RECORD.finditer(text))
    levels = _LEVELS.search(text)
    k = int(levels.group(1)) if levels else 1
    k_turn = None if k % 2 else k  # odd K: no quarter loop, the square gait from (hi, hi)
    if not records:
        return (2, -k)  # the gait's first move from the authors' start (hi, hi)
    last = records[-1]
    rng = _RANGE.search(text)
    lo, hi = (float(rng.group(1)), float(rng.group(2))) if rng else (-1.0, 1.0)

    def level(values: str) -> tuple[int, int] | None:
        try:
            v = [float(u) for u in values.split(",")]
        except ValueError:
            return None
        j = [round((u - lo) / (hi - lo) * k) for u in v[:2]]
        return (j[0], j[1]) if len(v) == 2 else None

    cur, prev = level(last.group(4)), level(last.group(1))
    if cur is None or prev is None:
        return None
    x, y = int(last.group(6)), int(last.group(8))
    heading = float(last.group(10))
    tx, ty = int(target.group(1)), int(target.group(2))
    bearing = _wrap(math.atan2(ty - y, tx - x) - heading)
    if k_turn is None:
        gait = {(k, k): (k, 0), (k, 0): (0, 0), (0, 0): (0, k), (0, k): (k, k)}
        nxt = gait.get(cur)
    elif cur in ((k, k), (0, 0)):
        m = k // 2
        was_back = (prev, cur) in (  # the last cycle ran backward: the reversed gait or loops
            ((k, 0), (k, k)),
            ((0, k), (0, 0)),
            ((k, m), (k, k)),
            ((0, m), (0, 0)),
        )
        nxt = _nav_choice(k, cur, bearing, was_back)
    else:
        follow = {}
        for cyc in _nav_cycles(k):
            for a, b, c in zip(cyc, cyc[1:], cyc[2:]):
                follow[(a, b)] = c
        nxt = follow.get((prev, cur))
    if nxt is None:  # off the cycles: each DOF to hi, D1 first
        dof = 0 if cur[0] != k else 1
        return (dof + 1, k - cur[dof])
    dof = 0 if nxt[0] != cur[0] else 1
    return (dof + 1, nxt[dof] - cur[dof])


def decide(text: str) -> tuple[int, int]:
    """The reference rule's action for a rendered prompt (docs/bench.md; a navigation prompt:
    [`nav_decide`][jswim.llm.reference.nav_decide])."""
    _, records, offered = read_prompt(text)
    nav = nav_decide(text)
    if nav is not None and nav in offered:
        return nav
    here = records[-1].after if records else None
    from_here = [r for r in records if r.before == here]
    if from_here:
        best = max(from_here, key=lambda r: r.progress)  # the first of equals: max keeps the first
        if best.progress > 0 and best.action in offered:
            return best.action
    shown = {r.action for r in from_here}
    stuck = {r.action for r in from_here if r.stuck}
    for action in sorted(offered, key=_order):
        if action not in shown and action not in stuck and not _blocked(action, here, text):
            return action
    moved = [r for r in from_here if r.action in offered and not r.stuck]
    if moved:
        return max(moved, key=lambda r: r.progress).action
    return sorted(offered, key=_order)[0]


def _prompt_of(messages: Sequence[dict[str, Any]]) -> str:
    """The first user message (the protocol's prompt; a follow-up adds turns after it)."""
    for m in messages:
        if m.get("role") == "user":
            content = m.get("content")
            if isinstance(content, list):
                return "".join(str(p.get("text", "")) for p in content if isinstance(p, dict))
            return str(content or "")
    return ""


def completion(body: dict[str, Any]) -> dict[str, Any]:
    """The chat.completion answering a request body."""
    messages = body.get("messages") or []
    dof, roc = decide(_prompt_of(messages))
    text = f"[{dof}, {roc}]"
    prompt, done = estimate_prompt_tokens(messages), estimate_tokens(text)
    return {
        "id": f"reference-{time.monotonic_ns()}",
        "object": "chat.completion",
        "created": int(time.time()),
        "model": MODEL,
        "system_fingerprint": "jswim-reference-rule",
        "choices": [
            {"index": 0, "message": {"role": "assistant", "content": text}, "finish_reason": "stop"}
        ],
        "usage": {
            "prompt_tokens": prompt,
            "completion_tokens": done,
            "total_tokens": prompt + done,
        },
    }


class _Handler(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"

    def log_message(
        self, *args: Any
    ) -> None:  # quiet: one line per request would drown a study's output
        return None

    def _send(self, status: int, payload: dict[str, Any]) -> None:
        data = json.dumps(payload).encode()
        self.send_response(status)
        self.send_header("Content-Type", "application/json")
        self.send_header("Content-Length", str(len(data)))
        self.end_headers()
        self.wfile.write(data)

    def do_GET(self) -> None:
        if self.path.rstrip("/") in ("/v1/models", "/models"):
            self._send(
                200,
                {"object": "list", "data": [{"id": MODEL, "object": "model", "owned_by": "jswim"}]},
            )
        elif self.path.rstrip("/") in ("/health", "/v1/health"):
            self._send(200, {"status": "ok"})
        else:
            self._send(404, {"error": {"message": f"no such endpoint: {self.path}"}})

    def do_POST(self) -> None:
        size = int(self.headers.get("Content-Length") or 0)
        raw = self.rfile.read(size) if size else b""
        if self.path.rstrip("/") not in ("/v1/chat/completions", "/chat/completions"):
            self._send(404, {"error": {"message": f"no such endpoint: {self.path}"}})
            return
        try:
            body = json.loads(raw)
            if not isinstance(body, dict):
                raise ValueError("not an object")
        except ValueError:
            self._send(400, {"error": {"message": "the request body is not a JSON object"}})
            return
        self._send(200, completion(body))


class _Server(ThreadingHTTPServer):
    daemon_threads = True

    def handle_error(self, request: Any, client_address: Any) -> None:
        return None  # a client that went away mid-answer (Ctrl-C of a study) is not an error here


class ReferenceServer:
    """The reference agent's server on ``127.0.0.1`` (port 0: a free one); a context manager.

    >>> with ReferenceServer() as srv:   # doctest: +SKIP
    ...     print(srv.url)               # http://127.0.0.1:PORT/v1, model "reference-rule"
    """

    def __init__(self, host: str = "127.0.0.1", port: int = 0) -> None:
        self._httpd = _Server((host, port), _Handler)
        self._thread: threading.Thread | None = None

    @property
    def url(self) -> str:
        host, port = self._httpd.server_address[:2]
        return f"http://{host}:{port}/v1"

    def start(self) -> ReferenceServer:
        self._thread = threading.Thread(
            target=self._httpd.serve_forever, name="jswim-reference", daemon=True
        )
        self._thread.start()
        return self

    def stop(self) -> None:
        self._httpd.shutdown()
        self._httpd.server_close()
        if self._thread is not None:
            self._thread.join(5)

    def serve_forever(self) -> None:
        """Serve in this thread until interrupted (``jswim serve reference``)."""
        try:
            self._httpd.serve_forever()
        finally:
            self._httpd.server_close()

    def __enter__(self) -> ReferenceServer:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()
