"""Figures of a navigation study in a background flow (``jswim study navigate --flow KIND``;
docs/navigation.md, *Pictures in a flow*), and the flow drawn under a picture.

Drawn only where the rows carry a flow (`flow_rows`): a still-fluid folder's figures are the
ones [`jswim.figures.navigation_plots`][jswim.figures.navigation_plots] draws, and no more.
In order of importance (`jswim.studies.kinds.navigate.FIGURE_ORDER`); every panel's
title names the flow (``uniform flow``), one panel per target (its group without the flow):

``navigate-flow-ratio``
    The result: steps to the target over the swimmer's own least time (``time_ratio``, the
    agent ``optimal``'s steps; 1 is optimal) against the flow speed in units of the swimming
    speed, the median over the runs that reached it with its bootstrap 95 % interval, one series
    per agent; Zermelo's point (no turning limit, the flow taken at its centre) as its own
    dashed line, his least time over the swimmer's (below 1: he turns at once). A folder
    written before the optimum draws the ratio to Zermelo's time instead, and says so.
``navigate-flow-success``
    Success rate against the flow speed with Wilson 95 % intervals, one series per agent.
    Flow speeds where Zermelo cannot reach the target are hatched and labelled
    ``unreachable``: no agent can, so a 0 there is not a failure to learn.
``navigate-flow-energy``
    Energy per ``a`` closed on the target (the mean over the cell's runs) against the flow
    speed, one series per agent (the same hatching).
``navigate-flow-paths``
    One panel per target (rows) and flow speed (columns): the flow's streamlines under every
    agent's path in its colour, Zermelo's least-time path dashed, the start and the targets with
    their success radius; a target no steerer can reach says so in its panel.

Every series shows its runs per cell in the legend (``n=16``) and joins two flow speeds by a
line only where both cells hold at least
`jswim.figures.navigation_plots.MIN_LINE_RUNS` runs
([`draw_series`][jswim.figures.navigation_plots.draw_series]).

`flow_of`, `flow_text`, `flow_field` and `draw_flow` are the pictures' one reading of a row's
flow: the report page's arrows and ``jswim animate``'s streamlines come from them too.
"""

from __future__ import annotations

import json
import math
import re
from typing import Any
from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patches import Patch

from jswim.env.flows import SWIM_SPEED, Flow, Poiseuille, Shear, TaylorGreen, Uniform
from jswim.env.flows import flow_from_dict
from jswim.errors import ConfigError
from jswim.figures.navigation_plots import (
    OPTIMUM_STYLE,
    ZERMELO_STYLE,
    agent_order,
    agent_style,
    draw_series,
    has_optimum,
    n_text,
    ratio_axes,
    ratio_cell,
    success_cell,
    target_points,
)
from jswim.figures.style import COLUMN_IN, NOTE_COLOR, PAGE_IN, styled
from jswim.results import as_run_rows

__all__ = [
    "FLOW_COLOR",
    "draw_flow",
    "flow_energy_figure",
    "flow_field",
    "flow_figures",
    "flow_label",
    "flow_name",
    "flow_of",
    "flow_paths_figure",
    "flow_ratio_figure",
    "flow_rows",
    "flow_success_figure",
    "flow_text",
]

#: Streamlines and arrows of a background flow: a muted blue that sits under the agents' colours
#: (the page's canvas draws its arrows in it too).
FLOW_COLOR = "#7EA6C8"
#: Hatching of flow speeds at which no steerer reaches the target.
UNREACHABLE_COLOR = NOTE_COLOR


def flow_of(raw: str | None) -> Flow | None:
    """The flow of a row's ``flow`` column (canonical JSON); ``None`` for still fluid, a row
    without one, or a record this version cannot read (its picture then draws no flow)."""
    if not raw:
        return None
    try:
        return flow_from_dict(json.loads(raw))
    except (ValueError, TypeError, ConfigError):
        return None


def flow_label(flow: Flow | None, fraction: float | None) -> str:
    """A short name for a panel or a legend: ``"uniform 0.9 v"``, ``"still fluid"``."""
    if flow is None or not flow.speed:
        return "still fluid" if fraction in (None, 0) else f"{fraction:g} v"
    f = flow.speed / SWIM_SPEED if fraction is None else fraction
    return f"{flow.kind} {f:g} v"


