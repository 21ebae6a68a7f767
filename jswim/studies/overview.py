"""Reading finished studies back: the summary table, ``jswim show`` and ``jswim compare``.

(Moved from ``jswim.overview``: it reads folders that studies write, below the pictures that use
its tables; the shared orderings are `jswim.results.orders`.)

Everything here only reads a study folder (``metadata.json`` and ``runs.jsonl``), so it works
on an interrupted study and on a read-only folder. Tables come back as columns and rows for
`jswim.console.print_table` (or as text), so no number or label is ever cut.
"""

from __future__ import annotations

import math
from collections import Counter
from pathlib import Path
from typing import Any
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from jswim._io.paths import path_kind
from jswim.console import Column, cost_text, plain_table, requests_text
from jswim.errors import ConfigError, ResultFolderError
from jswim._io.folderlock import describe_holder, holder
from jswim.results import RunRow, as_run_rows, read_metadata, read_run_rows
from jswim.console import EMBEDDED_UNPRICED, LOCAL_UNPRICED, REFERENCE_UNPRICED
from jswim.results.orders import (
    AGENT_ORDER,
    MIN_BOOTSTRAP_N,
    MIN_QUARTILE_N,
    STROKE_AGENT,
    SWIMMER_ORDER,
)
from jswim.studies.report import summarize

SETTING = ("agent", "swimmer", "direction", "group")

SUMMARY_NOTE = (
    "X/a end: mean displacement in the target direction after the last step, its 95% bootstrap interval "
    f"over the runs (none below {MIN_BOOTSTRAP_N} runs: [n<{MIN_BOOTSTRAP_N}]; rough below 10); learn: the "
    "step at which the final qualifying stroke starts, counted from 1 as in the paper (1 = the stroke from "
    f"the first action), quartiles over the runs that learned (the median alone below {MIN_QUARTILE_N}: "
    "'med 1.5'; learned: how many did; a fixed stroke learns nothing: 'fixed'); fail: LLM steps "
    "without a valid action."
)


def _fmt(v: Any, spec: str = ".3f") -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "-"
    if not isinstance(v, float):
        return str(v)
    text = format(v, spec)
    # A value that rounds to zero reads as zero, not "-0.000" (a sign the digits cannot show).
    return format(0.0, spec) if float(text) == 0.0 else text


def _dir(d: Any) -> str:
    return "+x" if (d or 1) > 0 else "-x"


def _p_cell(s: Mapping[str, Any]) -> str:
    return (
        f"{s['success_rate']:.2f} [{_fmt(s['success_lo'], '.2f')},{_fmt(s['success_hi'], '.2f')}]"
    )


def _x_cell(s: Mapping[str, Any]) -> str:
    if (s.get("n") or 0) < MIN_BOOTSTRAP_N:  # a bootstrap over one or two runs is no interval
        return f"{_fmt(s['mean_x'], '+.3f')} [n<{MIN_BOOTSTRAP_N}]"
    return f"{_fmt(s['mean_x'], '+.3f')} [{_fmt(s['mean_x_lo'], '+.2f')},{_fmt(s['mean_x_hi'], '+.2f')}]"


def _learn_cell(s: Mapping[str, Any]) -> str:
    if not s.get("learned"):
        return "-"
    if (
        s["learned"] < MIN_QUARTILE_N
    ):  # quartiles of 2 values (1.25/1.5/1.75) are interpolation, not data
        return f"med {_fmt(s['steps_to_learn_median'], 'g')}"
    return "/".join(
        _fmt(s[k], "g")
        for k in ("steps_to_learn_q25", "steps_to_learn_median", "steps_to_learn_q75")
    )


def _cost_cell(v: Any) -> str:
    return "-" if not v else f"{v:.4f}" if v < 1 else f"{v:.2f}"


def grid_order(rows: Sequence[Mapping[str, Any]], meta: Mapping[str, Any]) -> list[RunRow]:
    """``rows`` (in the order runs finished, which concurrency scrambles) with their groups in the
    order of the study's grid (``group_order`` in the metadata: n_ht 1 before 2 before 10, the
    full prompt before each sentence removed); groups it does not name keep their first place
    after those (folders made before it was recorded: the finishing order)."""
    rows = as_run_rows(rows)
    import re

    order = {g: i for i, g in enumerate(meta.get("group_order") or ())}
    first: dict[Any, int] = {}
    for i, r in enumerate(rows):
        first.setdefault(r.group, i)
    # Without a recorded order, one swept number (n_ht=10, T=0.25, zeta=1.5) is put in its order.
    swept = {g: re.fullmatch(r"(\w+)=(-?\d+(?:\.\d+)?)", str(g)) for g in first}
    if not order and all(swept.values()) and len({m.group(1) for m in swept.values()}) == 1:
        order = {g: i for i, g in enumerate(sorted(first, key=lambda g: float(swept[g].group(2))))}
    return sorted(rows, key=lambda r: (order.get(r.group, len(order)), first[r.group]))


