"""Statistics against a grid of settings (noise levels, sentences removed, starts, temperature,
competence variants): success rate p, steps to learn and X/a per agent."""

from __future__ import annotations

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
)
from jswim.figures.style import (
    AGENT_STYLE,
    PAGE_IN,
    styled,
)
from jswim.results import as_run_rows
from jswim.judging.stats import learn_stats, mean_interval, wilson_interval
from jswim.results.orders import AGENT_ORDER, SWIMMER_ORDER

# -- statistics against a grid (noise levels, sentences removed, starts) ------------------------


def _stats(g: Sequence[Mapping[str, Any]]) -> tuple[float, float, float, float, float, float]:
    """``p, p_lo, p_hi`` (Wilson 95%) and ``mean, lo, hi`` (bootstrap 95%) of target-direction X/a."""
    k = sum(bool(r.success) for r in g)
    lo, hi = wilson_interval(k, len(g))
    m, mlo, mhi = mean_interval([r.signed_final_x for r in g])
    return k / len(g), lo, hi, m, mlo, mhi


def _errorbars(
    ax: Any,
    x: np.ndarray,
    y: Sequence[float],
    lo: Sequence[float],
    hi: Sequence[float],
    connect: bool,
    **style: Any,
) -> Any:
    y, lo, hi = (np.asarray(v, float) for v in (y, lo, hi))
    # Intervals never come out negative; at p = 0 rounding can give -1e-17.
    err = [np.maximum(0.0, y - lo), np.maximum(0.0, hi - y)]
    return ax.errorbar(
        x,
        y,
        yerr=err,
        color=style["color"],
        marker=style["marker"],
        ls=style["ls"] if connect else "none",
        mfc="white" if style.get("hollow") else style["color"],
        elinewidth=0.8,
        capsize=2,
        label=style["label"],
        zorder=3,
    )


def _learn_points(
    ax: Any, x: np.ndarray, stats: Sequence[Any], connect: bool, style: Mapping[str, Any]
) -> None:
    """Median steps to learn with its IQR where some runs learned, each point labelled k/n; a
    value where none learned gets its "0/n" on the axis (no point: there is no median)."""
    have = [i for i, st in enumerate(stats) if st.learned]
    if have:
        _errorbars(
            ax,
            x[have],
            [stats[i].median for i in have],
            [stats[i].q25 for i in have],
            [stats[i].q75 for i in have],
            connect,
            **style,
        )
    tallest = max([stats[i].q75 for i in have] + [1.0])
    ax.set_ylim(
        0, max(ax.get_ylim()[1] if have else 0.0, tallest * 1.3)
    )  # room for the labels above the bars
    for xi, st in zip(x, stats):
        y = st.q75 if st.learned else 0.0
        ax.annotate(
            f"{st.learned}/{st.n}",
            (xi, y),
            xytext=(0, 3),
            textcoords="offset points",
            ha="center",
            va="bottom",
            fontsize=5,
            color=style["color"],
        )


@styled
def grid_figure(
    rows: Sequence[Mapping[str, Any]],
    key: str,
    *,
    order: Sequence[Any] | None = None,
    xlabel: str,
    numeric: bool = False,
    tick_labels: Mapping[Any, str] | None = None,
    note: str | None = None,
    learn: bool = False,
) -> Figure:
    """Success rate p and mean target-direction X/a against the values of ``key``, per agent.

    For each swimmer (Purcell first) two panels share the x axis, success rate ``p`` (95% Wilson
    interval) above mean ``X/a`` after the last step (95% bootstrap interval); one column per
    target direction. Agents share the axes, offset sideways so their intervals never overlap.
    ``numeric`` places the values of ``key`` on a number line (noise levels), otherwise one slot
    per value in ``order``. ``learn`` adds a panel between them: the median steps to learn with
    its interquartile range over the runs that learned ([`jswim.judging.stats.learn_stats`][jswim.judging.stats.learn_stats], counted
    from 1), each point labelled "k/n" (k of n runs learned; "0/n" on the axis where none did).
    """
    rows = as_run_rows(rows)
    keys = panel_keys(rows)
    swimmers = in_order({k[0] for k in keys}, SWIMMER_ORDER)
    dirs = in_order({k[1] for k in keys}, (1, -1))
    values = [v for v in (order or []) if any(r.get(key) == v for r in rows)]
    values += sorted({r.get(key) for r in rows} - set(values), key=lambda v: (str(type(v)), v))
    agents = in_order({r.agent for r in rows}, AGENT_ORDER)
    pos, offsets = _positions(values, agents, numeric)
    n_cols = len(dirs)
    per = 3 if learn else 2  # panels per swimmer: p, (steps to learn,) X/a
    fig, grid, legend_ax, top = legend_frame([1.3] * (per * len(swimmers)), n_cols, len(agents))
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
            sel = panel_rows(rows, sw, d)
            for a_i, agent in enumerate(agents):
                by = group_by([r for r in sel if r.agent == agent], key)
                vs = [v for v in values if v in by]
                if not vs:
                    continue
                stats = np.array([_stats(by[v]) for v in vs])
                x = np.array([pos[v] for v in vs]) + offsets[agent]
                style = dict(
                    AGENT_STYLE.get(agent, dict(color=f"C{a_i}", ls="-", marker="o", label=agent))
                )
                handles.setdefault(
                    agent,
                    _errorbars(ax_p, x, stats[:, 0], stats[:, 1], stats[:, 2], numeric, **style),
                )
                _errorbars(ax_x, x, stats[:, 3], stats[:, 4], stats[:, 5], numeric, **style)
                if ax_l is not None:
                    _learn_points(
                        ax_l,
                        x,
                        [learn_stats([r.steps_to_learn for r in by[v]]) for v in vs],
                        numeric,
                        style,
                    )
                counts[agent].update(len(by[v]) for v in vs)
            _label_panels(ax_p, ax_x, ax_l, sw, d)
    for ax in axes[-1]:
        _x_axis(ax, values, pos, numeric, xlabel, tick_labels, n_cols)
    draw_legend(legend_ax, _legend_handles(agents, handles, counts))
    mark_unfinished(fig, note)
    return fig