def flow_text(flow: Flow | None) -> str:
    """What the flow is, in one line with its numbers (``a / step``): ``"uniform stream
    u = (0, 0.043) a/step"``; ``"still fluid"`` for none or a flow of speed 0."""
    if flow is None or not flow.speed:
        return "still fluid (flow speed 0)"
    fraction = f"{flow.speed / SWIM_SPEED:.3g} of the swimming speed v = {SWIM_SPEED:.4f} a/step"
    if isinstance(flow, Uniform):
        what = f"uniform stream u = ({flow.u[0]:.3g}, {flow.u[1]:.3g}) a/step"
    elif isinstance(flow, Shear):
        what = f"simple shear u = ({flow.rate:.3g} y, 0) a/step (speed at |y| = 1 a)"
    elif isinstance(flow, Poiseuille):
        what = (
            f"Poiseuille channel along x, u_max = {flow.u_max:.3g} a/step on y = 0, "
            f"walls at y = \u00b1{flow.half_width:g} a"
        )
    elif isinstance(flow, TaylorGreen):
        what = f"Taylor-Green vortex cells {flow.cell:g} a square, u0 = {flow.u0:.3g} a/step"
    else:
        what = f"{flow.kind} flow, speed {flow.speed:.3g} a/step"
    return f"{what}; {fraction}"