def order_summary(
    summary: Sequence[Mapping[str, Any]], rows: Sequence[Mapping[str, Any]] = ()
) -> list[Mapping[str, Any]]:
    """Summary rows in reading order: agent (LLM first), Purcell before NG, +x before -x, and the
    groups in the order they first appear in ``rows`` (pass them through `grid_order`: the
    order the study's grid has them; zeta 0.5 before 1)."""
    rows = as_run_rows(rows)
    first: dict[Any, int] = {}
    for i, r in enumerate(rows):
        first.setdefault(r.group, i)

    def key(s: Mapping[str, Any]) -> tuple:
        a, sw = s.get("agent"), s.get("swimmer")
        return (
            AGENT_ORDER.index(a) if a in AGENT_ORDER else len(AGENT_ORDER),
            str(a),
            SWIMMER_ORDER.index(sw) if sw in SWIMMER_ORDER else len(SWIMMER_ORDER),
            str(sw),
            -(s.get("direction") or 1),
            first.get(s.get("group"), len(first)),
            str(s.get("group")),
        )

    return sorted(summary, key=key)


def summary_table(summary: Sequence[Mapping[str, Any]]) -> tuple[list[Column], list[list[str]]]:
    """Columns and rows of a study's summary (one row per agent, swimmer, direction and group).

    ``summary`` is what [`jswim.studies.summarize`][jswim.studies.report.summarize] returns. Groups, cost and ``samples``
    (independent samples of each run pooled in the row, ``--samples``; ``n`` counts them all)
    appear only when some row has them.
    """
    groups = any(s.get("group") for s in summary)
    cost = any(s.get("cost_usd") for s in summary)
    samples = any((s.get("samples") or 1) > 1 for s in summary)
    cols = [Column(h, False) for h in ("agent", "swimmer", "dir") + (("group",) if groups else ())]
    cols += [Column("samples")] if samples else []
    cols += [
        Column(h)
        for h in (
            "n",
            "success p [95% CI]",
            "X/a end [95% CI]",
            "learn q25/med/q75",
            "learned",
            "fail",
            "tok/step",
        )
    ]
    cols += [Column("cost $")] if cost else []
    rows = []
    for s in summary:
        fixed = s["agent"] == STROKE_AGENT  # plays its stroke from the first step: nothing to learn
        row = [str(s["agent"]), str(s["swimmer"]), _dir(s["direction"])] + (
            [str(s.get("group") or "")] if groups else []
        )
        row += [str(s.get("samples") or 1)] if samples else []
        row += [
            str(s["n"]),
            _p_cell(s),
            _x_cell(s),
            "-" if fixed else _learn_cell(s),
            "fixed" if fixed else f"{s.get('learned') or 0} of {s['n']}",
            str(s["failed_steps"]) if s["agent"] == "llm" else "-",
            _fmt(s.get("tokens_per_step"), ".0f"),
        ]
        row += [_cost_cell(s.get("cost_usd"))] if cost else []
        rows.append(row)
    return cols, rows


