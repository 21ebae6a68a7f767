"""The bench's leaderboard: one row per model (or baseline) and setting, from the study folders.

Read only from the folders, so it is the same after a resume and can be redrawn at any time.
Rows are written to ``leaderboard.csv`` / ``leaderboard.json`` (columns `FIELDS`, ``null``
where a value does not apply); each column is described in docs/bench.md (*The leaderboard*).
"""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any
from collections.abc import Mapping, Sequence

from jswim.console import REFERENCE_UNPRICED, Column, cost_text, plain_table
from jswim.results.orders import MIN_BOOTSTRAP_N, MIN_QUARTILE_N
from jswim.results import atomic_write, dumps, read_runs
from jswim.studies.report import summarize

FIELDS = (
    "row",
    "kind",
    "part",
    "swimmer",
    "direction",
    "group",
    "n",
    "samples",
    "success",
    "success_lo",
    "success_hi",
    "learned",
    "steps_median",
    "steps_q25",
    "steps_q75",
    "mean_x",
    "mean_x_lo",
    "mean_x_hi",
    "failed_steps",
    "tokens_per_step",
    "suite_cost_usd",
    "priced",
    "status",
    "unpriced",
)

_LABELS = {
    "qlearning": "Q-learning",
    "random": "random",
    "ppo": "PPO",
    "controller": "steering controller",
    "zermelo": "Zermelo (optimal path)",
}


def folder_rows(
    folder: Path,
    label: str,
    kind: str,
    part: str,
    cost: float | None,
    priced: bool | None,
    status: str,
) -> list[dict[str, Any]]:
    """Leaderboard rows of one study folder (nothing when it holds no finished runs)."""
    if not (folder / "metadata.json").exists():
        return []
    out = []
    for s in summarize(read_runs(folder)):
        agent = s["agent"]
        if kind == "baseline" and agent == "llm":
            continue
        out.append(
            {
                "row": _LABELS.get(agent, label) if kind == "baseline" else label,
                "kind": kind,
                "part": part,
                "swimmer": s["swimmer"],
                "direction": s["direction"],
                "group": s.get("group") or "",
                "n": s["n"],
                "samples": s.get("samples") or 1,
                "success": s["success_rate"],
                "success_lo": s["success_lo"],
                "success_hi": s["success_hi"],
                "learned": s["learned"],
                "steps_median": s["steps_to_learn_median"],
                "steps_q25": s["steps_to_learn_q25"],
                "steps_q75": s["steps_to_learn_q75"],
                "mean_x": s["mean_x"],
                "mean_x_lo": s["mean_x_lo"],
                "mean_x_hi": s["mean_x_hi"],
                "failed_steps": s["failed_steps"] if agent == "llm" else None,
                "tokens_per_step": s.get("tokens_per_step") if agent == "llm" else None,
                "suite_cost_usd": cost if kind != "baseline" else None,
                "priced": priced if kind != "baseline" else None,
                "status": status,
            }
        )
    return out


def _num(v: Any, spec: str) -> str:
    return "-" if v is None else format(v, spec)


#: The order of a row's kind within its setting: models, then the reference rule, then baselines.
_KIND_ORDER = {"llm": 0, "reference": 1, "baseline": 2}


def row_key(r: Mapping[str, Any]) -> tuple:
    """Sort key of leaderboard rows, for the table and the page: by part, Purcell's swimmer
    first, +x before -x, group, then models, the reference rule and baselines, each by name."""
    return (
        r["part"],
        r["swimmer"] != "purcell",
        r["swimmer"],
        -int(r["direction"]),
        str(r["group"]),
        _KIND_ORDER[r["kind"]],
        r["row"],
    )


def steps_text(r: Mapping[str, Any]) -> str:
    """Steps to learn of a leaderboard row: median [quartiles] (learners of runs), or ``-``."""
    if not r["learned"]:
        return f"- (0 of {r['n']})"
    if r["learned"] < MIN_QUARTILE_N:  # no IQR from fewer than 4 values
        return f"{r['steps_median']:g} ({r['learned']} of {r['n']})"
    return f"{r['steps_median']:g} [{r['steps_q25']:g}-{r['steps_q75']:g}] ({r['learned']} of {r['n']})"


def _why_unpriced(r: Mapping[str, Any]) -> str | None:
    if r["kind"] == "reference":
        return REFERENCE_UNPRICED
    if r["kind"] == "llm" and r.get("priced") is False:
        return r.get("unpriced") or "no price applies to the model"
    return None


