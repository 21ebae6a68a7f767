"""What the prompt knows of a swimmer: [`SwimmerText`][jswim.prompt.SwimmerText] (DOFs, ranges,
ROCs, scene), the actions a reply may name, and the sentences finer ROCs add.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from jswim.action_codes import check_action_set, check_roc_levels
from jswim.errors import ConfigError
from jswim.prompt.numbers import Action
from jswim.prompt.nav_text import NavView
from jswim.prompt.scene_text import SceneView


@dataclass(frozen=True)
class SwimmerText:
    """What the prompt needs to know about a swimmer.

    Attributes
    ----------
    n_dof : int
        Number of DOFs, named D1..Dn.
    lo, hi : float or tuple of float
        DOF range, shared by all DOFs or one value per DOF.
    dof_decimals : int
        Decimals of DOF values in text (angles 3, NG arm lengths 0 on the paper's corners; see
        `jswim.agents.defaults.dof_decimals` for finer ROC lattices).
    rocs : tuple of int
        ROCs an action may carry: ``(-1, 0, 1)`` (paper), ``(-1, 1)`` for 4-DOF swimmers; with
        ``roc_levels = K`` integers in ``-K..K`` (``k`` means ``k/K`` of the range per step).
    roc_levels : int
        ``K`` (1, the paper's set, by default). Above 1, S2 and S5 each get one sentence saying
        what the integer ROC means (`ROC_SCALE_SENTENCE`, `ROC_FORMAT_SENTENCE`).
    scene : SceneView, optional
        A wall and/or a second swimmer ([`SceneView`][jswim.prompt.SceneView]); ``None``: the paper's bulk fluid.
    nav : NavView, optional
        A navigation task ([`NavView`][jswim.prompt.NavView]: S1 names the target, records give X,
        Y and the heading); ``None``: the paper's task along +x or -x.
    """

    n_dof: int
    lo: float | tuple[float, ...]
    hi: float | tuple[float, ...]
    dof_decimals: int = 3
    rocs: tuple[int, ...] = (-1, 0, 1)
    roc_levels: int = 1
    scene: SceneView | None = None
    nav: NavView | None = None

    def __post_init__(self) -> None:
        if self.n_dof < 1:
            raise ConfigError(f"n_dof must be >= 1, got {self.n_dof}")
        k = check_roc_levels(self.roc_levels)
        if not self.rocs or any(
            isinstance(r, bool) or not isinstance(r, int) or abs(r) > k for r in self.rocs
        ):
            raise ConfigError(
                f"rocs must be a non-empty set of integers in -{k}..{k} (--roc-levels {k}), "
                f"got {self.rocs}"
            )
        object.__setattr__(self, "rocs", tuple(sorted(set(self.rocs))))

    def bounds(self, k: int) -> tuple[float, float]:
        """``(lo, hi)`` of DOF ``k`` (1-based)."""
        lo = self.lo[k - 1] if isinstance(self.lo, tuple) else self.lo
        hi = self.hi[k - 1] if isinstance(self.hi, tuple) else self.hi
        return float(lo), float(hi)

    @property
    def names(self) -> list[str]:
        return [f"D{k}" for k in range(1, self.n_dof + 1)]


#: S2's extra sentence when ``roc_levels = K > 1`` (the paper's K = 1 prompt has none).
ROC_SCALE_SENTENCE = (
    "In one step a ROC of k changes the DOF by k/{roc_levels} of its range, stopping at its limits."
)


#: S5's extra sentence when ``roc_levels = K > 1``: the reply carries a whole number, as the paper
#: advises (no decimals; the sign is the only non-digit).
ROC_FORMAT_SENTENCE = "The ROC is a whole number from -{roc_levels} to {roc_levels}{except_zero}."


def allowed_actions(
    swimmer: SwimmerText, action_set: str = "all", dof_values: Sequence[float] | None = None
) -> list[Action]:
    """The actions a reply may name, in (dof, roc) order.

    Parameters
    ----------
    swimmer : SwimmerText
        DOF count, ranges and ROC set.
    action_set : {"all", "shape-changing"}
        One of `jswim.action_codes.ACTION_SETS`. ``"all"``: every (dof, roc) pair (the paper's setting). ``"shape-changing"``: only moves
        that change the shape from ``dof_values``: a positive ROC below ``hi``, a negative one above ``lo``.
    dof_values : sequence of float, optional
        Current DOF values; required for ``"shape-changing"``.
    """
    check_action_set(action_set)
    pairs = [Action(k, r) for k in range(1, swimmer.n_dof + 1) for r in swimmer.rocs]
    if action_set == "all":
        return pairs
    if dof_values is None or len(dof_values) != swimmer.n_dof:
        raise ConfigError("action_set='shape-changing' needs the current value of every DOF")
    out = []
    for a in pairs:
        lo, hi = swimmer.bounds(a.dof)
        v = float(dof_values[a.dof - 1])
        tol = 1e-9 * max(1.0, abs(hi - lo))
        if (a.roc > 0 and v < hi - tol) or (a.roc < 0 and v > lo + tol):
            out.append(a)
    return out
