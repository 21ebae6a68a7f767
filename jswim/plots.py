"""Figures of the studies (matplotlib; PNG and PDF).

Every function takes the tidy run rows of a study (see :mod:`jswim.studies`) and returns a
``matplotlib.figure.Figure``; :func:`save` writes it as PNG and PDF. Axes carry the paper's
dimensionless units: displacement ``X/a`` (``a`` = link length or sphere radius) against the
execution step ``n``.
"""

from __future__ import annotations

import math
import os
from collections import defaultdict
from pathlib import Path
from typing import Any, Iterable, Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from jswim.stats import mean_interval, wilson_interval
from jswim.swimmers.models import SwimmerModel

AGENT_STYLE = {
    "llm": dict(color="C0", ls="-", label="LLM"),
    "qlearning": dict(color="C3", ls="--", label="Q-learning"),
    "random": dict(color="0.5", ls=":", label="random"),
}


def save(fig: Figure, folder: str | os.PathLike, name: str) -> list[Path]:
    """Write ``fig`` as ``name.png`` and ``name.pdf`` in ``folder``; returns the paths."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for ext in ("png", "pdf"):
        path = folder / f"{name}.{ext}"
        tmp = folder / f".{name}.tmp.{ext}"
        fig.savefig(tmp, dpi=150, bbox_inches="tight", format=ext)
        os.replace(tmp, path)
        paths.append(path)
    plt.close(fig)
    return paths


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
        ax.plot(pts[:, 0], pts[:, 1], "-", color=color, lw=2.5, solid_capstyle="round")
        ax.plot(pts[1:-1, 0], pts[1:-1, 1], "o", color=color, ms=3)
    else:
        ax.plot(pts[:, 0], pts[:, 1], "-", color=color, lw=1)
        for p in pts:
            ax.add_patch(plt.Circle(p, scale, fc="white", ec=color, lw=1.5))


def draw_cycle(ax: Any, model: SwimmerModel, start: Sequence[int], moves: Sequence[tuple[int, int]],
               title: str | None = None) -> None:
    """Sketch a stroke cycle: the start shape and the shape after each move, left to right."""
    levels = list(start)
    shapes = [list(levels)]
    for dof, roc in moves:
        if roc:
            levels[dof - 1] = 1 if roc > 0 else 0
        shapes.append(list(levels))
    span = 4.0 if model.planar else model.hi * model.n_dof + 4
    label_y = -2.2 if model.planar else -2.6
    for i, lv in enumerate(shapes):
        d = [model.lo + (model.hi - model.lo) * v for v in lv]
        draw_shape(ax, model, d, origin=(i * span, 0.0), color="C0" if i == 0 else "k")
        if i < len(moves):
            dof, roc = moves[i]
            # The move between two sketches, in the prompt's [DOF, ROC] notation.
            ax.annotate(f"[{dof}, {roc}]", (i * span + span / 2, label_y), ha="center", fontsize=7, color="0.3")
    ax.set_xlim(-span / 2, (len(shapes) - 0.5) * span)
    ax.set_ylim(label_y - 0.8, 2.0)
    ax.set_aspect("equal")
    ax.axis("off")
    if title:
        ax.set_title(title, fontsize=9)


# -- learning curves --------------------------------------------------------------------------


def _group(rows: Iterable[dict], *keys: str) -> dict[tuple, list[dict]]:
    out: dict[tuple, list[dict]] = defaultdict(list)
    for r in rows:
        out[tuple(r.get(k) for k in keys)].append(r)
    return dict(sorted(out.items(), key=lambda kv: tuple(str(v) for v in kv[0])))


def _x_matrix(rows: Sequence[dict]) -> np.ndarray:
    n = max(len(r["x"]) for r in rows)
    out = np.full((len(rows), n + 1), np.nan)
    for i, r in enumerate(rows):
        out[i, 0] = 0.0
        out[i, 1: len(r["x"]) + 1] = r["x"]
    return out


def _plot_mean(ax: Any, rows: Sequence[dict], signed: bool = False, **style: Any) -> None:
    xs = _x_matrix(rows)
    if signed:
        xs = xs * np.array([r.get("direction", 1) for r in rows])[:, None]
    n = np.arange(xs.shape[1])
    if len(rows) > 1:
        for row in xs[: min(len(rows), 20)]:
            ax.plot(n, row, color=style.get("color"), alpha=0.15, lw=0.7)
    label = style.pop("label", None)
    ax.plot(n, np.nanmean(xs, axis=0), lw=2, label=f"{label} (mean of {len(rows)})" if len(rows) > 1 else label, **style)


def curves_figure(rows: Sequence[dict], models: dict[str, SwimmerModel],
                  cycles: dict[str, tuple] | None = None) -> Figure:
    """X/a against step n for each agent, one column per swimmer (paper Fig. 2).

    ``cycles`` maps a swimmer name to ``(start levels, moves)`` or ``(start levels, moves, agent)``
    of the stroke cycle to sketch under its curves (e.g. the one the LLM learned).
    """
    swimmers = sorted({r["swimmer"] for r in rows})
    fig, axes = plt.subplots(2, len(swimmers), figsize=(5.2 * len(swimmers), 5.2), squeeze=False,
                             gridspec_kw=dict(height_ratios=[3, 1]))
    for j, sw in enumerate(swimmers):
        ax = axes[0, j]
        for (agent,), group in _group([r for r in rows if r["swimmer"] == sw], "agent").items():
            _plot_mean(ax, group, **dict(AGENT_STYLE.get(agent, dict(label=agent))))
        ax.axhline(0, color="0.8", lw=0.8)
        ax.set_xlabel("step n")
        ax.set_ylabel("X/a")
        ax.set_title(models[sw].label if sw in models else sw)
        ax.legend(fontsize=8)
        if cycles and sw in cycles and sw in models:
            start, moves, *who = cycles[sw]
            by = f" by {AGENT_STYLE.get(who[0], dict(label=who[0]))['label']}" if who else ""
            draw_cycle(axes[1, j], models[sw], start, moves, title=f"stroke cycle learned{by}")
        else:
            axes[1, j].axis("off")
    fig.tight_layout()
    return fig


def history_figure(rows: Sequence[dict]) -> Figure:
    """Target-direction displacement against step for each history length n_ht (paper Fig. 3)."""
    panels = _group(rows, "swimmer", "direction")
    fig, axes = plt.subplots(1, len(panels), figsize=(4.2 * len(panels), 3.6), squeeze=False)
    for ax, ((sw, direction), group) in zip(axes[0], panels.items()):
        for i, ((n_ht,), g) in enumerate(_group(group, "n_ht").items()):
            _plot_mean(ax, g, signed=True, color=plt.cm.viridis(i / max(1, len(_group(group, "n_ht")) - 1)),
                       label=f"n_ht={n_ht}")
        ax.set_title(f"{sw}, {'+x' if direction > 0 else '-x'}")
        ax.set_xlabel("step n")
        ax.set_ylabel("X/a" if direction > 0 else "-X/a")
        ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def _rate_and_mean(ax: Any, labels: Sequence[str], groups: Sequence[Sequence[dict]], xpos: Sequence[float],
                   xlabel: str, bar: bool = False) -> None:
    ps, plo, phi, ms, mlo, mhi = [], [], [], [], [], []
    for g in groups:
        k = sum(bool(r["success"]) for r in g)
        lo, hi = wilson_interval(k, len(g))
        ps.append(k / len(g) if g else math.nan)
        # Error bars must not be negative: at p = 0 or a constant sample, rounding can make them -1e-17.
        plo.append(max(0.0, ps[-1] - lo))
        phi.append(max(0.0, hi - ps[-1]))
        m, a, b = mean_interval([r["signed_final_x"] for r in g])
        ms.append(m)
        mlo.append(max(0.0, m - a))
        mhi.append(max(0.0, b - m))
    ax2 = ax.twinx()
    if bar:
        w = 0.38
        x = np.asarray(xpos, float)
        ax.bar(x - w / 2, ms, w, yerr=[mlo, mhi], color="C0", capsize=3, label="mean X/a")
        ax2.bar(x + w / 2, ps, w, yerr=[plo, phi], color="C1", capsize=3, label="success rate p")
        ax.set_xticks(x, labels, rotation=30, ha="right", fontsize=8)
    else:
        ax.errorbar(xpos, ms, yerr=[mlo, mhi], fmt="o-", color="C0", capsize=3, label="mean X/a")
        ax2.errorbar(xpos, ps, yerr=[plo, phi], fmt="s--", color="C1", capsize=3, label="success rate p")
    ax.set_xlabel(xlabel)
    ax.set_ylabel("mean X/a after the last step (target direction)", color="C0", fontsize=8)
    ax2.set_ylabel("success rate p (95% Wilson CI)", color="C1", fontsize=8)
    ax2.set_ylim(-0.05, 1.05)
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = ax2.get_legend_handles_labels()
    ax.legend(h1 + h2, l1 + l2, fontsize=7, loc="lower left")


def noise_figure(rows: Sequence[dict]) -> Figure:
    """Mean X/a and success rate p against noise level zeta (paper Fig. 4)."""
    panels = _group(rows, "swimmer", "agent")
    fig, axes = plt.subplots(1, len(panels), figsize=(5 * len(panels), 3.8), squeeze=False)
    for ax, ((sw, agent), group) in zip(axes[0], panels.items()):
        by = _group(group, "zeta")
        _rate_and_mean(ax, [str(z[0]) for z in by], list(by.values()), [z[0] for z in by], "noise level zeta")
        ax.set_title(f"{sw} ({agent}), n = {min(len(g) for g in by.values())}+ runs per level", fontsize=9)
    fig.tight_layout()
    return fig


def bars_figure(rows: Sequence[dict], key: str, order: Sequence[str] | None = None, title: str = "") -> Figure:
    """Mean X/a and success rate p per value of ``key`` (ablation masks, competence variants)."""
    panels = _group(rows, "swimmer")
    fig, axes = plt.subplots(1, len(panels), figsize=(max(5.0, 0.9 * len(order or []) + 2) * len(panels), 4.2),
                             squeeze=False)
    for ax, ((sw,), group) in zip(axes[0], panels.items()):
        by = {k[0]: g for k, g in _group(group, key).items()}
        labels = [k for k in (order or list(by)) if k in by]
        _rate_and_mean(ax, labels, [by[k] for k in labels], range(len(labels)), key, bar=True)
        ax.set_title(f"{sw} {title}".strip(), fontsize=9)
    fig.tight_layout()
    return fig


def competence_figure(rows: Sequence[dict], order: Sequence[str]) -> Figure:
    """Success rate p and mean X/a per LLM variant and per baseline, one row of panels per swimmer.

    Rows carry an ``entry`` label (a variant name, or ``"agent (allowed set)"`` for baselines);
    ``order`` lists the entries top to bottom. Horizontal bars keep long variant names readable,
    and the dotted line marks the random baseline on the same allowed set as the paper (all).
    """
    panels = _group(rows, "swimmer")
    n = max(1, len(order))
    fig, axes = plt.subplots(len(panels), 2, figsize=(10, 0.32 * n * len(panels) + 1.2), squeeze=False)
    for (ax_p, ax_x), ((sw,), group) in zip(axes, panels.items()):
        by = {k[0]: g for k, g in _group(group, "entry").items()}
        labels = [k for k in order if k in by]
        y = np.arange(len(labels))[::-1]
        colors = [AGENT_STYLE.get(by[k][0]["agent"], {}).get("color", "C0") for k in labels]
        for j, k in enumerate(labels):
            g = by[k]
            hits = sum(bool(r["success"]) for r in g)
            lo, hi = wilson_interval(hits, len(g))
            p = hits / len(g)
            ax_p.errorbar(p, y[j], xerr=[[max(0.0, p - lo)], [max(0.0, hi - p)]], fmt="o", color=colors[j], capsize=3)
            m, a, b = mean_interval([r["signed_final_x"] for r in g])
            ax_x.errorbar(m, y[j], xerr=[[max(0.0, m - a)], [max(0.0, b - m)]], fmt="s", color=colors[j], capsize=3)
        if "random (all)" in by:
            ax_x.axvline(float(np.mean([r["signed_final_x"] for r in by["random (all)"]])), color="0.5", ls=":", lw=1)
        for ax in (ax_p, ax_x):
            ax.set_yticks(y, [f"{k} (n={len(by[k])})" for k in labels], fontsize=7)
            ax.grid(axis="x", alpha=0.3)
        ax_p.set_xlim(-0.05, 1.05)
        ax_x.axvline(0, color="0.8", lw=0.8)
        ax_p.set_title(f"{sw}: success rate p (95% Wilson CI)", fontsize=9)
        ax_x.set_title(f"{sw}: mean X/a after the last step (95% bootstrap CI)", fontsize=9)
    fig.tight_layout()
    return fig


def gaits_figure(model: SwimmerModel, cycles: Sequence[Any], top: int = 4) -> Figure:
    """The best closed stroke cycles of a swimmer, with their displacement per step."""
    shown = list(cycles)[:top]
    fig, axes = plt.subplots(len(shown), 1, figsize=(8, 1.1 * len(shown) + 0.5), squeeze=False)
    for ax, cyc in zip(axes[:, 0], shown):
        draw_cycle(ax, model, cyc.start, cyc.moves,
                   title=f"period {cyc.period}: X/a per step = {cyc.per_step:+.5f}")
    fig.suptitle(f"best stroke cycles of the {model.label} swimmer", fontsize=10)
    fig.tight_layout()
    return fig