def _positions(
    values: Sequence[Any], agents: Sequence[str], numeric: bool
) -> tuple[dict[Any, float], dict[str, float]]:
    """Each value's place on the x axis (its number, or its slot) and each agent's sideways
    offset: the agents' points of one value spread over half the gap to the next value."""
    pos = {v: (float(v) if numeric else float(i)) for i, v in enumerate(values)}
    span = (max(pos.values()) - min(pos.values())) if len(pos) > 1 else 1.0
    step = (
        span / max(1, len(pos) - 1)
        if not numeric
        else min(np.diff(sorted(pos.values())), default=span)
    )
    width = 0.5 * step
    offsets = {
        a: (i - (len(agents) - 1) / 2) * width / max(1, len(agents)) for i, a in enumerate(agents)
    }
    return pos, offsets


def _label_panels(ax_p: Any, ax_x: Any, ax_l: Any | None, swimmer: str, direction: int) -> None:
    """Titles, axis labels, limits and grids of one swimmer-direction column's panels."""
    ax_p.set_ylim(-0.06, 1.06)
    ax_p.set_ylabel("success rate p\n(95% Wilson CI)")
    ax_p.set_title(panel_title(swimmer, direction))
    ax_x.axhline(0, color="0.75", lw=0.6, zorder=0)
    ax_x.set_ylabel(f"mean {displacement_label(direction)}\n(95% bootstrap CI)")
    lo, hi = ax_x.get_ylim()
    if hi - lo < 1e-9:  # all X/a equal (a swimmer that never moved): not an axis of 1e-17 rounding
        ax_x.set_ylim(lo - 0.05, hi + 0.05)
    if ax_l is not None:
        ax_l.set_ylabel("steps to learn\n(median, IQR)")
        ax_l.text(
            0.99,
            0.97,
            "k/n: runs that learned",
            transform=ax_l.transAxes,
            ha="right",
            va="top",
            fontsize=5,
            color="0.4",
        )
    for ax in (ax_p, ax_x) + ((ax_l,) if ax_l is not None else ()):
        ax.grid(axis="y", alpha=0.25, lw=0.5)


def _x_axis(
    ax: Any,
    values: Sequence[Any],
    pos: Mapping[Any, float],
    numeric: bool,
    xlabel: str,
    tick_labels: Mapping[Any, str] | None,
    n_cols: int,
) -> None:
    """The bottom panel's x label and ticks: numbers on a number line, else one labelled slot per
    value (rotated when the labels would collide)."""
    ax.set_xlabel(xlabel)
    if numeric:
        ax.set_xticks([pos[v] for v in values], [f"{v:g}" for v in values])
        return
    labels = [(tick_labels or {}).get(v, str(v)) for v in values]
    rotate = sum(len(t) for t in labels) > (40 if n_cols == 1 else 30)
    ax.set_xticks(
        [pos[v] for v in values],
        labels,
        rotation=30 if rotate else 0,
        ha="right" if rotate else "center",
    )
    ax.set_xlim(-0.6, len(values) - 0.4)


