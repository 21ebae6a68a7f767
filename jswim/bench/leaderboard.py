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
from jswim.overview import MIN_QUARTILE_N
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


def cost_cell(r: Mapping[str, Any], short: bool = False) -> str:
    """The row's cost in the one wording of `jswim.console.cost_text`, with why it is not
    priced; ``short`` (the terminal table): ``not priced ($0)``, the reasons under the table
    (`unpriced_notes`)."""
    if r["kind"] == "baseline":
        return "-"
    why = _why_unpriced(r)
    if why is not None:
        return "not priced ($0)" if short else cost_text(None, why)
    return cost_text(r["suite_cost_usd"])


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
    order = {"llm": 0, "reference": 1, "baseline": 2}
    key = lambda r: (
        r["part"],
        r["swimmer"] != "purcell",
        r["swimmer"],
        -int(r["direction"]),
        str(r["group"]),
        order[r["kind"]],
        r["row"],
    )
    cells = []
    for r in sorted(rows, key=key):
        cells.append(
            [r["part"], r["swimmer"], "+x" if r["direction"] > 0 else "-x"]
            + ([r["group"]] if groups else [])
            + [
                r["row"]
                + (" (rule, not an LLM)" if r["kind"] == "reference" else "")
                + (
                    ""
                    if r["status"] == "complete" or r["kind"] == "baseline"
                    else f" [{r['status']}]"
                )
            ]
            + [str(r.get("samples") or 1)] * samples
            + [
                str(r["n"]),
                f"{r['success']:.2f} [{r['success_lo']:.2f}, {r['success_hi']:.2f}]",
                steps_text(r),
                f"{r['mean_x']:+.3f}",
                _num(r["failed_steps"], "d"),
                _num(r["tokens_per_step"], ".0f"),
                cost_cell(r, short=True),
            ]
        )
    return plain_table(cols, cells, width=width)


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
    rows: ``{"row", "kind", "part", "why"}`` per study folder that gave none) and the figure."""
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
    paths = [folder / "leaderboard.csv", folder / "leaderboard.json"]
    if rows:
        paths += figure(folder, rows)
    return paths


def figure(folder: Path, rows: Sequence[Mapping[str, Any]]) -> list[Path]:
    """Success p and X/a end, each with its 95% interval, per row; a pair of panels per part,
    swimmer, direction and group (``leaderboard.png``/``.pdf``)."""
    from jswim.figures import plots  # lazy: matplotlib only when the leaderboard's figure is drawn

    return plots.save(figure_object(rows), folder, "leaderboard")


def figure_object(rows: Sequence[Mapping[str, Any]]) -> Any:
    """The leaderboard's matplotlib figure (see `figure`).

    With most p at 0 (short runs, weak models), success alone says nothing: X/a end, the mean
    displacement toward the target, is what separates the rows, so each setting has both panels.
    Every panel carries its own x tick labels (no shared axis leaves a panel unlabelled).
    """
    import matplotlib.pyplot as plt

    panels = sorted(
        {(r["part"], r["swimmer"], r["direction"], r["group"]) for r in rows},
        key=lambda k: (k[0], k[1] != "purcell", k[1], -k[2], str(k[3])),
    )
    labels = (
        sorted({r["row"] for r in rows if r["kind"] == "llm"})
        + sorted({r["row"] for r in rows if r["kind"] == "reference"})
        + ["Q-learning", "random"]
    )
    labels = [lab for lab in labels if any(r["row"] == lab for r in rows)]
    pairs = min(2, len(panels))
    nrow = -(-len(panels) // pairs)
    fig, axes = plt.subplots(
        nrow, 2 * pairs, figsize=(7.0, 0.5 + (0.3 * len(labels) + 0.9) * nrow), squeeze=False
    )
    colors = {"llm": "#0072B2", "reference": "#E69F00", "baseline": "#7f7f7f"}
    xs = [
        r.get(k) for r in rows for k in ("mean_x", "mean_x_lo", "mean_x_hi") if r.get(k) is not None
    ]
    span = max([0.1] + [abs(v) for v in xs]) * 1.15
    for n, (part, sw, d, g) in enumerate(panels):
        ax_p, ax_x = axes[n // pairs, 2 * (n % pairs)], axes[n // pairs, 2 * (n % pairs) + 1]
        for i, lab in enumerate(labels):
            r = next(
                (
                    r
                    for r in rows
                    if (r["part"], r["swimmer"], r["direction"], r["group"], r["row"])
                    == (part, sw, d, g, lab)
                ),
                None,
            )
            if r is None:
                continue
            err = [
                [max(0.0, r["success"] - r["success_lo"])],
                [max(0.0, r["success_hi"] - r["success"])],
            ]
            ax_p.errorbar(
                r["success"], i, xerr=err, fmt="o", ms=3, color=colors[r["kind"]], capsize=2, lw=1
            )
            if r.get("mean_x") is not None:
                lo, hi = r.get("mean_x_lo"), r.get("mean_x_hi")
                xerr = (
                    None
                    if lo is None or hi is None
                    else [[max(0.0, r["mean_x"] - lo)], [max(0.0, hi - r["mean_x"])]]
                )
                ax_x.errorbar(
                    r["mean_x"],
                    i,
                    xerr=xerr,
                    fmt="s",
                    ms=3,
                    color=colors[r["kind"]],
                    capsize=2,
                    lw=1,
                )
        direction = "+x" if d > 0 else "-x"
        ax_p.set_title(f"{part}: {sw} {direction}{' ' + g if g else ''}", fontsize=7, loc="left")
        ax_p.set_xlim(-0.05, 1.05)
        ax_x.set_xlim(-span, span)
        ax_x.axvline(0.0, color="0.6", lw=0.5)
        ax_p.set_xlabel("success p [95% CI]", fontsize=6)
        ax_x.set_xlabel(f"X/a end toward {direction} [95% CI]", fontsize=6)
        for j, ax in enumerate((ax_p, ax_x)):
            ax.set_yticks(
                range(len(labels)),
                labels if n % pairs == 0 and j == 0 else [""] * len(labels),
                fontsize=6,
            )
            ax.set_ylim(len(labels) - 0.5, -0.5)
            ax.tick_params(labelsize=6, labelbottom=True)
            ax.grid(axis="x", lw=0.3)
    for ax in list(axes.flat)[2 * len(panels) :]:
        ax.axis("off")
    fig.tight_layout()
    return fig
