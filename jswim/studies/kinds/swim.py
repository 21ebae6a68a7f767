"""``jswim swim``, the main job: a few LLM runs next to Q-learning and random learners, on
Purcell's swimmer."""

from __future__ import annotations

from jswim.studies.kinds.curves import cells
from jswim.studies.options import SWIM_VARIANT
from jswim.studies.study import Study
from jswim.studies.success import gait_rule

STUDY = Study(
    name="swim",
    help="the main job: LLM runs next to Q-learning and random learners",
    cells=cells,
    runs=4,
    init="paper",
    swimmers=("purcell",),
    command="swim",
    variant=SWIM_VARIANT,
    success=gait_rule,
    order=6,
    figures=("curves",),
)
