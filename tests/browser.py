"""Headless Chromium driven over the DevTools protocol (CDP), for tests of report pages.

A real browser (Debian's ``chromium`` package; ``.ci/run`` installs it), started with a
throw-away profile and a DevTools port on 127.0.0.1, spoken to with ``websocket-client``. It
records what a page logs (console errors, uncaught exceptions, failed loads) and every network
request, so a test can tell that a page loads clean and fetches nothing.

>>> with Browser() as b:                                 # doctest: +SKIP
...     b.open("file:///tmp/report.html")
...     b.eval("document.title")
...     b.screenshot("shot.png")
"""

from __future__ import annotations

import base64
import json
import os
import shutil
import subprocess
import tempfile
import time
import urllib.request
from pathlib import Path
from typing import Any

NAMES = ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable")


def find_browser() -> str | None:
    """A Chromium-family executable on PATH (``JSWIM_CHROMIUM`` overrides), or ``None``."""
    env = os.environ.get("JSWIM_CHROMIUM")
    if env:
        return env if Path(env).exists() else shutil.which(env)
    for name in NAMES:
        if path := shutil.which(name):
            return path
    return None


class BrowserError(RuntimeError):
    pass


class Browser:
    """One headless Chromium with one page; use as a context manager."""

    def __init__(
        self,
        executable: str | None = None,
        width: int = 1280,
        height: int = 1400,
        timeout: float = 60.0,
    ) -> None:
        self.executable = executable or find_browser()
        if not self.executable:
            raise BrowserError("no Chromium on PATH")
        self.size = (width, height)
        self.timeout = timeout
        self.errors: list[str] = []
        self.requests: list[str] = []
        self._events: list[dict[str, Any]] = []
        self._id = 0

    def __enter__(self) -> Browser:
        import websocket  # websocket-client (a test dependency)

        self._profile = tempfile.mkdtemp(prefix="jswim-chromium-")
        args = [
            self.executable,
            "--headless=new",
            "--no-sandbox",
            "--disable-gpu",
            "--disable-dev-shm-usage",
            "--no-first-run",
            "--no-default-browser-check",
            "--disable-extensions",
            "--mute-audio",
            "--disable-background-networking",
            "--disable-component-update",
            "--hide-scrollbars",
            f"--user-data-dir={self._profile}",
            "--remote-debugging-address=127.0.0.1",
            "--remote-debugging-port=0",
            "--remote-allow-origins=*",
            f"--window-size={self.size[0]},{self.size[1]}",
            "about:blank",
        ]
        self._proc = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        port_file = Path(self._profile) / "DevToolsActivePort"
        deadline = time.monotonic() + self.timeout
        while not (port_file.exists() and port_file.read_text().strip()):
            if self._proc.poll() is not None or time.monotonic() > deadline:
                self.__exit__(None, None, None)
                raise BrowserError(f"{self.executable} did not start (exit {self._proc.poll()})")
            time.sleep(0.05)
        port = int(port_file.read_text().split()[0])
        pages = []
        while not pages:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list", timeout=10) as resp:
                pages = [t for t in json.load(resp) if t.get("type") == "page"]
            if not pages:
                time.sleep(0.05)
        self._ws = websocket.create_connection(
            pages[0]["webSocketDebuggerUrl"], timeout=self.timeout, suppress_origin=True
        )
        for domain in ("Page", "Runtime", "Log", "Network"):
            self.call(f"{domain}.enable")
        self.call(
            "Emulation.setDeviceMetricsOverride",
            width=self.size[0],
            height=self.size[1],
            deviceScaleFactor=1,
            mobile=False,
        )
        return self

    def __exit__(self, *exc: Any) -> None:
        ws = getattr(self, "_ws", None)
        if ws is not None:
            try:
                ws.close()
            except Exception:
                pass
        proc = getattr(self, "_proc", None)
        if proc is not None and proc.poll() is None:
            proc.terminate()
            try:
                proc.wait(10)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()
        shutil.rmtree(getattr(self, "_profile", ""), ignore_errors=True)

    # -- protocol ----------------------------------------------------------------------------

    def _note(self, msg: dict[str, Any]) -> None:
        method, p = msg.get("method"), msg.get("params", {})
        if method == "Runtime.consoleAPICalled" and p.get("type") in ("error", "assert"):
            self.errors.append(
                "console: "
                + " ".join(str(a.get("value", a.get("description", ""))) for a in p.get("args", []))
            )
        elif method == "Runtime.exceptionThrown":
            d = p.get("exceptionDetails", {})
            self.errors.append(
                "exception: " + str(d.get("exception", {}).get("description") or d.get("text"))
            )
        elif method == "Log.entryAdded" and p.get("entry", {}).get("level") == "error":
            self.errors.append(
                "log: " + str(p["entry"].get("text")) + " " + str(p["entry"].get("url", ""))
            )
        elif method == "Network.requestWillBeSent":
            self.requests.append(p.get("request", {}).get("url", ""))
        self._events.append(msg)

    def call(self, method: str, **params: Any) -> dict[str, Any]:
        """Send one CDP command and wait for its answer (events meanwhile are recorded)."""
        self._id += 1
        mid = self._id
        self._ws.send(json.dumps({"id": mid, "method": method, "params": params}))
        while True:
            msg = json.loads(self._ws.recv())
            if msg.get("id") == mid:
                if "error" in msg:
                    raise BrowserError(f"{method}: {msg['error']}")
                return msg.get("result", {})
            self._note(msg)

    def wait_event(self, method: str, timeout: float | None = None) -> dict[str, Any]:
        for msg in self._events:
            if msg.get("method") == method:
                self._events.remove(msg)
                return msg
        deadline = time.monotonic() + (timeout or self.timeout)
        while time.monotonic() < deadline:
            msg = json.loads(self._ws.recv())
            self._note(msg)
            if msg.get("method") == method:
                self._events.remove(msg)
                return msg
        raise BrowserError(f"no {method} within {timeout or self.timeout} s")

    # -- conveniences ------------------------------------------------------------------------

    def open(self, url: str) -> None:
        """Load ``url`` and wait for its load event."""
        self._events = [e for e in self._events if e.get("method") != "Page.loadEventFired"]
        self.call("Page.navigate", url=url)
        self.wait_event("Page.loadEventFired")

    def eval(self, expression: str, await_promise: bool = True) -> Any:
        """The value of a JavaScript expression in the page (promises awaited)."""
        res = self.call(
            "Runtime.evaluate",
            expression=expression,
            awaitPromise=await_promise,
            returnByValue=True,
        )
        if "exceptionDetails" in res:
            d = res["exceptionDetails"]
            raise BrowserError(
                f"{expression!r}: {d.get('exception', {}).get('description') or d.get('text')}"
            )
        return res.get("result", {}).get("value")

    def pump(self, seconds: float) -> None:
        """Let the page run for ``seconds`` (timers fire), recording its events."""
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.eval("0")
            time.sleep(0.05)

    def screenshot(self, path: str | os.PathLike, full_page: bool = False) -> Path:
        """Save a PNG of the page (the viewport, or the whole page)."""
        params: dict[str, Any] = {"format": "png"}
        if full_page:
            params["captureBeyondViewport"] = True
        data = self.call("Page.captureScreenshot", **params)["data"]
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(base64.b64decode(data))
        return path


def browser_or_skip(**kwargs: Any) -> Browser:
    """A :class:`Browser` (not yet started: use it as a context manager), or the calling test
    skipped with the reason: websocket-client or Chromium missing."""
    import pytest

    try:
        import websocket  # noqa: F401  (websocket-client, a test dependency)
    except ImportError:
        pytest.skip("websocket-client is not installed (pip install -e '.[test]')")
    if find_browser() is None:
        pytest.skip("no Chromium installed (Debian: apt-get install chromium; .ci/run installs it)")
    return Browser(**kwargs)


def open_report_run(b: Browser, page: Path, run_id: str) -> None:
    """Open the report ``page`` in ``b``, select the run ``run_id`` and scroll to its view."""
    b.open(page.resolve().as_uri())
    b.eval("window.jswimReport.opened")
    i = b.eval(
        "JSON.parse(document.getElementById('report-data').textContent).runs"
        f".filter(r => r.run_id === {json.dumps(run_id)})[0].i"
    )
    b.eval(f"window.jswimReport.select({i})")
    b.pump(0.5)
    b.eval("document.getElementById('browser').scrollIntoView()")
