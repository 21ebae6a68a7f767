"""Reading what a study folder holds: its runs, its metadata, transcripts and the call journal.
Damaged records are skipped with one warning naming the file and line."""

from __future__ import annotations

import json
import math
import os
from pathlib import Path
from typing import Any
from collections.abc import Iterable, Mapping

from jswim._io.jsonl import SkippedRecord, read_records
from jswim.errors import ResultFolderError
from jswim.results.optimum import with_cell_optimum
from jswim.results.row import RunRow, as_run_rows
from jswim.results.migrate import migrate_metadata, migrate_row
from jswim.results.schema import META, RUNS, is_failed, run_problem


def read_runs(folder: str | os.PathLike) -> list[dict[str, Any]]:
    """Runs of a study folder (see [`StudyStore`][jswim.results.store.StudyStore]), one record per ``run_id`` in first-seen
    order, in today's form (an earlier version's record migrated as it is read:
    [`migrate_row`][jswim.results.migrate.migrate_row]).

    The first record of a run wins, except that a failed run ([`is_failed`][jswim.results.schema.is_failed]) is replaced by
    any later record of it: the one from the resume that ran it again. A line that is no run
    record (not UTF-8, not JSON, a field of the wrong type: [`run_problem`][jswim.results.schema.run_problem]) is skipped with
    a warning naming the file and the line (`jswim._io.jsonl.read_records`); that run counts as
    not done, as a torn line's does. A navigation row's optimum columns are its cell's
    ``optimal`` row's ([`with_cell_optimum`][jswim.results.optimum.with_cell_optimum]).
    """
    return with_cell_optimum(_records(folder))


def _records(folder: str | os.PathLike) -> list[dict[str, Any]]:
    """`read_runs` before the cell's optimum is read into its rows (`read_run_rows` does that
    once, on the typed rows)."""
    path = Path(folder) / RUNS
    _regular(path)
    by_id: dict[str, dict[str, Any]] = {}
    for _, row in read_records(path, run_problem, migrate_row):
        rid = row.get("run_id")
        if rid not in by_id or is_failed(by_id[rid]):
            by_id[rid] = row
    return list(by_id.values())


def _regular(path: Path) -> None:
    """Refuse a FIFO or a device where a record file belongs (reading it would hang or never end).

    Raises
    ------
    ResultFolderError
        ``path`` exists and is neither a regular file nor a folder.
    """
    if path.exists() and not (path.is_file() or path.is_dir()):
        raise ResultFolderError(
            f"{path} is not a regular file (a FIFO or a device); move it away to read the folder"
        )


def read_run_rows(folder: str | os.PathLike) -> list[RunRow]:
    """The runs of a study folder as typed rows ([`RunRow`][jswim.results.row.RunRow]), for the package's readers.

    Parameters
    ----------
    folder : str or os.PathLike
        A study folder (see [`StudyStore`][jswim.results.store.StudyStore]); a missing ``runs.jsonl`` reads as no runs.

    Returns
    -------
    list of RunRow
        [`read_runs`][jswim.results.read.read_runs]'s records (same rule: first record wins, a failed one is replaced, a
        damaged line skipped with a warning), each through [`RunRow.from_dict`][jswim.results.row.RunRow.from_dict].
    """
    return as_run_rows(_records(folder))  # as_run_rows reads each cell's optimum, once


#: Fields of ``metadata.json`` by the JSON type readers expect of them.
_META_TYPES: dict[str, tuple[type, ...]] = {
    "study": (str,),
    "status": (str,),
    "identity": (dict,),
    "summary": (dict,),
    "llm_totals": (dict,),
    "llm_server": (dict,),
    "grid": (dict,),
    "prompt_template": (dict,),
    "n_planned": (int,),
    "n_runs": (int,),
    "horizon": (int,),
    "group_order": (list,),
    "llm_variants": (list,),
    "roc_levels": (list,),
    "fidelity_deviations": (list,),
    "server": (str, type(None)),
    "prices_as_of": (str,),
    "error": (str, type(None)),
    "success_criterion": (str,),
    "model_range_notes": (list,),
}
_JSON_NAMES = {
    dict: "an object",
    list: "a list",
    str: "text",
    int: "a whole number",
    type(None): "null",
}


def _numbers(v: Any) -> bool:
    return isinstance(v, list) and all(_real(e) for e in v)


def _texts(v: Any) -> bool:
    return isinstance(v, list) and all(isinstance(e, str) for e in v)


