"""``jswim study ablation``: the full prompt and the prompt without each of its sentences S1..S5
(the paper's Fig. 5)."""

from __future__ import annotations

from jswim.prompt import SENTENCES
from jswim.studies.options import StudyOptions
from jswim.studies.plans import Cell
from jswim.studies.study import Study
from jswim.studies.success import gait_rule


def cells(o: StudyOptions, swimmer: str) -> list[Cell]:
    """The full prompt, then one cell per dropped sentence."""
    drops = [frozenset()] + [frozenset({s}) for s in SENTENCES]
    return [
        Cell("full" if not d else f"-{next(iter(d))}", ("llm",), n_ht=o.n_ht, drop=d) for d in drops
    ]


STUDY = Study(
    name="ablation",
    help="the prompt without each of its sentences S1..S5, free-text replies (Fig. 5)",
    cells=cells,
    runs=10,
    ignores=("zetas", "n_hts", "q_runs", "roc_levels_grid"),
    # Free-text replies unless --constrain says otherwise: with a grammar, removing S5 (the
    # reply's format) removes nothing.
    constrain="none",
    success=gait_rule,
    order=4,
    figures=("ablation",),
)