def flow_field(
    flow: Flow, box: Sequence[float], n: int = 24
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The flow's velocity on a regular grid over ``box = (x0, x1, y0, y1)`` (``a``): ``X, Y, U,
    V``, each ``(ny, nx)``, with ``n`` points along the longer side (``a / step``)."""
    x0, x1, y0, y1 = (float(v) for v in box)
    w, h = max(x1 - x0, 1e-9), max(y1 - y0, 1e-9)
    nx = max(2, round(n * w / max(w, h)))
    ny = max(2, round(n * h / max(w, h)))
    X, Y = np.meshgrid(np.linspace(x0, x1, nx), np.linspace(y0, y1, ny))
    uv = np.asarray(flow.velocity(np.stack([X, Y], axis=-1)), np.float64)
    return X, Y, uv[..., 0], uv[..., 1]


def draw_flow(
    ax: Any,
    flow: Flow | None,
    box: Sequence[float],
    zorder: float = 0.5,
    density: float = 0.5,
    arrowsize: float = 0.5,
) -> list[Any]:
    """Draw the flow's streamlines over ``box`` on ``ax`` (under the paths: ``zorder``; ``density``
    and ``arrowsize`` as matplotlib's ``streamplot``); a uniform stream's are straight, parallel
    and evenly spaced. Returns the artists (none for still fluid).
    """
    if flow is None or not flow.speed:
        return []
    X, Y, U, V = flow_field(flow, box, 40)
    speed = np.hypot(U, V)
    if not np.any(speed > 1e-12 * flow.speed):
        return []
    before = set(ax.patches)
    s = ax.streamplot(
        X,
        Y,
        U,
        V,
        density=density,
        color=FLOW_COLOR,
        linewidth=0.5,
        arrowsize=arrowsize,
        broken_streamlines=False,
        zorder=zorder,
    )
    # The arrowheads are the axes' own patches (``s.arrows`` is a collection never drawn).
    return [s.lines] + [p for p in ax.patches if p not in before]


def flow_rows(rows: Sequence[Mapping[str, Any]]) -> list[Any]:
    """The navigation rows that ran in a flow (a ``flow`` column; a speed of 0 counts: it is the
    study's still-fluid reference)."""
    return [r for r in as_run_rows(rows) if r.target and r.flow]


def _target_name(r: Any) -> str:
    """The row's target, its group without the flow suffix (``", uniform 0.9v"``)."""
    return re.sub(r", [a-z-]+ [0-9.e+-]+v$", "", str(r.group or "")) or str(r.target)


def _flow_key(r: Any) -> tuple[float, str]:
    return (float(r.flow_fraction or 0.0), str(r.flow))


def _targets(rows: Sequence[Any]) -> list[str]:
    return list(dict.fromkeys(_target_name(r) for r in rows))


def _unreachable(rows: Sequence[Any]) -> set[float]:
    """Flow speeds (fractions) at which Zermelo's steerer cannot reach the target."""
    return {float(r.flow_fraction or 0.0) for r in rows if r.reachable is False}


def _note(fig: Figure, note: str | None) -> None:
    if note:
        fig.suptitle(note, color=NOTE_COLOR, fontsize=7)


def _xy(r: Any) -> tuple[np.ndarray, np.ndarray]:
    xs = np.concatenate([[0.0], np.asarray(r.x or [], float)])
    ys = np.concatenate([[0.0], np.asarray(r.y or [0.0] * len(r.x or []), float)])
    return xs, ys


def _box(
    rows: Sequence[Any], pad: float = 1.0, aspect: float = 1.0
) -> tuple[float, float, float, float]:
    """A box holding every path and target of ``rows`` (and the start), ``pad`` around, widened
    or heightened about its centre to at least ``aspect`` (width over height) and at most 2: a
    long path still leaves its panel room for the flow beside it."""
    pts = [np.zeros((1, 2))]
    for r in rows:
        xs, ys = _xy(r)
        pts.append(np.stack([xs, ys], axis=-1))
        way, track = target_points(r.target, len(r.x or []))
        radius = float(json.loads(r.target).get("radius", 0.25))
        pts += [way + radius, way - radius, track.reshape(-1, 2)]
    p = np.concatenate(pts)
    p = p[np.all(np.isfinite(p), axis=1)]
    lo, hi = p.min(axis=0) - pad, p.max(axis=0) + pad
    (cx, cy), (w, h) = (lo + hi) / 2, hi - lo
    w, h = max(w, aspect * h), max(h, w / (2 * aspect))
    return float(cx - w / 2), float(cx + w / 2), float(cy - h / 2), float(cy + h / 2)


def _circle(xy: tuple[float, float], radius: float, **kw: Any) -> Any:
    from matplotlib.patches import Circle

    return Circle(xy, radius, **kw)


@styled
def flow_paths_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    """Paths over the flow's streamlines, one panel per target and flow speed (module docs)."""
    rows = flow_rows(rows)
    targets = _targets(rows)
    flows = sorted({_flow_key(r) for r in rows})
    ncols, nrows = len(flows), len(targets)
    height = 2.3 * nrows + 0.6
    fig = Figure(figsize=(PAGE_IN if ncols > 1 else COLUMN_IN, height))
    axes = fig.subplots(nrows, ncols, squeeze=False)
    for i, name in enumerate(targets):
        sel = [r for r in rows if _target_name(r) == name]
        box = _box(sel)  # one box per target: its flow speeds compare at a glance
        for j, key in enumerate(flows):
            ax = axes[i, j]
            cell = [r for r in sel if _flow_key(r) == key]
            flow = flow_of(key[1])
            draw_flow(ax, flow, box)
            if cell:
                _draw_cell(ax, cell)
            if any(r.reachable is False for r in cell):
                ax.text(
                    0.5,
                    0.97,
                    "unreachable:\nno steerer gets there",
                    transform=ax.transAxes,
                    ha="center",
                    va="top",
                    fontsize=6,
                    color=UNREACHABLE_COLOR,
                    bbox=dict(fc="white", ec="none", alpha=0.85, pad=1.0),
                    zorder=6,
                )
            ax.set_xlim(box[0], box[1])
            ax.set_ylim(box[2], box[3])
            ax.set_aspect("equal", adjustable="box")
            ax.set_title(f"{name}\n{flow_label(flow, key[0])}", fontsize=7)
            ax.set_xlabel("x / a")
            if j == 0:
                ax.set_ylabel("y / a")
    seen: dict[str, Any] = {}
    for ax in axes.flat:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            seen.setdefault(lab, h)
    if any(flow_of(k[1]) is not None and flow_of(k[1]).speed for k in flows):
        seen["flow streamlines"] = Line2D([], [], color=FLOW_COLOR, lw=0.8)
    fig.legend(seen.values(), seen.keys(), loc="lower center", ncol=min(len(seen), 4), fontsize=6)
    fig.subplots_adjust(bottom=0.75 / height, top=1 - 0.3 / height, hspace=0.55, wspace=0.3)
    _note(fig, note)
    return fig


def _draw_cell(ax: Any, cell: Sequence[Any]) -> None:
    """One panel's paths (every agent, Zermelo's dashed), targets and start."""
    longest = max(len(r.x or []) for r in cell)
    pts, track = target_points(cell[0].target, longest)
    radius = float(json.loads(cell[0].target).get("radius", 0.25))
    for r in sorted(cell, key=lambda r: agent_order(r.agent)):
        st = agent_style(r.agent)
        xs, ys = _xy(r)
        lw = 1.1 if r.agent == "zermelo" else 0.9
        ax.plot(xs, ys, color=st["color"], ls=st["ls"], lw=lw, label=st["label"], zorder=3)
        ax.plot(xs[-1:], ys[-1:], marker=st["marker"], color=st["color"], ms=3, zorder=3)
    for k, (px, py) in enumerate(pts, 1):
        ax.add_patch(
            _circle((px, py), radius, edgecolor="#B00000", facecolor="none", lw=0.8, zorder=4)
        )
        ax.plot([px], [py], marker="x", color="#B00000", ms=4, zorder=4)
        if len(pts) > 1:
            ax.annotate(str(k), (px, py), xytext=(3, 3), textcoords="offset points", fontsize=6)
    if len(track):
        ax.plot(track[:, 0], track[:, 1], ls=":", color="#B00000", lw=0.8, zorder=4)
    ax.plot([0], [0], marker="*", color="black", ms=5, zorder=5)


def _half_gap(fractions: Sequence[float]) -> float:
    """Half the smallest step between the study's flow speeds (0.1 for a single one)."""
    gaps = np.diff(sorted(set(fractions)))
    return float(gaps.min()) / 2 if len(gaps) else 0.1


def _xlim(ax: Any, fractions: Sequence[float]) -> None:
    """Every panel over the study's flow speeds, whichever of them its lines reach."""
    half = _half_gap(fractions)
    ax.set_xlim(min(fractions) - half, max(fractions) + half)


def _hatch_unreachable(ax: Any, fractions: Sequence[float], bad: set[float]) -> bool:
    """Hatch the flow speeds in ``bad`` (half-way to their neighbours) and label them; whether any
    was."""
    half = _half_gap(list(fractions) + list(bad))
    for f in sorted(bad):
        ax.axvspan(
            f - half,
            f + half,
            facecolor="none",
            edgecolor=UNREACHABLE_COLOR,
            hatch="///",
            lw=0,
            alpha=0.45,
            zorder=0.5,
        )
        ax.text(
            f,
            0.5,
            "unreachable",
            transform=ax.get_xaxis_transform(),
            rotation=90,
            ha="center",
            va="center",
            fontsize=6,
            color=UNREACHABLE_COLOR,
            bbox=dict(fc="white", ec="none", pad=0.5, alpha=0.8),
            zorder=6,
        )
    return bool(bad)


def _agents(rows: Sequence[Any], skip: tuple[str, ...] = ("zermelo",)) -> list[str]:
    """The agents that steer, in the figures' order (Zermelo is the reference line, not a
    series of his own; ``skip`` leaves others out too)."""
    names = {r.agent for r in rows if r.agent not in skip}
    return sorted(names, key=agent_order)


def _finish_axis(ax: Any, fractions: Sequence[float], sel: Sequence[Any]) -> bool:
    """Hatch the speeds where the target is unreachable and set the speed axis; whether any was
    hatched."""
    hatched = _hatch_unreachable(ax, fractions, _unreachable(sel))
    _xlim(ax, fractions)
    return hatched


def flow_name(rows: Sequence[Any]) -> str:
    """The study's flow for a title: ``"uniform flow"`` (the kinds of the rows that ran in a
    moving fluid; ``"still fluid"`` where none did: its reference of speed 0 is recorded as a
    uniform stream of 0)."""
    kinds = []
    for r in rows:
        f = flow_of(r.flow) if float(r.flow_fraction or 0.0) else None
        if f is not None and f.speed and f.kind not in kinds:
            kinds.append(f.kind)
    return " and ".join(kinds) + " flow" if kinds else "still fluid"


def _cells(
    rows: Sequence[Any], agent: str, fractions: Sequence[float], cell: Any
) -> list[tuple[float, float, float, int]]:
    """``cell(runs)`` (`success_cell`, `ratio_cell`, ...) of the agent's runs at each flow
    speed; a speed without runs is ``(nan, nan, nan, 0)``."""
    out = []
    for f in fractions:
        runs = [r for r in rows if r.agent == agent and float(r.flow_fraction or 0.0) == f]
        out.append(cell(runs) if runs else (math.nan, math.nan, math.nan, 0))
    return out


def _mean_cell(value: Any) -> Any:
    """A cell of the mean of ``value(row)`` over the runs where it is finite (no interval)."""

    def cell(runs: Sequence[Any]) -> tuple[float, float, float, int]:
        vs = [float(v) for v in map(value, runs) if v is not None and math.isfinite(v)]
        m = float(np.mean(vs)) if vs else math.nan
        return (m, m, m, len(runs))

    return cell


def _zermelo_ratio(rows: Sequence[Any], fractions: Sequence[float]) -> list[float]:
    """Zermelo's least time over the swimmer's own at each flow speed (nan where either is
    missing): the same for every row of a cell, read from the first that has both."""
    out = []
    for f in fractions:
        both = [
            r.zermelo_steps / r.optimal_steps
            for r in rows
            if float(r.flow_fraction or 0.0) == f and r.zermelo_steps and r.optimal_steps
        ]
        out.append(float(both[0]) if both else math.nan)
    return out


def _panel_grid(n: int, row_in: float, legend_in: float) -> tuple[Figure, np.ndarray]:
    """``n`` panels three to a row (the extra ones hidden), ``legend_in`` inches below them for
    the legend."""
    cols = min(max(n, 1), 3)
    nrows = math.ceil(max(n, 1) / cols)
    height = row_in * nrows + legend_in + 0.4  # and the title's
    fig = Figure(figsize=(PAGE_IN if cols > 1 else COLUMN_IN, height))
    axes = fig.subplots(nrows, cols, squeeze=False)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    fig.subplots_adjust(
        bottom=(legend_in + 0.35) / height, top=1 - 0.75 / height, hspace=0.75, wspace=0.3
    )
    return fig, axes


def _legend(fig: Figure, entries: Mapping[str, Any], hatched: bool, ncol: int = 3) -> None:
    seen = dict(entries)
    if hatched:
        seen["unreachable (Zermelo cannot reach the target)"] = Patch(
            facecolor="none", edgecolor=UNREACHABLE_COLOR, hatch="///", alpha=0.6
        )
    fig.legend(
        seen.values(), seen.keys(), loc="lower center", ncol=min(len(seen), ncol), fontsize=6
    )


def _series_panels(
    rows: Sequence[Mapping[str, Any]],
    cell: Any,
    *,
    skip: tuple[str, ...] = ("zermelo",),
    bars: bool = True,
    row_in: float = 2.1,
) -> tuple[Figure, list[tuple[Any, list[Any]]], list[float], dict[str, Any], bool]:
    """One panel per target, each agent's series of ``cell`` against the flow speed (agents a
    little apart along it, so that equal values stay visible side by side), the unreachable
    speeds hatched and the panel titled with its target and flow. Returns the figure, each
    panel's axes and rows, the flow speeds, the legend's entries (each agent with its runs per
    cell) and whether any speed was hatched."""
    rows = flow_rows(rows)
    agents = _agents(rows, skip)
    fractions = sorted({float(r.flow_fraction or 0.0) for r in rows})
    targets = _targets(rows)
    legend_in = 0.25 + 0.14 * math.ceil((len(agents) + 3) / 3)
    fig, axes = _panel_grid(len(targets), row_in, legend_in)
    span = (max(fractions) - min(fractions)) or 1.0
    flow = flow_name(rows)
    panels, runs_of, handles, hatched = [], {a: [] for a in agents}, {}, False
    for ax, name in zip(axes.flat, targets):
        sel = [r for r in rows if _target_name(r) == name]
        for i, agent in enumerate(agents):
            shift = (i - (len(agents) - 1) / 2) * 0.022 * span
            cells = _cells(sel, agent, fractions, cell)
            xs = [f + shift for f in fractions]
            h = draw_series(ax, xs, cells, agent_style(agent), bool(i % 2), agent, bars)
            handles.setdefault(agent, h)
            runs_of[agent] += [
                len([r for r in sel if r.agent == agent and float(r.flow_fraction or 0) == f])
                for f in fractions
            ]
        hatched |= _finish_axis(ax, fractions, sel)
        ax.set_title(f"{name}\n{flow}")
        ax.set_xlabel("flow / swim speed")
        panels.append((ax, sel))
    for ax in axes[:, 0]:
        ax.set_ylabel(" ")  # filled by the caller
    entries = {
        f"{agent_style(a)['label']} ({n_text(runs_of[a])})": handles[a]
        for a in agents
        if a in handles
    }
    return fig, panels, fractions, entries, hatched


@styled
def flow_ratio_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    """Time over the swimmer's own optimum against the flow speed, per agent, with bootstrap
    95 % intervals and Zermelo's point's ratio as its own line (module docs)."""
    rows = flow_rows(rows)
    own = has_optimum(rows)
    field = "time_ratio" if own else "zermelo_ratio"  # an older folder: Zermelo's yardstick
    # Zermelo is his own line, the optimum the line at 1; an agent that never reached the
    # target has no ratio (the success figure shows it).
    none = tuple({r.agent for r in rows} - {r.agent for r in rows if getattr(r, field)})
    fig, panels, fractions, entries, hatched = _series_panels(
        rows, lambda runs: ratio_cell(runs, field), skip=("zermelo", "optimal", *none)
    )
    for ax, sel in panels:
        ax.axhline(1.0, color=OPTIMUM_STYLE["color"], lw=0.9, zorder=1)
        if own:
            ax.plot(
                fractions,
                _zermelo_ratio(sel, fractions),
                color=ZERMELO_STYLE["color"],
                ls="--",
                marker=ZERMELO_STYLE["marker"],
                lw=0.9,
                zorder=2,
                gid="zermelo-ratio",
            )
    ratio_axes([ax for ax, _ in panels])
    who = "the swimmer's own least time" if own else "Zermelo's point's least time"
    for ax, _ in panels[::3]:
        ax.set_ylabel(
            "steps / swimmer's least\n(median, 95% interval)"
            if own
            else "steps / Zermelo's least\n(median, 95% interval)"
        )
    one = OPTIMUM_STYLE["label"] if own else f"{ZERMELO_STYLE['label']} (older folder: no optimum)"
    entries[f"{one} = 1"] = Line2D([], [], color=OPTIMUM_STYLE["color"], lw=0.9)
    if own:  # his time over the swimmer's: below 1, he turns at once and feels the flow at a point
        entries[ZERMELO_STYLE["label"]] = Line2D(
            [], [], color=ZERMELO_STYLE["color"], ls="--", marker=ZERMELO_STYLE["marker"], lw=0.9
        )
    _legend(fig, entries, hatched, ncol=2)
    _title(fig, f"Time to the target over {who} (runs that reached it)", note)
    return fig


@styled
def flow_success_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    """Success rate against the flow speed with Wilson 95 % intervals, per agent (module docs)."""
    fig, panels, _, entries, hatched = _series_panels(rows, success_cell)
    for ax, _sel in panels:
        ax.set_ylim(-0.05, 1.05)
    for ax, _ in panels[::3]:
        ax.set_ylabel("success rate\n(Wilson 95% interval)")
    _legend(fig, entries, hatched)
    _title(fig, "Success rate (runs that reached the target in its budget)", note)
    return fig


@styled
def flow_energy_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    """Energy per ``a`` closed against the flow speed, per agent (module docs)."""
    fig, panels, _, entries, hatched = _series_panels(
        rows, _mean_cell(lambda r: r.energy_per_distance), bars=False
    )
    for ax, _sel in panels:
        if any(ln.get_gid() and ln.get_gid().startswith("points:") for ln in ax.get_lines()):
            ax.set_yscale("log")
    for ax, _ in panels[::3]:
        ax.set_ylabel("energy per a closed\n(xi_par a^2 / tau)")
    _legend(fig, entries, hatched)
    _title(fig, "Energy per a closed on the target (mean of the cell's runs)", note)
    return fig


def _title(fig: Figure, title: str, note: str | None) -> None:
    """The figure's title, with an unfinished study's note under it in red."""
    fig.suptitle(title, fontsize=8, y=0.995, va="top")
    if note:
        fig.text(0.5, 0.955, note, color=NOTE_COLOR, fontsize=7, ha="center", va="top")


def flow_figures(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> dict[str, Figure]:
    """The flow figures by file name, in the order of importance; none where no row ran in a
    flow (a still-fluid folder)."""
    rows = flow_rows(rows)
    if not rows:
        return {}
    return {
        "navigate-flow-ratio": flow_ratio_figure(rows, note),
        "navigate-flow-success": flow_success_figure(rows, note),
        "navigate-flow-energy": flow_energy_figure(rows, note),
        "navigate-flow-paths": flow_paths_figure(rows, note),
    }
