"""Figures of the navigation study (``jswim study navigate``; docs/navigation.md).

Same conventions as [`jswim.figures.plots`][jswim.figures.plots] (paper sizes, the agents'
palette, ``note`` across the top of an unfinished study's figures); chosen by
[`jswim.figures.plots.study_figures`][jswim.figures.plots.study_figures].

The figures, in the order of `jswim.studies.kinds.navigate.FIGURE_ORDER` (the page's and `jswim plot`'s order: the
result first):

``navigate-ratio``
    Still fluid: steps to the target over the swimmer's own least time (``time_ratio``, the
    agent ``optimal``'s steps), the median over the runs that reached it with its bootstrap 95 %
    interval, per agent and target (1 is the optimum).
``navigate-bearing``
    Success rate against the fixed targets' bearing with Wilson 95 % intervals, one series per
    agent (one panel per distance, and in a background flow per flow speed).
``navigate-energy``
    Energy per link length closed on the target, per agent and target (bars; the runs that closed
    any distance), and steps to the target below.
``navigate-paths``
    One panel per target: every agent's centroid path in the plane (link lengths), the start, the
    target(s) with their success radius (a moving target's track as a dotted line from its
    start to where it was at the longest run's end).

Every series of cells (`draw_series`) shows its runs per cell (n) in the legend and joins
neighbouring cells by a line only where both hold at least `MIN_LINE_RUNS` runs: a cell of one
run is a marker with its interval, not a trend. A study in a background flow (``--flow``) draws
the flow figures of `jswim.figures.flow_plots` instead of ``navigate-ratio``; Zermelo's
point's least-time path is drawn dashed (`ZERMELO_STYLE`) wherever a path is.
"""

from __future__ import annotations

import json
import math
from typing import Any
from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure

from matplotlib.lines import Line2D

from jswim.figures.style import AGENT_STYLE, COLUMN_IN, NOTE_COLOR, PAGE_IN, styled
from jswim.judging.stats import median_interval, wilson_interval
from jswim.results import as_run_rows

__all__ = [
    "CONTROLLER_STYLE",
    "MIN_LINE_RUNS",
    "OPTIMUM_STYLE",
    "ZERMELO_STYLE",
    "agent_order",
    "agent_style",
    "bearing_figure",
    "draw_series",
    "energy_figure",
    "has_optimum",
    "n_text",
    "nav_figures",
    "paths_figure",
    "ratio_axes",
    "ratio_cell",
    "ratio_figure",
    "success_cell",
    "target_points",
]

#: The steering controller's line (the reference stroke of navigation).
CONTROLLER_STYLE = dict(color="black", ls="-", marker="x", label="steering controller")
#: Navigation's PPO is the categorical learner over the K-level action codes
#: ([`jswim.studies.kinds.navigate.nav_ppo_config`][jswim.studies.kinds.navigate.nav_ppo_config]), not the
#: continuous study's real-ROC one.
NAV_PPO_STYLE = {**AGENT_STYLE["ppo"], "label": "PPO (categorical, K-level codes)"}
#: Zermelo's optimal point steerer (in a flow, docs/navigation.md): a point with no turning
#: limit that feels the flow at its centre, so no bound on the swimmer (docs/zermelo.md); dashed
#: so that an agent's path drawn on it stays visible.
ZERMELO_STYLE = dict(
    color="#CC79A7",
    ls="--",
    marker="+",
    label="Zermelo's point (no turning limit, flow at its centre)",
)
#: The swimmer's own least time (the agent ``optimal``, `jswim.agents.optimal`): the line at 1
#: of the time-ratio figures, and its replayed rows elsewhere.
OPTIMUM_STYLE = dict(
    color="#E69F00", ls="-", marker="*", label="optimal (the swimmer's own least time)"
)
#: The model-predictive agent (`jswim.agents.mpc`): the optimum re-planned from its own state.
MPC_STYLE = dict(color="#56B4E9", ls="--", marker="v", label="MPC (re-planned optimum)")
_STYLES = {
    **AGENT_STYLE,
    "ppo": NAV_PPO_STYLE,
    "controller": CONTROLLER_STYLE,
    "mpc": MPC_STYLE,
    "optimal": OPTIMUM_STYLE,
    "zermelo": ZERMELO_STYLE,
}

#: Bearing offset between neighbouring agents' points in the bearing figure (degrees), so that
#: agents with the same success rate stay visible side by side.
BEARING_DODGE = 3.0
_ORDER = ("llm", "qlearning", "ppo", "controller", "mpc", "optimal", "random")

