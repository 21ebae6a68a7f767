"""Figures of the studies (matplotlib; PNG and PDF), sized for a paper's columns.

Every figure function takes the tidy run rows of a study (one dict per run, as in
``runs.jsonl``) and returns a ``matplotlib.figure.Figure``; :func:`save` writes it as PNG and
PDF, and :func:`study_figures` picks a study's figures. The rules every figure keeps:

- **One panel per swimmer and target direction.** Displacement is plotted in the target
  direction (``X/a`` toward +x, ``-X/a`` toward -x, as in the paper's Fig. 3), and runs with
  opposite targets are never averaged together.
- **Agents on shared axes**, told apart by colour (a colour-blind-safe palette), line style and
  marker; series that coincide stay visible (markers at staggered steps, later series drawn
  thinner on top).
- **Paper sizes**: 3.4 in wide for one column of panels, 7 in for two (the single- and
  double-column widths of Phys. Rev.), 7-8 pt text; PNG at 300 dpi and vector PDF.
- A figure of an unfinished study says so in red across its top (``note``).

Units are the paper's dimensionless ones: displacement ``X/a`` (``a`` = link length or sphere
radius) against the execution step ``n``.
"""

from __future__ import annotations

import functools
import math
import os
from collections import defaultdict
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from jswim.agents.variants import VARIANTS
from jswim.overview import AGENT_ORDER, SWIMMER_ORDER  # noqa: F401  (the reading order of tables and panels)
from jswim.results import unfinished_note, writing  # noqa: F401  (unfinished_note: its old home)
from jswim.judging.stats import learn_stats, mean_interval, wilson_interval
from jswim.swimmers.models import SwimmerModel, make_model

from jswim.figures.scenes import scene_figures
from jswim.figures.style import (  # noqa: F401  (the style's old home)
    AGENT_STYLE, COLUMN_IN, NOTE_COLOR, PAGE_IN, RC, REFERENCE_STYLE, _styled, tidy,
)


def save(fig: Figure, folder: str | os.PathLike, name: str, dpi: int = 300) -> list[Path]:
    """Write ``fig`` as ``name.png`` (``dpi``) and ``name.pdf`` in ``folder``; returns the paths.

    Each file is written to a temporary name and moved into place, so a kill never leaves half a
    figure.

    Raises
    ------
    StudyFolderError
        When ``folder`` cannot be written (read-only, a file in the way); one line.
    """
    folder = Path(folder)
    paths = []
    try:
        with writing(folder, "choose a writable folder"), plt.rc_context(RC):
            folder.mkdir(parents=True, exist_ok=True)
            for ext in ("png", "pdf"):
                path = folder / f"{name}.{ext}"
                tmp = folder / f".{name}.tmp.{ext}"
                try:
                    fig.savefig(tmp, dpi=dpi, bbox_inches="tight", pad_inches=0.03, format=ext)
                    os.replace(tmp, path)
                except BaseException:
                    tmp.unlink(missing_ok=True)
                    raise
                paths.append(path)
    finally:
        plt.close(fig)
    return paths


# -- grouping ---------------------------------------------------------------------------------


def _order(values: Iterable[Any], order: Sequence[Any]) -> list[Any]:
    vals = set(values)
    return [v for v in order if v in vals] + sorted(vals - set(order), key=str)


def panel_keys(rows: Iterable[Mapping[str, Any]]) -> list[tuple[str, int]]:
    """The ``(swimmer, direction)`` panels of ``rows``: Purcell first, +x before -x."""
    rows = list(rows)
    swimmers = _order({r["swimmer"] for r in rows}, SWIMMER_ORDER)
    dirs = _order({int(r.get("direction", 1)) for r in rows}, (1, -1))
    present = {(r["swimmer"], int(r.get("direction", 1))) for r in rows}
    return [(s, d) for s in swimmers for d in dirs if (s, d) in present]


def _by(rows: Iterable[Mapping[str, Any]], key: str) -> dict[Any, list[Mapping[str, Any]]]:
    out: dict[Any, list[Mapping[str, Any]]] = defaultdict(list)
    for r in rows:
        out[r.get(key)].append(r)
    return dict(out)


def _select(rows: Iterable[Mapping[str, Any]], swimmer: str, direction: int) -> list[Mapping[str, Any]]:
    return [r for r in rows if r["swimmer"] == swimmer and int(r.get("direction", 1)) == direction]


def _dir_text(direction: int) -> str:
    return "+x" if direction > 0 else "\u2212x"


