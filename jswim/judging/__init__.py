"""Judging a run: the success criterion (`gait`), the K-level ROC lattice (`lattice`), real-valued
strokes (`shape_judge`) and the statistics of steps to learn (`stats`).
"""

from jswim._exports import lazy_exports

#: Public name -> the module that defines it (loaded on first use).
_HOMES = {
    "Criterion": ".gait",
    "PAPER": ".gait",
    "GaitReport": ".gait",
    "Cycle": ".gait",
    "judge": ".gait",
    "best_cycles": ".gait",
    "replay": ".gait",
    "stroke_report": ".gait",
    "LatticeCycle": ".lattice",
    "best_lattice_cycles": ".lattice",
    "move_table": ".lattice",
    "judge_shapes": ".shape_judge",
    "LearnStats": ".stats",
    "learn_stats": ".stats",
    "wilson_interval": ".stats",
    "mean_interval": ".stats",
    "quartiles": ".stats",
}

__all__ = list(_HOMES)

__getattr__, __dir__ = lazy_exports(__name__, _HOMES)
