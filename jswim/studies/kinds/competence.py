"""``jswim study competence``: every protocol variant (`jswim.agents.variants.VARIANTS`) next to
random and Q-learning baselines on both action sets: how much of the swimming is the model's."""

from __future__ import annotations

from jswim.action_codes import ACTION_SETS
from jswim.studies.options import COMPETENCE_VARIANTS, StudyOptions
from jswim.studies.plans import Cell
from jswim.studies.study import Study
from jswim.studies.success import gait_rule


def cells(o: StudyOptions, swimmer: str) -> list[Cell]:
    """One LLM cell per variant of ``--variant`` (default `COMPETENCE_VARIANTS`), then the random
    policy and Q-learning on each action set."""
    llm = [Cell(v, ("llm",), n_ht=o.n_ht, variant=v) for v in o.variants or COMPETENCE_VARIANTS]
    return llm + [
        Cell(s, (agent,), action_set=s) for agent in ("random", "qlearning") for s in ACTION_SETS
    ]


STUDY = Study(
    name="competence",
    help="every protocol variant next to random and Q-learning baselines",
    cells=cells,
    runs=10,
    variants_grid=True,
    success=gait_rule,
    order=7,
    figures=("competence",),
    # The grid sets each group's moves: the baselines run on both sets, and a shape-changing
    # variant offers its own whatever --action-set says.
    setting_notes={
        "action_set": "{v} for the LLM variants without shape-changing in their name; the "
        "shape-changing variants offer the moves that change the shape; the baselines run on both "
        "sets (their group names the set)"
    },
)