def _disp_label(direction: int) -> str:
    """The paper's axis label: X/a toward +x, -X/a toward -x."""
    return "X/a" if direction > 0 else "\u2212X/a"


def _swimmer_label(swimmer: str) -> str:
    try:
        return make_model(swimmer).label
    except Exception:  # an unknown name still gets a panel
        return swimmer


def _panel_title(swimmer: str, direction: int) -> str:
    return f"{_swimmer_label(swimmer)}, target {_dir_text(direction)}"


def target_displacement(rows: Sequence[Mapping[str, Any]]) -> np.ndarray:
    """Displacement in each run's target direction, ``direction * X/a``, shape ``(runs, steps + 1)``.

    Column 0 is the start (0); shorter runs are padded with NaN.
    """
    n = max((len(r["x"]) for r in rows), default=0)
    out = np.full((len(rows), n + 1), np.nan)
    for i, r in enumerate(rows):
        out[i, 0] = 0.0
        out[i, 1: len(r["x"]) + 1] = np.asarray(r["x"], float) * int(r.get("direction", 1))
    return out


def _mark_unfinished(fig: Figure, note: str | None) -> None:
    if note:
        fig.suptitle(note, color=NOTE_COLOR, fontsize=8, fontweight="bold")


def _legend_cols(width: float, entries: int, most: int = 3) -> int:
    return max(1, min(entries, most if width > COLUMN_IN + 0.1 else 2))


def _frame(heights: Sequence[float], n_cols: int, legend_entries: int,
           most: int = 3) -> tuple[Figure, Any, Any, int]:
    """A figure of panel rows ``heights`` (inches) under a legend row spanning every column.

    The legend gets its own row of the grid (not constrained layout's "outside" legend, which
    collides with a suptitle), so the note of an unfinished study sits above it. Returns the
    figure, its grid, the legend's (blank) axes and the grid row of the first panel row.
    """
    width = _width(n_cols)
    lines = math.ceil(legend_entries / _legend_cols(width, legend_entries, most)) if legend_entries else 0
    top = 0.14 * lines + 0.04 if lines else 0.0
    fig = plt.figure(figsize=(width, sum(heights) + top), layout="constrained")
    grid = fig.add_gridspec(len(heights) + (1 if lines else 0), n_cols,
                            height_ratios=([top] if lines else []) + list(heights))
    legend_ax = None
    if lines:
        legend_ax = fig.add_subplot(grid[0, :])
        legend_ax.axis("off")
    return fig, grid, legend_ax, 1 if lines else 0


def _legend(legend_ax: Any, handles: Sequence[Any], most: int = 3) -> None:
    if legend_ax is None or not handles:
        return
    width = legend_ax.figure.get_figwidth()
    legend_ax.legend(handles=list(handles), loc="center", ncol=_legend_cols(width, len(handles), most),
                     handlelength=2.6, columnspacing=1.2, borderaxespad=0.0, borderpad=0.0)


def _width(n_cols: int) -> float:
    return COLUMN_IN if n_cols <= 1 else PAGE_IN


# -- reference: the signature gait from step 0 ---------------------------------------------------


@functools.lru_cache(maxsize=64)
def _signature_path(swimmer: str, direction: int, init: tuple[int, ...], steps: int) -> tuple[float, ...] | None:
    """Target-direction X/a after 0..steps steps of the best closed cycle started from ``init``.

    ``None`` when the best cycle does not pass through ``init`` (then no run from there can
    follow it from step 0).
    """
    from jswim import env  # lazy: JAX only when a reference line is drawn (jswim.overview imports plots)
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
    r = env.rollout(swimmer, actions, init=list(init), direction=direction)
    return (0.0, *(float(direction * v) for v in np.asarray(r.x)))


def signature_reference(rows: Sequence[Mapping[str, Any]]) -> np.ndarray | None:
    """Mean target-direction X/a the runs of one panel would reach with the signature gait from step 0.

    The upper bound of a mean curve: every run from its own start following the swimmer's best
    closed stroke cycle (:func:`jswim.judging.gait.best_cycles`) from the first step. ``None`` if some
    start is not on that cycle or the swimmer is unknown.
    """
    if not rows:
        return None
    steps = max(len(r["x"]) for r in rows)
    paths = []
    for r in rows:
        init = r.get("init")
        if not isinstance(init, str) or set(init) - {"+", "-"}:
            return None
        try:
            p = _signature_path(r["swimmer"], int(r.get("direction", 1)), tuple(int(c == "+") for c in init), steps)
        except Exception:  # unknown swimmer or model: no reference, not a broken figure
            return None
        if p is None:
            return None
        paths.append(p)
    return np.mean(np.asarray(paths), axis=0)


