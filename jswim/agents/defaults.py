"""Per-swimmer defaults of the agents: the ROC set they are offered, the history length n_ht and
how DOF values are written in the prompt. Physics (:class:`jswim.swimmers.models.SwimmerModel`)
knows nothing of these; every agent reads them here.
"""

from __future__ import annotations

from jswim.prompt import SwimmerText
from jswim.swimmers.models import SwimmerModel


def default_rocs(model: SwimmerModel) -> tuple[int, ...]:
    """ROCs offered to an agent: the paper's {-1, 0, 1} for two DOFs, {-1, 1} for more (the
    published four-DOF setting)."""
    return (-1, 0, 1) if model.n_dof == 2 else (-1, 1)


def default_n_ht(model: SwimmerModel, direction: int = 1) -> int:
    """History records shown to the LLM by default.

    The paper picks n_ht = 3 (+x) and 6 (-x) for NG's swimmer and reports that n_ht = 1 works for
    Purcell's only by coincidence; 4 (one stroke cycle) is used for Purcell here. The published
    four-DOF setting uses 20.
    """
    if model.n_dof > 2:
        return 20
    if model.kind in ("ng", "nsphere"):
        return 3 if direction > 0 else 6
    return 4


def dof_decimals(model: SwimmerModel) -> int:
    """Decimals of DOF values in the prompt: angles 3, sphere arms 0."""
    return 3 if model.planar else 0


def swimmer_text(model: SwimmerModel, rocs: tuple[int, ...] | None = None) -> SwimmerText:
    """What the prompt needs to know about ``model`` (``rocs`` default :func:`default_rocs`)."""
    return SwimmerText(model.n_dof, model.lo, model.hi, dof_decimals(model),
                       tuple(default_rocs(model) if rocs is None else rocs))
