"""Figures of the navigation study (``jswim study navigate``; docs/navigation.md).

Same conventions as [`jswim.figures.plots`][jswim.figures.plots] (paper sizes, the agents'
palette, ``note`` across the top of an unfinished study's figures); chosen by
[`jswim.figures.plots.study_figures`][jswim.figures.plots.study_figures].

``navigate-paths``
    One panel per target: every agent's centroid path in the plane (link lengths), the start, the
    target(s) with their success radius (a moving target's track as a dotted line from its
    start to where it was at the longest run's end).
``navigate-bearing``
    Success rate against the fixed targets' bearing, one line per agent (one panel per distance,
    and in a background flow per flow speed).
``navigate-energy``
    Energy per link length closed on the target, per agent and target (bars; the runs that closed
    any distance), and steps to the target below.

A study in a background flow (``--flow``) adds the flow figures of
`jswim.figures.flow_plots`; Zermelo's least-time path is drawn
dashed (`ZERMELO_STYLE`) wherever a path is.
"""

from __future__ import annotations

import json
import math
from typing import Any
from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure

from jswim.figures.style import AGENT_STYLE, COLUMN_IN, NOTE_COLOR, PAGE_IN, styled
from jswim.results import as_run_rows

__all__ = [
    "CONTROLLER_STYLE",
    "ZERMELO_STYLE",
    "agent_order",
    "agent_style",
    "bearing_figure",
    "energy_figure",
    "nav_figures",
    "paths_figure",
    "target_points",
]

#: The steering controller's line (the reference stroke of navigation).
CONTROLLER_STYLE = dict(color="black", ls="-", marker="x", label="steering controller")
#: Navigation's PPO is the categorical learner over the K-level action codes
#: ([`jswim.studies.navigate.nav_ppo_config`][jswim.studies.navigate.nav_ppo_config]), not the
#: continuous study's real-ROC one.
NAV_PPO_STYLE = {**AGENT_STYLE["ppo"], "label": "PPO (categorical, K-level codes)"}
#: Zermelo's optimal point steerer (in a flow, docs/navigation.md): the least-time reference,
#: dashed so that an agent's path drawn on it stays visible.
ZERMELO_STYLE = dict(color="#CC79A7", ls="--", marker="+", label="Zermelo (least time)")
_STYLES = {
    **AGENT_STYLE,
    "ppo": NAV_PPO_STYLE,
    "controller": CONTROLLER_STYLE,
    "zermelo": ZERMELO_STYLE,
}

#: Bearing offset between neighbouring agents' points in the bearing figure (degrees), so that
#: agents with the same success rate stay visible side by side.
BEARING_DODGE = 3.0
_ORDER = ("llm", "qlearning", "ppo", "controller", "random")


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
    fig.legend(seen.values(), seen.keys(), loc="lower center", ncol=len(seen), fontsize=6)
    fig.subplots_adjust(bottom=0.32 / (nrows + 0.4), hspace=0.55, wspace=0.35)
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
    if n <= 2:  # one or two distances in still fluid: a column each
        fig = Figure(figsize=(COLUMN_IN * n, 2.4))
        axes = fig.subplots(1, n, squeeze=False)[0]
    else:  # several flow speeds: three to a row across the page
        nrows = math.ceil(n / 3)
        fig = Figure(figsize=(PAGE_IN, 2.4 * nrows))
        axes = list(fig.subplots(nrows, 3, squeeze=False).ravel())
        for ax in axes[n:]:
            ax.set_visible(False)
        fig.subplots_adjust(hspace=0.6, wspace=0.35)
    agents = [a for a in _ORDER if any(r.agent == a for r in rows)]
    for ax, (d, flow) in zip(axes, panels):
        for i, agent in enumerate(agents):
            shift = (i - (len(agents) - 1) / 2) * BEARING_DODGE
            by: dict[float, list[bool]] = {}
            for r in rows:
                dist, b = _bearing(r)
                if r.agent == agent and dist == d and _flow_of(r) == flow:
                    by.setdefault(b, []).append(bool(r.reached))
            bs = sorted(by)
            st = _style(agent)
            ax.plot(
                [b + shift for b in bs],
                [np.mean(by[b]) for b in bs],
                color=st["color"],
                ls=st["ls"],
                marker=st["marker"],
                mfc="none" if i % 2 else st["color"],
                label=st["label"],
            )
        ax.set_title(f"targets {d:g} a away" + flow[1])
        ax.set_xlabel(
            f"bearing (degrees; agents {BEARING_DODGE:g} degrees apart)"
            if n <= 2
            else f"bearing (deg; agents {BEARING_DODGE:g} apart)"
        )
        ax.set_ylabel("success rate")
        ax.set_ylim(-0.05, 1.05)
    if panels:
        axes[0].legend(fontsize=6)
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


def nav_figures(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> dict[str, Figure]:
    """The navigation study's figures by file name (none without navigation rows)."""
    rows = [r for r in as_run_rows(rows) if r.target]
    if not rows:
        return {}
    out = {"navigate-paths": paths_figure(rows, note), "navigate-energy": energy_figure(rows, note)}
    if any(_bearing(r) is not None for r in rows):
        out["navigate-bearing"] = bearing_figure(rows, note)
    return out
