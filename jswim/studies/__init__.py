"""The paper's experiments as study grids, run in batches and stored resumably.

- [`jswim.studies.options`][jswim.studies.options]: [`StudyOptions`][jswim.studies.options.StudyOptions], the knobs; [`jswim.studies.specs`][jswim.studies.specs]:
  every study's defaults and cells as one table (`SPECS`) and [`build`][jswim.studies.specs.build] (study -> list
  of [`Plan`][jswim.studies.plans.Plan], [`jswim.studies.plans`][jswim.studies.plans]; the scene studies' cells in
  [`jswim.studies.scene_grids`][jswim.studies.scene_grids]); [`jswim.studies.baselines`][jswim.studies.baselines]: every non-LLM run's one
  pipeline;
- [`jswim.studies.run`][jswim.studies.run]: [`run_study`][jswim.studies.run.run_study] (runs what a study folder lacks, stores, summarises; draws nothing);
- [`jswim.studies.report`][jswim.studies.report]: [`summarize`][jswim.studies.report.summarize] (the table);
- `jswim.studies.overview`: reading a folder back (`StudyFolder`, the summary table, ``jswim show``
  and ``jswim compare``). A study ends at its folder: figures and ``report.html`` are drawn from
  it by `jswim.viz.publish`;
- `jswim.studies.qlearn`: the Q-learning steps-to-learn distributions (``jswim qlearn``);
- `jswim.studies.ensemble`: one stroke or policy over many noisy swimmers, X/a statistics
  per step (``jswim ensemble``).

Studies (``jswim study NAME``):

``curves``     X/a against step n: LLM, Q-learning and random policy, both swimmers (Fig. 2)
``history``    the n_ht sweep, both directions, both swimmers (Fig. 3)
``noise``      mean X/a and success rate p against zeta (Fig. 4)
``ablation``   the full prompt and the prompt without each of S1..S5 (Fig. 5)
``inits``      all four initial configurations, both directions
``swim``       the main job: a few LLM runs next to Q-learning and random learners
``competence`` every protocol variant (`jswim.agents.variants.VARIANTS`) next to random and
               Q-learning baselines on both action sets: how much of the swimming is the model's
"""

from __future__ import annotations

from jswim._exports import lazy_exports

#: Public name -> the submodule that owns it, imported on first access (PEP 562), so that
#: ``jswim.studies.specs`` (all the command line needs to build its parser) loads alone.
_EXPORTS = {
    **dict.fromkeys(
        (
            "AGENTS",
            "COMPETENCE_VARIANTS",
            "DEFAULT_ZETAS",
            "INIT_CHOICES",
            "SWIM_VARIANT",
            "StudyOptions",
        ),
        "jswim.studies.options",
    ),
    **dict.fromkeys(("SPECS", "STUDIES", "StudySpec", "build"), "jswim.studies.specs"),
    "Plan": "jswim.studies.plans",
    "summarize": "jswim.studies.report",
    **dict.fromkeys(
        ("StudyResult", "default_folder", "identity", "run_study"),
        "jswim.studies.run",
    ),
    **dict.fromkeys(("ProgressFn", "StudySession"), "jswim.studies.session"),
    **dict.fromkeys(("Backend", "check_server"), "jswim.llm.backend"),
}

__all__ = sorted(_EXPORTS)

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