#: Fewest runs in a cell for its series' line to join it to a neighbouring cell: fewer, and the
#: cell is a marker with its interval alone (one run going 0 to 1 is no trend).
MIN_LINE_RUNS = 5


def agent_style(agent: str) -> dict[str, Any]:
    """An agent's colour, line, marker and label in the navigation figures."""
    return _STYLES.get(agent, dict(color="#999999", ls="-", marker=".", label=agent))


_style = agent_style


def agent_order(agent: str) -> int:
    """An agent's place in the navigation figures' order (Zermelo's reference last)."""
    return _ORDER.index(agent) if agent in _ORDER else 9 + (agent == "zermelo")


def _note(fig: Figure, note: str | None) -> None:
    if note:
        fig.suptitle(note, color=NOTE_COLOR, fontsize=7)


def success_cell(rows: Sequence[Any]) -> tuple[float, float, float, int]:
    """``(rate, lo, hi, n)`` of a cell's runs: the success rate and its Wilson 95 % interval
    (nan without runs)."""
    n = len(rows)
    k = sum(bool(r.reached) for r in rows)
    lo, hi = wilson_interval(k, n)
    return (k / n if n else math.nan, lo, hi, n)


def ratio_cell(rows: Sequence[Any], field: str = "time_ratio") -> tuple[float, float, float, int]:
    """``(median, lo, hi, n)`` of a cell's time ratios (``field``) over its runs that reached
    the target: the median, its bootstrap 95 % interval and how many runs it is of (nan with
    none; the median alone with one), as the study's table (`jswim.studies.kinds.navigate.nav_summary`)."""
    vals = [getattr(r, field) for r in rows if r.reached and getattr(r, field) is not None]
    m, lo, hi = median_interval(vals)
    return (m, lo, hi, len(vals))


#: A ratio figure's axis turns logarithmic where its values span more than this factor (a random
#: run that reached at 9 times the optimum would squeeze the learners' 1.0 to 1.3 flat).
LOG_SPAN = 3.0


def ratio_axes(axes: Sequence[Any]) -> None:
    """Set the time-ratio panels' value axis: linear holding 1 (the optimum), logarithmic where
    the drawn values and intervals span more than `LOG_SPAN` (every panel alike)."""
    ys = []
    for ax in axes:
        for a in ax.get_children():
            gid = a.get_gid() or ""
            if gid.startswith("points:") or gid == "zermelo-ratio":
                ys += list(np.asarray(a.get_ydata(), float))
            elif gid.startswith("bars:"):
                ys += [y for seg in a.get_segments() for y in np.asarray(seg)[:, 1]]
    ys = [y for y in ys if math.isfinite(y) and y > 0]
    lo, hi = min(ys + [0.9]), max(ys + [1.1])
    for ax in axes:
        if hi / lo > LOG_SPAN:
            ax.set_yscale("log")
            ax.set_ylim(lo / 1.1, hi * 1.1)
        else:
            pad = 0.05 * (hi - lo)
            ax.set_ylim(lo - pad, hi + pad)


def n_text(ns: Sequence[int]) -> str:
    """The runs per cell of a series for its legend: ``"n=16"``, or ``"n=1-16"`` where they
    differ (cells without runs left out)."""
    ns = sorted({int(n) for n in ns if n})
    if not ns:
        return "n=0"
    return f"n={ns[0]}" if len(ns) == 1 else f"n={ns[0]}-{ns[-1]}"