# -- swimmer sketches -------------------------------------------------------------------------


def shape_points(model: SwimmerModel, d: Sequence[float]) -> np.ndarray:
    """Body-frame outline of a shape: link end points ``(N+1, 2)`` or sphere centres ``(N, 2)``."""
    d = np.asarray(d, float)
    if model.planar:
        n = d.size + 1
        m = (n - 1) // 2
        cum = np.concatenate([[0.0], np.cumsum(d)])
        phi = cum - cum[m]
        t = np.stack([np.cos(phi), np.sin(phi)], -1)
        joints = np.concatenate([[np.zeros(2)], np.cumsum(t, axis=0)])
        return joints - joints.mean(axis=0)
    x = np.concatenate([[0.0], np.cumsum(d)])
    return np.stack([x - x.mean(), np.zeros_like(x)], -1)


def draw_shape(ax: Any, model: SwimmerModel, d: Sequence[float], origin: tuple[float, float] = (0, 0),
               scale: float = 1.0, color: str = "k") -> None:
    """Draw one swimmer shape (links as a polyline, spheres as circles) at ``origin``."""
    pts = shape_points(model, d) * scale + np.asarray(origin)
    if model.planar:
        ax.plot(pts[:, 0], pts[:, 1], "-", color=color, lw=2.0, solid_capstyle="round")
        ax.plot(pts[1:-1, 0], pts[1:-1, 1], "o", color=color, ms=2.5)
    else:
        ax.plot(pts[:, 0], pts[:, 1], "-", color=color, lw=0.8)
        for p in pts:
            ax.add_patch(plt.Circle(p, scale, fc="white", ec=color, lw=1.0))


def draw_cycle(ax: Any, model: SwimmerModel, start: Sequence[int], moves: Sequence[tuple[int, int]],
               title: str | None = None, color: str = "#0072B2") -> None:
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
            ax.annotate(f"[{dof}, {roc}]", (i * span + span / 2, label_y), ha="center", va="center", fontsize=6,
                        color="0.3", bbox=dict(fc="white", ec="none", pad=0.3) if not model.planar else None)
    ax.set_xlim(-span / 2, (len(shapes) - 0.5) * span)
    ax.set_ylim(label_y - 0.8 if model.planar else -2.0, 2.0)
    ax.set_aspect("equal")
    ax.axis("off")
    if title:
        ax.set_title(title, fontsize=7)


def learned_cycles(rows: Sequence[Mapping[str, Any]]) -> dict[tuple[str, int], tuple[list[int], list[tuple[int, int]], str]]:
    """The stroke cycle to sketch per panel: the earliest learner's, the LLM's first if it learned one.

    Returns ``{(swimmer, direction): (levels at the cycle's start, moves, agent)}`` for the
    panels where some run met the success criterion.
    """
    out = {}
    for sw, d in panel_keys(rows):
        ok = [r for r in _select(rows, sw, d) if r.get("success") and r.get("steps_to_learn") is not None]
        if not ok:
            continue
        r = min(ok, key=lambda r: ({"llm": 0, "qlearning": 1}.get(r["agent"], 2), r["steps_to_learn"]))
        s, acts = r["steps_to_learn"] - 1, [tuple(a) for a in r["actions"]]  # 1-based count -> index
        levels = [1 if ch == "+" else 0 for ch in r["init"]]
        for dof, roc in acts[:s]:
            if roc:
                levels[dof - 1] = 1 if roc > 0 else 0
        out[(sw, d)] = (levels, acts[s: s + r["period"]], r["agent"])
    return out


# -- learning curves --------------------------------------------------------------------------


