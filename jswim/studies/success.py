"""Each study kind's success rule in one line: what its rows' ``success`` means, as the code that
judges them has it. A folder's ``metadata.json`` records it (``success_criterion``) and its page
shows it, so the record names the rule its runs were judged by, not another study's.

- The paper's studies (swim, curves, noise, history, ablation, inits, competence, temperature):
  the gait criterion ([`jswim.judging.gait.judge`][jswim.judging.gait.judge], with the study's
  [`Criterion`][jswim.judging.gait.Criterion]).
- ``continuous``: the same on each cell's K lattice, and for PPO's real-valued runs with cycles
  read from the shape ([`jswim.judging.shape_judge`][jswim.judging.shape_judge]).
- ``wall``, ``pair``, ``school``: the gait criterion on each swimmer's own moves, with the bulk
  fluid's displacements (`jswim.studies.scene_studies`); a pair or
  a school succeeds when every swimmer does; the wall's fate is measured beside it, not judged.
- ``navigate``: the target reached within its step budget
  ([`jswim.studies.navigate.nav_row`][jswim.studies.navigate.nav_row]); no gait is judged.
"""

from __future__ import annotations

import json
from collections.abc import Sequence

from jswim.env.targets import BUDGET_SAFETY, target_from_dict
from jswim.judging.gait import Criterion
from jswim.judging.shape_judge import SHAPE_TOL
from jswim.studies.options import CONTINUOUS_AGENT
from jswim.studies.plans import Plan
from jswim.studies.specs import SPECS
from jswim.swimmers.models import SWIMMERS

#: The studies whose runs move in a scene (a wall, other swimmers), judged per swimmer.
SCENE_STUDIES = ("wall", "pair", "school")


def success_rule(study: str, plans: Sequence[Plan], horizon: int, steps: int | None) -> str:
    """The one line that says what ``success`` means in ``study``'s rows.

    Parameters
    ----------
    study : str
        One of `jswim.studies.specs.STUDIES`.
    plans : sequence of Plan
        The runs the folder plans (their agents, scenes, targets, flows and lengths).
    horizon : int
        Steps of the gait criterion's horizon (`StudyOptions.horizon`).
    steps : int or None
        ``--steps`` as given (``None``: the study's own lengths; a navigation target's budget).

    Returns
    -------
    str
        The rule, naming the code that applies it.
    """
    spec = SPECS.get(study)
    if spec is not None and not spec.judged:
        return _navigation_rule(plans, steps)
    lengths = [p.steps for p in plans if p.steps is not None]
    gait = Criterion(horizon=horizon).describe(max(lengths, default=None))
    ppo = any(p.agent == CONTINUOUS_AGENT for p in plans)
    real = (
        f"; PPO's real-valued runs: the same, with a cycle a return to the same shape within "
        f"{SHAPE_TOL:g} of each DOF's range (jswim.judging.shape_judge)"
        if ppo
        else ""
    )
    unjudged = (
        "; a registered world's runs are not judged (the threshold is a paper swimmer's best stroke)"
        if any(p.swimmer not in SWIMMERS for p in plans)
        else ""
    )
    if study in SCENE_STUDIES:
        many = max((_swimmers(p.scene) for p in plans), default=1)
        who = (
            "; a pair or a school succeeds when every one of its swimmers does" if many > 1 else ""
        )
        fate = (
            "; the fate (trapped, escaped, gliding) is measured beside it, not judged"
            if study == "wall"
            else ""
        )
        return (
            f"{gait}, on each swimmer's own moves with the bulk fluid's displacements "
            f"(jswim.studies.scene_studies){who}{real}{fate}{unjudged}"
        )
    if study == "continuous":
        levels = sorted({p.roc_levels for p in plans if p.roc_levels})
        on = ", ".join(f"K={k}" for k in levels)
        return f"{gait}, on each cell's ROC lattice ({on}){real}{unjudged}"
    return f"{gait}{real}{unjudged}"


def _swimmers(scene: str) -> int:
    """How many swimmers a plan's scene holds (1 without one)."""
    if not scene:
        return 1
    n = json.loads(scene).get("swimmers", 1)
    return n if isinstance(n, int) and not isinstance(n, bool) else 1


def _navigation_rule(plans: Sequence[Plan], steps: int | None) -> str:
    """The navigation study's rule: the target reached within its budget."""
    from jswim.studies.navigate import FLOW_BUDGET_FACTOR  # lazy: the navigation module loads JAX

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
        "ended; no gait is judged (jswim.studies.navigate.nav_row)"
    )
