"""``run_sync`` inside a running event loop (a notebook's kernel): an interrupt cancels the coroutine.

The kernel's Stop sends SIGINT, which Python raises as KeyboardInterrupt in the main thread only;
the coroutine runs on its own loop in a worker thread. The interrupt must cancel it there (its
``finally`` runs, no further step is taken) and the call must raise KeyboardInterrupt promptly.
"""

from __future__ import annotations

import asyncio
import os
import signal
import threading
import time
import warnings

import pytest

from jswim._io import callsite
from jswim.llm.sync import run_sync


def _in_a_running_loop(fn):
    """Call ``fn()`` from a coroutine on a loop with no SIGINT handler of its own (as a kernel's)."""

    async def cell():
        return fn()

    loop = asyncio.new_event_loop()
    try:
        return loop.run_until_complete(cell())
    finally:
        loop.close()


@pytest.fixture
def python_sigint():
    """Python's own SIGINT handler, as in a kernel: an xdist worker may ignore SIGINT, and an
    earlier test of the same worker may have left jswim's session handler installed."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


def test_an_interrupt_cancels_the_coroutine_in_its_worker_thread(python_sigint):
    ticks: list[float] = []
    cleaned: list[str] = []

    async def work():
        try:
            while time.monotonic() - t0 < 10.0:  # bounded: a lost interrupt fails, never hangs
                ticks.append(time.monotonic())
                await asyncio.sleep(0.02)
        finally:
            cleaned.append(threading.current_thread().name)

    threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT)).start()
    t0 = time.monotonic()
    with pytest.raises(KeyboardInterrupt):
        _in_a_running_loop(lambda: run_sync(work()))
    back = time.monotonic()
    n = len(ticks)
    time.sleep(0.1)
    assert back - t0 < 1.0  # not the coroutine's end (it has none)
    assert cleaned == ["jswim-loop"]  # cancelled in its own thread, its finally ran
    assert len(ticks) == n and ticks[-1] < back  # no step after the call returned


def test_results_and_errors_come_back_from_the_worker_thread():
    async def value():
        await asyncio.sleep(0)
        return 42

    async def fails():
        raise ValueError("bad")

    assert _in_a_running_loop(lambda: run_sync(value())) == 42
    with pytest.raises(ValueError, match="bad"):
        _in_a_running_loop(lambda: run_sync(fails()))


def test_a_warning_from_the_worker_thread_names_the_callers_line():
    # A coroutine whose code sits in jswim's package, as the study's own code does.
    inside = os.path.join(os.path.dirname(callsite.__file__), "_as_if_jswim.py")
    space: dict = {"warn_user": callsite.warn_user}
    exec(
        compile("async def warns():\n    warn_user('look here', UserWarning)\n", inside, "exec"),
        space,
    )
    warns = space["warns"]

    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        _in_a_running_loop(lambda: run_sync(warns()))  # the line a warning must name
    line = _line_of("_in_a_running_loop(lambda: run_sync(warns()))  # the line")
    assert [(w.filename, w.lineno) for w in got] == [(__file__, line)]


def _line_of(text: str) -> int:
    with open(__file__) as f:
        return next(i for i, ln in enumerate(f, 1) if text in ln and "_line_of" not in ln)
