"""The success rules study kinds declare (`jswim.studies.study.Study.success`), each in one line:
what a study's rows' ``success`` means, as the code that judges them has it. A folder's
``metadata.json`` records it (``success_criterion``) and its page shows it, so the record names
the rule its runs were judged by, not another study's.

- `gait_rule` (the paper's studies): the gait criterion
  ([`jswim.judging.gait.judge`][jswim.judging.gait.judge], with the study's
  [`Criterion`][jswim.judging.gait.Criterion]).
- `lattice_rule` (``continuous``): the same on each cell's K lattice, and for PPO's real-valued
  runs with cycles read from the shape ([`jswim.judging.shape_judge`][jswim.judging.shape_judge]).
- `scene_rule` and `wall_rule` (``pair``, ``school``, ``wall``): the gait criterion on each
  swimmer's own moves, with the bulk fluid's displacements (`jswim.studies.scene_studies`); a
  pair or a school succeeds when every swimmer does; the wall's fate is measured beside it, not
  judged.
- `navigation_rule` (``navigate``): the target reached within its step budget
  ([`jswim.studies.kinds.navigate.nav_row`][jswim.studies.kinds.navigate.nav_row]); no gait is
  judged.

Each takes ``(plans, horizon, steps)``: the runs the folder plans (their agents, scenes, targets,
flows and lengths), the gait criterion's horizon (`StudyOptions.horizon`) and ``--steps`` as given
(``None``: the study's own lengths; a navigation target's budget); each returns the rule, naming
the code that applies it.
"""

from __future__ import annotations

import json
from collections.abc import Sequence

from jswim.env.targets import BUDGET_SAFETY, FLOW_BUDGET_FACTOR, target_from_dict
from jswim.judging.gait import Criterion
from jswim.judging.shape_judge import SHAPE_TOL
from jswim.studies.options import CONTINUOUS_AGENT
from jswim.studies.plans import Plan
from jswim.swimmers.models import SWIMMERS

__all__ = ["gait_rule", "lattice_rule", "navigation_rule", "scene_rule", "wall_rule"]


def _gait(plans: Sequence[Plan], horizon: int) -> str:
    lengths = [p.steps for p in plans if p.steps is not None]
    return Criterion(horizon=horizon).describe(max(lengths, default=None))


def _real(plans: Sequence[Plan]) -> str:
    if not any(p.agent == CONTINUOUS_AGENT for p in plans):
        return ""
    return (
        f"; PPO's real-valued runs: the same, with a cycle a return to the same shape within "
        f"{SHAPE_TOL:g} of each DOF's range (jswim.judging.shape_judge)"
    )


def _unjudged(plans: Sequence[Plan]) -> str:
    if all(p.swimmer in SWIMMERS for p in plans):
        return ""
    return "; a registered world's runs are not judged (the threshold is a paper swimmer's best stroke)"


def gait_rule(plans: Sequence[Plan], horizon: int, steps: int | None = None) -> str:
    """The paper's criterion: a stroke found (`jswim.judging.gait.judge`)."""
    return f"{_gait(plans, horizon)}{_real(plans)}{_unjudged(plans)}"


def lattice_rule(plans: Sequence[Plan], horizon: int, steps: int | None = None) -> str:
    """The paper's criterion on each cell's ROC lattice K (the continuous study)."""
    levels = sorted({p.roc_levels for p in plans if p.roc_levels})
    on = ", ".join(f"K={k}" for k in levels)
    return f"{_gait(plans, horizon)}, on each cell's ROC lattice ({on}){_real(plans)}{_unjudged(plans)}"


def scene_rule(
    plans: Sequence[Plan], horizon: int, steps: int | None = None, fate: str = ""
) -> str:
    """The paper's criterion on each swimmer's own moves in a scene (a pair, a school)."""
    many = max((_swimmers(p.scene) for p in plans), default=1)
    who = "; a pair or a school succeeds when every one of its swimmers does" if many > 1 else ""
    return (
        f"{_gait(plans, horizon)}, on each swimmer's own moves with the bulk fluid's displacements "
        f"(jswim.studies.scene_studies){who}{_real(plans)}{fate}{_unjudged(plans)}"
    )


def wall_rule(plans: Sequence[Plan], horizon: int, steps: int | None = None) -> str:
    """`scene_rule` above a wall, whose fate is measured beside success."""
    fate = "; the fate (trapped, escaped, gliding) is measured beside it, not judged"
    return scene_rule(plans, horizon, steps, fate)


def _swimmers(scene: str) -> int:
    """How many swimmers a plan's scene holds (1 without one)."""
    if not scene:
        return 1
    n = json.loads(scene).get("swimmers", 1)
    return n if isinstance(n, int) and not isinstance(n, bool) else 1


def navigation_rule(plans: Sequence[Plan], horizon: int, steps: int | None = None) -> str:
    """The navigation study's rule: the target reached within its budget."""
    radii = sorted({target_from_dict(json.loads(p.target)).radius for p in plans if p.target})
    within = ", ".join(f"{r:g}" for r in radii) or "?"
    if steps is not None:
        budget = f"--steps {steps}"
    else:
        budget = f"the steering controller's estimated steps times {BUDGET_SAFETY:g}"
        if any(p.flow for p in plans):
            budget += f", in a flow at least {FLOW_BUDGET_FACTOR} times Zermelo's least time"
    return (
        f"the target reached: the swimmer's centroid within the target's radius ({within} a) of "
        "it (a path: of its last waypoint; a moving target: of where it is then) within the "
        f"target's step budget ({budget}); Q-learning and PPO: their last training episode that "
        "ended; no gait is judged (jswim.studies.kinds.navigate.nav_row)"
    )