def nav_table(rows: Sequence[Any]) -> tuple[list[Column], list[list[str]], str]:
    """Columns, rows and note of a navigation study's table (one row per target and agent):
    reached, mean steps to the target and path ratio (runs that reached it), energy and energy
    per distance closed (`jswim.studies.kinds.navigate.nav_summary`); the console, ``jswim show`` and
    the report page print it, each from here."""
    from jswim.studies.kinds.navigate import nav_summary  # lazy: the navigation study loads JAX

    summary = nav_summary(rows)
    flow = any("zermelo_steps" in g for g in summary)
    cols = [Column("target", False), Column("agent", False)] + [
        Column(h)
        for h in (
            "reached [95% CI]",
            "steps",
            "path ratio",
            "energy",
            "energy/dist",
            "optimal",
            "time ratio [95% CI]",
        )
        + (("Zermelo", "Zermelo ratio") if flow else ())
    ]
    cells = [
        [
            g["group"],
            g["agent"],
            f"{g['reached']}/{g['n']} {_interval(g['success_ci'], '.2f')}",
            _fmt(g["steps_to_target"], ".0f"),
            _fmt(g["path_ratio"], ".2f"),
            _fmt(g["energy"], ".1f"),
            _fmt(g["energy_per_distance"], ".1f"),
            _fmt(g["optimal_steps"], ".0f"),
            _ratio_cell(g),
        ]
        + (_flow_cells(g) if flow else [])
        for g in summary
    ]
    note = (
        "reached: runs whose centroid came within the target's radius of it (a path: of its last "
        "waypoint; a moving target: of where it is then) within the target's step budget, the "
        "navigation success rule, with its Wilson 95% interval; steps and path ratio (path length "
        "over the straight distance): means over the runs that reached it; energy: the swimmer's "
        "dissipation over the run (xi_par a^3/tau); energy/dist: energy per a closed. optimal: "
        "the swimmer's own least time (steps; the least-time sequence of the world's own actions, "
        "jswim.agents.optimal; its row replays it); time ratio: steps over it, median over the "
        "runs that reached the target with a bootstrap 95% interval (n < 2: the value alone; 1 "
        "is the optimum). controller: the steering controller (the reference stroke); mpc: the "
        "optimum re-planned from the swimmer's own state; ppo: PPO with a categorical policy over "
        "the K-level action codes."
    )
    if flow:
        note += (
            " In a flow (the group's speed, a fraction of the swimming speed v = 0.0478 a per "
            "step): Zermelo: the least time (steps) of a point with no turning limit steering at "
            "speed v through the flow taken at its centre (zermelo: its path); it is no bound on "
            "the swimmer (docs/zermelo.md); Zermelo ratio: steps over it, mean over the runs that "
            "reached the target; 'unreachable': no heading reaches it, for any agent."
        )
    return cols, cells, note


def nav_overview_table(rows: Sequence[Any]) -> tuple[list[Column], list[list[str]], str]:
    """Columns, rows and note of a navigation study's first table, agent x flow x target kind
    (`jswim.studies.kinds.navigate.nav_overview`): success with its interval, the median time ratio
    to the swimmer's own optimum with its interval, energy per distance; the console,
    ``jswim show`` and the report page print it first, each from here."""
    from jswim.studies.kinds.navigate import nav_overview  # lazy: the navigation study loads JAX

    table = nav_overview(rows)
    cols = [Column("flow", False), Column("target", False), Column("agent", False)] + [
        Column(h) for h in ("n", "success [95% CI]", "time ratio [95% CI]", "energy/dist")
    ]
    cells = []
    for g in table:
        flow = _flow_label(g)
        ratio = "-"
        if g["time_ratio"] is not None:
            ci = _interval(g["time_ratio_ci"], ".2f") if g["n_ratio"] >= 2 else ""
            ratio = f"{_fmt(g['time_ratio'], '.2f')} {ci}".strip()
        cells.append(
            [
                flow,
                g["target"],
                g["agent"],
                str(g["n"]),
                f"{g['reached'] / g['n']:.2f} {_interval(g['success_ci'], '.2f')}",
                ratio,
                _fmt(g["energy_per_distance"], ".1f"),
            ]
        )
    note = (
        "The result at a glance: success (the share of runs that reached the target within its "
        "budget, Wilson 95% interval); time ratio: steps to the target over the swimmer's own "
        "least time (the optimal agent's: the least-time sequence of the world's own actions), "
        "median over the runs that reached it with a bootstrap 95% interval (one run: the value "
        "alone; 1 is the optimum); energy/dist: median energy (xi_par a^3/tau) per a closed. n: "
        "runs of the cell (learners: one seed each; deterministic agents: one run per start)."
    )
    below = [g for g in table if g.get("n_below")]
    if below:  # the optimum is a search's shortest sequence: say where a run beat it
        where = "; ".join(
            f"{g['agent']} {g['n_below']}/{g['n_ratio']} in {_flow_label(g)} {g['target']}"
            for g in below[:4]
        )
        more = f" and {len(below) - 4} more" if len(below) > 4 else ""
        note += (
            " The optimum is the shortest sequence the search found (seeded with the cell's runs "
            "known when it was searched), an upper bound on the least time, and some runs were "
            f"shorter (time ratio below 1; a run added to the folder after it, or a noisy run): "
            f"{where}{more}."
        )
    return cols, cells, note


def _flow_label(g: dict[str, Any]) -> str:
    """An overview row's flow as the table shows it: ``still`` or ``shear 0.5v``."""
    return "still" if not g["flow"] else f"{g['flow']} {g['flow_fraction']:g}v"