def _marks(n_steps: int, index: int, count: int) -> tuple[int, int]:
    """``markevery`` of series ``index`` of ``count``: markers every ~n/8 steps, staggered."""
    every = max(2, n_steps // 8)
    return (int(round(index * every / max(count, 1))), every)


def _mean_curve(ax: Any, rows: Sequence[Mapping[str, Any]], index: int, count: int, *, singles: bool,
                lw: float, zorder: float, **style: Any) -> Any:
    xs = target_displacement(rows)
    n = np.arange(xs.shape[1])
    if singles and len(rows) > 1:
        for row in xs[:20]:
            ax.plot(n, row, color=style["color"], alpha=0.18, lw=0.5, zorder=1)
    (line,) = ax.plot(n, np.nanmean(xs, axis=0), lw=lw, zorder=zorder, markevery=_marks(len(n), index, count),
                      mfc="white" if index % 2 else style["color"], **style)
    return line


@_styled
def curves_figure(rows: Sequence[Mapping[str, Any]], models: Mapping[str, SwimmerModel] | None = None,
                  cycles: Mapping[tuple[str, int], tuple] | None = None, note: str | None = None,
                  reference: bool = True) -> Figure:
    """Target-direction displacement against step n for each agent (paper Fig. 2).

    One panel per swimmer (rows, Purcell first) and target direction (columns): the mean of each
    agent's runs (thick) over up to 20 single runs (thin), and the signature gait from step 0
    (:func:`signature_reference`) as the upper bound. ``cycles`` (see :func:`learned_cycles`)
    adds a row of stroke-cycle sketches under a swimmer's panels; swimmers with nothing learned
    get none.
    """
    keys = panel_keys(rows)
    swimmers = _order({k[0] for k in keys}, SWIMMER_ORDER)
    dirs = _order({k[1] for k in keys}, (1, -1))
    cycles = dict(cycles or {})
    sketch = {sw: any((sw, d) in cycles for d in dirs) for sw in swimmers}
    heights = [h for sw in swimmers for h in ([2.1, 0.65] if sketch[sw] else [2.1])]
    n_agents = len({r["agent"] for r in rows})
    fig, grid, legend_ax, row = _frame(heights, len(dirs), n_agents + int(reference), most=2)
    handles: dict[str, Any] = {}
    counts: dict[str, set[int]] = defaultdict(set)
    for sw in swimmers:
        for j, d in enumerate(dirs):
            ax = fig.add_subplot(grid[row, j])
            sel = _select(rows, sw, d)
            by = _by(sel, "agent")
            agents = _order(by, AGENT_ORDER)
            if reference:
                ref = signature_reference(sel)
                if ref is not None:
                    handles["reference"] = ax.plot(np.arange(ref.size), ref, zorder=2, **REFERENCE_STYLE)[0]
            for i, agent in enumerate(agents):
                style = dict(AGENT_STYLE.get(agent, dict(color=f"C{i}", ls="-", marker="o", label=agent)))
                # Later agents drawn thinner and on top: a mean hidden under another still shows.
                handles.setdefault(agent, _mean_curve(ax, by[agent], i, len(agents), singles=True,
                                                      lw=2.0 - 0.45 * i, zorder=3 + i, **style))
                counts[agent].add(len(by[agent]))
            ax.axhline(0, color="0.75", lw=0.6, zorder=0)
            ax.set_title(_panel_title(sw, d))
            ax.set_xlabel("step n")
            ax.set_ylabel(_disp_label(d))
            if not sel:
                ax.text(0.5, 0.5, "no runs", transform=ax.transAxes, ha="center")
        row += 1
        if sketch[sw]:
            model = (models or {}).get(sw) or make_model(sw)
            for j, d in enumerate(dirs):
                ax = fig.add_subplot(grid[row, j])
                if (sw, d) in cycles:
                    start, moves, *who = cycles[(sw, d)]
                    by_text = f" by {AGENT_STYLE.get(who[0], dict(label=who[0]))['label']}" if who else ""
                    draw_cycle(ax, model, start, moves, title=f"stroke cycle learned{by_text}",
                               color=AGENT_STYLE.get(who[0], {}).get("color", "#0072B2") if who else "#0072B2")
                else:
                    ax.axis("off")
            row += 1
    legend = []
    for agent in _order([a for a in handles if a != "reference"], AGENT_ORDER):
        h = handles[agent]
        n = counts[agent]
        h.set_label(f"{AGENT_STYLE.get(agent, {}).get('label', agent)}, mean of {n.pop()}" if len(n) == 1
                    else AGENT_STYLE.get(agent, {}).get("label", agent))
        legend.append(h)
    if "reference" in handles:
        legend.append(handles["reference"])
    _legend(legend_ax, legend, most=2)
    _mark_unfinished(fig, note)
    return fig


@_styled
def history_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None, reference: bool = True) -> Figure:
    """Target-direction displacement against step for each history length n_ht (paper Fig. 3).

    One panel per swimmer and target direction (``X/a`` toward +x, ``-X/a`` toward -x). Each
    n_ht has its own colour, marker and line width (the first drawn widest), so equal curves
    stay visible.
    """
    keys = panel_keys(rows)
    swimmers = _order({k[0] for k in keys}, SWIMMER_ORDER)
    dirs = _order({k[1] for k in keys}, (1, -1))
    n_hts = sorted({r.get("n_ht") for r in rows}, key=lambda v: (v is None, v))
    markers = "osD^vPX*<>"
    cmap = plt.get_cmap("viridis")
    fig, grid, legend_ax, top = _frame([2.1] * len(swimmers), len(dirs), len(n_hts) + int(reference), most=5)
    axes = np.array([[fig.add_subplot(grid[top + i, j]) for j in range(len(dirs))] for i in range(len(swimmers))])
    handles: dict[Any, Any] = {}
    sizes: set[int] = set()
    for i, sw in enumerate(swimmers):
        for j, d in enumerate(dirs):
            ax = axes[i, j]
            sel = _select(rows, sw, d)
            by = _by(sel, "n_ht")
            if reference:
                ref = signature_reference(sel)
                if ref is not None:
                    handles["reference"] = ax.plot(np.arange(ref.size), ref, zorder=2, **REFERENCE_STYLE)[0]
            for k, h in enumerate(n_hts):
                if h not in by:
                    continue
                style = dict(color=cmap(0.9 * k / max(1, len(n_hts) - 1)), ls="-", marker=markers[k % len(markers)],
                             label=f"n_ht = {h}")
                handles.setdefault(h, _mean_curve(ax, by[h], k, len(n_hts), singles=False,
                                                  lw=max(0.8, 3.0 - 2.2 * k / max(1, len(n_hts) - 1)),
                                                  zorder=3 + k, **style))
                sizes.add(len(by[h]))
            ax.axhline(0, color="0.75", lw=0.6, zorder=0)
            ax.set_title(_panel_title(sw, d))
            ax.set_xlabel("step n")
            ax.set_ylabel(_disp_label(d))
    legend = [handles[h] for h in n_hts if h in handles]
    if len(sizes) == 1 and (n := sizes.pop()) > 1:
        for h in legend:
            h.set_label(f"{h.get_label()} (mean of {n})")
    if "reference" in handles:
        legend.append(handles["reference"])
    _legend(legend_ax, legend, most=5)
    _mark_unfinished(fig, note)
    return fig


