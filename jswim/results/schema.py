"""What a run record holds: the fields readers compute with and their kinds, the statuses of
failed runs (today's form: an earlier version's record is translated first,
`jswim.results.migrate`)."""

from __future__ import annotations

import functools
import json
from typing import Any
from collections.abc import Mapping

from jswim.errors import JswimError
from jswim.results.migrate import RENAMED

#: The study folder's durable record and its metadata.
RUNS = "runs.jsonl"
META = "metadata.json"

#: Statuses of runs that did not finish (the server failed them): recorded with their error, not
#: done. A resume runs them again, and a later record of the same run replaces them.
FAILED_STATUSES = frozenset({"llm_error", "aborted"})


def is_failed(row: Mapping[str, Any]) -> bool:
    """Whether a run record is a failed run (`FAILED_STATUSES`), not a finished one."""
    return row.get("status") in FAILED_STATUSES


#: The fields of a run record that readers compute with, by kind: a record where one of them has
#: another type (a hand edit, a foreign writer) is skipped with a warning naming the field
#: ([`run_problem`][jswim.results.schema.run_problem]). Every reader reads rows through it, so a field
#: listed here is one no reader needs to check again.
_RUN_TEXT = ("run_id", "agent")  # names; run_id required (a missing agent reads as "": RunRow)
_RUN_NUMBERS = (
    "final_x",
    "signed_final_x",
    "zeta",
    "cost_usd",
    "temperature",
    "temperature_sent",
    "direction",
    "steps",
    "calls",
    "billed_calls",
    "replayed_calls",
    "cache_hits",
    "prompt_tokens",
    "completion_tokens",
    "cached_tokens",
    "reasoning_tokens",
    "parse_retries",
    "http_retries",
    "failed_steps",
    "below_x_min",
    "n_clears",
    "tokens_seen",
    "seed",
    "sample",
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
    "plane_height",
    "energy",
    "energy_per_distance",
    "efficiency",
    "steps_to_target",
    "path_length",
    "path_ratio",
    "flow_fraction",
    "zermelo_steps",
    "time_ratio",
    "zermelo_ratio",
)
_RUN_FLAGS = ("success", "learned", "reached", "reachable", "summary", "shuffle", "share_identical")
_RUN_STRINGS = (
    "swimmer",
    "status",
    "variant",
    "action_set",
    "init",
    "drop",
    "error",
    "constraint",
    "order",
    "pair_prompt",
    "scene",
    "medium",
    "fate",
    "target",
    "flow",
)
_RUN_SERIES = ("x", "y", "orientation", "progress")
# Rows are checked as the file holds them (the message names its field): a renamed field is
# checked under its earlier names too (`jswim.results.migrate.RENAMED`).
_RUN_NUMBERS, _RUN_FLAGS, _RUN_STRINGS = (
    (*kind, *(old for old, new in RENAMED.items() if new in kind))
    for kind in (_RUN_NUMBERS, _RUN_FLAGS, _RUN_STRINGS)
)
#: Per step, per swimmer: numbers (``xs``, ``heights``, ``tilts``) or flags (``contact``,
#: ``stuck``; also one flag per step).
_RUN_TRACKS = ("xs", "heights", "tilts")
_RUN_STEP_FLAGS = ("contact", "stuck")


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def run_problem(row: Mapping[str, Any]) -> str | None:
    """What makes ``row`` no run record readers can use, or ``None``: no ``run_id`` (or a ``flow``
    without its ``flow_fraction``), a field of the wrong type, series of different lengths, or a
    ``scene``, ``target`` or ``flow`` that is not the JSON text of one
    ([`json_field_problem`][jswim.results.schema.json_field_problem]). The answer names the field.
    ``row`` is checked as the file holds it, before
    [`migrate_row`][jswim.results.migrate.migrate_row]: a renamed field under either name."""
    if "run_id" not in row:
        return "no 'run_id'"
    for k in _RUN_TEXT:
        if k in row and (not isinstance(row[k], str) or not row[k]):
            return f"{k!r} is {_shown(row[k])}, not a name"
    for k in _RUN_NUMBERS:
        if row.get(k) is not None and not _number(row[k]):
            return f"{k!r} is {_shown(row[k])}, not a number"
    for k in _RUN_FLAGS:
        if row.get(k) is not None and not isinstance(row[k], bool):
            return f"{k!r} is {_shown(row[k])}, not true or false"
    for k in _RUN_STRINGS:
        if row.get(k) is not None and not isinstance(row[k], str):
            return f"{k!r} is {_shown(row[k])}, not text"
    if row.get("flow") and row.get("flow_fraction") is None:  # a flow's rows are by its speed
        return "'flow' without its 'flow_fraction'"
    if row.get("group") is not None and not isinstance(row["group"], str):
        return f"'group' is {_shown(row['group'])}, not text"
    for k in _RUN_SERIES:
        v = row.get(k)
        if v is not None and not (isinstance(v, list) and all(e is None or _number(e) for e in v)):
            return f"{k!r} is not a list of numbers"
    acts = row.get("actions")
    if acts is not None and not (
        isinstance(acts, list)
        and all(isinstance(a, list) and len(a) == 2 and all(map(_number, a)) for a in acts)
    ):
        return "'actions' is not a list of [dof, roc] pairs of numbers"
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
    for k in ("scene", "target", "flow"):
        if row.get(k):  # "" or absent: none (the bulk fluid, no target, still fluid)
            why = json_field_problem(k, row[k])
            if why:
                return why
    return None