def _interval(ci: Any, spec: str) -> str:
    """``[lo-hi]`` of an interval (empty where there is none)."""
    if ci is None or any(v is None or not math.isfinite(float(v)) for v in ci):
        return ""
    return f"[{format(float(ci[0]), spec)}-{format(float(ci[1]), spec)}]"


def _ratio_cell(g: dict[str, Any]) -> str:
    """The median time ratio to the optimum with its interval (only where n >= 2)."""
    if g["time_ratio"] is None:
        return "-"
    reached = g["reached"]
    ci = _interval(g["time_ratio_ci"], ".2f") if reached >= 2 else ""
    return f"{_fmt(g['time_ratio'], '.2f')} {ci}".strip()


def _flow_cells(g: dict[str, Any]) -> list[str]:
    """A navigation summary row's Zermelo cells ("-" in still fluid)."""
    if "zermelo_steps" not in g:
        return ["-", "-"]
    if not g["reachable"]:
        return ["unreachable", "unreachable"]
    return [_fmt(g["zermelo_steps"], ".1f"), _fmt(g["zermelo_ratio"], ".2f")]


def is_navigation(rows: Sequence[Any]) -> bool:
    """Whether ``rows`` are a navigation study's (its runs swim to targets)."""
    return any(r.target for r in as_run_rows(rows))


# -- a study's tables ---------------------------------------------------------------------------
# What the console prints after a run, ``jswim show`` prints and the report page shows, each from
# `study_tables`: a study names its tables (`jswim.studies.study.Study.tables`, names of `TABLES`).


@dataclass(frozen=True)
class Table:
    """One table of a study.

    Attributes
    ----------
    key : str
        Its id on the report page (``summary-table``, ``overview-table``, ``scenes``).
    title : str
        Its title in ``jswim show`` and, where set, its heading on the page (``""``: none).
    caption : str
        Its title on the console after a run (``""``: the run's own line).
    columns, cells
        Its columns (`jswim.console.Column`) and rows of text.
    notes : tuple of str
        What its columns mean, a line each.
    heading : bool
        The page shows ``title`` above it.
    """

    key: str
    title: str
    caption: str
    columns: list[Column]
    cells: list[list[str]]
    notes: tuple[str, ...]
    heading: bool = False


def _runs(rows: Sequence[Any], summary: Sequence[Mapping[str, Any]] | None) -> Table | None:
    """Success, X/a and steps to learn per agent, swimmer, direction and group."""
    cols, cells = summary_table(
        order_summary(summarize(list(rows)) if summary is None else summary, rows)
    )
    return Table("summary-table", "", "", cols, cells, (SUMMARY_NOTE,))


def _scenes(rows: Sequence[Any], summary: Any = None) -> Table | None:
    """A scene study's own table (per cycle, per step, fates, mean height); none without scenes."""
    if not any(r.scene for r in rows):
        return None
    from jswim.studies.scene_studies import (
        columns_note,
        scene_summary,
        table,
        table_note,
    )  # lazy: the scene studies load JAX

    scenes = scene_summary(rows)
    cols, cells = table(scenes)
    notes = (columns_note(cols), *([note] if (note := table_note(scenes)) else []))
    caption = "scenes: displacement per stroke cycle, speed per step (second half)"
    return Table("scenes", "scenes", caption, cols, cells, notes, heading=True)


def _overview(rows: Sequence[Any], summary: Any = None) -> Table | None:
    """The navigation study's first table: agent x flow x target kind."""
    cols, cells, note = nav_overview_table(rows)
    caption = "agents x flows: success, time over the swimmer's optimum, energy"
    return Table("overview-table", "agents x flows", caption, cols, cells, (note,))


def _navigation(rows: Sequence[Any], summary: Any = None) -> Table | None:
    """Every target's row: reached, steps, path ratio, energy (and the flow's columns)."""
    cols, cells, note = with_flow_columns(*nav_table(rows), rows)
    caption = "navigation: targets reached, steps to the target, path ratio, energy"
    return Table("summary-table", "navigation", caption, cols, cells, (note,))


#: Every table a study may name (`jswim.studies.study.Study.tables`):
#: ``(rows, summary) -> Table or None``.
TABLES: dict[str, Callable[[Sequence[Any], Any], Table | None]] = {
    "runs": _runs,
    "scenes": _scenes,
    "agents x flows": _overview,
    "navigation": _navigation,
}


