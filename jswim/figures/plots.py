"""Figures of the studies (matplotlib; PNG and PDF), sized for a paper's columns.

Every figure function takes the tidy run rows of a study (one dict per run, as in
``runs.jsonl``) and returns a ``matplotlib.figure.Figure``; [`save`][jswim.figures.panels.save] writes it as PNG and
PDF, and [`study_figures`][jswim.figures.plots.study_figures] picks a study's figures. The rules every figure keeps:

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

from pathlib import Path
from typing import Any
from collections.abc import Callable, Iterable, Mapping, Sequence

from matplotlib.figure import Figure

from jswim.agents.variants import VARIANTS
from jswim.results import as_run_rows, is_failed
from jswim.results.row import RunRow

from jswim.figures.scene_plots import pair_figures, school_figures, wall_figures
from jswim.figures.navigation_plots import nav_figures
from jswim.figures.flow_plots import flow_figures
from jswim.figures.panels import save
from jswim.figures.sketches import learned_cycles
from jswim.figures.curves import curves_figure, history_figure
from jswim.figures.grid import (
    ablation_figure,
    competence_figure,
    grid_figure,
    inits_figure,
    noise_figure,
)


# -- a study's figures ------------------------------------------------------------------------

#: A figure set's builder: ``(study, rows, note) -> {file name: Figure}``.
FigureSet = Callable[[str, list[RunRow], Any], dict[str, Figure]]


def _temperature(study: str, rows: list[RunRow], note: str | None) -> dict[str, Figure]:
    """p, steps to learn and X/a against the sampling temperature T."""
    fig = grid_figure(
        rows, "temperature", xlabel="sampling temperature T", numeric=True, note=note, learn=True
    )
    return {"temperature": fig}


def _competence(study: str, rows: list[RunRow], note: str | None) -> dict[str, Figure]:
    """One entry per LLM variant, then one per baseline (agent, action set)."""
    entries = [
        {**r, "entry": r.group if r.agent == "llm" else f"{r.agent} ({r.group})"} for r in rows
    ]
    order = [v for v in VARIANTS if any(e["entry"] == v for e in entries)]
    order += sorted({e["entry"] for e in entries} - set(order))
    return {"competence": competence_figure(entries, order, note=note)}


#: Every figure set a study may declare (`jswim.studies.study.Study.figures`), by name.
FIGURE_SETS: dict[str, FigureSet] = {
    # X/a against step n, under the study's own name (curves.png, swim.png)
    "curves": lambda study, rows, note: {
        study: curves_figure(rows, cycles=learned_cycles(rows), note=note)
    },
    "history": lambda study, rows, note: {"history": history_figure(rows, note=note)},
    "noise": lambda study, rows, note: {"noise": noise_figure(rows, note=note)},
    "ablation": lambda study, rows, note: {"ablation": ablation_figure(rows, note=note)},
    "inits": lambda study, rows, note: {"inits": inits_figure(rows, note=note)},
    "temperature": _temperature,
    "competence": _competence,
    "continuous": lambda study, rows, note: continuous_figures(rows, note=note),
    "wall": lambda study, rows, note: wall_figures(rows, note=note),
    "pair": lambda study, rows, note: pair_figures(rows, note=note),
    "school": lambda study, rows, note: school_figures(rows, note=note),
    # the ratio to the optimum, success, energy, then the paths
    "navigation": lambda study, rows, note: nav_figures(rows, note=note),
    # in a background flow, each against the flow speed, and the paths over its streamlines
    "flow": lambda study, rows, note: flow_figures(rows, note=note),
}


def figure_order(study: str, names: Iterable[str]) -> list[str]:
    """``names`` (a study's figures, without extension) in the order the page and ``jswim
    plot`` show them: the study's `jswim.studies.study.Study.figure_order` first, then any
    other by name."""
    from jswim.studies.study import find  # lazy: the study kinds load JAX

    spec = find(study)
    order = {n: i for i, n in enumerate(spec.figure_order if spec else ())}
    return sorted(names, key=lambda n: (order.get(n, len(order)), n))


def study_figures(
    study: str, rows: Sequence[Mapping[str, Any]], note: str | None = None
) -> dict[str, Figure]:
    """The figures of ``study`` from its run rows, by file name (without extension): its figure
    sets (`jswim.studies.study.Study.figures`, `FIGURE_SETS`), in its ``figure_order`` where
    it gives one; none for a study this version does not know.

    ``note`` (e.g. ``"unfinished: 12 of 40 runs"``) is written across the top of each.
    """
    from jswim.studies.study import find  # lazy: the study kinds load JAX

    rows = as_run_rows(rows)
    spec = find(study)
    if not rows or spec is None:
        return {}
    figs: dict[str, Figure] = {}
    for name in spec.figures:
        figs.update(FIGURE_SETS[name](study, rows, note))
    if spec.figure_order:
        return {name: figs[name] for name in figure_order(study, figs)}
    return figs


def continuous_figures(
    rows: Sequence[Mapping[str, Any]], note: str | None = None
) -> dict[str, Figure]:
    """The continuous study: success rate p and mean X/a against the ROC lattice K (and real ROCs)
    per agent, and X/a against step n for each lattice (``continuous-K<K>``, ``continuous-real``).

    Stroke sketches are drawn for the paper's lattice (K = 1) only, whose cycles go corner to corner.
    """
    rows = as_run_rows(rows)
    groups = sorted(
        {r.group for r in rows},
        key=lambda g: (g == "continuous", int(g[2:]) if g[:2] == "K=" else 0),
    )
    labels = {g: ("real" if g == "continuous" else g[2:]) for g in groups}
    figs = {
        "continuous": grid_figure(
            rows,
            "group",
            order=groups,
            tick_labels=labels,
            xlabel="ROC levels K (real: PPO on real-valued ROCs)",
            note=note,
        )
    }
    for g in groups:
        sel = [r for r in rows if r.group == g]
        cycles = learned_cycles(sel) if g == "K=1" else None
        figs[f"continuous-{'real' if g == 'continuous' else 'K' + g[2:]}"] = curves_figure(
            sel, cycles=cycles, note=note
        )
    return figs


def draw_figures(
    study: str, rows: Sequence[Mapping[str, Any]], folder: str | Path, note: str | None = None
) -> list[Path]:
    """The study's figures (`study_figures`) as PNG and PDF in ``folder``.

    Parameters
    ----------
    study : str
        The study's name (``metadata.json``'s ``study``): it picks the figures.
    rows : sequence of mappings
        The study's run rows (``runs.jsonl``); failed runs (`jswim.results.is_failed`) are left out.
    folder : path
        Where the files go (created if missing), usually ``FOLDER/figures``.
    note : str, optional
        Written across each figure in red (`jswim.results.unfinished_note`).

    Returns
    -------
    list of Path
        The files written, a PNG and a PDF per figure.
    """
    typed = [r for r in as_run_rows(rows) if not is_failed(r)]  # failed runs are not results
    paths: list[Path] = []
    for name, fig in study_figures(study, typed, note=note).items():
        paths += save(fig, folder, name)
    return paths
