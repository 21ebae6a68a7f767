"""Every request a study sends, written down before it goes out, with what it cost.

``requests.jsonl`` is the study's money ledger, kept beside the call journal (``calls.jsonl``,
which holds the answers). Each HTTP request that may be billed gets a line *before* it is sent
(its reservation, ``bound_usd``); its outcome gets a second line when known:

- ``{"id": 7, "bound_usd": b}``: sent (written and flushed first: a request that cannot be
  written down is not sent);
- ``{"id": 7, "cost_usd": c}``: answered, or answered with a body that is no chat completion,
  and billed ``c``;
- ``{"id": 7, "released": true}``: refused or never delivered (a 429, a 5xx, a refused
  connection): not billed.

A request with no outcome line got no answer (a timeout, a cut connection, a kill): the server
may have billed it, so its bound stays counted. What a folder spent, what may still be billed,
and how far the provider's bills ran above the reservations are recomputed from these lines on
every open: the totals in ``metadata.json`` are a report, never the ledger. docs/paid-apis.md
(*Cap*) states what the cost cap guarantees from them.
"""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any
from collections.abc import Mapping

from jswim._io.jsonl import read_records, repair_tail
from jswim._io.permissions import opener
from jswim.errors import StudyFolderError
from jswim.llm.journal import CallJournal

LEDGER = "requests.jsonl"


def _usd(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v >= 0


def ledger_problem(rec: Mapping[str, Any]) -> str | None:
    """What makes ``rec`` no ledger line (``None`` when it is one)."""
    if not (isinstance(rec.get("id"), int) and not isinstance(rec.get("id"), bool)):
        return f"'id' is {rec.get('id')!r}, not a request number"
    kinds = [k for k in ("bound_usd", "cost_usd", "released", "carried_usd") if k in rec]
    if len(kinds) != 1:
        return "not one of sent, billed, released or carried"
    if kinds[0] == "released":
        return None if rec["released"] is True else f"'released' is {rec['released']!r}"
    if not _usd(rec[kinds[0]]):
        return f"{kinds[0]!r} is {rec[kinds[0]]!r}, not a price"
    return None


class RequestLedger:
    """The money ledger of a study folder (``folder / requests.jsonl``).

    Parameters
    ----------
    folder : path
        The study folder.
    journal : CallJournal, optional
        The folder's call journal: opened for appending here (a journal that cannot be written
        stops the study before anything is sent), and its answered calls' cost carried over once
        (a ``carried_usd`` line) into a ledger younger than the journal (an older jswim's folder).

    Attributes
    ----------
    spent_usd : float
        Billed, over every session: the outcome lines' costs plus what was carried over.
    unanswered_usd : float
        Bounds of the requests sent that have no outcome line.
    ratio : float
        The largest bill-to-reservation ratio seen (1 when every bill kept within its
        reservation): later reservations are scaled by it.
    """

    def __init__(
        self,
        folder: str | os.PathLike,
        journal: CallJournal | None = None,
        *,
        read_only: bool = False,
    ) -> None:
        self.path = Path(folder) / LEDGER
        answered_usd = journal.spent_usd if journal is not None else 0.0
        if journal is not None and not read_only:
            try:
                journal.open_for_append()
            except OSError as exc:
                why = exc.strerror or type(exc).__name__
                raise StudyFolderError(
                    f"cannot write the call journal {journal.path} ({why}); nothing was sent: "
                    "make it writable or choose another --out"
                ) from None
        if not read_only:
            try:
                repair_tail(self.path)
            except OSError as exc:
                raise StudyFolderError(self._cannot(exc)) from None
        self._bounds: dict[int, float] = {}
        self._next = 0
        self.spent_usd = 0.0
        self.ratio = 1.0
        carried = False
        for _, rec in read_records(self.path, ledger_problem):
            n = rec["id"]
            self._next = max(self._next, n + 1)
            if "bound_usd" in rec:
                self._bounds[n] = float(rec["bound_usd"])
            elif "carried_usd" in rec:
                carried = True
                self.spent_usd += float(rec["carried_usd"])
            elif n in self._bounds:
                bound = self._bounds.pop(n)
                if "cost_usd" in rec:
                    cost = float(rec["cost_usd"])
                    self.spent_usd += cost
                    if bound > 0:
                        self.ratio = max(self.ratio, cost / bound)
        self._fh: Any = None
        #: An older jswim's folder (a journal, no ledger line yet): its answered calls' cost,
        #: carried into the ledger as its first line when the first request is written down.
        self._carry = answered_usd if not carried and self._next == 0 else 0.0
        self.spent_usd += self._carry

    @property
    def unanswered_usd(self) -> float:
        return sum(self._bounds.values())

    @property
    def unanswered(self) -> int:
        return len(self._bounds)

    def _cannot(self, exc: OSError) -> str:
        why = exc.strerror or type(exc).__name__
        return (
            f"cannot write the request ledger {self.path} ({why}); nothing was sent: "
            "make the folder writable or choose another --out"
        )

    def _take(self) -> int:
        n = self._next
        self._next += 1
        return n

    def _write(self, rec: dict[str, Any]) -> None:
        try:
            if self._fh is None:
                self.path.parent.mkdir(parents=True, exist_ok=True)
                self._fh = open(self.path, "a", encoding="utf-8", opener=opener)
            if self._carry > 0:
                self._fh.write(json.dumps({"id": self._take(), "carried_usd": self._carry}) + "\n")
                self._carry = 0.0
            self._fh.write(json.dumps(rec) + "\n")
            self._fh.flush()
        except OSError as exc:
            raise StudyFolderError(self._cannot(exc)) from None

    def sent(self, bound_usd: float) -> int:
        """Write down a request about to go out; returns its number.

        Raises
        ------
        StudyFolderError
            The line could not be written: the request must not be sent.
        """
        n = self._take()
        self._write({"id": n, "bound_usd": bound_usd})
        self._bounds[n] = bound_usd
        return n

    def billed(self, n: int, cost_usd: float) -> None:
        """Request ``n`` was answered and billed ``cost_usd``."""
        bound = self._bounds.pop(n, None)
        self.spent_usd += cost_usd
        if bound:
            self.ratio = max(self.ratio, cost_usd / bound)
        self._after(lambda: self._write({"id": n, "cost_usd": cost_usd}))

    def released(self, n: int) -> None:
        """Request ``n`` was not billed (refused, or never delivered)."""
        self._bounds.pop(n, None)
        self._after(lambda: self._write({"id": n, "released": True}))

    @staticmethod
    def _after(write: Any) -> None:
        # An outcome that cannot be written leaves the request counted as unanswered (at its
        # bound): pessimistic, never cheaper. The next request's own line fails and stops sending.
        try:
            write()
        except StudyFolderError:
            pass

    def close(self) -> None:
        if self._fh is not None:
            try:
                self._fh.flush()
                os.fsync(self._fh.fileno())
                self._fh.close()
            except OSError:
                pass
            self._fh = None


def folder_money(folder: str | os.PathLike) -> tuple[float, float]:
    """``(spent, unanswered)`` USD of a study folder, recomputed from its journal and ledger
    (read only): spent is the larger of the two files' sums, so neither file alone can lower it."""
    journal = CallJournal(folder) if (Path(folder) / "calls.jsonl").exists() else None
    ledger = RequestLedger(folder, journal, read_only=True)
    spent = max(ledger.spent_usd, journal.spent_usd if journal is not None else 0.0)
    return spent, ledger.unanswered_usd
