"""Learning curves: X/a against the execution step per agent, with the signature gait from step 0
as the upper bound."""

from __future__ import annotations

import functools
from collections import defaultdict
from typing import Any
from collections.abc import Mapping, Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from jswim.figures.panels import (
    group_by,
    displacement_label,
    legend_frame,
    draw_legend,
    mark_unfinished,
    in_order,
    panel_title,
    panel_rows,
    panel_keys,
    target_displacement,
)
from jswim.figures.sketches import draw_cycle
from jswim.figures.style import (
    AGENT_STYLE,
    REFERENCE_STYLE,
    styled,
)
from jswim.results.orders import AGENT_ORDER, SWIMMER_ORDER
from jswim.swimmers.models import SwimmerModel, make_model
from jswim.results import as_run_rows

# -- reference: the signature gait from step 0 ---------------------------------------------------


@functools.lru_cache(maxsize=64)
def _signature_path(
    swimmer: str, direction: int, init: tuple[int, ...], steps: int
) -> tuple[float, ...] | None:
    """Target-direction X/a after 0..steps steps of the best closed cycle started from ``init``.

    ``None`` when the best cycle does not pass through ``init`` (then no run from there can
    follow it from step 0).
    """
    from jswim import (
        env,
    )  # lazy: JAX only when a reference line is drawn
    from jswim.judging import gait  # lazy: as above

    model = make_model(swimmer)
    cyc = gait.best_cycles(model, direction)[0]
    levels = list(cyc.start)
    corners = []
    for dof, roc in cyc.moves:
        corners.append(tuple(levels))
        if roc:
            levels[dof - 1] = 1 if roc > 0 else 0
    if tuple(init) not in corners:
        return None
    k = corners.index(tuple(init))
    moves = list(cyc.moves[k:] + cyc.moves[:k])
    actions = (moves * (steps // len(moves) + 1))[:steps]
    r = env.rollout_moves(swimmer, actions, init=list(init), direction=direction)
    return (0.0, *(float(direction * v) for v in np.asarray(r.x)))


def signature_reference(rows: Sequence[Mapping[str, Any]]) -> np.ndarray | None:
    """Mean target-direction X/a the runs of one panel would reach with the signature gait from step 0.

    The upper bound of a mean curve: every run from its own start following the swimmer's best
    closed stroke cycle ([`jswim.judging.gait.best_cycles`][jswim.judging.gait.best_cycles]) from the first step. ``None`` if some
    start is not on that cycle or the swimmer is unknown.
    """
    rows = as_run_rows(rows)
    if not rows:
        return None
    steps = max(len(r.x) for r in rows)
    paths = []
    for r in rows:
        init = r.init
        if not isinstance(init, str) or set(init) - {"+", "-"}:
            return None
        try:
            p = _signature_path(
                r.swimmer, int(r.direction or 1), tuple(int(c == "+") for c in init), steps
            )
        except Exception:  # unknown swimmer or model: no reference, not a broken figure
            return None
        if p is None:
            return None
        paths.append(p)
    return np.mean(np.asarray(paths), axis=0)


# -- learning curves --------------------------------------------------------------------------


def _marks(n_steps: int, index: int, count: int) -> tuple[int, int]:
    """``markevery`` of series ``index`` of ``count``: markers every ~n/8 steps, staggered."""
    every = max(2, n_steps // 8)
    return (round(index * every / max(count, 1)), every)


def _mean_curve(
    ax: Any,
    rows: Sequence[Mapping[str, Any]],
    index: int,
    count: int,
    *,
    singles: bool,
    lw: float,
    zorder: float,
    **style: Any,
) -> Any:
    rows = as_run_rows(rows)
    xs = target_displacement(rows)
    n = np.arange(xs.shape[1])
    if singles and len(rows) > 1:
        for row in xs[:20]:
            ax.plot(n, row, color=style["color"], alpha=0.18, lw=0.5, zorder=1)
    (line,) = ax.plot(
        n,
        np.nanmean(xs, axis=0),
        lw=lw,
        zorder=zorder,
        markevery=_marks(len(n), index, count),
        mfc="white" if index % 2 else style["color"],
        **style,
    )
    return line


@styled
def curves_figure(
    rows: Sequence[Mapping[str, Any]],
    models: Mapping[str, SwimmerModel] | None = None,
    cycles: Mapping[tuple[str, int], tuple] | None = None,
    note: str | None = None,
    reference: bool = True,
) -> Figure:
    """Target-direction displacement against step n for each agent (paper Fig. 2).

    One panel per swimmer (rows, Purcell first) and target direction (columns): the mean of each
    agent's runs (thick) over up to 20 single runs (thin), and the signature gait from step 0
    ([`signature_reference`][jswim.figures.curves.signature_reference]) as the upper bound. ``cycles`` (see [`learned_cycles`][jswim.figures.sketches.learned_cycles])
    adds a row of stroke-cycle sketches under a swimmer's panels; swimmers with nothing learned
    get none.
    """
    rows = as_run_rows(rows)
    keys = panel_keys(rows)
    swimmers = in_order({k[0] for k in keys}, SWIMMER_ORDER)
    dirs = in_order({k[1] for k in keys}, (1, -1))
    cycles = dict(cycles or {})
    sketch = {sw: any((sw, d) in cycles for d in dirs) for sw in swimmers}
    heights = [h for sw in swimmers for h in ([2.1, 0.65] if sketch[sw] else [2.1])]
    n_agents = len({r.agent for r in rows})
    fig, grid, legend_ax, row = legend_frame(heights, len(dirs), n_agents + int(reference), most=2)
    handles: dict[str, Any] = {}
    counts: dict[str, set[int]] = defaultdict(set)
    for sw in swimmers:
        for j, d in enumerate(dirs):
            ax = fig.add_subplot(grid[row, j])
            sel = panel_rows(rows, sw, d)
            by = group_by(sel, "agent")
            agents = in_order(by, AGENT_ORDER)
            if reference:
                ref = signature_reference(sel)
                if ref is not None:
                    handles["reference"] = ax.plot(
                        np.arange(ref.size), ref, zorder=2, **REFERENCE_STYLE
                    )[0]
            for i, agent in enumerate(agents):
                style = dict(
                    AGENT_STYLE.get(agent, dict(color=f"C{i}", ls="-", marker="o", label=agent))
                )
                # Later agents drawn thinner and on top: a mean hidden under another still shows.
                handles.setdefault(
                    agent,
                    _mean_curve(
                        ax,
                        by[agent],
                        i,
                        len(agents),
                        singles=True,
                        lw=2.0 - 0.45 * i,
                        zorder=3 + i,
                        **style,
                    ),
                )
                counts[agent].add(len(by[agent]))
            ax.axhline(0, color="0.75", lw=0.6, zorder=0)
            ax.set_title(panel_title(sw, d))
            ax.set_xlabel("step n")
            ax.set_ylabel(displacement_label(d))
            if not sel:
                ax.text(0.5, 0.5, "no runs", transform=ax.transAxes, ha="center")
        row += 1
        if sketch[sw]:
            model = (models or {}).get(sw) or make_model(sw)
            for j, d in enumerate(dirs):
                ax = fig.add_subplot(grid[row, j])
                if (sw, d) in cycles:
                    start, moves, *who = cycles[(sw, d)]
                    by_text = (
                        f" by {AGENT_STYLE.get(who[0], dict(label=who[0]))['label']}" if who else ""
                    )
                    draw_cycle(
                        ax,
                        model,
                        start,
                        moves,
                        title=f"stroke cycle learned{by_text}",
                        color=AGENT_STYLE.get(who[0], {}).get("color", "#0072B2")
                        if who
                        else "#0072B2",
                    )
                else:
                    ax.axis("off")
            row += 1
    legend = []
    for agent in in_order([a for a in handles if a != "reference"], AGENT_ORDER):
        h = handles[agent]
        n = counts[agent]
        h.set_label(
            f"{AGENT_STYLE.get(agent, {}).get('label', agent)}, mean of {n.pop()}"
            if len(n) == 1
            else AGENT_STYLE.get(agent, {}).get("label", agent)
        )
        legend.append(h)
    if "reference" in handles:
        legend.append(handles["reference"])
    draw_legend(legend_ax, legend, most=2)
    mark_unfinished(fig, note)
    return fig


@styled
def history_figure(
    rows: Sequence[Mapping[str, Any]], note: str | None = None, reference: bool = True
) -> Figure:
    """Target-direction displacement against step for each history length n_ht (paper Fig. 3).

    One panel per swimmer and target direction (``X/a`` toward +x, ``-X/a`` toward -x). Each
    n_ht has its own colour, marker and line width (the first drawn widest), so equal curves
    stay visible.
    """
    rows = as_run_rows(rows)
    keys = panel_keys(rows)
    swimmers = in_order({k[0] for k in keys}, SWIMMER_ORDER)
    dirs = in_order({k[1] for k in keys}, (1, -1))
    n_hts = sorted({r.n_ht for r in rows}, key=lambda v: (v is None, v))
    markers = "osD^vPX*<>"
    cmap = plt.get_cmap("viridis")
    fig, grid, legend_ax, top = legend_frame(
        [2.1] * len(swimmers), len(dirs), len(n_hts) + int(reference), most=5
    )
    axes = np.array(
        [
            [fig.add_subplot(grid[top + i, j]) for j in range(len(dirs))]
            for i in range(len(swimmers))
        ]
    )
    handles: dict[Any, Any] = {}
    sizes: set[int] = set()
    for i, sw in enumerate(swimmers):
        for j, d in enumerate(dirs):
            ax = axes[i, j]
            sel = panel_rows(rows, sw, d)
            by = group_by(sel, "n_ht")
            if reference:
                ref = signature_reference(sel)
                if ref is not None:
                    handles["reference"] = ax.plot(
                        np.arange(ref.size), ref, zorder=2, **REFERENCE_STYLE
                    )[0]
            for k, h in enumerate(n_hts):
                if h not in by:
                    continue
                style = dict(
                    color=cmap(0.9 * k / max(1, len(n_hts) - 1)),
                    ls="-",
                    marker=markers[k % len(markers)],
                    label=f"n_ht = {h}",
                )
                handles.setdefault(
                    h,
                    _mean_curve(
                        ax,
                        by[h],
                        k,
                        len(n_hts),
                        singles=False,
                        lw=max(0.8, 3.0 - 2.2 * k / max(1, len(n_hts) - 1)),
                        zorder=3 + k,
                        **style,
                    ),
                )
                sizes.add(len(by[h]))
            ax.axhline(0, color="0.75", lw=0.6, zorder=0)
            ax.set_title(panel_title(sw, d))
            ax.set_xlabel("step n")
            ax.set_ylabel(displacement_label(d))
    legend = [handles[h] for h in n_hts if h in handles]
    if len(sizes) == 1 and (n := sizes.pop()) > 1:
        for h in legend:
            h.set_label(f"{h.get_label()} (mean of {n})")
    if "reference" in handles:
        legend.append(handles["reference"])
    draw_legend(legend_ax, legend, most=5)
    mark_unfinished(fig, note)
    return fig
