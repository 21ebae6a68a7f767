"""jswim: a large language model teaches model microswimmers to swim.

A reproduction and extension of Xu & Zhu, "Training microrobots to swim by a large language
model" (Phys. Rev. Applied 23, 044058, 2025): Purcell's and Najafi-Golestanian's swimmers in JAX,
the paper's five-sentence prompt driving them through any OpenAI-compatible server, a tabular
Q-learning baseline and the paper's studies.

Where to start
--------------
- Any world through one protocol: ``env, params = jswim.make("ng", scene)``, then
  ``env.reset``/``env.step`` or ``jswim.rollout(env, params, key, actions)`` (:mod:`jswim.env.base`).
- Step a named swimmer by ``(dof, roc)`` moves: ``jswim.env.rollout("purcell", [(2, -1), (1, -1),
  (2, 1), (1, 1)])`` (one square gait cycle, float64), or the functional environment
  ``make_params``, ``reset``, ``step``, ``step_batch`` (:mod:`jswim.env`).
- Run a study: ``jswim.run_study("swim")`` (the ``jswim swim`` job; options in
  :class:`jswim.studies.StudyOptions`), then ``jswim.load(folder)`` for its runs and trajectories as
  pandas DataFrames (and ``study.transcript(run_id)``, ``study.calls``).
- See runs: ``jswim.animate(study, run_id)`` (inline in Jupyter; ``.save("runs.gif")``), and
  ``jswim.report(folder)`` writes the folder's self-contained ``report.html``.
- The command line: ``jswim --help``. The architecture map: ``docs/design.md``.

The names above load on first use, so ``import jswim`` stays light (JAX loads with them).
"""

from __future__ import annotations

import importlib
from typing import Any

__version__ = "0.1.0"

#: Public name -> the module that owns it (imported on first access, PEP 562).
_EXPORTS = {
    "rollout": "jswim.env.episodes",
    "make": "jswim.env.worlds",
    "register_world": "jswim.env.worlds",
    "make_params": "jswim.env",
    "reset": "jswim.env",
    "step": "jswim.env",
    "step_batch": "jswim.env",
    "run_study": "jswim.studies",
    "StudyOptions": "jswim.studies",
    "load": "jswim.results",
    "animate": "jswim.viz.animate",
    "report": "jswim.viz.page",
    "JswimError": "jswim.errors",
}

__all__ = [*_EXPORTS, "__version__"]


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        value = getattr(importlib.import_module(_EXPORTS[name]), name)
        globals()[name] = value  # later look-ups skip this function
        return value
    raise AttributeError(f"module 'jswim' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))