def _shown(v: Any) -> str:
    """``v`` as a message shows it: its repr, cut to 40 characters."""
    text = repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


_SCENE_NUMBERS = ("height", "tilt", "separation", "swimmers")


@functools.lru_cache(maxsize=256)
def json_field_problem(field: str, text: str) -> str | None:
    """What makes ``text`` no value of a row's ``scene``, ``target`` or ``flow`` column, or ``None``.

    Each is the canonical JSON of an object: a target and a flow are read by the parsers that
    build them ([`jswim.env.targets.target_from_dict`][jswim.env.targets.target_from_dict],
    [`jswim.env.flows.flow_from_dict`][jswim.env.flows.flow_from_dict]; imported only for a row
    that has one, as they load JAX); a scene must hold the fields its pictures read as numbers
    (``height``, ``tilt``, ``separation``, ``swimmers``; ``obstacles`` as (x, z, radius)
    triples). Cached per text: a folder repeats a few values over many rows.
    """
    try:
        data = json.loads(text)
    except ValueError:
        return f"{field!r} is {_shown(text)}, not the JSON text of a {field}"
    if not isinstance(data, dict):
        return f"{field!r} is {_shown(text)}, not the JSON text of a {field} (an object)"
    if field == "scene":
        for k in _SCENE_NUMBERS:
            if data.get(k) is not None and not _number(data[k]):
                return f"'scene' field {k!r} is {_shown(data[k])}, not a number"
        obstacles = data.get("obstacles") or []
        if not (
            isinstance(obstacles, list)
            and all(isinstance(o, list) and len(o) == 3 and all(map(_number, o)) for o in obstacles)
        ):
            return "'scene' field 'obstacles' is not a list of (x, z, radius) triples"
        return None
    if field == "target":
        from jswim.env.targets import target_from_dict  # lazy: loads JAX

        parse: Any = target_from_dict
    else:
        from jswim.env.flows import flow_from_dict  # lazy: loads JAX

        parse = flow_from_dict
    try:
        parse(data)
    except JswimError as exc:  # the parser's one line names the field inside
        return f"{field!r} is no {field} this version reads ({exc})"
    except Exception as exc:  # foreign data: any failure to parse it is "unreadable"
        return f"{field!r} is no {field} this version reads ({type(exc).__name__})"
    return None


SCALAR_TYPES = (str, int, float, bool, type(None))
