"""``jswim study inits``: the LLM from each of the four initial configurations, both
directions."""

from __future__ import annotations

from jswim.agents.variants import init_label
from jswim.env import all_inits
from jswim.studies.options import StudyOptions
from jswim.studies.plans import Cell
from jswim.studies.study import Study
from jswim.studies.success import gait_rule


def cells(o: StudyOptions, swimmer: str) -> list[Cell]:
    """One LLM cell per initial configuration (++, +-, -+, --)."""
    return [
        Cell(f"init {init_label(i)}", ("llm",), n_ht=o.n_ht, init=init_label(i))
        for i in all_inits(2)
    ]


STUDY = Study(
    name="inits",
    help="the four initial configurations",
    cells=cells,
    runs=1,
    directions=(1, -1),
    ignores=("zetas", "n_hts", "q_runs", "init", "roc_levels_grid"),
    success=gait_rule,
    order=5,
    figures=("inits",),
)
