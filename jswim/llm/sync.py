"""Run a coroutine to completion from synchronous code, also where an event loop already runs."""

from __future__ import annotations

import asyncio
import concurrent.futures
from typing import Any, TypeVar
from collections.abc import Coroutine

from jswim._io import interrupts

T = TypeVar("T")


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
    with concurrent.futures.ThreadPoolExecutor(1, thread_name_prefix="jswim-loop") as pool:
        return pool.submit(asyncio.run, coro).result()
