"""``jswim study history``: the n_ht sweep of the history length, both directions, both
swimmers (the paper's Fig. 3)."""

from __future__ import annotations

from jswim.studies.options import StudyOptions
from jswim.studies.plans import Cell
from jswim.studies.study import Study
from jswim.studies.success import gait_rule


def cells(o: StudyOptions, swimmer: str) -> list[Cell]:
    """One LLM cell per n_ht of ``--n-hts``."""
    return [Cell(f"n_ht={h}", ("llm",), n_ht=h) for h in o.n_hts]


STUDY = Study(
    name="history",
    help="the n_ht sweep of the history length (Fig. 3)",
    cells=cells,
    runs=1,
    init="paper",
    directions=(1, -1),
    ignores=("zetas", "n_ht", "q_runs", "roc_levels_grid"),
    success=gait_rule,
    order=2,
    figures=("history",),
)