def study_tables(
    study: str, rows: Sequence[Any], summary: Sequence[Mapping[str, Any]] | None = None
) -> list[Table]:
    """The tables of ``study``'s ``rows``, its summary first (none without rows).

    Parameters
    ----------
    study : str
        The study's name (`jswim.studies.names`); one this version does not know gets the
        navigation tables where its rows swim to targets, else the runs and scene tables.
    rows : sequence of dict or RunRow
        Its finished runs.
    summary : sequence of dict, optional
        `jswim.studies.report.summarize`'s rows where already made (else made from ``rows``).
    """
    from jswim.studies.study import find  # lazy: the study kinds load JAX

    rows = as_run_rows(rows)
    if not rows:
        return []
    spec = find(study)
    if spec is not None:
        kinds = spec.tables
    else:
        kinds = ("agents x flows", "navigation") if is_navigation(rows) else ("runs", "scenes")
    return [t for k in kinds if (t := TABLES[k](rows, summary)) is not None]


#: The navigation table's columns of a study in a background flow (`with_flow_columns`), each
#: with the other names it may already have there and its line of the table's note.
FLOW_COLUMNS = {
    "flow speed": ((), "flow speed: the flow's, in units of the swimming speed v"),
    "reachable": (
        (),
        "reachable: Zermelo's optimal point steerer at speed v reaches the target (no: no agent can)",
    ),
    "Zermelo steps": (("zermelo",), "Zermelo steps: his least time to the target"),
    "time ratio": (
        ("time ratio [95% ci]",),
        "time ratio: steps to the target over the swimmer's own optimum, median over the runs "
        "that reached it (1 is optimal)",
    ),
}


def with_flow_columns(
    cols: Sequence[Any], cells: Sequence[Sequence[str]], note: str, rows: Sequence[Any]
) -> tuple[list[Any], list[list[str]], str]:
    """The navigation table (`jswim.studies.overview.nav_table`'s) with the flow's columns
    (`FLOW_COLUMNS`) where its rows ran in a flow and the table lacks them; unchanged in still
    fluid."""
    from jswim.studies.kinds.navigate import nav_summary  # lazy: the navigation study loads JAX

    have = {c.header.lower() for c in cols}
    new = [h for h, (aliases, _) in FLOW_COLUMNS.items() if not ({h.lower(), *aliases} & have)]
    if not new or not any(r.flow for r in as_run_rows(rows) if r.target):
        return list(cols), [list(c) for c in cells], note
    by = {(g["group"], g["agent"]): g for g in nav_summary(rows)}

    def fmt(v: Any, spec: str) -> str:
        return "-" if v is None or not math.isfinite(float(v)) else format(float(v), spec)

    def values(g: Mapping[str, Any]) -> dict[str, str]:
        if "flow_fraction" not in g:
            return dict.fromkeys(FLOW_COLUMNS, "-")
        return {
            "flow speed": f"{fmt(g['flow_fraction'], 'g')} v",
            "reachable": "yes" if g["reachable"] else "no",
            "Zermelo steps": fmt(g["zermelo_steps"], ".0f"),
            "time ratio": fmt(g["time_ratio"], ".2f"),
        }

    out = [list(c) + [values(by.get((c[0], c[1]), {}))[h] for h in new] for c in cells]
    said = "; ".join(FLOW_COLUMNS[h][1] for h in new)
    return list(cols) + [Column(h, h != "reachable") for h in new], out, f"{note} {said}."


