"""SIGINT, SIGTERM and SIGHUP end a ``jswim`` session the same way, once.

A batch scheduler, ``systemd`` or ``timeout`` stops a job with SIGTERM; a closed terminal sends
SIGHUP; a user presses Ctrl-C. Each must end a study the same way: every finished run and
answered call kept, the folder's status ``interrupted``, one line on stderr. :func:`install`
(called by the ``jswim`` command, never on import) routes all three to one handler:

- the first signal stops the session: inside the event loop the main task is cancelled (as
  :func:`asyncio.run` does for Ctrl-C, so every ``finally`` runs and transcripts are closed),
  elsewhere :class:`KeyboardInterrupt` is raised;
- every later signal is only noted: the session is already saving what it has, and a second
  Ctrl-C must not tear that save or print a traceback from a cleanup or ``atexit`` callback.

:func:`quiet` makes even the first signal a note (the session is over; only exit remains).

The first signal is acted on at a moment that can take it. Not inside an import: an exception
raised while a C extension initialises (JAX's ``jaxlib._jax``, pyarrow) leaves it half made, an
``ImportError`` traceback or a crash at exit; the handler then looks again every 50 ms (SIGALRM)
until the import is over. And not lost: a :class:`KeyboardInterrupt` raised inside a callback that
cannot raise (a garbage-collector callback, a ``__del__``) is swallowed by Python; the
unraisable hook sees it and delivers it again the same way.
"""

from __future__ import annotations

import signal
import sys
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # asyncio itself is not needed to handle a signal (and costs 0.1 s of start-up)
    import asyncio

SIGNALS = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))

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
    """The task that the first signal cancels while an event loop runs (:func:`jswim.llm.sync.run_sync`)."""
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
    """A :class:`KeyboardInterrupt` of ours raised where Python cannot raise (a gc callback, a
    ``__del__``) is delivered again soon instead of printed and lost."""
    global _undelivered
    if isinstance(unraisable.exc_value, KeyboardInterrupt) and _received is not None and _armed:
        _undelivered = True
        _later()
        return
    _previous_unraisablehook(unraisable)
