"""Planning is cheap: building a study's grid computes no physics. A navigation run's steps are its
target's budget, which the world measures; `with_budgets` fills them in before the runs start."""

from __future__ import annotations

import dataclasses
import json
import sys

from jswim.env.targets import default_budget, target_from_dict
from jswim.studies.kinds import navigate
from jswim.studies.options import PPO_SHARE, StudyOptions
from jswim.studies.specs import build
from jswim.swimmers.models import make_model

PHYSICS = ("env/loops.py", "env/step_tables.py", "env/work.py", "swimmers/turning.py")


def _physics_calls(fn):
    seen = []

    def profile(frame, event, arg):
        name = frame.f_code.co_filename.replace("\\", "/")
        if event == "call" and "/jswim/" in name and name.endswith(PHYSICS):
            seen.append(f"{name.rsplit('/jswim/', 1)[1]}:{frame.f_code.co_name}")

    sys.setprofile(profile)
    try:
        out = fn()
    finally:
        sys.setprofile(None)
    return out, seen


def test_building_the_navigation_grid_computes_no_physics():
    plans, seen = _physics_calls(lambda: build("navigate", StudyOptions(roc_levels=2)))
    assert plans and not seen, seen[:5]
    assert all(p.steps is None for p in plans)  # the targets' budgets, left to their worlds


def test_with_budgets_gives_each_run_its_target_s_budget_times_its_episodes():
    o = StudyOptions(roc_levels=2)
    plans = navigate.with_budgets(build("navigate", o))
    model = make_model("purcell")
    for p in plans:
        budget = default_budget(target_from_dict(json.loads(p.target)), model, p.roc_levels)
        learner = p.agent in ("qlearning", "ppo")
        share = PPO_SHARE if p.agent == "ppo" else 1
        episodes = max(1, o.train_episodes // share) if learner else 1
        assert p.steps == budget * episodes, p.run_id
    assert {p.agent for p in plans if p.episodes > 1} == {"qlearning", "ppo"}


def test_steps_given_are_kept_and_other_studies_plan_their_steps_as_before():
    o = dataclasses.replace(StudyOptions(roc_levels=2), steps=30)
    plans = build("navigate", o)
    assert {p.steps for p in plans if p.agent == "llm"} == {30}
    assert navigate.with_budgets(plans) == plans
    curves = build("curves", StudyOptions())
    assert all(isinstance(p.steps, int) for p in curves)
