"""``jswim study continuous`` (an extension; README "Continuous strokes"): the LLM, lattice
Q-learning and the random policy at ROC lattices K in {1, 2, 5, 10}, and the real-valued RL
baseline (PPO), both swimmers, both directions."""

from __future__ import annotations

from jswim.studies.options import (
    CONTINUOUS_AGENT,
    DEFAULT_ROC_LEVELS,
    WITH_BASELINES,
    StudyOptions,
    continuous_agent_available,
)
from jswim.studies.plans import Cell
from jswim.studies.study import Study
from jswim.studies.success import lattice_rule


def cells(o: StudyOptions, swimmer: str) -> list[Cell]:
    """Each lattice for the LLM and both tabular baselines, then PPO once (when installed)."""
    lattices = [
        Cell(f"K={k}", WITH_BASELINES, n_ht=o.n_ht, roc_levels=k) for k in o.roc_levels_grid
    ]
    real = (
        [Cell("continuous", (CONTINUOUS_AGENT,), roc_levels=0)]
        if continuous_agent_available()
        else []
    )
    return lattices + real


STUDY = Study(
    name="continuous",
    help="finer ROCs (K in 1, 2, 5, 10) for the LLM, lattice Q-learning and random policy, and "
    "the real-valued PPO baseline",
    cells=cells,
    runs=2,
    init="paper",
    directions=(1, -1),
    ignores=("zetas", "n_hts", "roc_levels"),
    success=lattice_rule,
    order=9,
    figures=("continuous",),
    option_help={
        "--roc-levels": "the ROC levels K to compare (an extension): a reply's ROC k in -K..K "
        "moves the DOF by k/K of its range, for the LLM and the lattice baselines alike "
        f"(default {','.join(map(str, DEFAULT_ROC_LEVELS))}; 1 is the paper's -1, 0, 1)"
    },
)