def draw_series(
    ax: Any,
    xs: Sequence[float],
    cells: Sequence[tuple[float, float, float, int]],
    style: Mapping[str, Any],
    hollow: bool = False,
    gid: str = "",
    bars: bool = True,
    join: bool = True,
) -> Line2D:
    """One agent's cells ``(value, lo, hi, n)`` at ``xs``: a marker each with its interval as an
    error bar (``bars``), and a line joining neighbours only where both hold at least
    `MIN_LINE_RUNS` runs (``join=False``: never, for categories). The artists' gids are ``points:GID``, ``bars:GID``, ``joins:GID``.
    Returns the legend's handle (line, marker and colour; the caller labels it)."""
    x = np.asarray(xs, float)
    v, lo, hi, n = np.asarray(cells, float).reshape(-1, 4).T
    ok = np.isfinite(v)
    mfc = "none" if hollow else style["color"]
    if ok.any():
        if bars:
            err = np.vstack([np.clip(v - lo, 0, None), np.clip(hi - v, 0, None)])[:, ok]
            c = ax.errorbar(
                x[ok],
                v[ok],
                yerr=np.nan_to_num(err),
                fmt=style["marker"],
                color=style["color"],
                mfc=mfc,
                ms=3.5,
                elinewidth=0.7,
                capsize=1.5,
                zorder=3,
            )
            c.lines[0].set_gid(f"points:{gid}")
            for b in c.lines[2]:
                b.set_gid(f"bars:{gid}")
        else:
            ax.plot(
                x[ok], v[ok], ls="none", marker=style["marker"], color=style["color"], mfc=mfc,
                ms=3.5, zorder=3, gid=f"points:{gid}",
            )  # fmt: skip
        # The line: through the cells of enough runs only; nan breaks it around the others.
        joined = np.where(ok & (n >= MIN_LINE_RUNS), v, np.nan)
        pairs = np.isfinite(joined[:-1]) & np.isfinite(joined[1:])
        if join and pairs.any():
            ax.plot(x, joined, color=style["color"], ls=style["ls"], lw=1.0, zorder=2.5,
                    gid=f"joins:{gid}")  # fmt: skip
    return Line2D([], [], color=style["color"], ls=style["ls"], marker=style["marker"], mfc=mfc)


def target_points(target: str, steps: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A target's waypoints ``(P, 2)`` (link lengths, lab frame) and, for a moving target, its
    track over ``steps`` steps ``(2, 2)`` (start, end); an empty track otherwise. Read from the
    row's ``target`` (the spec's JSON), so old rows need nothing else."""
    t = json.loads(target)
    if t.get("points"):
        pts = np.asarray(t["points"], np.float64).reshape(-1, 2)
    else:
        b = math.radians(float(t.get("bearing", 0.0)))
        pts = np.array([[t["distance"] * math.cos(b), t["distance"] * math.sin(b)]])
    v = np.asarray(t.get("velocity") or (0.0, 0.0), np.float64)
    if not np.any(v):
        return pts, np.zeros((0, 2))
    return pts, np.vstack([pts[-1], pts[-1] + v * steps])


def _groups(rows: Sequence[Any]) -> list[str]:
    return list(dict.fromkeys(r.group for r in rows))


@styled
def paths_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    """Every run's path in the plane, one panel per target (module docs)."""
    rows = [r for r in as_run_rows(rows) if r.target]
    groups = _groups(rows)
    n = len(groups)
    cols = min(n, 3)
    nrows = math.ceil(n / cols)
    fig = Figure(figsize=(PAGE_IN, 2.3 * nrows))
    axes = fig.subplots(nrows, cols, squeeze=False)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    for ax, group in zip(axes.flat, groups):
        g = [r for r in rows if r.group == group]
        longest = max(len(r.x) for r in g)
        pts, track = target_points(g[0].target, longest)
        radius = float(json.loads(g[0].target).get("radius", 0.25))
        for r in sorted(g, key=lambda r: agent_order(r.agent)):
            st = _style(r.agent)
            xs = np.concatenate([[0.0], np.asarray(r.x, float)])
            ys = np.concatenate([[0.0], np.asarray(r.y or [0.0] * len(r.x), float)])
            ax.plot(xs, ys, color=st["color"], ls=st["ls"], lw=0.9, label=st["label"])
            ax.plot(xs[-1:], ys[-1:], marker=st["marker"], color=st["color"], ms=3)
        for k, (px, py) in enumerate(pts, 1):
            ax.add_patch(_circle((px, py), radius, edgecolor="#B00000", facecolor="none", lw=0.8))
            ax.plot([px], [py], marker="x", color="#B00000", ms=4)
            if len(pts) > 1:
                ax.annotate(str(k), (px, py), xytext=(3, 3), textcoords="offset points", fontsize=6)
        if len(track):
            ax.plot(track[:, 0], track[:, 1], ls=":", color="#B00000", lw=0.8)
        ax.plot([0], [0], marker="*", color="black", ms=5)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(group)
        ax.set_xlabel("x / a")
        ax.set_ylabel("y / a")
    handles, labels = axes.flat[0].get_legend_handles_labels()
    seen = dict(zip(labels, handles))
    # Four to a row: seven agents and Zermelo's point's long label stay within the page.
    fig.legend(seen.values(), seen.keys(), loc="lower center", ncol=min(len(seen), 4), fontsize=6)
    legend_rows = math.ceil(len(seen) / 4)
    fig.subplots_adjust(bottom=(0.2 + 0.12 * legend_rows) / (nrows + 0.4), hspace=0.55, wspace=0.35)
    _note(fig, note)
    return fig


