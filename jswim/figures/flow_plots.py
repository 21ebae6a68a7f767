"""Figures of a navigation study in a background flow (``jswim study navigate --flow KIND``;
docs/navigation.md, *Pictures in a flow*), and the flow drawn under a picture.

Drawn only where the rows carry a flow (`flow_rows`): a still-fluid folder's figures are the
ones [`jswim.figures.navigation_plots`][jswim.figures.navigation_plots] draws, and no more.

``navigate-flow-paths``
    One panel per target (rows) and flow speed (columns): the flow's streamlines under every
    agent's path in its colour, Zermelo's least-time path dashed, the start and the targets with
    their success radius; a target no steerer can reach says so in its panel.
``navigate-flow-success``
    Success rate (top) and steps to the target over Zermelo's least time (below, the runs that
    reached it; 1 is optimal) against the flow speed in units of the swimming speed, one line
    per agent, one column per target. Flow speeds where Zermelo cannot reach the target are
    hatched and labelled ``unreachable``: no agent can, so a 0 there is not a failure to learn.
``navigate-flow-energy``
    Energy per ``a`` closed on the target against the flow speed, one line per agent, one
    column per target (the same hatching).

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
from jswim.figures.navigation_plots import ZERMELO_STYLE, agent_order, agent_style, target_points
from jswim.figures.style import COLUMN_IN, NOTE_COLOR, PAGE_IN, styled
from jswim.results import as_run_rows

__all__ = [
    "FLOW_COLOR",
    "draw_flow",
    "flow_energy_figure",
    "flow_field",
    "flow_figures",
    "flow_label",
    "flow_of",
    "flow_paths_figure",
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


def _agents(rows: Sequence[Any]) -> list[str]:
    """The agents that steer (Zermelo is the reference line, not a line of his own)."""
    names = {r.agent for r in rows if r.agent != "zermelo"}
    return sorted(names, key=agent_order)


def _per_fraction(rows: Sequence[Any], agent: str, value: Any) -> tuple[list[float], list[float]]:
    """``(fractions, means)`` of ``value(row)`` (None: left out) over the agent's rows."""
    by: dict[float, list[float]] = {}
    for r in rows:
        if r.agent == agent:
            v = value(r)
            by.setdefault(float(r.flow_fraction or 0.0), [])
            if v is not None and math.isfinite(v):
                by[float(r.flow_fraction or 0.0)].append(float(v))
    fs = sorted(by)
    return fs, [float(np.mean(by[f])) if by[f] else np.nan for f in fs]


def _columns_figure(n: int, nrows: int, height: float) -> tuple[Figure, np.ndarray]:
    fig = Figure(figsize=(PAGE_IN if n > 1 else COLUMN_IN, height))
    return fig, fig.subplots(nrows, n, squeeze=False, sharex="col")


def _legend(fig: Figure, axes: np.ndarray, hatched: bool) -> None:
    seen: dict[str, Any] = {}
    for ax in axes.flat:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            seen.setdefault(lab, h)
    if hatched:
        seen["unreachable (Zermelo cannot reach the target)"] = Patch(
            facecolor="none", edgecolor=UNREACHABLE_COLOR, hatch="///", alpha=0.6
        )
    fig.legend(seen.values(), seen.keys(), loc="lower center", ncol=min(len(seen), 3), fontsize=6)


def _target_panels(
    rows: Sequence[Mapping[str, Any]], nrows: int, height: float
) -> tuple[Figure, np.ndarray, list[str], list[float], list[tuple[str, list[Any]]]]:
    """One column of panels per target: the figure, its axes, the agents that steer, the flow
    speeds (fractions of v) and each target's name and rows."""
    rows = flow_rows(rows)
    targets = _targets(rows)
    fig, axes = _columns_figure(len(targets), nrows, height)
    fractions = sorted({float(r.flow_fraction or 0.0) for r in rows})
    cells = [(name, [r for r in rows if _target_name(r) == name]) for name in targets]
    return fig, axes, _agents(rows), fractions, cells


