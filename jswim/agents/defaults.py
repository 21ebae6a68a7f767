"""Per-swimmer defaults of the agents, from the paper and, where it is silent, the authors' code
(``../shared/fidelity.md``): the ROC set offered, the history length n_ht, the clearing rule,
the start, the reply length limit and how DOF values are written in the prompt. Physics
([`jswim.swimmers.models.SwimmerModel`][jswim.swimmers.models.SwimmerModel]) knows nothing of these; every agent reads them here.
"""

from __future__ import annotations

from jswim.agents.memory import ClearingRule
from jswim.action_codes import check_roc_levels, offered_rocs
from jswim.prompt import SwimmerText
from jswim.swimmers.models import SwimmerModel


def default_rocs(model: SwimmerModel, roc_levels: int = 1) -> tuple[int, ...]:
    """ROCs offered to an agent on ``model`` ([`offered_rocs`][jswim.action_codes.offered_rocs])."""
    return offered_rocs(model.n_dof, roc_levels)


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
    [`jswim.env.start_orientation`][jswim.env.state.start_orientation]'s).
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


def dof_decimals(model: SwimmerModel, roc_levels: int = 1) -> int:
    """Decimals of DOF values in the prompt: angles 3; sphere arms as few as write every point of
    the ROC lattice exactly.

    On the paper's corners (``roc_levels = 1``) arms are whole numbers (6 and 10): 0 decimals. A
    ROC lattice of ``K`` levels puts arms at ``lo + j (hi - lo) / K``: NG's arms (6..10) need 0
    decimals for K = 2 or 4 (steps of 2 and 1), 1 for K = 5 or 10 (0.8, 0.4), and 3 (the angles'
    precision, which tells lattice points 0.001 apart) when no decimal count up to 3 is exact
    (K = 3: steps of 1.333...).
    """
    if model.planar:
        return 3
    k = check_roc_levels(roc_levels)
    lo, step = float(model.lo), (float(model.hi) - float(model.lo)) / k
    for d in range(4):
        if all(abs(v * 10**d - round(v * 10**d)) < 1e-9 for v in (lo, step)):
            return d
    return 3


def swimmer_text(
    model: SwimmerModel, rocs: tuple[int, ...] | None = None, roc_levels: int = 1
) -> SwimmerText:
    """What the prompt needs to know about ``model`` (``rocs`` default `default_rocs`) with
    ROCs on ``roc_levels`` levels (1: the paper's)."""
    return SwimmerText(
        model.n_dof,
        model.lo,
        model.hi,
        dof_decimals(model, roc_levels),
        tuple(default_rocs(model, roc_levels) if rocs is None else rocs),
        roc_levels,
    )