# -- statistics against a grid (noise levels, sentences removed, starts) ------------------------


def _stats(g: Sequence[Mapping[str, Any]]) -> tuple[float, float, float, float, float, float]:
    """``p, p_lo, p_hi`` (Wilson 95%) and ``mean, lo, hi`` (bootstrap 95%) of target-direction X/a."""
    k = sum(bool(r["success"]) for r in g)
    lo, hi = wilson_interval(k, len(g))
    m, mlo, mhi = mean_interval([r["signed_final_x"] for r in g])
    return k / len(g), lo, hi, m, mlo, mhi


def _errorbars(ax: Any, x: np.ndarray, y: Sequence[float], lo: Sequence[float], hi: Sequence[float],
               connect: bool, **style: Any) -> Any:
    y, lo, hi = (np.asarray(v, float) for v in (y, lo, hi))
    # Intervals never come out negative; at p = 0 rounding can give -1e-17.
    err = [np.maximum(0.0, y - lo), np.maximum(0.0, hi - y)]
    return ax.errorbar(x, y, yerr=err, color=style["color"], marker=style["marker"], ls=style["ls"] if connect else "none",
                       mfc="white" if style.get("hollow") else style["color"], elinewidth=0.8, capsize=2,
                       label=style["label"], zorder=3)


def _learn_points(ax: Any, x: np.ndarray, stats: Sequence[Any], connect: bool, style: Mapping[str, Any]) -> None:
    """Median steps to learn with its IQR where some runs learned, each point labelled k/n; a
    value where none learned gets its "0/n" on the axis (no point: there is no median)."""
    have = [i for i, st in enumerate(stats) if st.learned]
    if have:
        _errorbars(ax, x[have], [stats[i].median for i in have], [stats[i].q25 for i in have],
                   [stats[i].q75 for i in have], connect, **style)
    tallest = max([stats[i].q75 for i in have] + [1.0])
    ax.set_ylim(0, max(ax.get_ylim()[1] if have else 0.0, tallest * 1.3))  # room for the labels above the bars
    for xi, st in zip(x, stats):
        y = st.q75 if st.learned else 0.0
        ax.annotate(f"{st.learned}/{st.n}", (xi, y), xytext=(0, 3), textcoords="offset points", ha="center",
                    va="bottom", fontsize=5, color=style["color"])


