"""SIGINT, SIGTERM and SIGHUP end a ``jswim`` session the same way, once.

A scheduler's SIGTERM, a closed terminal's SIGHUP and Ctrl-C must each end a study the same way:
every finished run and answered call kept, the status ``interrupted``, one line on stderr.
`install` (called by the ``jswim`` command, never on import) routes all three to one
handler; when it acts on the first signal (never inside an import) and why later ones are only
noted is in docs/design.md (*Study folders under kills, signals and a second writer*).
"""

from __future__ import annotations

import signal
import sys
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # asyncio itself is not needed to handle a signal (and costs 0.1 s of start-up)
    import asyncio

SIGNALS = tuple(
    getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name)
)

_received: int | None = None
_armed = False
_main_task: asyncio.Task | None = None
_undelivered = False  # the first signal is waiting for a moment that can take it
_RETRY_S = 0.05
_previous_unraisablehook = sys.unraisablehook


def install() -> None:
    """Route SIGINT, SIGTERM and SIGHUP to the session's one handler (main thread only)."""
    global _armed
    for sig in SIGNALS:
        signal.signal(sig, _handler)
    if hasattr(signal, "SIGALRM"):
        signal.signal(signal.SIGALRM, _retry)
    sys.unraisablehook = _unraisable
    _armed = True


def quiet() -> None:
    """From now on signals are noted, never raised (the work is done; cleanup and exit remain)."""
    global _armed
    _armed = False
    if hasattr(signal, "setitimer"):
        try:
            signal.setitimer(signal.ITIMER_REAL, 0)  # no delivery left pending
        except (ValueError, OSError):
            pass


def ignore() -> None:
    """Ignore every later signal: the interpreter is about to exit.

    At finalisation CPython puts back the default, fatal, disposition of every signal that had
    a Python handler, so a Ctrl-C landing then would kill the process (exit -2) after its one
    line was printed; an ignored signal stays ignored through finalisation.
    """
    quiet()
    for sig in (*SIGNALS, *((signal.SIGALRM,) if hasattr(signal, "SIGALRM") else ())):
        try:
            signal.signal(sig, signal.SIG_IGN)
        except (ValueError, OSError):  # not the main thread: nothing to do
            pass


def received() -> int | None:
    """The first signal received (its number), or ``None``."""
    return _received


def name(signum: int | None) -> str:
    """``"SIGTERM"`` for 15; ``"Ctrl-C"`` for SIGINT or ``None``."""
    if signum is None or signum == signal.SIGINT:
        return "Ctrl-C"
    return signal.Signals(signum).name


def set_main_task(task: asyncio.Task | None) -> None:
    """The task that the first signal cancels while an event loop runs (`jswim.llm.sync.run_sync`)."""
    global _main_task
    _main_task = task


def _handler(signum: int, frame: Any) -> None:
    global _received, _undelivered
    if _received is not None or not _armed:
        _received = _received or signum
        return
    _received = signum
    _undelivered = True
    _deliver(frame)


def _importing(frame: Any) -> bool:
    """Whether an import is running in this frame's stack (importlib's frames are below it)."""
    while frame is not None:
        if frame.f_code.co_filename.startswith("<frozen importlib._bootstrap"):
            return True
        frame = frame.f_back
    return False


def _later() -> None:
    if hasattr(signal, "setitimer"):
        signal.setitimer(signal.ITIMER_REAL, _RETRY_S)


def _deliver(frame: Any) -> None:
    """Stop the session now, or look again in 50 ms when an import is running."""
    global _undelivered
    if not _undelivered or not _armed:
        return
    if _importing(frame):
        _later()
        return
    _undelivered = False
    task = _main_task
    if task is not None and not task.done():
        task.cancel()
        task.get_loop().call_soon_threadsafe(lambda: None)  # wake a loop waiting in select()
        return
    raise KeyboardInterrupt


def _retry(signum: int, frame: Any) -> None:
    _deliver(frame)


def _unraisable(unraisable: Any) -> None:
    """A `KeyboardInterrupt` of ours raised where Python cannot raise (a gc callback, a
    ``__del__``) is delivered again soon instead of printed and lost."""
    global _undelivered
    if isinstance(unraisable.exc_value, KeyboardInterrupt) and _received is not None and _armed:
        _undelivered = True
        _later()
        return
    _previous_unraisablehook(unraisable)