def _line(st: Mapping[str, Any], i: int) -> dict[str, Any]:
    """An agent's line and markers (every other agent's hollow, so that coinciding ones show)."""
    return dict(
        color=st["color"], ls=st["ls"], marker=st["marker"], mfc="none" if i % 2 else st["color"]
    )


def _finish_axis(ax: Any, fractions: Sequence[float], sel: Sequence[Any]) -> bool:
    """Hatch the speeds where the target is unreachable and set the speed axis; whether any was
    hatched."""
    hatched = _hatch_unreachable(ax, fractions, _unreachable(sel))
    _xlim(ax, fractions)
    return hatched


@styled
def flow_success_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    """Success rate and time over Zermelo's against the flow speed, per agent (module docs)."""
    fig, axes, agents, fractions, cells = _target_panels(rows, 2, 4.4)
    hatched = False
    for j, (name, sel) in enumerate(cells):
        span = (max(fractions) - min(fractions)) or 1.0
        top, bottom = axes[0, j], axes[1, j]
        for i, agent in enumerate(agents):
            st = agent_style(agent)
            # Agents a little apart along x, so that equal rates stay visible side by side.
            shift = (i - (len(agents) - 1) / 2) * 0.012 * span
            fs, rate = _per_fraction(sel, agent, lambda r: float(bool(r.reached)))
            top.plot(
                [f + shift for f in fs],
                rate,
                **_line(st, i),
                label=st["label"],
            )
            fs, ratio = _per_fraction(sel, agent, lambda r: r.time_ratio)
            bottom.plot(
                [f + shift for f in fs],
                ratio,
                **_line(st, i),
            )
        bottom.axhline(
            1.0, color=ZERMELO_STYLE["color"], ls="--", lw=0.9, label="Zermelo (least time)"
        )
        for ax in (top, bottom):
            hatched |= _finish_axis(ax, fractions, sel)
        top.set_ylim(-0.05, 1.05)
        top.set_title(name)
        bottom.set_ylim(bottom=0.0)
        bottom.set_xlabel("flow / swim speed")
        if j == 0:
            top.set_ylabel("success rate")
            bottom.set_ylabel("steps / Zermelo's least\n(runs that reached it)")
    _legend(fig, axes, hatched)
    fig.subplots_adjust(bottom=0.2, hspace=0.25, wspace=0.3)
    _note(fig, note)
    return fig


@styled
def flow_energy_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    """Energy per ``a`` closed against the flow speed, per agent (module docs)."""
    fig, axes, agents, fractions, cells = _target_panels(rows, 1, 2.6)
    hatched = False
    for j, (name, sel) in enumerate(cells):
        ax = axes[0, j]
        drawn = False
        for i, agent in enumerate(agents):
            st = agent_style(agent)
            fs, e = _per_fraction(sel, agent, lambda r: r.energy_per_distance)
            if all(not np.isfinite(v) for v in e):
                continue
            drawn = True
            ax.plot(
                fs,
                e,
                **_line(st, i),
                label=st["label"],
            )
        if drawn:
            ax.set_yscale("log")
        hatched |= _finish_axis(ax, fractions, sel)
        ax.set_title(name)
        ax.set_xlabel("flow / swim speed")
        if j == 0:
            ax.set_ylabel("energy per a closed\n(xi_par a^2 / tau)")
    _legend(fig, axes, hatched)
    fig.subplots_adjust(bottom=0.36, wspace=0.3)
    _note(fig, note)
    return fig


def flow_figures(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> dict[str, Figure]:
    """The flow figures by file name; none where no row ran in a flow (a still-fluid folder)."""
    rows = flow_rows(rows)
    if not rows:
        return {}
    return {
        "navigate-flow-paths": flow_paths_figure(rows, note),
        "navigate-flow-success": flow_success_figure(rows, note),
        "navigate-flow-energy": flow_energy_figure(rows, note),
    }