def _real(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def _whole(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


_NUMBERS = (_numbers, "a list of numbers")
_TEXTS = (_texts, "a list of texts")
_OBJECT = (lambda v: isinstance(v, dict), "an object")
#: Fields inside the objects of ``metadata.json`` that readers compute with (dotted paths; null
#: is always accepted, as a field left unset): what each must be. The top-level field itself is
#: checked by `_META_TYPES` first.
_META_NESTED: dict[str, tuple[Any, str]] = {
    **{
        f"grid.{k}": _NUMBERS
        for k in (
            "flows",
            "bearings",
            "distances",
            "zetas",
            "heights",
            "n_hts",
            "roc_levels_grid",
            "separations",
            "tilts",
            "phases",
            "school_sizes",
            "temperatures",
        )
    },
    "grid.formations": _TEXTS,
    "grid.prompt_files": _TEXTS,
    **{f"grid.{k}": (_whole, "a whole number") for k in ("runs", "q_runs", "samples")},
    "identity.options": _OBJECT,
    "identity.backend": _OBJECT,
    "identity.options.flow": (lambda v: isinstance(v, str), "text"),
    "identity.options.agents": _TEXTS,
    **{
        f"identity.backend.{k}": (lambda v: isinstance(v, str), "text")
        for k in ("kind", "model", "base_url", "constrain")
    },
    "identity.backend.temperature": (_real, "a number"),
    "summary.reasoning": _OBJECT,
    "summary.llm_speed": _OBJECT,
    "summary.navigation": (lambda v: isinstance(v, list), "a list"),
    **{
        f"summary.llm_speed.{k}": (_real, "a number")
        for k in ("wall_s", "calls_per_s", "billed_calls_per_s", "cost_usd", "study_cost_usd")
    },
    "llm_server.unpriced": (lambda v: isinstance(v, str), "text"),
}


def _drop_nested(meta: dict[str, Any], path: str | os.PathLike) -> dict[str, Any]:
    """``meta`` without the nested fields of `_META_NESTED` that have the wrong type, each
    dropped with one `SkippedRecord` warning naming the file and the field's dotted path (the
    objects above it copied, never changed in place)."""
    import warnings

    for dotted, (ok, want) in _META_NESTED.items():
        *parents, leaf = dotted.split(".")
        node: Any = meta
        for k in parents:
            node = node.get(k) if isinstance(node, dict) else None
        if not isinstance(node, dict) or node.get(leaf) is None or ok(node[leaf]):
            continue
        warnings.warn(
            SkippedRecord(
                f"{path}: {dotted!r} is {_shown(node[leaf])}, not {want}; that field is ignored"
            ),
            stacklevel=4,
        )
        meta = dict(meta)
        holder = meta
        for k in parents:  # copy the path down to the field, so the caller's dicts stay as read
            holder[k] = dict(holder[k])
            holder = holder[k]
        holder.pop(leaf)
    return meta


def _shown(v: Any) -> str:
    text = repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


def clean_metadata(meta: dict[str, Any], path: str | os.PathLike) -> dict[str, Any]:
    """``meta`` without the fields of the wrong type (a hand edit: ``"summary": 5``,
    ``"grid": {"flows": ["fast"]}``), each dropped with one `SkippedRecord` warning naming the
    file and the field (a nested one by its dotted path, ``'grid.flows'``); the fields left are
    what a reader may compute with. ``summary.groups`` must be a list of objects."""
    import warnings

    out = dict(meta)
    for k, types in _META_TYPES.items():
        v = out.get(k)
        if k in out and not (isinstance(v, types) and not isinstance(v, bool)):
            want = " or ".join(_JSON_NAMES[t] for t in types)
            warnings.warn(
                SkippedRecord(f"{path}: {k!r} is {_shown(v)}, not {want}; that field is ignored"),
                stacklevel=3,
            )
            out.pop(k)
    out = _drop_nested(out, path)
    totals = out.get("llm_totals")
    if totals is not None:
        out["llm_totals"] = _clean_totals(totals, path)
    groups = (out.get("summary") or {}).get("groups")
    if groups is not None and not (
        isinstance(groups, list) and all(isinstance(g, dict) for g in groups)
    ):
        warnings.warn(
            SkippedRecord(
                f"{path}: 'summary.groups' is not a list of objects; the summary is ignored"
            ),
            stacklevel=3,
        )
        out.pop("summary")
    return out


def _count_like(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v >= 0


def _clean_totals(totals: dict[str, Any], path: str | os.PathLike) -> dict[str, Any]:
    """``llm_totals`` with only numbers >= 0 (and ``faults``, a table of them): the totals are a
    report (the money ledger is ``requests.jsonl``); a value edited into another type is dropped
    with one warning, and readers see it as missing."""
    import warnings

    out: dict[str, Any] = {}
    dropped = []
    for k, v in totals.items():
        if k == "faults":
            if isinstance(v, dict) and all(_count_like(n) for n in v.values()):
                out[k] = v
            else:
                dropped.append(k)
        elif _count_like(v):
            out[k] = v
        else:
            dropped.append(k)
    if dropped:
        warnings.warn(
            SkippedRecord(
                f"{path}: llm_totals {', '.join(map(repr, dropped))} not numbers >= 0; ignored"
            ),
            stacklevel=4,
        )
    return out


def read_metadata(folder: str | os.PathLike, as_written: bool = False) -> dict[str, Any]:
    """The study's ``metadata.json`` in today's form ([`migrate_metadata`][jswim.results.migrate.migrate_metadata]); [`ResultFolderError`][jswim.errors.ResultFolderError] if
    the folder is not a study. A field of the wrong type is dropped with a warning
    ([`clean_metadata`][jswim.results.read.clean_metadata]); ``as_written``: the object as the
    file holds it, neither checked nor migrated (what ``jswim migrate`` rewrites)."""
    path = Path(folder) / META
    if not path.exists():
        raise ResultFolderError(f"{folder} is not a jswim study folder (no {META})")
    _regular(path)
    try:
        meta = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:  # ValueError: bad JSON or bad UTF-8
        raise ResultFolderError(f"{path} is unreadable ({exc})") from None
    if not isinstance(meta, dict):
        kind = {list: "list", str: "text", bool: "true or false", type(None): "null"}.get(
            type(meta), "number"
        )
        raise ResultFolderError(f"{path} is not a study's metadata (a JSON {kind}, not an object)")
    return meta if as_written else migrate_metadata(clean_metadata(meta, path))


def unfinished_note(status: str | None, done: int, planned: int | None) -> str | None:
    """The red line of a figure whose study has not finished (``None`` when it has)."""
    if status == "complete" and (planned is None or done >= planned):
        return None
    of = f" of {planned}" if planned else ""
    return f"UNFINISHED STUDY: {done}{of} runs done ({status or 'status unknown'})"


# -- transcripts and the call journal ------------------------------------------------------------

TRANSCRIPT_COLUMNS = (
    "step",
    "prompt",
    "reply",
    "action",
    "failed",
    "attempts",
    "http_retries",
    "prompt_tokens",
    "completion_tokens",
    "cost_usd",
    "latency_s",
    "cache_hit",
    "x_before",
    "x_after",
    "progress",
    "stuck",
    "cleared",
    "n_clears",
    "dofs_after",
    "replies",
)
CALL_COLUMNS = (
    "run",
    "n",
    "key",
    "text",
    "raw",
    "prompt_tokens",
    "completion_tokens",
    "cached_tokens",
    "cost_usd",
    "cache_hit",
    "shared",
    "constraint",
    "finish_reason",
)


def _jsonl(path: Path) -> list[dict[str, Any]]:
    """The JSON objects of a JSON-lines file; torn or foreign lines are skipped, a missing file is empty."""
    _regular(path)
    return [rec for _, rec in read_records(path)]


def read_transcript(folder: str | os.PathLike, run_id: str) -> list[dict[str, Any]]:
    """The records of ``transcripts/RUN.jsonl`` (``meta``, one ``step`` per step, ``end``); ``[]`` if none.

    A run id that is not a plain file name (a path, ``..``) reads nothing."""
    name = f"{run_id}.jsonl"
    if Path(name).name != name or run_id in ("", ".", ".."):
        return []
    return _jsonl(Path(folder) / "transcripts" / name)


def transcript_steps(records: Iterable[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """One flat dict per ``step`` record of a transcript (see [`Study.transcript`][jswim.results.load.Study.transcript] for the keys)."""
    out = []
    for r in records:
        if r.get("type") != "step":
            continue
        att = [a for a in (r.get("attempts") or []) if isinstance(a, dict)]

        def total(key: str) -> float:
            return sum(float(a.get(key) or 0) for a in att)

        out.append(
            {
                "step": r.get("step"),
                "prompt": r.get("prompt"),
                "reply": att[-1].get("text") if att else None,
                "action": r.get("action"),
                "failed": bool(r.get("failed")),
                "attempts": len(att),
                "http_retries": int(total("retries")),
                "prompt_tokens": int(total("prompt_tokens")),
                "completion_tokens": int(total("completion_tokens")),
                "cost_usd": total("cost_usd"),
                "latency_s": total("latency_s"),
                "cache_hit": any(bool(a.get("cache_hit")) for a in att),
                "x_before": r.get("x_before"),
                "x_after": r.get("x_after"),
                "progress": r.get("progress"),
                "stuck": r.get("stuck"),
                "cleared": bool(r.get("cleared")),
                "n_clears": r.get("n_clears"),
                "dofs_after": r.get("dofs_after"),
                "replies": att,
            }
        )
    return out


def read_calls(folder: str | os.PathLike) -> list[dict[str, Any]]:
    """The answered calls of ``calls.jsonl``, flat (``usage`` split into its three token counts)."""
    out = []
    from jswim.llm.journal import (
        call_problem,
    )  # lazy: the journal's rule, without httpx for other readers

    _regular(Path(folder) / "calls.jsonl")
    for _, c in read_records(Path(folder) / "calls.jsonl", call_problem):
        usage = c.get("usage") if isinstance(c.get("usage"), list) else []
        usage = (list(usage) + [None, None, None])[:3]
        row = {k: c.get(k) for k in CALL_COLUMNS}
        row.update(prompt_tokens=usage[0], completion_tokens=usage[1], cached_tokens=usage[2])
        out.append(row)
    return out
