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

The ledger also says what each session sent, so that a session killed without a word (kill -9,
a power cut) counts like one that ended normally ([`folder_totals`][jswim.llm.ledger.folder_totals]):

- ``{"id": 9, "session": 2, "t": T}``: session 2 began (its requests are the lines after it);
  the first one in a folder an older jswim began also carries ``"earlier"``, what
  ``metadata.json`` said of the sessions before it (their lines name no session);
- ``{"id": 40, "ended": 2, "t": T}``: session 2 ended (a killed one has no such line);
- a retry's sent line carries ``"retry": true``; the outcome line of a transient fault names
  its kind (``"fault": "429"``), and ``{"id": 7, "fault": "timeout"}`` notes the fault of a
  request that got no answer (no outcome: its bound stays counted);
- every line carries ``"t"``, the Unix time it was written: a killed session's LLM wall time
  is counted to its last line.
"""

from __future__ import annotations

import json
import math
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from collections.abc import Mapping

from jswim._io.jsonl import read_records, repair_tail
from jswim._io.permissions import opener
from jswim.errors import StudyFolderError
from jswim.llm.journal import JOURNAL, CallJournal, call_problem

LEDGER = "requests.jsonl"

#: A ledger line's kind: exactly one of these keys (a note names only a ``fault``).
_MONEY = ("bound_usd", "cost_usd", "released", "carried_usd")
_SESSION = ("session", "ended")


def _usd(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v >= 0


def _number(v: Any) -> bool:
    """A session number: a whole number >= 1 (not a bool)."""
    return isinstance(v, int) and not isinstance(v, bool) and v >= 1


def ledger_problem(rec: Mapping[str, Any]) -> str | None:
    """What makes ``rec`` no ledger line (``None`` when it is one)."""
    if not (isinstance(rec.get("id"), int) and not isinstance(rec.get("id"), bool)):
        return f"'id' is {rec.get('id')!r}, not a request number"
    t = rec.get("t")
    if t is not None and not (
        isinstance(t, (int, float)) and not isinstance(t, bool) and math.isfinite(t)
    ):
        return f"'t' is {t!r}, not a time"
    if "fault" in rec and not isinstance(rec["fault"], str):
        return f"'fault' is {rec['fault']!r}, not a fault's kind"
    if "retry" in rec and not isinstance(rec["retry"], bool):
        return f"'retry' is {rec['retry']!r}, not true or false"
    kinds = [k for k in _MONEY + _SESSION if k in rec]
    if not kinds and "fault" in rec:
        return None  # a note: the fault of a request that got no answer
    if len(kinds) != 1:
        return "not one of sent, billed, released, carried, a session begun or ended"
    if kinds[0] == "released":
        return None if rec["released"] is True else f"'released' is {rec['released']!r}"
    if kinds[0] in _SESSION:
        return (
            None
            if _number(rec[kinds[0]])
            else f"{kinds[0]!r} is {rec[kinds[0]]!r}, not a session number"
        )
    if not _usd(rec[kinds[0]]):
        return f"{kinds[0]!r} is {rec[kinds[0]]!r}, not a price"
    return None


@dataclass
class SessionCount:
    """What one session sent, as its ledger lines say.

    Attributes
    ----------
    number : int
        The session's number (1, 2, ...); 0 for the lines an older jswim wrote, which name no
        session.
    start, last : float or None
        Unix times of its first and last line (s).
    ended : bool
        It wrote its end line: it ended normally (a killed one did not).
    requests, retries : int
        Requests it sent, and of them retries.
    faults : dict
        Transient faults by kind (``"429"``, ``"5xx"``, ``"timeout"``, ...).
    earlier : dict or None
        What ``metadata.json`` said of the sessions before the ledger named them (the first
        session of an older jswim's folder).
    """

    number: int
    start: float | None = None
    last: float | None = None
    ended: bool = False
    requests: int = 0
    retries: int = 0
    faults: dict[str, int] = field(default_factory=dict)
    earlier: dict[str, Any] | None = None

    @property
    def wall_s(self) -> float:
        """From its first line to its end line, or to its last line when it was killed."""
        if self.start is None or self.last is None:
            return 0.0
        return max(0.0, self.last - self.start)


def _stamp(rec: Mapping[str, Any]) -> float | None:
    t = rec.get("t")
    return float(t) if t is not None else None


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
    read_only : bool
        Only read (``jswim show``): nothing is repaired or opened for writing.

    Attributes
    ----------
    spent_usd : float
        Billed, over every session: the outcome lines' costs plus what was carried over.
    unanswered_usd : float
        Bounds of the requests sent that have no outcome line.
    ratio : float
        The largest bill-to-reservation ratio seen (1 when every bill kept within its
        reservation): later reservations are scaled by it.
    sessions : list of SessionCount
        What each session sent (number 0 first where an older jswim wrote lines naming none).
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
        self.sessions: list[SessionCount] = []
        #: The session this object writes (``None`` before `begin_session`).
        self.session: int | None = None
        carried = False
        for _, rec in read_records(self.path, ledger_problem):
            n = rec["id"]
            self._next = max(self._next, n + 1)
            self._count(rec)
            if "bound_usd" in rec:
                self._bounds[n] = float(rec["bound_usd"])
            elif "carried_usd" in rec:
                carried = True
                self.spent_usd += float(rec["carried_usd"])
            elif n in self._bounds and ("cost_usd" in rec or "released" in rec):
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

    def _count(self, rec: Mapping[str, Any]) -> None:
        """Count one line (read back or just written) into the session it belongs to: the
        latest session line before it (number 0 before any)."""
        if "session" in rec:
            earlier = rec.get("earlier")
            self.sessions.append(
                SessionCount(
                    int(rec["session"]),
                    start=_stamp(rec),
                    last=_stamp(rec),
                    earlier=dict(earlier) if isinstance(earlier, dict) else None,
                )
            )
            return
        if not self.sessions:
            self.sessions.append(SessionCount(0))
        s = self.sessions[-1]
        t = _stamp(rec)
        if t is not None:
            s.start = t if s.start is None else s.start
            s.last = t if s.last is None else max(s.last, t)
        if "ended" in rec:
            s.ended = s.ended or rec["ended"] == s.number
        elif "bound_usd" in rec:
            s.requests += 1
            s.retries += rec.get("retry") is True
        if isinstance(rec.get("fault"), str):
            s.faults[rec["fault"]] = s.faults.get(rec["fault"], 0) + 1

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
        rec["t"] = round(time.time(), 3)
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
        self._count(rec)

    def begin_session(self, earlier: Mapping[str, Any] | None = None) -> int:
        """Write down that a session begins; returns its number (one past the last).

        Parameters
        ----------
        earlier : mapping, optional
            ``metadata.json``'s ``llm_totals`` of the sessions before, kept in the line only
            where no earlier line names a session (an older jswim's folder).

        Raises
        ------
        StudyFolderError
            The line could not be written: nothing may be sent.
        """
        n = max((s.number for s in self.sessions), default=0) + 1
        rec: dict[str, Any] = {"id": self._take(), "session": n}
        kept = _earlier(earlier) if n == 1 else {}
        if kept:
            rec["earlier"] = kept
        self._write(rec)
        self.session = n
        return n

    def end_session(self) -> None:
        """Write down that this session ended normally (a kill writes nothing)."""
        if self.session is not None:
            self._after(lambda: self._write({"id": self._take(), "ended": self.session}))

    def sent(self, bound_usd: float, retry: bool = False) -> int:
        """Write down a request about to go out (``retry``: it is a retry); returns its number.

        Raises
        ------
        StudyFolderError
            The line could not be written: the request must not be sent.
        """
        n = self._take()
        rec: dict[str, Any] = {"id": n, "bound_usd": bound_usd}
        if retry:
            rec["retry"] = True
        self._write(rec)
        self._bounds[n] = bound_usd
        return n

    def billed(self, n: int, cost_usd: float, fault: str | None = None) -> None:
        """Request ``n`` was answered and billed ``cost_usd`` (``fault``: answered with a body
        that is no chat completion, ``"bad body"``)."""
        bound = self._bounds.pop(n, None)
        self.spent_usd += cost_usd
        if bound:
            self.ratio = max(self.ratio, cost_usd / bound)
        self._after(lambda: self._write(_with_fault({"id": n, "cost_usd": cost_usd}, fault)))

    def released(self, n: int, fault: str | None = None) -> None:
        """Request ``n`` was not billed (refused, or never delivered; ``fault``: the transient
        fault's kind, when one was the cause)."""
        self._bounds.pop(n, None)
        self._after(lambda: self._write(_with_fault({"id": n, "released": True}, fault)))

    def no_answer(self, n: int, fault: str) -> None:
        """Note the fault of request ``n``, which got no answer (its bound stays counted)."""
        self._after(lambda: self._write({"id": n, "fault": fault}))

    @staticmethod
    def _after(write: Any) -> None:
        # An outcome that cannot be written leaves the request counted as unanswered (at its
        # bound): pessimistic, never cheaper. The next request's own line fails and stops sending.
        try:
            write()
        except StudyFolderError:
            pass

    def totals(self, earlier: Mapping[str, Any] | None = None) -> dict[str, Any]:
        """The study's LLM totals over every session the ledger holds, killed ones included.

        Parameters
        ----------
        earlier : mapping, optional
            ``metadata.json``'s ``llm_totals``, read only for a folder whose ledger names no
            session yet (an older jswim's): what it says of the sessions before.

        Returns
        -------
        dict
            ``sessions``, ``not_ended`` (of them, those with no end line: killed, or running
            now), ``wall_s`` (s), ``requests``, ``retries``, ``faults`` (by kind),
            ``unanswered`` and ``unanswered_usd`` (requests sent with no outcome line, and their
            bounds: the server may have billed them).
        """
        named = [s for s in self.sessions if s.number > 0]
        older = next((s for s in self.sessions if s.number == 0), SessionCount(0))
        before = next((s.earlier for s in named if s.earlier), None)
        if before is None and not named:
            before = dict(earlier) if isinstance(earlier, Mapping) else None
        before = before or {}

        def was(key: str) -> float:
            v = before.get(key)
            return float(v) if _usd(v) else 0.0

        faults: dict[str, int] = {}
        old = before.get("faults")
        for k, v in old.items() if isinstance(old, Mapping) else ():
            if _usd(v):
                faults[str(k)] = int(v)
        for s in named:
            for k, v in s.faults.items():
                faults[k] = faults.get(k, 0) + v
        return {
            "sessions": len(named) + max(int(was("sessions")), 1 if older.requests else 0),
            "not_ended": sum(not s.ended for s in named),
            "wall_s": sum(s.wall_s for s in named) + was("wall_s"),
            "requests": sum(s.requests for s in named) + max(older.requests, int(was("requests"))),
            "retries": sum(s.retries for s in named) + int(was("retries")),
            "faults": dict(sorted(faults.items())),
            "unanswered": self.unanswered,
            "unanswered_usd": self.unanswered_usd,
        }

    def close(self) -> None:
        if self._fh is not None:
            try:
                self._fh.flush()
                os.fsync(self._fh.fileno())
                self._fh.close()
            except OSError:
                pass
            self._fh = None


def _earlier(totals: Mapping[str, Any] | None) -> dict[str, Any]:
    """Of ``metadata.json``'s ``llm_totals``, what the ledger keeps of an older jswim's sessions:
    their count, time, requests, retries and faults (numbers >= 0 only: the totals are a report)."""
    if not isinstance(totals, Mapping) or not totals.get("sessions"):
        return {}
    out: dict[str, Any] = {
        k: totals[k] for k in ("sessions", "wall_s", "requests", "retries") if _usd(totals.get(k))
    }
    faults = totals.get("faults")
    if isinstance(faults, Mapping):
        out["faults"] = {str(k): v for k, v in faults.items() if _usd(v)}
    return out


def _with_fault(rec: dict[str, Any], fault: str | None) -> dict[str, Any]:
    if fault is not None:
        rec["fault"] = fault
    return rec


def folder_money(folder: str | os.PathLike) -> tuple[float, float]:
    """``(spent, unanswered)`` USD of a study folder, recomputed from its journal and ledger
    (read only): spent is the larger of the two files' sums, so neither file alone can lower it."""
    journal = CallJournal(folder) if (Path(folder) / "calls.jsonl").exists() else None
    ledger = RequestLedger(folder, journal, read_only=True)
    spent = max(ledger.spent_usd, journal.spent_usd if journal is not None else 0.0)
    return spent, ledger.unanswered_usd


def answered_calls(folder: str | os.PathLike) -> int:
    """Answered calls in the folder's journal (``calls.jsonl``), every session's (read only:
    nothing is repaired)."""
    path = Path(folder) / JOURNAL
    if not path.is_file():  # none yet; a FIFO in its place would block the read
        return 0
    return sum(1 for _ in read_records(path, call_problem))


def folder_totals(
    folder: str | os.PathLike, earlier: Mapping[str, Any] | None = None
) -> dict[str, Any] | None:
    """A study folder's LLM totals, recomputed from its ledger and journal (read only): every
    session counted, killed ones included (`RequestLedger.totals`), with ``answered_calls``
    and ``calls_per_s`` (answered calls over the LLM wall time). ``None`` for a folder with no
    ledger (no LLM request was ever written down). ``earlier``: ``metadata.json``'s
    ``llm_totals``, for a folder an older jswim began."""
    if not (Path(folder) / LEDGER).is_file():
        return None
    t = RequestLedger(folder, read_only=True).totals(earlier)
    t["answered_calls"] = answered_calls(folder)
    t["calls_per_s"] = t["answered_calls"] / t["wall_s"] if t["wall_s"] > 0 else 0.0
    return t