@_styled
def grid_figure(rows: Sequence[Mapping[str, Any]], key: str, *, order: Sequence[Any] | None = None,
                xlabel: str, numeric: bool = False, tick_labels: Mapping[Any, str] | None = None,
                note: str | None = None, learn: bool = False) -> Figure:
    """Success rate p and mean target-direction X/a against the values of ``key``, per agent.

    For each swimmer (Purcell first) two panels share the x axis, success rate ``p`` (95% Wilson
    interval) above mean ``X/a`` after the last step (95% bootstrap interval); one column per
    target direction. Agents share the axes, offset sideways so their intervals never overlap.
    ``numeric`` places the values of ``key`` on a number line (noise levels), otherwise one slot
    per value in ``order``. ``learn`` adds a panel between them: the median steps to learn with
    its interquartile range over the runs that learned (:func:`jswim.judging.stats.learn_stats`, counted
    from 1), each point labelled "k/n" (k of n runs learned; "0/n" on the axis where none did).
    """
    keys = panel_keys(rows)
    swimmers = _order({k[0] for k in keys}, SWIMMER_ORDER)
    dirs = _order({k[1] for k in keys}, (1, -1))
    values = [v for v in (order or []) if any(r.get(key) == v for r in rows)]
    values += sorted({r.get(key) for r in rows} - set(values), key=lambda v: (str(type(v)), v))
    agents = _order({r["agent"] for r in rows}, AGENT_ORDER)
    pos = {v: (float(v) if numeric else float(i)) for i, v in enumerate(values)}
    span = (max(pos.values()) - min(pos.values())) if len(pos) > 1 else 1.0
    step = span / max(1, len(pos) - 1) if not numeric else min(np.diff(sorted(pos.values())), default=span)
    width = 0.5 * step  # the agents' points of one value spread over half the gap to the next
    offsets = {a: (i - (len(agents) - 1) / 2) * width / max(1, len(agents)) for i, a in enumerate(agents)}
    n_cols = len(dirs)
    per = 3 if learn else 2  # panels per swimmer: p, (steps to learn,) X/a
    fig, grid, legend_ax, top = _frame([1.3] * (per * len(swimmers)), n_cols, len(agents))
    axes = np.empty((per * len(swimmers), n_cols), object)
    for j in range(n_cols):
        for i in range(per * len(swimmers)):
            axes[i, j] = fig.add_subplot(grid[top + i, j], sharex=axes[0, j] if i else None)
            if i < per * len(swimmers) - 1:
                axes[i, j].tick_params(labelbottom=False)
    handles: dict[str, Any] = {}
    counts: dict[str, set[int]] = defaultdict(set)
    for i, sw in enumerate(swimmers):
        for j, d in enumerate(dirs):
            ax_p, ax_x = axes[per * i, j], axes[per * i + per - 1, j]
            ax_l = axes[per * i + 1, j] if learn else None
            sel = _select(rows, sw, d)
            for a_i, agent in enumerate(agents):
                by = _by([r for r in sel if r["agent"] == agent], key)
                vs = [v for v in values if v in by]
                if not vs:
                    continue
                stats = np.array([_stats(by[v]) for v in vs])
                x = np.array([pos[v] for v in vs]) + offsets[agent]
                style = dict(AGENT_STYLE.get(agent, dict(color=f"C{a_i}", ls="-", marker="o", label=agent)))
                handles.setdefault(agent, _errorbars(ax_p, x, stats[:, 0], stats[:, 1], stats[:, 2], numeric, **style))
                _errorbars(ax_x, x, stats[:, 3], stats[:, 4], stats[:, 5], numeric, **style)
                if ax_l is not None:
                    _learn_points(ax_l, x, [learn_stats([r.get("steps_to_learn") for r in by[v]]) for v in vs],
                                  numeric, style)
                counts[agent].update(len(by[v]) for v in vs)
            ax_p.set_ylim(-0.06, 1.06)
            ax_p.set_ylabel("success rate p\n(95% Wilson CI)")
            ax_p.set_title(_panel_title(sw, d))
            ax_x.axhline(0, color="0.75", lw=0.6, zorder=0)
            ax_x.set_ylabel(f"mean {_disp_label(d)}\n(95% bootstrap CI)")
            lo, hi = ax_x.get_ylim()
            if hi - lo < 1e-9:  # all X/a equal (a swimmer that never moved): not an axis of 1e-17 rounding
                ax_x.set_ylim(lo - 0.05, hi + 0.05)
            if ax_l is not None:
                ax_l.set_ylabel("steps to learn\n(median, IQR)")
                ax_l.text(0.99, 0.97, "k/n: runs that learned", transform=ax_l.transAxes, ha="right", va="top",
                          fontsize=5, color="0.4")
            for ax in (ax_p, ax_x) + ((ax_l,) if ax_l is not None else ()):
                ax.grid(axis="y", alpha=0.25, lw=0.5)
    for ax in axes[-1]:
        ax.set_xlabel(xlabel)
        if not numeric:
            labels = [(tick_labels or {}).get(v, str(v)) for v in values]
            rotate = sum(len(t) for t in labels) > (40 if n_cols == 1 else 30)
            ax.set_xticks([pos[v] for v in values], labels, rotation=30 if rotate else 0,
                          ha="right" if rotate else "center")
            ax.set_xlim(-0.6, len(values) - 0.4)
        else:
            ax.set_xticks([pos[v] for v in values], [f"{v:g}" for v in values])
    legend = []
    for agent in agents:
        if agent in handles:
            h = handles[agent]
            n = counts[agent]
            base = AGENT_STYLE.get(agent, {}).get("label", agent)
            h.set_label(f"{base}, n = {n.pop()}" if len(n) == 1 else f"{base}, n = {min(n)}-{max(n)}")
            legend.append(h)
    _legend(legend_ax, legend)
    _mark_unfinished(fig, note)
    return fig


