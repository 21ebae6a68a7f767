"""``jswim study curves``: X/a against step n for the LLM, Q-learning and random policy, both
swimmers (the paper's Fig. 2)."""

from __future__ import annotations

from jswim.studies.options import WITH_BASELINES, StudyOptions
from jswim.studies.plans import Cell
from jswim.studies.study import Study
from jswim.studies.success import gait_rule


def cells(o: StudyOptions, swimmer: str) -> list[Cell]:
    """One cell: the LLM next to Q-learning and the random policy."""
    return [Cell("", WITH_BASELINES, n_ht=o.n_ht)]


STUDY = Study(
    name="curves",
    help="X/a against step n for the LLM, Q-learning and random policy (Fig. 2)",
    cells=cells,
    runs=1,
    init="paper",
    success=gait_rule,
    order=1,
    figures=("curves",),
)
