"""Per-swimmer defaults of the agents, from the paper and, where it is silent, the authors' code
(``../shared/fidelity.md``): the ROC set offered, the history length n_ht, the clearing rule,
the start, the reply length limit and how DOF values are written in the prompt. Physics
(:class:`jswim.swimmers.models.SwimmerModel`) knows nothing of these; every agent reads them here.
"""

from __future__ import annotations

from jswim.agents.memory import ClearingRule
from jswim.prompt import SwimmerText
from jswim.swimmers.models import SwimmerModel


def default_rocs(model: SwimmerModel) -> tuple[int, ...]:
    """ROCs offered to an agent: the paper's {-1, 0, 1} for two DOFs, {-1, 1} for more (the
    published four-DOF setting)."""
    return (-1, 0, 1) if model.n_dof == 2 else (-1, 1)


def default_n_ht(model: SwimmerModel, direction: int = 1) -> int:
    """History records shown to the LLM by default.

    NG's swimmer: 3 toward +x and 6 toward -x (the paper's choice). Purcell's: 3, the authors'
    code's default (the paper reports that n_ht = 1 works only by coincidence and 2 degrades).
    More than two DOFs: 20 (the authors' four-DOF code).
    """
    if model.n_dof > 2:
        return 20
    if model.kind in ("ng", "nsphere"):
        return 3 if direction > 0 else 6
    return 3


def default_clearing(model: SwimmerModel) -> ClearingRule:
    """The authors' clearing rule for ``model`` (all: from step 6, with >= 6 records since the
    last clear).

    - two DOFs (Purcell, NG): the last 4 displacements, summed and rounded to 3 decimals, < 0.01;
    - four-link (more hinges): the last 40, not rounded, < 0.05;
    - four-sphere (more arms): the last 5, rounded to 3 decimals, < 0.05.
    """
    if model.n_dof == 2:
        return ClearingRule(min_steps=6, min_records=6, window=4, threshold=0.01, decimals=3)
    if model.planar:
        return ClearingRule(min_steps=6, min_records=6, window=40, threshold=0.05, decimals=None)
    return ClearingRule(min_steps=6, min_records=6, window=5, threshold=0.05, decimals=3)


def paper_init(model: SwimmerModel) -> tuple[int, ...]:
    """The authors' start as levels (1 = hi, 0 = lo).

    Purcell (pi/3, pi/3): ``(1, 1)``; NG (10, 6): ``(1, 0)``; four-sphere (6, 10, 10):
    ``(0, 1, 1)`` (longer: the first arm short, the others long); four-link: every hinge at
    +2pi/9, ``(1, 1, 1)`` (the orientation, chain symmetric about x, is
    :func:`jswim.env.start_orientation`'s).
    """
    n = model.n_dof
    if model.kind == "ng":
        return (1, 0)
    if model.kind == "nsphere":
        return (0,) + (1,) * (n - 1)
    return (1,) * n


def default_max_tokens(model: SwimmerModel) -> int:
    """Reply length limit of a request: 10 tokens for two DOFs, 20 for more (the authors' code)."""
    return 10 if model.n_dof == 2 else 20


def dof_decimals(model: SwimmerModel) -> int:
    """Decimals of DOF values in the prompt: angles 3, sphere arms 0."""
    return 3 if model.planar else 0


def swimmer_text(model: SwimmerModel, rocs: tuple[int, ...] | None = None) -> SwimmerText:
    """What the prompt needs to know about ``model`` (``rocs`` default :func:`default_rocs`)."""
    return SwimmerText(model.n_dof, model.lo, model.hi, dof_decimals(model),
                       tuple(default_rocs(model) if rocs is None else rocs))
