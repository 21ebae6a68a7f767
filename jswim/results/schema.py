"""What a run record holds: the fields readers compute with and their kinds, the statuses of
failed runs, the fields renamed since folders were first written."""

from __future__ import annotations

from typing import Any
from collections.abc import Mapping

#: The study folder's durable record and its metadata.
RUNS = "runs.jsonl"
META = "metadata.json"

#: Statuses of runs that did not finish (the server failed them): recorded with their error, not
#: done. A resume runs them again, and a later record of the same run replaces them.
FAILED_STATUSES = frozenset({"llm_error", "aborted"})


def is_failed(row: Mapping[str, Any]) -> bool:
    """Whether a run record is a failed run (`FAILED_STATUSES`), not a finished one."""
    return row.get("status") in FAILED_STATUSES


#: Fields renamed since folders were first written: old name -> new name. Folders keep what they
#: were written with; readers translate ([`upgrade_names`][jswim.results.schema.upgrade_names]), so an old folder still resumes,
#: summarises and plots.
RENAMED = {"allowed": "action_set"}


def upgrade_names(obj: Any) -> Any:
    """``obj`` (rows, metadata, an identity; nested dicts and lists) with old field names renamed
    to new ones (`RENAMED`)."""
    if isinstance(obj, dict):
        return {RENAMED.get(k, k): upgrade_names(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [upgrade_names(v) for v in obj]
    return obj


def legacy_names(obj: Any) -> Any:
    """The inverse of [`upgrade_names`][jswim.results.schema.upgrade_names] (for hashes that must stay what they were)."""
    back = {new: old for old, new in RENAMED.items()}
    if isinstance(obj, dict):
        return {back.get(k, k): legacy_names(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [legacy_names(v) for v in obj]
    return obj


#: The fields of a run record that readers compute with, by kind: a record where one of them has
#: another type (a hand edit) is skipped with a warning ([`run_problem`][jswim.results.schema.run_problem]).
_RUN_TEXT = ("run_id", "agent")  # run_id required
_RUN_NUMBERS = (
    "final_x",
    "signed_final_x",
    "zeta",
    "cost_usd",
    "temperature",
    "direction",
    "steps",
    "calls",
    "billed_calls",
    "cache_hits",
    "prompt_tokens",
    "completion_tokens",
    "cached_tokens",
    "reasoning_tokens",
    "parse_retries",
    "http_retries",
    "failed_steps",
    "n_clears",
    "tokens_seen",
    "seed",
    "period",
    "n_ht",
    "steps_to_learn",
    "truncated",
    "cut_thinking",
    "roc_levels",
    "max_tokens",
    "n_swimmers",
    "start_height",
    "separation",
    "mean_height",
    "speed",
    "per_cycle",
)
_RUN_FLAGS = ("success", "learned")
_RUN_STRINGS = (
    "swimmer",
    "group",
    "status",
    "variant",
    "action_set",
    "error",
    "constraint",
    "scene",
    "medium",
    "fate",
)
_RUN_SERIES = ("x", "y", "orientation", "progress")
#: Per step, per swimmer: numbers (``xs``, ``heights``, ``tilts``) or flags (``contact``,
#: ``stuck``; also one flag per step).
_RUN_TRACKS = ("xs", "heights", "tilts")
_RUN_STEP_FLAGS = ("contact", "stuck")


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def run_problem(row: Mapping[str, Any]) -> str | None:
    """What makes ``row`` no run record readers can use (a field of the wrong type), or ``None``."""
    row = upgrade_names(dict(row))
    for k in _RUN_TEXT:
        if k == "run_id" and "run_id" not in row:
            return "no 'run_id'"
        if k in row and (not isinstance(row[k], str) or not row[k]):
            return f"{k!r} is {row[k]!r}, not a name"
    for k in _RUN_NUMBERS:
        if row.get(k) is not None and not _number(row[k]):
            return f"{k!r} is {row[k]!r}, not a number"
    for k in _RUN_FLAGS:
        if row.get(k) is not None and not isinstance(row[k], bool):
            return f"{k!r} is {row[k]!r}, not true or false"
    for k in _RUN_STRINGS:
        if row.get(k) is not None and not isinstance(row[k], str):
            return f"{k!r} is {row[k]!r}, not text"
    for k in _RUN_SERIES:
        v = row.get(k)
        if v is not None and not (isinstance(v, list) and all(e is None or _number(e) for e in v)):
            return f"{k!r} is not a list of numbers"
    acts = row.get("actions")
    if acts is not None and not isinstance(acts, list):
        return "'actions' is not a list"
    steps = len(row["x"]) if isinstance(row.get("x"), list) else None
    for k in ("y", "orientation", "progress"):
        v = row.get(k)
        if v is not None and steps is not None and len(v) != steps:
            return f"{k!r} has {len(v)} steps, 'x' {steps}"
    for k in (*_RUN_TRACKS, *_RUN_STEP_FLAGS):
        v = row.get(k)
        if v is None:
            continue
        flags = k in _RUN_STEP_FLAGS
        one = (
            (lambda e: e is None or isinstance(e, bool))
            if flags
            else (lambda e: e is None or _number(e))
        )
        if not isinstance(v, list) or (steps is not None and len(v) != steps):
            return f"{k!r} is not a list of one entry per step"
        if flags and all(one(e) for e in v):
            continue
        if not all(isinstance(e, list) and all(one(x) for x in e) for e in v):
            return f"{k!r} is not a list per step of {'flags' if flags else 'numbers'}"
        if len({len(e) for e in v}) > 1:
            return f"{k!r} has steps with different numbers of swimmers"
    return None


SCALAR_TYPES = (str, int, float, bool, type(None))
