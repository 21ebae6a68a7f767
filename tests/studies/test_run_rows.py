"""The typed run row: one builder for the bulk and the scene rows, the LLM fields merged
in one step, today's columns in today's order, and rows that round-trip through their dict."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from jswim.agents.llm import RunResult
from jswim.agents.variants import LLMRunSpec
from jswim.judging.gait import GaitReport
from jswim.llm.usage import UsageTotals
from jswim.results import RunRow
from jswim.studies import baselines, rows, scene_studies
from jswim.studies.plans import Plan
from jswim.studies.scene_grids import wall_scene, pair_scene

# The documented columns (docs: RunRow), written out here.
HEAD = [
    "run_id",
    "agent",
    "swimmer",
    "direction",
    "init",
    "zeta",
    "seed",
    "n_ht",
    "drop",
    "action_set",
    "group",
    "variant",
    "steps",
    "final_x",
    "signed_final_x",
    "success",
    "learned",
    "steps_to_learn",
    "period",
    "roc_levels",
]
USAGE = [
    "error",
    "failed_steps",
    "parse_retries",
    "truncated",
    "cut_thinking",
    "reasoning_tokens",
    "http_retries",
    "n_clears",
    "calls",
    "billed_calls",
    "cache_hits",
    "prompt_tokens",
    "completion_tokens",
    "cached_tokens",
    "cost_usd",
    "tokens_seen",
    "replayed_calls",
]
SCENE = [
    "scene",
    "medium",
    "n_swimmers",
    "start_height",
    "separation",
    "fate",
    "mean_height",
    "speed",
    "per_cycle",
]
# The LLM agent's switches as the driver records them; "variant" and "action_set" are the plan's columns.
KNOBS = {
    "variant": "paper",
    "action_set": "all",
    "summary": False,
    "shuffle": False,
    "temperature": 0.0,
    "order": "oldest",
    "share_identical": True,
    "constraint": "none",
    "max_tokens": 64,
}
KNOB_COLUMNS = [
    "summary",
    "shuffle",
    "temperature",
    "order",
    "share_identical",
    "constraint",
    "max_tokens",
]

VERDICT = {"success": True, "learned": True, "steps_to_learn": 2, "period": 4}
X = [0.5, 0.25, 1.0, 1.5]


def _plan(agent: str, scene: str = "") -> Plan:
    return Plan(
        run_id=f"g-{agent}-0",
        agent=agent,
        swimmer="ng",
        direction=-1,
        init=(1, 0),
        zeta=0.1,
        seed=7,
        steps=len(X),
        n_ht=3 if agent == "llm" else None,
        drop=frozenset({"S3", "S1"}),
        group="g",
        variant="paper" if agent == "llm" else "",
        scene=scene,
    )


def _result(plan: Plan, swimmers: int = 1) -> RunResult:
    spec = LLMRunSpec(
        swimmer="ng",
        direction=plan.direction,
        zeta=plan.zeta,
        seed=plan.seed,
        n_steps=len(X),
        run_id=plan.run_id,
        scene=plan.scene,
    )
    r = RunResult(
        plan.run_id,
        spec,
        3,
        (-1, 0, 1),
        status="below_x_min",
        levels0=[1, 0],
        x=list(X),
        y=[0.0] * 4,
        orientation=[0.1] * 4,
        actions=[5, 0, 3, 2],
        stuck=[False] * 4,
        failed_steps=1,
        usage=UsageTotals(calls=4, prompt_tokens=100, completion_tokens=8, cost_usd=0.25),
        tokens_seen=108,
        below_x_min=2,
        knobs=dict(KNOBS),
        per_swimmer=bool(plan.scene),
    )
    if plan.scene:
        r.xs, r.heights = [[v] * swimmers for v in X], [[3.0] * swimmers for _ in X]
        r.tilts, r.contact = [[0.0] * swimmers for _ in X], [False] * 4
    return r


def _scene_row(plan: Plan, tracks: dict, z0: float = 3.0) -> RunRow:
    # The verdict given, as the real-valued agent gives its own: the lattice judge is tested elsewhere.
    return scene_studies.scene_row(
        plan,
        [5, 0, 3, 2],
        list(X),
        tracks,
        50,
        z0=np.array([z0]),
        tilt0=np.zeros(1),
        judged=dict(VERDICT),
    )


def _tracks(swimmers: int = 1) -> dict:
    return {
        "xs": [[v] * swimmers for v in X],
        "heights": [[3.0] * swimmers for _ in X],
        "tilts": [[0.0] * swimmers for _ in X],
        "contact": [False] * 4,
        "stuck": [False] * 4,
    }


def test_bulk_rows_have_todays_columns_in_order():
    plan = _plan("qlearning")
    pose = (np.zeros((1, 4)), np.ones((1, 4)))
    row = rows.judged_rows(
        [plan],
        np.zeros((1, 4), np.int64),
        np.array([X]),
        np.array([[1, 0]]),
        50,
        pose=pose,
        report=_report(),
    )[0]
    assert list(row.to_dict()) == HEAD + [
        "sample",
        "x",
        "actions",
        "progress",
        "energy",
        "energy_per_distance",
        "efficiency",
        "status",
        "y",
        "orientation",
    ]
    assert row.init == "+-" and row.drop == "S1,S3" and row.sample == 0 and row.scene is None
    assert row.final_x == 1.5 and row.signed_final_x == -1.5  # toward -x
    assert row.progress == pytest.approx([-0.5, 0.25, -0.75, -0.5])
    assert (row.success, row.learned, row.steps_to_learn, row.period) == (True, True, 2, 4)


def _report() -> GaitReport:
    """A judge's verdict on one run (learned at step 2, period 4), given: the judge is tested elsewhere."""
    one = {"success": True, "learned": True, "steps_to_learn": 2, "period": 4}
    return GaitReport(**{k: np.array([one.get(k, 0)]) for k in GaitReport._fields})