def noise_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    """Success rate p and mean X/a against the noise level zeta (paper Fig. 4)."""
    return grid_figure(rows, "zeta", xlabel="noise level \u03b6", numeric=True, note=note)


def ablation_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    """The full prompt and the prompt without each sentence S1..S5 (paper Fig. 5)."""
    order = ["full"] + [f"-S{i}" for i in range(1, 6)]
    labels = {"full": "full", **{f"-S{i}": f"\u2212S{i}" for i in range(1, 6)}}
    return grid_figure(rows, "group", order=order, tick_labels=labels, xlabel="sentence removed from the prompt",
                       note=note)


def inits_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    """Each of the four initial configurations (signs of D1, D2)."""
    order = [f"init {a}{b}" for a in "+-" for b in "+-"]
    labels = {g: f"({g[5]}, {g[6]})".replace("-", "\u2212") for g in order}
    return grid_figure(rows, "group", order=order, tick_labels=labels,
                       xlabel="initial configuration (signs of D1, D2)", note=note)


@_styled
def competence_figure(rows: Sequence[Mapping[str, Any]], order: Sequence[str], note: str | None = None) -> Figure:
    """Success rate p and mean target-direction X/a per LLM variant and per baseline.

    Rows carry an ``entry`` label (a variant name, or ``"agent (action set)"`` for baselines);
    ``order`` lists the entries top to bottom. One pair of panels per swimmer and target
    direction; horizontal intervals keep long variant names readable, and the dotted line marks
    the random baseline on the paper's action set (all).
    """
    keys = panel_keys(rows)
    n = max(1, len(order))
    fig, axes = plt.subplots(len(keys), 2, figsize=(PAGE_IN, (0.17 * n + 0.75) * len(keys) + 0.3), squeeze=False,
                             layout="constrained")
    for (ax_p, ax_x), (sw, d) in zip(axes, keys):
        by = _by(_select(rows, sw, d), "entry")
        labels = [k for k in order if k in by]
        y = np.arange(len(labels))[::-1]
        for j, k in enumerate(labels):
            g = by[k]
            style = AGENT_STYLE.get(g[0]["agent"], dict(color="C0", marker="o"))
            p, plo, phi, m, mlo, mhi = _stats(g)
            ax_p.errorbar(p, y[j], xerr=[[max(0.0, p - plo)], [max(0.0, phi - p)]], fmt=style["marker"],
                          color=style["color"], capsize=2, elinewidth=0.8)
            ax_x.errorbar(m, y[j], xerr=[[max(0.0, m - mlo)], [max(0.0, mhi - m)]], fmt=style["marker"],
                          color=style["color"], capsize=2, elinewidth=0.8)
        if "random (all)" in by:
            ax_x.axvline(float(np.mean([r["signed_final_x"] for r in by["random (all)"]])), color="0.5", ls=":", lw=0.8)
        ax_p.set_yticks(y, [f"{k} (n={len(by[k])})" for k in labels], fontsize=6)
        ax_x.set_yticks(y, [""] * len(labels))  # the entries are named once, on the left
        ax_x.set_ylim(ax_p.get_ylim())
        for ax in (ax_p, ax_x):
            ax.grid(axis="x", alpha=0.3, lw=0.5)
        ax_p.set_xlim(-0.05, 1.05)
        ax_x.axvline(0, color="0.8", lw=0.6)
        ax_p.set_title(f"{_panel_title(sw, d)}: success rate p", fontsize=7)
        ax_x.set_title(f"{_panel_title(sw, d)}: mean {_disp_label(d)}", fontsize=7)
        ax_p.set_xlabel("p (95% Wilson CI)")
        ax_x.set_xlabel(f"mean {_disp_label(d)} after the last step (95% bootstrap CI)")
    _mark_unfinished(fig, note)
    return fig