def _circle(xy: tuple[float, float], radius: float, **kw: Any) -> Any:
    from matplotlib.patches import Circle

    return Circle(xy, radius, **kw)


def _flow_of(r: Any) -> tuple[float, str]:
    """``(speed fraction, title suffix)`` of a row's background flow; ``(0, "")`` in still fluid."""
    if not r.flow:
        return 0.0, ""
    f = float(r.flow_fraction or 0.0)
    if not f:  # the study's still-fluid reference (recorded as a uniform stream of speed 0)
        return f, "\nstill fluid"
    kind = str(json.loads(r.flow).get("kind", "flow"))
    return f, f"\n{kind} {f:g} v"


def _bearing(r: Any) -> tuple[float, float] | None:
    t = json.loads(r.target)
    if t.get("kind") != "fixed":
        return None
    return float(t["distance"]), float(t["bearing"])


@styled
def bearing_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    """Success rate against the fixed targets' bearing, per agent (one panel per distance)."""
    rows = [r for r in as_run_rows(rows) if r.target and _bearing(r) is not None]
    # One panel per distance (and, in a flow, per flow speed: rates in different flows are
    # never averaged together).
    panels = sorted({(_bearing(r)[0], _flow_of(r)) for r in rows}, key=lambda k: (k[0], k[1][0]))
    n = max(len(panels), 1)
    agents = [a for a in _ORDER if any(r.agent == a for r in rows)]
    legend_in = 0.15 + 0.13 * math.ceil(len(agents) / 2)  # the legend below, two to a row
    cols = n if n <= 2 else 3  # one or two distances in still fluid: a column each
    nrows = math.ceil(n / cols)
    height = 2.4 * nrows + legend_in
    fig = Figure(figsize=(COLUMN_IN * n if n <= 2 else PAGE_IN, height))
    axes = list(fig.subplots(nrows, cols, squeeze=False).ravel())
    for ax in axes[n:]:
        ax.set_visible(False)
    fig.subplots_adjust(
        bottom=(legend_in + 0.45) / height, top=1 - 0.35 / height, hspace=0.6, wspace=0.35
    )
    handles: dict[str, Any] = {}
    for k, (ax, (d, flow)) in enumerate(zip(axes, panels)):
        for i, agent in enumerate(agents):
            shift = (i - (len(agents) - 1) / 2) * BEARING_DODGE
            by: dict[float, list[Any]] = {}
            for r in rows:
                dist, b = _bearing(r)
                if r.agent == agent and dist == d and _flow_of(r) == flow:
                    by.setdefault(b, []).append(r)
            bs = sorted(by)
            cells = [success_cell(by[b]) for b in bs]
            st = _style(agent)
            h = draw_series(ax, [b + shift for b in bs], cells, st, hollow=bool(i % 2), gid=agent)
            ns = [c[3] for c in cells]
            handles.setdefault(agent, (h, ns))
            handles[agent][1].extend(ns)
        ax.set_title(f"targets {d:g} a away" + flow[1])
        ax.set_xlabel(
            f"bearing (degrees; agents {BEARING_DODGE:g} degrees apart)"
            if n <= 2
            else f"bearing (deg; agents {BEARING_DODGE:g} apart)"
        )
        if k % cols == 0:
            ax.set_ylabel("success rate\n(Wilson 95% interval)")
        ax.set_ylim(-0.05, 1.05)
    if panels:
        fig.legend(
            [h for h, _ in handles.values()],
            [f"{_style(a)['label']} ({n_text(ns)})" for a, (_, ns) in handles.items()],
            loc="lower center",
            ncol=2,
            fontsize=6,
        )
    _note(fig, note)
    return fig


