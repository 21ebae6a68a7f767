"""Run a coroutine to completion from synchronous code, also where an event loop already runs.

In a notebook the kernel's own event loop already runs in the main thread, so the coroutine runs
on a loop of its own in a worker thread. The kernel's Stop button (SIGINT) raises
`KeyboardInterrupt` only in the main thread; `run_sync` turns it into a cancel of the
worker's task, the same cancel the ``jswim`` command's Ctrl-C makes: no request goes out after
it, calls in flight are journaled as unanswered, and the call returns within moments.
"""

from __future__ import annotations

import asyncio
import contextvars
import sys
import threading
import time
from typing import Any, Generic, TypeVar
from collections.abc import Coroutine

from jswim._io import callsite, interrupts

T = TypeVar("T")

#: How long an interrupted call waits for its worker to wind down (journal, close the folder's
#: files) before it gives up on it and raises anyway.
WIND_DOWN_S = 10.0


async def _main(coro: Coroutine[Any, Any, T]) -> T:
    """``coro`` as the task a signal cancels (`jswim._io.interrupts`)."""
    interrupts.set_main_task(asyncio.current_task())
    try:
        return await coro
    finally:
        interrupts.set_main_task(None)


def run_sync(coro: Coroutine[Any, Any, T]) -> T:
    """Run ``coro`` to completion and return its result.

    Outside an event loop this is `asyncio.run`. Inside one (Jupyter, IPython, an async
    application) ``asyncio.run`` refuses to start a second loop in the same thread, so the
    coroutine gets its own loop in a worker thread and this call blocks until it is done. An
    httpx client is bound to the loop it was opened on, so ``coro`` must open its own client.

    Raises
    ------
    KeyboardInterrupt
        On an interrupt (Ctrl-C, a signal the ``jswim`` command routes, a notebook's Stop),
        after the coroutine was cancelled and had wound down.
    """
    try:
        asyncio.get_running_loop()
    except RuntimeError:
        try:
            return asyncio.run(_main(coro))
        except asyncio.CancelledError:
            if interrupts.received() is not None:  # cancelled by a signal: an interrupt, as Ctrl-C
                raise KeyboardInterrupt from None
            raise
    return _LoopThread(coro).result()


class _LoopThread(Generic[T]):
    """A coroutine on its own event loop in a worker thread, cancellable from the caller's thread."""

    def __init__(self, coro: Coroutine[Any, Any, T]) -> None:
        self._coro = coro
        self._loop: asyncio.AbstractEventLoop | None = None
        self._task: asyncio.Task[T] | None = None
        self._started = threading.Event()
        self._value: T | None = None
        self._error: BaseException | None = None
        # The worker runs in a copy of the caller's context: a kernel's output routing and the
        # user's call site (callsite.CALL_SITE, where a warning from the worker points) go along.
        context = contextvars.copy_context()
        context.run(callsite.CALL_SITE.set, callsite.user_call_site(sys._getframe(2)))
        self._thread = threading.Thread(
            target=context.run, args=(self._run,), name="jswim-loop", daemon=True
        )

    def _run(self) -> None:
        async def main() -> T:
            self._loop = asyncio.get_running_loop()
            self._task = asyncio.current_task()  # type: ignore[assignment]
            self._started.set()
            return await self._coro

        try:
            self._value = asyncio.run(main())
        except BaseException as exc:  # handed to the caller's thread
            self._error = exc
        finally:
            self._started.set()

    def _cancel(self) -> None:
        """Cancel the task from the caller's thread (a no-op once the loop has closed)."""
        self._started.wait()
        loop, task = self._loop, self._task
        if loop is None or task is None:
            return
        try:
            loop.call_soon_threadsafe(task.cancel)
        except RuntimeError:  # the loop already closed: nothing left to cancel
            pass

    def result(self) -> T:
        self._thread.start()
        try:
            while self._thread.is_alive():
                self._thread.join(0.1)  # a timed wait, so an interrupt is raised here at once
        except KeyboardInterrupt:
            self._cancel()
            self._wind_down()
            raise
        if self._error is not None:
            raise self._error
        return self._value  # type: ignore[return-value]

    def _wind_down(self) -> None:
        """Wait for the cancelled coroutine's cleanup; a second interrupt does not cut it short."""
        deadline = time.monotonic() + WIND_DOWN_S
        while self._thread.is_alive() and time.monotonic() < deadline:
            try:
                self._thread.join(0.1)
            except KeyboardInterrupt:
                continue
