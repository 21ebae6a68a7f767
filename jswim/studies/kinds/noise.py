"""``jswim study noise``: mean X/a and success rate p against the noise level zeta (the paper's
Fig. 4)."""

from __future__ import annotations

from jswim.studies.options import WITH_BASELINES, StudyOptions
from jswim.studies.plans import Cell
from jswim.studies.study import Study
from jswim.studies.success import gait_rule


def cells(o: StudyOptions, swimmer: str) -> list[Cell]:
    """One cell per zeta of ``--zetas``: the LLM next to Q-learning and the random policy."""
    return [Cell(f"zeta={z:g}", WITH_BASELINES, zeta=z, n_ht=o.n_ht) for z in o.zetas]


STUDY = Study(
    name="noise",
    help="mean X/a and success rate p against the noise level zeta (Fig. 4)",
    cells=cells,
    runs=10,
    ignores=("zeta", "n_hts", "roc_levels_grid"),
    success=gait_rule,
    order=3,
    figures=("noise",),
)
