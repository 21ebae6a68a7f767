"""Figures of the scene studies (extensions of the paper): ``jswim study wall`` and ``jswim study pair``.

Same conventions as [`jswim.figures.plots`][jswim.figures.plots] (paper sizes, the agents' palette, ``note`` across the
top of an unfinished study's figures); chosen by [`jswim.figures.plots.study_figures`][jswim.figures.plots.study_figures].

wall
    ``wall``: the square stroke's displacement per cycle against the starting height (log axis; level starts),
    with the same stroke in the unbounded fluid of the same solver as a line (Purcell's swimmer:
    heights in link lengths, the bulk RFT stroke as the line; one series per swimmer); ``wall-track``:
    height (top) and X/a (bottom) against step for every agent at every height (one colour per
    agent, darker for lower starts).
pair
    ``pair``: the pair's displacement per cycle (both swimmers one square each; their mean x)
    against the phase offset, one line per D, with the lone swimmer's as a line and the agents'
    mean progress per 8 steps (whole runs) as markers at the right; ``pair-track``: X/a against step per agent and D.
school
    ``school``: the school's displacement per cycle (every swimmer one square; their mean x)
    against N, one line per formation and D, the lone swimmer's as a line.
"""

from __future__ import annotations

import json
from typing import Any
from collections.abc import Mapping, Sequence

import numpy as np
from matplotlib.figure import Figure

from jswim.figures.style import AGENT_STYLE, COLUMN_IN, NOTE_COLOR, styled
from jswim.results import as_run_rows

STROKE_STYLE = dict(color="black", ls="-", marker="o", label="square stroke")
_STYLES = {**AGENT_STYLE, "stroke": STROKE_STYLE}


def _note(fig: Figure, note: str | None) -> None:
    if note:
        fig.suptitle(note, color=NOTE_COLOR, fontsize=7)


def _scene_rows(rows: Sequence[Mapping[str, Any]]) -> list[Any]:
    return [r for r in as_run_rows(rows) if r.scene]