def cells(r: Mapping[str, Any], short: bool = False) -> dict[str, str]:
    """A row's cells by column, in the one wording of the bench page and the terminal table
    (each titles and lays out the columns its own way; a missing value is ``-``).

    Parameters
    ----------
    r : mapping
        A leaderboard row (`FIELDS`); a key the terminal table reads that it lacks raises
        (`valid_rows` drops such rows).
    short : bool
        The terminal table's cells: X/a end without its interval, and ``not priced ($0)`` for
        a cost not priced (the reasons go under the table, `unpriced_notes`).

    Returns
    -------
    dict
        ``part``, ``swimmer``, ``dir``, ``group``, ``row``, ``samples``, ``n``, ``success``,
        ``steps``, ``mean_x``, ``fail``, ``tok/step`` and ``cost``, as text.
    """
    name = r["row"] + (" (rule, not an LLM)" if r["kind"] == "reference" else "")
    if r["kind"] != "baseline" and r["status"] not in (None, "complete"):
        name += f" [{r['status']}]"
    mean_x = f"{r['mean_x']:+.3f}"
    if not short and (r.get("n") or 0) < MIN_BOOTSTRAP_N:  # no interval from 1 or 2 runs
        mean_x += f" [n<{MIN_BOOTSTRAP_N}]"
    elif not short and r.get("mean_x_lo") is not None and r.get("mean_x_hi") is not None:
        mean_x += f" [{r['mean_x_lo']:+.3f}, {r['mean_x_hi']:+.3f}]"
    if r["kind"] == "baseline":
        cost = "-"
    elif (why := _why_unpriced(r)) is None:
        cost = cost_text(r["suite_cost_usd"])
    else:
        cost = "not priced ($0)" if short else cost_text(None, why)
    return {
        "part": r["part"],
        "swimmer": r["swimmer"],
        "dir": "+x" if r["direction"] > 0 else "-x",
        "group": r["group"] or "",
        "row": name,
        "samples": str(r.get("samples") or 1),
        "n": str(r["n"]),
        "success": f"{r['success']:.2f} [{r['success_lo']:.2f}, {r['success_hi']:.2f}]",
        "steps": steps_text(r),
        "mean_x": mean_x,
        "fail": _num(r["failed_steps"], "d"),
        "tok/step": _num(r["tokens_per_step"], ".0f"),
        "cost": cost,
    }


def unpriced_notes(rows: Sequence[Mapping[str, Any]]) -> list[str]:
    """One line per row name whose calls are not priced, saying why (under the terminal table)."""
    seen: dict[str, str] = {}
    for r in rows:
        why = _why_unpriced(r)
        if why is not None:
            seen.setdefault(str(r["row"]), why)
    return [f"{name}: {cost_text(None, why)}" for name, why in seen.items()]


def table_text(rows: Sequence[Mapping[str, Any]], width: int | None = None) -> str:
    """The leaderboard as a plain table, grouped by setting, models then reference then baselines."""
    groups = any(r["group"] for r in rows)
    samples = any((r.get("samples") or 1) > 1 for r in rows)
    cols = [Column("part", False), Column("swimmer", False), Column("dir", False)]
    cols += [Column("group", False)] if groups else []
    cols += [Column("row", False)] + [Column("samples")] * samples
    cols += [
        Column(h)
        for h in (
            "n",
            "success p [95% CI]",
            "steps to learn, median [IQR] (k of n learned)",
            "X/a end",
            "fail",
            "tok/step",
            "suite $",
        )
    ]
    keys = ["part", "swimmer", "dir"] + ["group"] * groups + ["row"] + ["samples"] * samples
    keys += ["n", "success", "steps", "mean_x", "fail", "tok/step", "cost"]
    lines = [
        [c[k] for k in keys] for c in (cells(r, short=True) for r in sorted(rows, key=row_key))
    ]
    return plain_table(cols, lines, width=width)


def valid_rows(rows: Any) -> list[Mapping[str, Any]]:
    """The rows of a stored ``leaderboard.json`` that the table can show (a list of objects, each
    with its fields of the right types); a row edited or damaged into another shape is left out."""
    if not isinstance(rows, list):
        return []
    out = []
    for r in rows:
        if not isinstance(r, Mapping):
            continue
        try:
            table_text([r])
            unpriced_notes([r])
        except (KeyError, TypeError, ValueError, AttributeError):
            continue
        out.append(r)
    return out


def missing_text(missing: Sequence[Mapping[str, Any]]) -> list[str]:
    """One line per study folder of the bench that gave the leaderboard no row, and why."""
    return [f"missing rows: {m['row']} {m['part']} ({m['why']})" for m in missing]


def write_files(
    folder: Path,
    rows: Sequence[Mapping[str, Any]],
    meta: Mapping[str, Any],
    missing: Sequence[Mapping[str, Any]] = (),
) -> list[Path]:
    """``leaderboard.csv``, ``leaderboard.json`` (rows, the bench's definition and the ``missing``
    rows: ``{"row", "kind", "part", "why"}`` per study folder that gave none). The figure is drawn
    by the pictures layer (`jswim.figures.leaderboard.figure`), which reads these rows."""
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=FIELDS)
    w.writeheader()
    w.writerows({k: ("" if r.get(k) is None else r.get(k)) for k in FIELDS} for r in rows)
    atomic_write(folder / "leaderboard.csv", buf.getvalue())
    atomic_write(
        folder / "leaderboard.json",
        dumps(
            {
                "schema": list(FIELDS),
                "bench": dict(meta),
                "rows": list(rows),
                "missing": list(missing),
            },
            indent=1,
        ),
    )
    return [folder / "leaderboard.csv", folder / "leaderboard.json"]
