"""The bench's leaderboard figure: success p and X/a end with their intervals, per row.

Reads the rows that `jswim.bench.leaderboard` computes from the bench's study folders (moved here
from ``jswim.bench.leaderboard``: the bench computes, the pictures draw).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any
from collections.abc import Mapping, Sequence

from jswim.figures.panels import save


def figure(folder: Path, rows: Sequence[Mapping[str, Any]]) -> list[Path]:
    """Success p and X/a end, each with its 95% interval, per row; a pair of panels per part,
    swimmer, direction and group (``leaderboard.png``/``.pdf``)."""
    return save(figure_object(rows), folder, "leaderboard")


def figure_object(rows: Sequence[Mapping[str, Any]]) -> Any:
    """The leaderboard's matplotlib figure (see `figure`).

    With most p at 0 (short runs, weak models), success alone says nothing: X/a end, the mean
    displacement toward the target, is what separates the rows, so each setting has both panels.
    Every panel carries its own x tick labels (no shared axis leaves a panel unlabelled).
    """
    import matplotlib.pyplot as plt

    panels = sorted(
        {(r["part"], r["swimmer"], r["direction"], r["group"]) for r in rows},
        key=lambda k: (k[0], k[1] != "purcell", k[1], -k[2], str(k[3])),
    )
    labels = (
        sorted({r["row"] for r in rows if r["kind"] == "llm"})
        + sorted({r["row"] for r in rows if r["kind"] == "reference"})
        + ["Q-learning", "random"]
    )
    labels = [lab for lab in labels if any(r["row"] == lab for r in rows)]
    pairs = min(2, len(panels))
    nrow = -(-len(panels) // pairs)
    fig, axes = plt.subplots(
        nrow, 2 * pairs, figsize=(7.0, 0.5 + (0.3 * len(labels) + 0.9) * nrow), squeeze=False
    )
    colors = {"llm": "#0072B2", "reference": "#E69F00", "baseline": "#7f7f7f"}
    xs = [
        r.get(k) for r in rows for k in ("mean_x", "mean_x_lo", "mean_x_hi") if r.get(k) is not None
    ]
    span = max([0.1] + [abs(v) for v in xs]) * 1.15
    for n, (part, sw, d, g) in enumerate(panels):
        ax_p, ax_x = axes[n // pairs, 2 * (n % pairs)], axes[n // pairs, 2 * (n % pairs) + 1]
        for i, lab in enumerate(labels):
            r = next(
                (
                    r
                    for r in rows
                    if (r["part"], r["swimmer"], r["direction"], r["group"], r["row"])
                    == (part, sw, d, g, lab)
                ),
                None,
            )
            if r is None:
                continue
            err = [
                [max(0.0, r["success"] - r["success_lo"])],
                [max(0.0, r["success_hi"] - r["success"])],
            ]
            ax_p.errorbar(
                r["success"], i, xerr=err, fmt="o", ms=3, color=colors[r["kind"]], capsize=2, lw=1
            )
            if r.get("mean_x") is not None:
                lo, hi = r.get("mean_x_lo"), r.get("mean_x_hi")
                xerr = (
                    None
                    if lo is None or hi is None
                    else [[max(0.0, r["mean_x"] - lo)], [max(0.0, hi - r["mean_x"])]]
                )
                ax_x.errorbar(
                    r["mean_x"],
                    i,
                    xerr=xerr,
                    fmt="s",
                    ms=3,
                    color=colors[r["kind"]],
                    capsize=2,
                    lw=1,
                )
        direction = "+x" if d > 0 else "-x"
        ax_p.set_title(f"{part}: {sw} {direction}{' ' + g if g else ''}", fontsize=7, loc="left")
        ax_p.set_xlim(-0.05, 1.05)
        ax_x.set_xlim(-span, span)
        ax_x.axvline(0.0, color="0.6", lw=0.5)
        ax_p.set_xlabel("success p [95% CI]", fontsize=6)
        ax_x.set_xlabel(f"X/a end toward {direction} [95% CI]", fontsize=6)
        for j, ax in enumerate((ax_p, ax_x)):
            ax.set_yticks(
                range(len(labels)),
                labels if n % pairs == 0 and j == 0 else [""] * len(labels),
                fontsize=6,
            )
            ax.set_ylim(len(labels) - 0.5, -0.5)
            ax.tick_params(labelsize=6, labelbottom=True)
            ax.grid(axis="x", lw=0.3)
    for ax in list(axes.flat)[2 * len(panels) :]:
        ax.axis("off")
    fig.tight_layout()
    return fig
