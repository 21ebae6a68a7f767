"""Figures of the commands that write no study folder: ``jswim qlearn`` and ``jswim ensemble``.

Both follow the study figures' rules ([`jswim.figures.plots`][jswim.figures.plots]: paper sizes, 7-8 pt text, colour-blind
safe colours, PNG and PDF through [`jswim.figures.save`][jswim.figures.panels.save]) and name the agent or stroke they
show in their title, so a figure taken out of its folder still says what it is.
"""

from __future__ import annotations

from typing import Any
from collections.abc import Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from jswim.figures.panels import direction_text, displacement_label, swimmer_label
from jswim.figures.style import COLUMN_IN, PAGE_IN, RC
from jswim.results.orders import SWIMMER_ORDER

#: Colours of the two action sets (Okabe-Ito).
SET_STYLE = {
    "all": dict(color="#D55E00", label="all six actions (the paper's)"),
    "shape-changing": dict(color="#0072B2", label="shape-changing moves only"),
}


def qlearn_figure(rows: Sequence[Any], title: str) -> Figure:
    """Histograms of steps to learn, one panel per swimmer (rows) and target direction (columns).

    ``rows`` are `jswim.studies.qlearn.Summary` with their histogram ``hist`` (learners
    per steps-to-learn value, counted from 1). One outline per action set; the dashed line is
    its median, and the legend says how many learners never learned.
    """
    keys = sorted(
        {(r.swimmer, r.direction) for r in rows},
        key=lambda k: (SWIMMER_ORDER.index(k[0]) if k[0] in SWIMMER_ORDER else 9, -k[1]),
    )
    swimmers = list(dict.fromkeys(k[0] for k in keys))
    dirs = sorted({k[1] for k in keys}, reverse=True)
    with plt.rc_context(RC):
        fig, axes = plt.subplots(
            len(swimmers),
            len(dirs),
            squeeze=False,
            layout="constrained",
            figsize=(COLUMN_IN if len(dirs) == 1 else PAGE_IN, 2.4 * len(swimmers) + 0.45),
        )
        for i, sw in enumerate(swimmers):
            for j, d in enumerate(dirs):
                ax = axes[i, j]
                sel = [r for r in rows if r.swimmer == sw and r.direction == d]
                for r in sel:
                    style = SET_STYLE.get(
                        r.action_set, dict(color=f"C{len(ax.lines)}", label=r.action_set)
                    )
                    hist = np.asarray(r.hist, float)
                    never = r.n - r.n_learned
                    label = (
                        f"{style['label']}: median {r.median:g}, never learned {never:,} of {r.n:,}"
                        if r.n_learned
                        else f"{style['label']}: never learned {never:,} of {r.n:,}"
                    )
                    if hist.size > 1:
                        steps = np.arange(hist.size)
                        ax.stairs(
                            hist[1:] / max(r.n, 1), steps, color=style["color"], lw=1.2, label=label
                        )
                    else:
                        ax.plot([], [], color=style["color"], label=label)
                    if r.n_learned:
                        ax.axvline(r.median, color=style["color"], ls="--", lw=0.9)
                ax.set_title(f"{swimmer_label(sw)}, target {direction_text(d)}")
                ax.set_xlabel("steps to learn (from 1: the step the final stroke starts)")
                ax.set_ylabel("fraction of learners")
                ax.set_xlim(left=0)
                ax.set_ylim(bottom=0)
                # Below the axis, never over the bars or the tick labels (constrained layout makes room).
                ax.legend(
                    loc="upper center",
                    bbox_to_anchor=(0.5, -0.32),
                    fontsize=6,
                    frameon=False,
                    borderaxespad=0.0,
                )
        fig.suptitle(title, fontsize=8)
    return fig


def ensemble_figure(stats: Sequence[Any], title: str, direction: int = 1) -> Figure:
    """Mean target-direction X/a against step with its quantile band, one curve per noise level.

    ``stats`` are `jswim.studies.ensemble.EnsembleStats`. Left: the mean (solid) and the
    outermost reported quantiles (5% and 95% by default, thin dashed); right: the width of that
    band, where the noise levels part (their means coincide: the noise has mean zero).
    """
    cmap = plt.get_cmap("viridis")
    qs = stats[0].qs if stats else ()
    with plt.rc_context(RC):
        fig, (ax, ax_w) = plt.subplots(1, 2, figsize=(PAGE_IN, 2.7), layout="constrained")
        for k, s in enumerate(stats):
            c = cmap(0.9 * k / max(1, len(stats) - 1))
            steps = np.concatenate([[0], s.steps])
            mean = np.concatenate([[0.0], s.mean])
            ax.plot(
                steps,
                mean,
                color=c,
                lw=2.2 - 1.4 * k / max(1, len(stats) - 1),
                label=f"\u03b6 = {s.zeta:g}",
                zorder=3 + k,
            )
            if len(qs) >= 2:
                q = np.vstack([np.zeros((1, len(qs))), s.quantiles])
                ax.plot(steps, q[:, 0], color=c, lw=0.7, ls="--")
                ax.plot(steps, q[:, -1], color=c, lw=0.7, ls="--")
                ax_w.plot(steps, q[:, -1] - q[:, 0], color=c, lw=1.2, label=f"\u03b6 = {s.zeta:g}")
        ax.axhline(0, color="0.75", lw=0.6, zorder=0)
        ax.set_xlabel("step n")
        ax.set_ylabel(displacement_label(direction))
        ax.set_title(
            "mean (solid)"
            + (
                f", {100 * qs[0]:g}% and {100 * qs[-1]:g}% quantiles (dashed)"
                if len(qs) >= 2
                else ""
            ),
            fontsize=7,
        )
        ax.legend(loc="upper left", fontsize=6, ncol=2 if len(stats) > 4 else 1)
        if len(qs) >= 2:
            ax_w.set_xlabel("step n")
            ax_w.set_ylabel(f"spread of {displacement_label(direction)}")
            ax_w.set_title(f"{100 * qs[-1]:g}% \u2212 {100 * qs[0]:g}% quantile", fontsize=7)
            ax_w.legend(loc="upper left", fontsize=6, ncol=2 if len(stats) > 4 else 1)
        else:
            ax_w.axis("off")
        fig.suptitle(title, fontsize=8)
    return fig
