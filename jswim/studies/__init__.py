"""The paper's experiments as study grids, run in batches and stored resumably.

- [`jswim.studies.study`][jswim.studies.study]: a study kind as one object
  ([`Study`][jswim.studies.study.Study]: its defaults, cells, options, success rule and figures)
  and the registry, [`get`][jswim.studies.study.get] and [`names`][jswim.studies.study.names];
  each kind is one module of [`jswim.studies.kinds`][jswim.studies.kinds];
- [`jswim.studies.options`][jswim.studies.options]: [`StudyOptions`][jswim.studies.options.StudyOptions], the knobs; [`jswim.studies.specs`][jswim.studies.specs]:
  [`build`][jswim.studies.specs.build] (study -> list of [`Plan`][jswim.studies.plans.Plan],
  [`jswim.studies.plans`][jswim.studies.plans]; the scene studies' cells in
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

Studies (``jswim study NAME``, ``jswim swim``): `jswim.studies.names()`, each one module of
`jswim.studies.kinds` that says what it measures.
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
    "build": "jswim.studies.specs",
    **dict.fromkeys(("Study", "get", "names"), "jswim.studies.study"),
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
