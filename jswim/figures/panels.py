"""Panels of the study figures: grouping rows by swimmer and target direction, labels, the frame
of panels and legend, saving as PNG and PDF."""

from __future__ import annotations

import math
import os
from collections import defaultdict
from pathlib import Path
from typing import Any
from collections.abc import Iterable, Mapping, Sequence

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.figure import Figure

from jswim.figures.style import (
    COLUMN_IN,
    NOTE_COLOR,
    PAGE_IN,
    RC,
)
from jswim.results.orders import SWIMMER_ORDER
from jswim.results import as_run_rows, writing
from jswim.swimmers.models import make_model


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


def in_order(values: Iterable[Any], order: Sequence[Any]) -> list[Any]:
    """The distinct ``values`` in the order of ``order``; values not in it follow, sorted as text."""
    vals = set(values)
    return [v for v in order if v in vals] + sorted(vals - set(order), key=str)


def panel_keys(rows: Iterable[Mapping[str, Any]]) -> list[tuple[str, int]]:
    """The ``(swimmer, direction)`` panels of ``rows``: Purcell first, +x before -x."""
    rows = as_run_rows(rows)
    rows = list(rows)
    swimmers = in_order({r.swimmer for r in rows}, SWIMMER_ORDER)
    dirs = in_order({int(r.direction or 1) for r in rows}, (1, -1))
    present = {(r.swimmer, int(r.direction or 1)) for r in rows}
    return [(s, d) for s in swimmers for d in dirs if (s, d) in present]


def group_by(rows: Iterable[Mapping[str, Any]], key: str) -> dict[Any, list[Mapping[str, Any]]]:
    """``rows`` grouped by their value of ``key`` (a missing key groups under ``None``)."""
    out: dict[Any, list[Mapping[str, Any]]] = defaultdict(list)
    for r in rows:
        out[r.get(key)].append(r)
    return dict(out)


def panel_rows(
    rows: Iterable[Mapping[str, Any]], swimmer: str, direction: int
) -> list[Mapping[str, Any]]:
    """The runs of ``rows`` that belong to the ``(swimmer, direction)`` panel."""
    rows = as_run_rows(rows)
    return [r for r in rows if r.swimmer == swimmer and int(r.direction or 1) == direction]


def direction_text(direction: int) -> str:
    """``+x`` or ``\u2212x`` (a true minus sign) for a target direction of +1 or -1."""
    return "+x" if direction > 0 else "\u2212x"


def displacement_label(direction: int) -> str:
    """The paper's axis label: X/a toward +x, -X/a toward -x."""
    return "X/a" if direction > 0 else "\u2212X/a"


def swimmer_label(swimmer: str) -> str:
    """The swimmer model's display name; an unknown name is shown as it is."""
    try:
        return make_model(swimmer).label
    except Exception:  # an unknown name still gets a panel
        return swimmer


def panel_title(swimmer: str, direction: int) -> str:
    """A panel's title: the swimmer and its target direction."""
    return f"{swimmer_label(swimmer)}, target {direction_text(direction)}"


def target_displacement(rows: Sequence[Mapping[str, Any]]) -> np.ndarray:
    """Displacement in each run's target direction, ``direction * X/a``, shape ``(runs, steps + 1)``.

    Column 0 is the start (0); shorter runs are padded with NaN.
    """
    rows = as_run_rows(rows)
    n = max((len(r.x) for r in rows), default=0)
    out = np.full((len(rows), n + 1), np.nan)
    for i, r in enumerate(rows):
        out[i, 0] = 0.0
        out[i, 1 : len(r.x) + 1] = np.asarray(r.x, float) * int(r.direction or 1)
    return out


def mark_unfinished(fig: Figure, note: str | None) -> None:
    """Write ``note`` (an unfinished study's line) above the figure in red; nothing if ``None``."""
    if note:
        fig.suptitle(note, color=NOTE_COLOR, fontsize=8, fontweight="bold")


def legend_columns(width: float, entries: int, most: int = 3) -> int:
    """Legend columns for a figure ``width`` inches wide: ``most`` on a page, 2 on a column."""
    return max(1, min(entries, most if width > COLUMN_IN + 0.1 else 2))


def legend_frame(
    heights: Sequence[float], n_cols: int, legend_entries: int, most: int = 3
) -> tuple[Figure, Any, Any, int]:
    """A figure of panel rows ``heights`` (inches) under a legend row spanning every column.

    The legend gets its own row of the grid (not constrained layout's "outside" legend, which
    collides with a suptitle), so the note of an unfinished study sits above it. Returns the
    figure, its grid, the legend's (blank) axes and the grid row of the first panel row.
    """
    width = figure_width(n_cols)
    lines = (
        math.ceil(legend_entries / legend_columns(width, legend_entries, most))
        if legend_entries
        else 0
    )
    top = 0.14 * lines + 0.04 if lines else 0.0
    fig = plt.figure(figsize=(width, sum(heights) + top), layout="constrained")
    grid = fig.add_gridspec(
        len(heights) + (1 if lines else 0),
        n_cols,
        height_ratios=([top] if lines else []) + list(heights),
    )
    legend_ax = None
    if lines:
        legend_ax = fig.add_subplot(grid[0, :])
        legend_ax.axis("off")
    return fig, grid, legend_ax, 1 if lines else 0


def draw_legend(legend_ax: Any, handles: Sequence[Any], most: int = 3) -> None:
    """Draw ``handles`` as one centred legend in the legend row made by `legend_frame`."""
    if legend_ax is None or not handles:
        return
    width = legend_ax.figure.get_figwidth()
    legend_ax.legend(
        handles=list(handles),
        loc="center",
        ncol=legend_columns(width, len(handles), most),
        handlelength=2.6,
        columnspacing=1.2,
        borderaxespad=0.0,
        borderpad=0.0,
    )


def figure_width(n_cols: int) -> float:
    """A figure's width (inches): one journal column for one panel column, else the page."""
    return COLUMN_IN if n_cols <= 1 else PAGE_IN
