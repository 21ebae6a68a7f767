"""``jswim study temperature``: p and steps to learn against the sampling temperature T, both
swimmers and directions (the paper's "next thing to study": T = 0 was its only setting)."""

from __future__ import annotations

from jswim.studies.options import StudyOptions
from jswim.studies.plans import Cell
from jswim.studies.study import Study
from jswim.studies.success import gait_rule

#: The temperatures swept when ``--temperatures`` is not given.
DEFAULT_TEMPERATURES = (0.0, 0.25, 0.5, 0.75, 1.0)


def cells(o: StudyOptions, swimmer: str) -> list[Cell]:
    """One LLM cell per temperature."""
    return [
        Cell(f"T={t:g}", ("llm",), n_ht=o.n_ht, temperature=t)
        for t in o.temperatures or DEFAULT_TEMPERATURES
    ]


STUDY = Study(
    name="temperature",
    help="the LLM runs over a grid of sampling temperatures",
    cells=cells,
    runs=5,
    init="paper",
    directions=(1, -1),
    ignores=("zetas", "n_hts", "q_runs", "roc_levels_grid"),
    temperatures=DEFAULT_TEMPERATURES,
    success=gait_rule,
    order=8,
    figures=("temperature",),
)