class StudyFolder:
    """A study folder read once: metadata, finished runs and their summary (read-only)."""

    def __init__(self, folder: str | Path) -> None:
        self.folder = Path(folder)
        if not self.folder.is_dir():
            raise ResultFolderError(f"{folder}: {path_kind(folder, 'a study folder')}")
        self.meta = read_metadata(self.folder)
        self.rows = grid_order(read_run_rows(self.folder), self.meta)
        self.summary = order_summary(summarize(self.rows), self.rows)

    @property
    def study(self) -> str:
        return str(self.meta.get("study", "?"))

    @property
    def planned(self) -> int | None:
        n = self.meta.get("n_planned")
        return int(n) if isinstance(n, int) else None

    @property
    def finished(self) -> bool:
        return self.meta.get("status") == "complete" and (
            self.planned is None or len(self.rows) >= self.planned
        )

    def status_text(self) -> str:
        """``complete`` or ``UNFINISHED: k of N runs done (status)``; a folder whose status reads
        ``running`` says whether a live session holds it (`jswim._io.folderlock.holder`)."""
        if self.finished:
            return "complete"
        of = f" of {self.planned}" if self.planned else ""
        status = str(self.meta.get("status", "unknown"))
        if status == "running":
            info = holder(self.folder)
            if info is not None and info.get("alive") is not False:
                status = f"running now: {describe_holder(info)}"
            else:  # the session that wrote "running" died without a word (kill -9, power loss)
                status = "running, but no live session holds the folder (killed?); the same command resumes"
        return f"UNFINISHED: {len(self.rows)}{of} runs done (status {status})"

    def model_text(self) -> str:
        from jswim.studies.study import find  # lazy: the study kinds load JAX

        b = (self.meta.get("identity") or {}).get("backend")
        spec = find(self.study)
        strokes = spec is not None and spec.strokes_only  # a school: no LLM
        if not b or (strokes and not any(r.agent == "llm" for r in self.rows)):
            return "no LLM runs"
        # The address is not the identity (it may change between sessions): the latest session's.
        where = (
            "embedded"
            if b.get("kind") == "embedded"
            else (self.meta.get("server") or b.get("base_url") or "remote")
        )
        # Decoding as the runs recorded it (``auto`` is resolved per server: grammar, json_schema
        # or none, i.e. free text); the setting only while no LLM run has finished.
        used = sorted({str(r.constraint) for r in self.rows if r.agent == "llm" and r.constraint})
        decoding = ("constrain " + ",".join(used)) if used else f"constrain {b.get('constrain')}"
        if used == ["none"]:
            decoding = "free text (constrain none)"
        temperature = f"temperature {_fmt(b.get('temperature'), 'g')}"
        # A reasoning model that accepts one temperature was sent that one (the runs record it).
        sent = sorted(
            {
                r.temperature_sent
                for r in self.rows
                if r.agent == "llm" and r.temperature_sent is not None
            }
        )
        if sent:
            temperature += (
                f" asked, {','.join(_fmt(t, 'g') for t in sent)} sent (all the model accepts)"
            )
        thinking = (self.meta.get("summary") or {}).get("reasoning") or {}
        room = (
            f", reasoning model: {thinking.get('token_field')}={thinking.get('budget')}"
            if thinking.get("active")
            else ""
        )
        return f"{b.get('model')} ({where}), {temperature}, {decoding}{room}"

    def label(self) -> str:
        """Short name for a comparison: the folder name and the model."""
        b = (self.meta.get("identity") or {}).get("backend") or {}
        return f"{self.folder.name} ({b.get('model') or 'no LLM'})"

    def usage(self) -> dict[str, float]:
        """LLM calls, tokens and cost over the finished runs."""
        llm = [r for r in self.rows if r.agent == "llm"]
        return {
            k: sum(getattr(r, k) or (0.0 if k == "cost_usd" else 0) for r in llm)
            for k in ("calls", "prompt_tokens", "completion_tokens", "cost_usd")
        }

    def figures(self) -> list[Path]:
        fig_dir = self.folder / "figures"
        return (
            sorted(fig_dir.glob("*.png")) + sorted(fig_dir.glob("*.pdf"))
            if fig_dir.is_dir()
            else []
        )


def _settings_text(options: Mapping[str, Any], skip: Sequence[str] = ()) -> str:
    """The options of a study's identity worth reading, without those the study has no use for."""
    keep = (
        "swimmers",
        "directions",
        "runs",
        "q_runs",
        "steps",
        "n_ht",
        "zeta",
        "zetas",
        "n_hts",
        "init",
        "action_set",
        "variant",
        "variants",
        "seed",
    )
    parts = []
    for k in keep:
        v = options.get(k)
        if v is None or k in skip:
            continue
        if isinstance(v, list):
            v = ",".join(_fmt(x, "g") if isinstance(x, float) else str(x) for x in v)
        parts.append(f"{k.replace('_', '-')} {v}")
    return "; ".join(parts)


def unpriced_reason(meta: Mapping[str, Any], cost_usd: float | None) -> str | None:
    """Why a study folder's calls are not priced (`jswim.console.cost_text`), from its record:
    the embedded model, the reference rule, the reason the session recorded, or a local server
    whose calls cost nothing; ``None`` when they are priced."""

    backend = (meta.get("identity") or {}).get("backend") or {}
    if backend.get("kind") == "embedded":
        return EMBEDDED_UNPRICED
    if backend.get("model") == "reference-rule" and not cost_usd:
        # jswim.llm.reference.MODEL (not imported: no httpx here); priced only by --prices
        return REFERENCE_UNPRICED
    why = (meta.get("llm_server") or {}).get("unpriced")
    if why:
        return str(why)
    server = str(meta.get("server") or "")
    if not cost_usd and any(h in server for h in ("//127.", "//localhost", "//[::1]", "//0.0.0.0")):
        return LOCAL_UNPRICED
    return None