def _legend_handles(
    agents: Sequence[str], handles: Mapping[str, Any], counts: Mapping[str, set[int]]
) -> list[Any]:
    """One legend entry per agent drawn, labelled with its runs per point ("n = 20", or a range
    where points differ)."""
    legend = []
    for agent in agents:
        if agent in handles:
            h = handles[agent]
            n = set(counts[agent])
            base = AGENT_STYLE.get(agent, {}).get("label", agent)
            h.set_label(
                f"{base}, n = {n.pop()}" if len(n) == 1 else f"{base}, n = {min(n)}-{max(n)}"
            )
            legend.append(h)
    return legend


def noise_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    """Success rate p and mean X/a against the noise level zeta (paper Fig. 4)."""
    return grid_figure(rows, "zeta", xlabel="noise level \u03b6", numeric=True, note=note)


def ablation_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    """The full prompt and the prompt without each sentence S1..S5 (paper Fig. 5)."""
    order = ["full"] + [f"-S{i}" for i in range(1, 6)]
    labels = {"full": "full", **{f"-S{i}": f"\u2212S{i}" for i in range(1, 6)}}
    return grid_figure(
        rows,
        "group",
        order=order,
        tick_labels=labels,
        xlabel="sentence removed from the prompt",
        note=note,
    )


def inits_figure(rows: Sequence[Mapping[str, Any]], note: str | None = None) -> Figure:
    """Each of the four initial configurations (signs of D1, D2)."""
    order = [f"init {a}{b}" for a in "+-" for b in "+-"]
    labels = {g: f"({g[5]}, {g[6]})".replace("-", "\u2212") for g in order}
    return grid_figure(
        rows,
        "group",
        order=order,
        tick_labels=labels,
        xlabel="initial configuration (signs of D1, D2)",
        note=note,
    )


@styled
def competence_figure(
    rows: Sequence[Mapping[str, Any]], order: Sequence[str], note: str | None = None
) -> Figure:
    """Success rate p and mean target-direction X/a per LLM variant and per baseline.

    Rows carry an ``entry`` label (a variant name, or ``"agent (action set)"`` for baselines);
    ``order`` lists the entries top to bottom. One pair of panels per swimmer and target
    direction; horizontal intervals keep long variant names readable, and the dotted line marks
    the random baseline on the paper's action set (all).
    """
    rows = as_run_rows(rows)
    keys = panel_keys(rows)
    n = max(1, len(order))
    fig, axes = plt.subplots(
        len(keys),
        2,
        figsize=(PAGE_IN, (0.17 * n + 0.75) * len(keys) + 0.3),
        squeeze=False,
        layout="constrained",
    )
    for (ax_p, ax_x), (sw, d) in zip(axes, keys):
        by = group_by(panel_rows(rows, sw, d), "entry")
        labels = [k for k in order if k in by]
        y = np.arange(len(labels))[::-1]
        for j, k in enumerate(labels):
            g = by[k]
            style = AGENT_STYLE.get(g[0]["agent"], dict(color="C0", marker="o"))
            p, plo, phi, m, mlo, mhi = _stats(g)
            ax_p.errorbar(
                p,
                y[j],
                xerr=[[max(0.0, p - plo)], [max(0.0, phi - p)]],
                fmt=style["marker"],
                color=style["color"],
                capsize=2,
                elinewidth=0.8,
            )
            ax_x.errorbar(
                m,
                y[j],
                xerr=[[max(0.0, m - mlo)], [max(0.0, mhi - m)]],
                fmt=style["marker"],
                color=style["color"],
                capsize=2,
                elinewidth=0.8,
            )
        if "random (all)" in by:
            ax_x.axvline(
                float(np.mean([r.signed_final_x for r in by["random (all)"]])),
                color="0.5",
                ls=":",
                lw=0.8,
            )
        ax_p.set_yticks(y, [f"{k} (n={len(by[k])})" for k in labels], fontsize=6)
        ax_x.set_yticks(y, [""] * len(labels))  # the entries are named once, on the left
        ax_x.set_ylim(ax_p.get_ylim())
        for ax in (ax_p, ax_x):
            ax.grid(axis="x", alpha=0.3, lw=0.5)
        ax_p.set_xlim(-0.05, 1.05)
        ax_x.axvline(0, color="0.8", lw=0.6)
        ax_p.set_title(f"{panel_title(sw, d)}: success rate p", fontsize=7)
        ax_x.set_title(f"{panel_title(sw, d)}: mean {displacement_label(d)}", fontsize=7)
        ax_p.set_xlabel("p (95% Wilson CI)")
        ax_x.set_xlabel(f"mean {displacement_label(d)} after the last step (95% bootstrap CI)")
    mark_unfinished(fig, note)
    return fig
