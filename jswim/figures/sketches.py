"""Sketches of a swimmer's shape and of a stroke cycle drawn on its shapes."""

from __future__ import annotations

from typing import Any
from collections.abc import Mapping, Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from jswim.figures.panels import panel_rows, panel_keys
from jswim.figures.style import (
    PAGE_IN,
    styled,
)
from jswim.swimmers.models import SwimmerModel
from jswim.results import as_run_rows
from jswim.swimmers.outline import outline

# -- swimmer sketches -------------------------------------------------------------------------


def shape_points(model: SwimmerModel, d: Sequence[float]) -> np.ndarray:
    """Body-frame outline of a shape: link end points ``(N+1, 2)`` or sphere centres ``(N, 2)``
    ([`jswim.swimmers.outline.outline`][jswim.swimmers.outline.outline], the pictures' one outline)."""
    return outline(model, d)


def draw_shape(
    ax: Any,
    model: SwimmerModel,
    d: Sequence[float],
    origin: tuple[float, float] = (0, 0),
    scale: float = 1.0,
    color: str = "k",
) -> None:
    """Draw one swimmer shape (links as a polyline, spheres as circles) at ``origin``."""
    pts = shape_points(model, d) * scale + np.asarray(origin)
    if model.planar:
        ax.plot(pts[:, 0], pts[:, 1], "-", color=color, lw=2.0, solid_capstyle="round")
        ax.plot(pts[1:-1, 0], pts[1:-1, 1], "o", color=color, ms=2.5)
    else:
        ax.plot(pts[:, 0], pts[:, 1], "-", color=color, lw=0.8)
        for p in pts:
            ax.add_patch(plt.Circle(p, scale, fc="white", ec=color, lw=1.0))


def draw_cycle(
    ax: Any,
    model: SwimmerModel,
    start: Sequence[int],
    moves: Sequence[tuple[int, int]],
    title: str | None = None,
    color: str = "#0072B2",
) -> None:
    """Sketch a stroke cycle: the start shape (in ``color``, the learner's) and the shape after each
    move, left to right, with the moves between them."""
    levels = list(start)
    shapes = [list(levels)]
    for dof, roc in moves:
        if roc:
            levels[dof - 1] = 1 if roc > 0 else 0
        shapes.append(list(levels))
    # Room between sketches: a sphere swimmer at full arms is hi * n_dof + 2 radii long, and a row
    # of them is so flat that a label under it would overlap the spheres: the move's label sits in
    # the gap between two shapes, on their axis, and the gap is wide enough to hold it.
    span = 4.0 if model.planar else model.hi * model.n_dof + 24
    label_y = -2.2 if model.planar else 0.0
    for i, lv in enumerate(shapes):
        d = [model.lo + (model.hi - model.lo) * v for v in lv]
        draw_shape(ax, model, d, origin=(i * span, 0.0), color=color if i == 0 else "k")
        if i < len(moves):
            dof, roc = moves[i]
            # The move between two sketches, in the prompt's [DOF, ROC] notation.
            ax.annotate(
                f"[{dof}, {roc}]",
                (i * span + span / 2, label_y),
                ha="center",
                va="center",
                fontsize=6,
                color="0.3",
                bbox=dict(fc="white", ec="none", pad=0.3) if not model.planar else None,
            )
    ax.set_xlim(-span / 2, (len(shapes) - 0.5) * span)
    ax.set_ylim(label_y - 0.8 if model.planar else -2.0, 2.0)
    ax.set_aspect("equal")
    ax.axis("off")
    if title:
        ax.set_title(title, fontsize=7)


def learned_cycles(
    rows: Sequence[Mapping[str, Any]],
) -> dict[tuple[str, int], tuple[list[int], list[tuple[int, int]], str]]:
    """The stroke cycle to sketch per panel: the earliest learner's, the LLM's first if it learned one.

    Returns ``{(swimmer, direction): (levels at the cycle's start, moves, agent)}`` for the
    panels where some run met the success criterion.
    """
    rows = as_run_rows(rows)
    out = {}
    for sw, d in panel_keys(rows):
        ok = [r for r in panel_rows(rows, sw, d) if r.success and r.steps_to_learn is not None]
        if not ok:
            continue
        r = min(ok, key=lambda r: ({"llm": 0, "qlearning": 1}.get(r.agent, 2), r.steps_to_learn))
        s, acts = r.steps_to_learn - 1, [tuple(a) for a in r.actions]  # 1-based count -> index
        levels = [1 if ch == "+" else 0 for ch in r.init]
        for dof, roc in acts[:s]:
            if roc:
                levels[dof - 1] = 1 if roc > 0 else 0
        out[(sw, d)] = (levels, acts[s : s + r.period], r.agent)
    return out


@styled
def gaits_figure(model: SwimmerModel, cycles: Sequence[Any], top: int = 4) -> Figure:
    """The best closed stroke cycles of a swimmer, with their displacement per step."""
    shown = list(cycles)[:top]
    fig, axes = plt.subplots(
        len(shown),
        1,
        figsize=(PAGE_IN, 0.95 * len(shown) + 0.4),
        squeeze=False,
        layout="constrained",
    )
    for ax, cyc in zip(axes[:, 0], shown):
        draw_cycle(
            ax,
            model,
            cyc.start,
            cyc.moves,
            title=f"period {cyc.period}: X/a per step = {cyc.per_step:+.5f}",
        )
    fig.suptitle(f"best stroke cycles of the {model.label} swimmer", fontsize=8)
    return fig