@_styled
def gaits_figure(model: SwimmerModel, cycles: Sequence[Any], top: int = 4) -> Figure:
    """The best closed stroke cycles of a swimmer, with their displacement per step."""
    shown = list(cycles)[:top]
    fig, axes = plt.subplots(len(shown), 1, figsize=(PAGE_IN, 0.95 * len(shown) + 0.4), squeeze=False,
                             layout="constrained")
    for ax, cyc in zip(axes[:, 0], shown):
        draw_cycle(ax, model, cyc.start, cyc.moves,
                   title=f"period {cyc.period}: X/a per step = {cyc.per_step:+.5f}")
    fig.suptitle(f"best stroke cycles of the {model.label} swimmer", fontsize=8)
    return fig


# -- a study's figures ------------------------------------------------------------------------


def study_figures(study: str, rows: Sequence[Mapping[str, Any]], note: str | None = None) -> dict[str, Figure]:
    """The figures of ``study`` from its run rows, by file name (without extension).

    ``note`` (e.g. ``"unfinished: 12 of 40 runs"``) is written across the top of each.
    """
    if not rows:
        return {}
    if study in ("curves", "swim"):
        return {study: curves_figure(rows, cycles=learned_cycles(rows), note=note)}
    if study == "history":
        return {"history": history_figure(rows, note=note)}
    if study == "noise":
        return {"noise": noise_figure(rows, note=note)}
    if study == "ablation":
        return {"ablation": ablation_figure(rows, note=note)}
    if study == "inits":
        return {"inits": inits_figure(rows, note=note)}
    if study == "temperature":  # p, steps to learn and X/a against the sampling temperature T
        return {"temperature": grid_figure(rows, "temperature", xlabel="sampling temperature T", numeric=True,
                                           note=note, learn=True)}
    if study == "continuous":
        return continuous_figures(rows, note=note)
    if study in ("wall", "pair", "school"):  # walls and pairs (issue 19), schools (issue 34)
        return scene_figures(study, rows, note=note)
    if study == "competence":
        # One entry per LLM variant, then one per baseline (agent, action set).
        entries = [{**r, "entry": r["group"] if r["agent"] == "llm" else f"{r['agent']} ({r['group']})"} for r in rows]
        order = [v for v in VARIANTS if any(e["entry"] == v for e in entries)]
        order += sorted({e["entry"] for e in entries} - set(order))
        return {"competence": competence_figure(entries, order, note=note)}
    return {}


def continuous_figures(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> dict[str, Figure]:
    """The continuous study: success rate p and mean X/a against the ROC lattice K (and real ROCs)
    per agent, and X/a against step n for each lattice (``continuous-K<K>``, ``continuous-real``).

    Stroke sketches are drawn for the paper's lattice (K = 1) only, whose cycles go corner to corner.
    """
    groups = sorted({r["group"] for r in rows}, key=lambda g: (g == "continuous", int(g[2:]) if g[:2] == "K=" else 0))
    labels = {g: ("real" if g == "continuous" else g[2:]) for g in groups}
    figs = {"continuous": grid_figure(rows, "group", order=groups, tick_labels=labels,
                                      xlabel="ROC levels K (real: the continuous RL baseline)", note=note)}
    for g in groups:
        sel = [r for r in rows if r["group"] == g]
        cycles = learned_cycles(sel) if g == "K=1" else None
        figs[f"continuous-{'real' if g == 'continuous' else 'K' + g[2:]}"] = curves_figure(sel, cycles=cycles, note=note)
    return figs
