"""Batching the steps of concurrent runs: what arrives in one event-loop turn is one env call.

Each LLM run is its own pipeline and hands its action over when its reply lands; the runs of a
group share one batched environment state. :class:`StepBatcher` collects the actions handed in
since the group's last step and takes them together at the next turn of the event loop
(``call_soon``): replies that land together are stepped together, and nobody waits for a reply
that has not landed. Members with no action this turn take the no-op and are masked out.
"""

from __future__ import annotations

import asyncio
from typing import Any, Callable, Sequence

import numpy as np


class StepBatcher:
    """Base of the bulk and scene groups. Subclasses set ``members`` (sequence), ``_noop`` (the
    env code of the no-op), ``_pending = {}`` and ``n_steps = 0``, and implement :meth:`_step`."""

    members: Sequence[Any]
    _noop: int
    _pending: dict[int, tuple[int, asyncio.Future]]
    n_steps: int

    def submit(self, pos: int, action: int) -> asyncio.Future:
        """Step member ``pos`` with env action ``action`` soon; the future gets its step's outputs."""
        loop = asyncio.get_running_loop()
        fut = loop.create_future()
        if not self._pending:
            loop.call_soon(self._flush)
        self._pending[pos] = (action, fut)
        return fut

    def _step(self, codes: np.ndarray, mask: np.ndarray) -> Callable[[int], dict[str, Any]]:
        """Advance the members in ``mask`` by ``codes`` (int32 ``(n,)``); return each member's
        outputs by position."""
        raise NotImplementedError

    def _flush(self) -> None:
        pending, self._pending = self._pending, {}
        codes = np.full(len(self.members), self._noop, np.int32)
        mask = np.zeros(len(self.members), bool)
        for pos, (a, _) in pending.items():
            codes[pos], mask[pos] = a, True
        try:
            outputs = self._step(codes, mask)
        except BaseException as exc:  # pragma: no cover - an env failure reaches every waiting run
            for _, fut in pending.values():
                if not fut.done():
                    fut.set_exception(exc)
            return
        self.n_steps += 1
        for pos, (_, fut) in pending.items():
            if not fut.done():  # a cancelled run (Ctrl-C) no longer waits
                fut.set_result(outputs(pos))
