"""The paper's experiments as study grids, run in batches and stored resumably.

- :mod:`jswim.studies.grids`: every study's defaults and cells as one table (:data:`SPECS`),
  :class:`StudyOptions` and :func:`build` (study -> list of :class:`Plan`);
- :mod:`jswim.studies.run`: :func:`run_study` (runs what a study folder lacks, stores, summarises);
- :mod:`jswim.studies.report`: :func:`summarize` (the table) and :func:`draw_figures`;
- :mod:`jswim.studies.qlearn`: the Q-learning steps-to-learn distributions (``jswim qlearn``).

Studies (``jswim study NAME``):

``curves``     X/a against step n: LLM, Q-learning and random policy, both swimmers (Fig. 2)
``history``    the n_ht sweep, both directions, both swimmers (Fig. 3)
``noise``      mean X/a and success rate p against zeta (Fig. 4)
``ablation``   the full prompt and the prompt without each of S1..S5 (Fig. 5)
``inits``      all four initial configurations, both directions
``swim``       the main job: a few LLM runs next to Q-learning and random learners
``competence`` every protocol variant (:data:`jswim.agents.variants.VARIANTS`) next to random and
               Q-learning baselines on both action sets: how much of the swimming is the model's
"""

from jswim.llm.backend import Backend, check_server
from jswim.studies.grids import (
    AGENTS,
    COMPETENCE_VARIANTS,
    DEFAULT_ZETAS,
    INIT_CHOICES,
    SPECS,
    STUDIES,
    SWIM_VARIANT,
    Plan,
    StudyOptions,
    StudySpec,
    build,
)
from jswim.studies.report import draw_figures, summarize
from jswim.studies.run import ProgressFn, StudyResult, default_folder, identity, run_study

__all__ = [
    "AGENTS", "Backend", "COMPETENCE_VARIANTS", "DEFAULT_ZETAS", "INIT_CHOICES", "Plan", "ProgressFn", "SPECS",
    "STUDIES", "SWIM_VARIANT", "StudyOptions", "StudyResult", "StudySpec", "build", "check_server",
    "default_folder", "draw_figures", "identity", "run_study", "summarize",
]
