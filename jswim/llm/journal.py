"""The answered calls of a study, kept so that a resume never pays for a call twice.

Every answered call is appended to ``calls.jsonl`` at once, before the answer is used; a resumed
run's calls are answered from it, matched by (run, index, request hash). The journal is also the
study's ledger: the sum of its ``cost_usd`` is what ``--max-cost`` is compared with. docs/paid-apis.md
(*Nothing is paid twice*) describes both.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
from pathlib import Path
from typing import Any
from collections.abc import Mapping, Sequence

from jswim._io.jsonl import read_records, repair_tail
from jswim.llm.result import ChatResult
from jswim.llm.usage import Usage
from jswim._io.permissions import opener

JOURNAL = "calls.jsonl"


def _count(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool) and v >= 0


def call_problem(rec: Mapping[str, Any]) -> str | None:
    """What makes ``rec`` no answered call that can be replayed or summed, or ``None``.

    A record is replayed as the answer it holds, so every field the replay uses must have its
    type: ``run`` and ``key`` text, ``n`` a count, ``text`` (and ``raw``) text, ``usage`` four
    counts, ``cost_usd`` a finite number >= 0.
    """
    if not isinstance(rec.get("run"), str):
        return f"'run' is {rec.get('run')!r}, not a run id"
    if not _count(rec.get("n")):
        return f"'n' is {rec.get('n')!r}, not a call index"
    if not isinstance(rec.get("key"), str):
        return f"'key' is {rec.get('key')!r}, not a request hash"
    for k in ("text", "raw"):
        if (k == "text" or k in rec) and not isinstance(rec.get(k), str):
            return f"{k!r} is {rec.get(k)!r}, not text"
    usage = rec.get("usage")
    if not (isinstance(usage, list) and 2 <= len(usage) <= 4 and all(_count(u) for u in usage)):
        return f"'usage' is {usage!r}, not token counts"
    cost = rec.get("cost_usd")
    if cost is not None and not (
        isinstance(cost, (int, float))
        and not isinstance(cost, bool)
        and math.isfinite(cost)
        and cost >= 0
    ):
        return f"'cost_usd' is {cost!r}, not a price"
    for k in ("cache_hit", "shared"):
        if rec.get(k) is not None and not isinstance(rec[k], bool):
            return f"{k!r} is {rec[k]!r}, not true or false"
    for k in ("constraint", "finish_reason"):
        if rec.get(k) is not None and not isinstance(rec[k], str):
            return f"{k!r} is {rec[k]!r}, not text"
    t = rec.get("temperature_sent")
    if t is not None and not (isinstance(t, (int, float)) and not isinstance(t, bool)):
        return f"'temperature_sent' is {t!r}, not a number"
    return None


def call_key(messages: Sequence[Mapping[str, Any]], **params: Any) -> str:
    """Hash of what defines a call's answer: the messages and the sampling parameters."""
    blob = json.dumps(
        [list(map(dict, messages)), params],
        sort_keys=True,
        separators=(",", ":"),
        ensure_ascii=False,
    )
    return hashlib.sha256(blob.encode()).hexdigest()[:32]


class CallJournal:
    """Append-only record of answered calls (``calls.jsonl``), read back for replay.

    Parameters
    ----------
    folder : path
        The study folder; the journal is ``folder / calls.jsonl``.

    Attributes
    ----------
    spent_usd : float
        What the recorded calls cost (all sessions).
    """

    def __init__(self, folder: str | os.PathLike) -> None:
        self.path = Path(folder) / JOURNAL
        self._calls: dict[str, dict[int, dict[str, Any]]] = {}
        self.spent_usd = 0.0
        self.n_calls = 0
        #: Bytes of a torn last line cut on open (0: none).
        self.repaired_bytes = repair_tail(self.path)  # the next record starts on a line of its own
        if self.path.exists():
            # A line that is no valid record (cut or edited by hand, a text of null) is skipped
            # with a warning: that one call is asked again, under its own index, and the calls
            # after it still replay (nothing shifts, nothing else is paid twice).
            for _, rec in read_records(self.path, call_problem):
                # The latest record of a (run, index) wins: a resume that took another path
                # recorded that call anew.
                self._calls.setdefault(str(rec.get("run")), {})[rec["n"]] = rec
                self.spent_usd += float(rec.get("cost_usd") or 0.0)
                self.n_calls += 1
        self._fh = None

    def replay(self, run_id: str, index: int, key: str) -> ChatResult | None:
        """The recorded answer of call ``index`` of ``run_id`` if it was this very request (same
        hash ``key``), else ``None``; a missing index is no reason to stop replaying later ones."""
        rec = self._calls.get(run_id, {}).get(index)
        if rec is None or rec.get("key") != key:
            return None
        return ChatResult(
            text=rec["text"],
            usage=Usage(*rec["usage"]),
            latency_s=0.0,
            cache_hit=bool(rec.get("cache_hit")),
            shared=bool(rec.get("shared")),
            retries=0,
            cost_usd=float(rec.get("cost_usd") or 0.0),
            constraint=rec.get("constraint", "none"),
            finish_reason=rec.get("finish_reason"),
            raw=rec.get("raw", ""),
            temperature_sent=rec.get("temperature_sent"),
        )

    def open_for_append(self) -> None:
        """Open the journal for appending now, before any request is sent: a journal that cannot
        be written (a read-only file, a dangling link) must stop a study before it pays a call
        it could not keep.

        Raises
        ------
        OSError
            The journal cannot be opened for appending.
        """
        if self._fh is None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._fh = open(
                self.path, "a", encoding="utf-8", opener=opener
            )  # owner only (jswim._io.permissions)

    def record(self, run_id: str, index: int, key: str, res: ChatResult) -> None:
        """Append one answered call (flushed, so it survives an interrupt)."""
        self.open_for_append()
        u = res.usage
        billed = not (res.cache_hit or res.shared)
        rec = {
            "run": run_id,
            "n": index,
            "key": key,
            "text": res.text,
            "raw": res.raw,
            "usage": [u.prompt_tokens, u.completion_tokens, u.cached_tokens, u.reasoning_tokens],
            "temperature_sent": res.temperature_sent,
            "cost_usd": res.cost_usd if billed else 0.0,
            "cache_hit": res.cache_hit,
            "shared": res.shared,
            "constraint": res.constraint,
            "finish_reason": res.finish_reason,
        }
        self._fh.write(json.dumps(rec, ensure_ascii=False) + "\n")
        self._fh.flush()
        self.spent_usd += rec["cost_usd"]
        self.n_calls += 1

    def forget(self, run_id: str) -> None:
        """Drop the replay entries of a run (kept on disk as a record of what was paid)."""
        self._calls.pop(run_id, None)

    def close(self) -> None:
        if self._fh is not None:
            self._fh.flush()
            os.fsync(self._fh.fileno())
            self._fh.close()
            self._fh = None