def test_bulk_llm_row_merges_the_runs_fields():
    plan = _plan("llm")
    judged = rows.judged_rows(
        [plan], np.zeros((1, 4), np.int64), np.array([X]), np.array([[1, 0]]), 50, report=_report()
    )[0]
    row = rows.with_llm(judged, _result(plan))
    assert (
        list(row.to_dict())
        == HEAD
        + ["sample", "x", "actions", "progress", "energy", "energy_per_distance", "efficiency"]
        + ["status"]
        + USAGE
        + ["y", "orientation", "below_x_min"]
        + KNOB_COLUMNS
    )
    assert (
        row.status == "below_x_min"
        and row.calls == 4
        and row.cost_usd == 0.25
        and row.tokens_seen == 108
    )
    assert row.y == [0.0] * 4 and row.orientation == [0.1] * 4  # the run's own trajectory
    assert (
        row.max_tokens == 64 and row["constraint"] == "none" and row["variant"] == "paper"
    )  # the plan's column
    assert "pair_prompt" not in row and "temperature_sent" not in row  # written only where set
    sent = rows.with_llm(
        judged, dataclasses.replace(_result(plan), knobs={**KNOBS, "temperature_sent": 1.0})
    )
    assert list(sent.to_dict())[-1] == "temperature_sent" and sent.temperature_sent == 1.0


@pytest.mark.parametrize("scene", [wall_scene(3.0), pair_scene(30.0)])
def test_scene_rows_add_the_scene_columns(scene):
    swimmers = baselines.scene_of(_plan("stroke", scene)).swimmers
    stroke = _scene_row(_plan("stroke", scene), _tracks(swimmers))
    assert list(stroke.to_dict()) == HEAD + SCENE + [
        "x",
        "y",
        "orientation",
        "actions",
        "progress",
        "energy",
        "energy_per_distance",
        "efficiency",
        "status",
        "xs",
        "heights",
        "tilts",
        "contact",
        "stuck",
    ]
    assert (
        stroke.medium in ("wall", "free")
        and stroke.n_swimmers == swimmers
        and "sample" not in stroke
    )
    assert (stroke.start_height == 3.0) == (stroke.medium == "wall")
    assert (stroke.separation == 30.0) == (swimmers == 2)
    plan = _plan("llm", scene)
    r = _result(plan, swimmers)
    llm = rows.with_llm(_scene_row(plan, {k: getattr(r, k) for k in _tracks()}), r)
    assert list(llm.to_dict()) == HEAD + SCENE + [
        "x",
        "y",
        "orientation",
        "actions",
        "progress",
        "energy",
        "energy_per_distance",
        "efficiency",
        "status",
    ] + USAGE + ["stuck", "below_x_min"] + KNOB_COLUMNS + ["xs", "heights", "tilts", "contact"]
    assert llm.y == [3.0] * 4  # swimmer 1's height, not the run's bulk y
    assert llm.fate == ("gliding" if llm.medium == "wall" else None)


def test_a_row_round_trips_and_reads_as_a_mapping():
    plan = _plan("llm", wall_scene(3.0))
    r = _result(plan)
    row = rows.with_llm(_scene_row(plan, {k: getattr(r, k) for k in _tracks()}), r)
    d = row.to_dict()
    back = RunRow.from_dict(d)
    assert back == row and list(back.to_dict()) == list(d) and back.to_dict() == d
    assert dict(row) == d and row["fate"] == row.fate and row.get("no such column") is None
    with pytest.raises(KeyError):
        _ = rows.build_row(_plan("random"), X, [], VERDICT, init="+-")[
            "medium"
        ]  # a bulk row has no scene
    old = RunRow.from_dict({"run_id": "r", "agent": "random", "allowed": "two", "extra_column": 1})
    assert old.action_set == "two" and old["extra_column"] == 1 and old.medium is None
