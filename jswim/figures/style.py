"""The figures' shared style: the paper's journal column widths, one colour, line and marker per
agent (Okabe-Ito, legible with the common colour-vision deficiencies and in grey), the rc settings
every figure is built under, and [`tidy`][jswim.figures.style.tidy], what every figure gets.

Its own module so that every figure module ([`jswim.figures.plots`][jswim.figures.plots], [`jswim.figures.scene_plots`][jswim.figures.scene_plots]) reads
the style from below, and neither imports the other to get it.
"""

from __future__ import annotations

import functools
from typing import Any

import matplotlib.pyplot as plt
from matplotlib.figure import Figure

#: Single- and double-column widths of the paper's journal (inches).
COLUMN_IN = 3.4
PAGE_IN = 7.0


# Okabe-Ito colours: distinguishable with the common colour-vision deficiencies and in grey.
AGENT_STYLE: dict[str, dict[str, Any]] = {
    "llm": dict(color="#0072B2", ls="-", marker="o", label="LLM"),
    "qlearning": dict(color="#D55E00", ls="--", marker="s", label="Q-learning"),
    "random": dict(color="#555555", ls=":", marker="^", label="random policy"),
    "ppo": dict(color="#009E73", ls="-.", marker="D", label="PPO (real ROC)"),
}
REFERENCE_STYLE = dict(color="black", ls="-.", lw=0.8, label="signature gait from step 0")
NOTE_COLOR = "#B00000"

RC = {
    "font.size": 8,
    "axes.titlesize": 8,
    "axes.labelsize": 8,
    "xtick.labelsize": 7,
    "ytick.labelsize": 7,
    "legend.fontsize": 7,
    "lines.linewidth": 1.3,
    "lines.markersize": 3.5,
    "errorbar.capsize": 2,
    "axes.linewidth": 0.6,
    "savefig.dpi": 300,
    "pdf.fonttype": 42,
    "ps.fonttype": 42,
    "legend.frameon": False,
}


def styled(fn):
    """Build the figure under the paper's rc settings (sizes are fixed when artists are made)."""

    @functools.wraps(fn)
    def wrapper(*args: Any, **kwargs: Any) -> Figure:
        with plt.rc_context(RC):
            fig = fn(*args, **kwargs)
            if isinstance(fig, Figure):
                tidy(fig)
            return fig

    return wrapper


def tidy(fig: Figure) -> Figure:
    """What every figure gets: ticks at whole steps on step axes (not 2.5, 7.5, ...), plain tick
    labels on log axes (3, 5, 10, not "3x10^0 4x10^0" run together), and the signature-gait line
    on top, dashed and outlined, so a perfect LLM line drawn on it cannot hide it."""
    from matplotlib import patheffects
    from matplotlib.ticker import FuncFormatter, LogLocator, MaxNLocator, NullFormatter

    for ax in fig.axes:
        if ax.get_xlabel().startswith("step"):
            ax.xaxis.set_major_locator(MaxNLocator(integer=True))
        for axis, scale in ((ax.xaxis, ax.get_xscale()), (ax.yaxis, ax.get_yscale())):
            if scale == "log":
                axis.set_major_locator(LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
                axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
                axis.set_minor_formatter(NullFormatter())
        for line in ax.get_lines():
            if line.get_label() == REFERENCE_STYLE["label"]:
                line.set_zorder(20)
                line.set_linestyle((0, (4, 2, 1, 2)))
                line.set_linewidth(1.0)
                line.set_path_effects([patheffects.withStroke(linewidth=2.6, foreground="white")])
    return fig