def wall_figures(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> dict[str, Figure]:
    """The wall study's figures by file name (none without scene rows)."""
    rows = _scene_rows(rows)
    if not rows:
        return {}
    return {
        "wall": wall_figure(rows, note),
        "wall-track": track_figure(rows, "start_height", note, heights=True),
    }


def pair_figures(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> dict[str, Figure]:
    """The pair study's figures by file name (none without scene rows)."""
    rows = _scene_rows(rows)
    if not rows:
        return {}
    return {
        "pair": pair_figure(rows, note),
        "pair-track": track_figure(rows, "separation", note, heights=False),
    }


def school_figures(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> dict[str, Figure]:
    """The school study's figure (none without scene rows)."""
    rows = _scene_rows(rows)
    return {"school": school_figure(rows, note)} if rows else {}


@styled
def wall_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    rows = as_run_rows(rows)
    fig = Figure(figsize=(COLUMN_IN, 2.4))
    ax = fig.add_subplot()
    kinds = sorted({str(r.swimmer or "ng") for r in rows})
    for sw in kinds:  # NG (a = sphere radius) and Purcell (a = link length)
        tag = f"{sw}, " if len(kinds) > 1 else ""
        for d in sorted(
            {int(r.direction) for r in rows if str(r.swimmer or "ng") == sw}, reverse=True
        ):
            own = [
                r
                for r in rows
                if r.agent == "stroke"
                and str(r.swimmer or "ng") == sw
                and r.per_cycle is not None
                and int(r.direction) == d
            ]
            # the curve is the level starts' (a tilted start's first cycles are another stroke's)
            pts = sorted(
                (r.start_height, d * r.per_cycle)
                for r in own
                if r.start_height and not json.loads(r.scene or "{}").get("tilt")
            )
            if pts:
                h, v = zip(*pts)
                ax.plot(
                    h,
                    v,
                    **{
                        **STROKE_STYLE,
                        "label": f"{tag}square stroke ({'+x' if d > 0 else '-x'}), wall",
                        **(
                            {"marker": "s", "ls": "-."}
                            if sw == "purcell" and len(kinds) > 1
                            else {}
                        ),
                    },
                )
            # the no-wall reference: the same solver without the wall (NG: "free"; Purcell: bulk RFT)
            free = [d * r.per_cycle for r in own if r.medium in ("free", "bulk")]
            if free:
                ax.axhline(
                    float(np.mean(free)),
                    color="0.4",
                    ls="--",
                    lw=0.8,
                    label=f"{tag}same stroke, no wall",
                )
    ax.set_xscale("log")
    ax.set_xlabel("starting height h/a above the wall")
    ax.set_ylabel("X/a per cycle (target direction)")
    ax.legend(loc="best")
    _note(fig, note)
    return fig


@styled
def pair_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    rows = as_run_rows(rows)
    fig = Figure(figsize=(COLUMN_IN, 2.4))
    ax = fig.add_subplot()
    strokes = [r for r in rows if r.agent == "stroke" and r.separation and r.per_cycle is not None]
    for i, dist in enumerate(sorted({r.separation for r in strokes})):
        pts = sorted(
            (int(str(r.variant).removeprefix("phase")), r.direction * r.per_cycle)
            for r in strokes
            if r.separation == dist
        )
        ph, v = zip(*pts)
        ax.plot(
            ph,
            v,
            marker="o",
            ls="-",
            color=str(0.15 + 0.5 * i / max(1, len(strokes))),
            label=f"two strokes, D={dist:g}",
        )
    alone = [
        r.direction * r.per_cycle
        for r in rows
        if r.agent == "stroke" and not r.separation and r.per_cycle is not None
    ]
    if alone:
        ax.axhline(float(np.mean(alone)), color="0.4", ls="--", lw=0.8, label="one swimmer alone")
    agents_at = 4.3  # the agents choose their own phase: a labelled column right of the offsets
    for agent in ("llm", "qlearning", "random", "ppo"):
        got = [8 * r.signed_final_x / r.steps for r in rows if r.agent == agent and r.steps]
        if got:  # 8 steps per joint cycle: the whole run's mean progress per step, times 8
            st = _STYLES[agent]
            ax.plot(
                [agents_at],
                [float(np.mean(got))],
                marker=st["marker"],
                color=st["color"],
                ls="none",
                label=f"{st['label']} (mean, 8 x X/a end / steps)",
            )
    ax.axvline(3.65, color="0.8", lw=0.6)
    ax.set_xticks([0, 1, 2, 3, agents_at], ["0", "1", "2", "3", "agents\n(own phase)"])
    ax.set_xlabel("phase offset (quarter cycles of swimmer 2 ahead)")
    ax.set_ylabel("pair X/a per cycle")
    ax.legend(loc="best", fontsize=6)
    _note(fig, note)
    return fig


@styled
def school_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    rows = as_run_rows(rows)
    fig = Figure(figsize=(COLUMN_IN, 2.4))
    ax = fig.add_subplot()
    strokes = [r for r in rows if r.agent == "stroke" and r.per_cycle is not None]
    alone = [r.direction * r.per_cycle for r in strokes if not r.separation]
    lines: dict[tuple[str, float], list[tuple[int, float]]] = {}
    for r in strokes:
        if r.separation:
            form = json.loads(r.scene).get("formation", "line")
            lines.setdefault((form, r.separation), []).append(
                (int(r.n_swimmers), r.direction * r.per_cycle)
            )
    for i, ((form, dist), pts) in enumerate(sorted(lines.items())):
        n, v = zip(*sorted(pts + ([(1, float(np.mean(alone)))] if alone else [])))
        ax.plot(
            n,
            v,
            marker="o" if form == "line" else "s",
            ls="-" if form == "line" else "--",
            color=str(0.1 + 0.6 * i / max(1, len(lines))),
            label=f"{form}, D={dist:g}",
        )
    if alone:
        ax.axhline(float(np.mean(alone)), color="0.4", ls=":", lw=0.8, label="one swimmer alone")
    ax.set_xticks(sorted({int(r.n_swimmers) for r in strokes}))
    ax.set_xlabel("swimmers N")
    ax.set_ylabel("school X/a per cycle")
    ax.legend(loc="best", fontsize=6)
    _note(fig, note)
    return fig


@styled
def track_figure(
    rows: Sequence[Mapping[str, Any]], key: str, note: str | None = None, *, heights: bool
) -> Figure:
    rows = as_run_rows(rows)
    panels = 2 if heights else 1
    fig = Figure(figsize=(COLUMN_IN, 1.8 * panels + 0.4))
    axes = [fig.add_subplot(panels, 1, i + 1) for i in range(panels)]
    values = sorted({r.get(key) for r in rows if r.get(key) is not None})
    seen: set[str] = set()
    for r in rows:
        if r.get(key) is None:
            continue
        st = _STYLES.get(r.agent, AGENT_STYLE["random"])
        shade = 0.35 + 0.65 * (values.index(r[key]) + 1) / len(values)
        label = st["label"] if r.agent not in seen else None
        seen.add(r.agent)
        steps = np.arange(1, len(r.x) + 1)
        kw = dict(color=st["color"], ls=st["ls"], alpha=shade, lw=0.8, label=label)
        if heights:  # the recorded heights (Purcell's row y is its in-plane y)
            axes[0].plot(steps, [h[0] for h in r.heights] if r.heights else r.y, **kw)
        axes[-1].plot(steps, r.direction * np.asarray(r.x), **kw)
    if heights:
        axes[0].set_yscale("log")
        axes[0].set_ylabel("height h/a")
    axes[-1].set_ylabel("X/a (target direction)")
    axes[-1].set_xlabel("step n")
    axes[0].legend(loc="best", fontsize=6)
    axes[0].set_title(
        ("starting heights " if heights else "distances D ") + ", ".join(f"{v:g}" for v in values)
    )
    _note(fig, note)
    return fig