def _llm_totals(s: StudyFolder) -> Mapping[str, Any]:
    """The study's LLM totals, recomputed from its ledger (`jswim.llm.ledger.folder_totals`:
    every session, a killed one included); ``metadata.json``'s report where there is no ledger."""
    from jswim.llm.ledger import folder_totals  # lazy: only show reads the ledger

    recorded = s.meta.get("llm_totals")
    return folder_totals(s.folder, recorded) or recorded or {}


def show_text(folder: str | Path, width: int | None = None) -> str:
    """What ``jswim show FOLDER`` prints: status, model, settings, usage, summary table, figures."""
    s = StudyFolder(folder)
    agents = Counter(r.agent for r in s.rows)
    u = s.usage()
    lines = [f"study {s.study} in {s.folder}: {s.status_text()}", f"model: {s.model_text()}"]
    opts = (s.meta.get("identity") or {}).get("options") or {}
    if opts:
        from jswim.studies.study import find  # lazy: the study kinds load JAX

        spec = find(s.study)
        ignores = spec.ignores if spec is not None else ()
        settings = _settings_text(opts, ignores)
        if opts.get("flow"):  # still fluid ("") goes unsaid, as on the page
            speeds = ",".join(
                f"{float(f):g}" for f in (s.meta.get("grid") or {}).get("flows") or ()
            )
            settings += f"; flow {opts['flow']} at {speeds or '?'} v (the swimming speed)"
        lines.append(f"settings: {settings}")
    lines.append(
        f"runs: {len(s.rows)} (" + ", ".join(f"{a} {n}" for a, n in sorted(agents.items())) + ")"
    )
    if agents.get("llm"):
        lines.append(
            f"LLM usage: {u['calls']:,} calls, {u['prompt_tokens']:,} prompt + {u['completion_tokens']:,} "
            f"completion tokens, cost {cost_text(u['cost_usd'], unpriced_reason(s.meta, u['cost_usd']), 'estimate from the price table')}"
        )
    totals = _llm_totals(s)
    if totals.get("sessions"):  # the study's own numbers, over all its sessions (one source each)
        cut = totals.get("not_ended") or 0
        lines.append(
            f"LLM wall time: {totals.get('wall_s', 0):.1f} s over {totals['sessions']} session(s)"
            + (
                f" ({cut:.0f} of them not ended: killed, or running now; timed to their last request)"
                if cut
                else ""
            )
            + f" for {totals.get('answered_calls', 0):,} answered calls ({totals.get('calls_per_s', 0):.2f} calls/s)"
        )
        lines.append(f"HTTP requests: {requests_text(totals)}")
    else:  # folders written before the study's totals were kept: the last session's
        speed = (s.meta.get("summary") or {}).get("llm_speed") or {}
        if speed.get("wall_s"):
            lines.append(
                f"LLM wall time (last session): {speed['wall_s']:.1f} s "
                f"({speed.get('calls_per_s', 0):.2f} calls/s)"
            )
    lines.append("")
    for i, t in enumerate(study_tables(s.study, s.rows, s.summary)):
        lines += [""] if i else []
        lines += [plain_table(t.columns, t.cells, title=t.title or None, width=width), *t.notes]
    if not s.rows:
        lines.append("no finished runs yet")
    lines.append("")
    figs = s.figures()
    if figs:
        lines.append("figures:")
        lines += [f"  {f}" for f in figs]
    else:
        lines.append(f"no figures yet; draw them with: jswim plot {s.folder}")
    return "\n".join(lines)