@styled
def energy_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    """Energy per link length closed, and steps to the target, per agent and target (bars)."""
    rows = [r for r in as_run_rows(rows) if r.target]
    groups = _groups(rows)
    agents = [a for a in _ORDER if any(r.agent == a for r in rows)]
    fig = Figure(figsize=(PAGE_IN, 3.6))
    top, bottom = fig.subplots(2, 1, sharex=True)
    width = 0.8 / max(len(agents), 1)
    for i, agent in enumerate(agents):
        st = _style(agent)
        e, s = [], []
        for g in groups:
            sel = [r for r in rows if r.agent == agent and r.group == g]
            per = [r.energy_per_distance for r in sel if r.energy_per_distance is not None]
            steps = [r.steps_to_target for r in sel if r.steps_to_target is not None]
            e.append(np.mean(per) if per else np.nan)
            s.append(np.mean(steps) if steps else np.nan)
        xs = np.arange(len(groups)) + (i - (len(agents) - 1) / 2) * width
        top.bar(xs, e, width, color=st["color"], label=st["label"])
        bottom.bar(xs, s, width, color=st["color"])
    top.set_yscale("log")
    top.set_ylabel("energy per a closed\n(xi_par a^2 / tau)")
    bottom.set_ylabel("steps to target\n(runs that reached it)")
    bottom.set_xticks(np.arange(len(groups)))
    bottom.set_xticklabels(groups, rotation=20, ha="right", fontsize=6)
    top.legend(fontsize=6, ncol=len(agents))
    _note(fig, note)
    return fig


@styled
def ratio_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    """Still fluid: each agent's time ratio to the swimmer's own optimum per target, the median
    over the runs that reached it with its bootstrap 95 % interval (module docs). The agent
    ``optimal`` is the line at 1, Zermelo's point has no row here (a flow's yardstick)."""
    rows = [r for r in as_run_rows(rows) if r.target]
    groups = _groups(rows)
    # The agents with a ratio (one that never reached the target has none).
    agents = [
        a for a in _ORDER if a != "optimal" and any(r.agent == a and r.time_ratio for r in rows)
    ]
    fig = Figure(figsize=(PAGE_IN if len(groups) > 2 else COLUMN_IN, 2.8))
    ax = fig.subplots()
    width = 0.7 / max(len(agents), 1)
    labels = []
    handles = []
    for i, agent in enumerate(agents):
        cells = [ratio_cell([r for r in rows if r.agent == agent and r.group == g]) for g in groups]
        xs = np.arange(len(groups)) + (i - (len(agents) - 1) / 2) * width
        st = _style(agent)
        # Targets are categories, not a trend: markers and intervals, never a line between them.
        handles.append(draw_series(ax, xs, cells, st, bool(i % 2), agent, join=False))
        runs = [len([r for r in rows if r.agent == agent and r.group == g]) for g in groups]
        labels.append(f"{st['label']} ({n_text(runs)})")
    ax.axhline(1.0, color=OPTIMUM_STYLE["color"], lw=0.9, zorder=1)
    handles.append(Line2D([], [], color=OPTIMUM_STYLE["color"], lw=0.9))
    labels.append(f"{OPTIMUM_STYLE['label']} = 1")
    ax.set_xticks(np.arange(len(groups)))
    ax.set_xticklabels(groups, rotation=20, ha="right", fontsize=6)
    ax.set_ylabel(
        "steps / the swimmer's least\n(median of the runs that\nreached it, 95% interval)"
    )
    ratio_axes([ax])
    ax.set_title("still fluid: time to the target over the swimmer's own optimum")
    ax.legend(handles, labels, fontsize=6, ncol=2 if len(labels) > 3 else 1)
    _note(fig, note)
    return fig


def has_optimum(rows: Sequence[Any]) -> bool:
    """Whether the rows carry the swimmer's own optimum (``optimal_steps``: a folder of jswim
    from the issue-60 rows on)."""
    return any(r.optimal_steps is not None for r in rows)


def nav_figures(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> dict[str, Figure]:
    """The navigation study's figures by file name, in `jswim.studies.kinds.navigate.FIGURE_ORDER` (none without
    navigation rows). The still-fluid ratio figure is for a study without a flow (a flow's is
    `jswim.figures.flow_plots.flow_ratio_figure`) whose rows carry the optimum."""
    rows = [r for r in as_run_rows(rows) if r.target]
    if not rows:
        return {}
    out = {}
    if not any(r.flow for r in rows) and has_optimum(rows):
        out["navigate-ratio"] = ratio_figure(rows, note)
    if any(_bearing(r) is not None for r in rows):
        out["navigate-bearing"] = bearing_figure(rows, note)
    out["navigate-energy"] = energy_figure(rows, note)
    out["navigate-paths"] = paths_figure(rows, note)
    return out