def compare_table(
    folders: Sequence[str | Path],
) -> tuple[list[StudyFolder], list[Column], list[list[str]], int]:
    """Studies side by side, per setting (agent, swimmer, direction, group) present in all of them.

    Returns the studies, the table's columns and rows (for each setting one row per study, in the
    order given) and how many settings were left out because some study lacks them.
    """
    if len(folders) < 2:
        raise ConfigError("compare needs at least two study folders")
    studies = [StudyFolder(f) for f in folders]
    if all(is_navigation(st.rows) for st in studies):
        return _nav_compare(studies)
    keyed = [{tuple(s.get(k) for k in SETTING): s for s in st.summary} for st in studies]
    common = set(keyed[0]).intersection(*keyed[1:])
    every = set().union(*keyed)
    order = [key for key in keyed[0] if key in common]  # the first study's reading order
    groups = any(key[3] for key in order)
    cols = [Column(h, False) for h in ("agent", "swimmer", "dir") + (("group",) if groups else ())]
    cols += [Column("study", False)] + [
        Column(h)
        for h in (
            "n",
            "success p [95% CI]",
            "X/a end [95% CI]",
            "learn median",
            "tok/step",
            "cost $",
        )
    ]
    rows = []
    for key in order:
        # A baseline (Q-learning, random) is the same rows in every study of the same grid and
        # seed: print it once, naming the studies that hold it, instead of once per study.
        shown: dict[tuple, list[int]] = {}
        for i, k in enumerate(keyed):
            s = k[key]
            same = (
                (s["n"], s.get("success_rate"), s.get("mean_x"), s.get("steps_to_learn_median"))
                if key[0] != "llm"
                else (i,)
            )
            shown.setdefault(same, []).append(i)
        for members in shown.values():
            s = keyed[members[0]][key]
            row = [str(key[0]), str(key[1]), _dir(key[2])] + ([str(key[3] or "")] if groups else [])
            row += [
                "".join(f"[{i + 1}]" for i in members),
                str(s["n"]),
                _p_cell(s),
                _x_cell(s),
                _fmt(s["steps_to_learn_median"], "g") if s.get("learned") else "-",
                _fmt(s.get("tokens_per_step"), ".0f"),
                _cost_cell(s.get("cost_usd")),
            ]
            rows.append(row)
    return studies, cols, rows, len(every - common)


def _nav_compare(
    studies: Sequence[StudyFolder],
) -> tuple[list[StudyFolder], list[Column], list[list[str]], int]:
    """`compare_table` of navigation studies: per (target, agent) present in all of them, the
    navigation table's columns, one row per study (a still-fluid study beside one in a flow: its
    Zermelo and time-ratio cells are "-")."""
    built = [nav_table(st.rows) for st in studies]
    cols = max((b[0] for b in built), key=len)
    tables = [{(c[0], c[1]): c + ["-"] * (len(cols) - len(c)) for c in b[1]} for b in built]
    common = set(tables[0]).intersection(*tables[1:])
    every = set().union(*tables)
    rows = [
        [*key, f"[{i + 1}]", *t[key][2:]]
        for key in tables[0]
        if key in common
        for i, t in enumerate(tables)
    ]
    return list(studies), cols[:2] + [Column("study", False)] + cols[2:], rows, len(every - common)


def setting_differences(studies: Sequence[StudyFolder]) -> list[str]:
    """Every setting whose value differs between ``studies`` (their identities, the success
    criterion's horizon), each with every study's value: ``steps: [1] 12, [2] 20``. A setting
    one study does not record reads ``not set``."""
    flats = []
    for st in studies:
        flat = _flatten(st.meta.get("identity") or {})
        if "horizon" in st.meta:
            flat["horizon"] = st.meta["horizon"]
        flats.append(flat)
    out = []
    for key in sorted(set().union(*flats)):
        values = [f.get(key, _UNSET) for f in flats]
        if all(v == values[0] for v in values[1:]):
            continue
        name = key.removeprefix("options.")
        out.append(
            f"{name}: " + ", ".join(f"[{i + 1}] {_setting_value(v)}" for i, v in enumerate(values))
        )
    return out


_UNSET = object()


def _flatten(d: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested settings by their dotted path (``backend.model``)."""
    out: dict[str, Any] = {}
    for k, v in d.items():
        if isinstance(v, Mapping):
            out.update(_flatten(v, f"{prefix}{k}."))
        else:
            out[f"{prefix}{k}"] = v
    return out


def _setting_value(v: Any) -> str:
    if v is _UNSET or v is None:
        return "not set"
    if isinstance(v, (list, tuple)):
        return ",".join(map(str, v)) or "none"
    return str(v)


def compare_text(folders: Sequence[str | Path], width: int | None = None) -> str:
    """What ``jswim compare FOLDER...`` prints: each study, every setting that differs between
    them (their rows are lined up by setting regardless: the note says what else differs), the
    table and what was left out."""
    studies, cols, rows, left_out = compare_table(folders)
    lines = [
        f"[{i + 1}] {s.label()}: study {s.study}, {s.status_text()}, {len(s.rows)} runs"
        for i, s in enumerate(studies)
    ]
    differ = setting_differences(studies)
    if differ:
        lines.append(
            "settings that differ (the rows below are lined up regardless): " + "; ".join(differ)
        )
    lines.append("")
    if rows:
        lines.append(plain_table(cols, rows, width=width))
    else:
        lines.append(
            "no target and agent is present in every study"
            if all(is_navigation(s.rows) for s in studies)
            else "no setting (agent, swimmer, direction, group) is present in every study"
        )
    if left_out:
        lines.append(f"{left_out} setting(s) not present in every study are left out")
    return "\n".join(lines)
