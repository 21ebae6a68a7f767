"""``jswim study wall --swimmer purcell`` (issue 34): its cells, rows, figure and pictures."""

from __future__ import annotations

import json

import numpy as np
import pytest

from jswim.studies.grids import StudyOptions, build
from jswim.studies.run import run_study
from jswim.swimmers import wall_rft
from jswim.viz import worlds
from jswim.viz.tracks import track

BULK_CYCLE = 0.19124724  # DESIGN.md


def test_purcell_cells_run_every_agent_at_each_height():
    plans = build("wall", StudyOptions(swimmers=("purcell",), heights=(1.5, 10.0), q_runs=2))
    agents = {(p.agent, p.group) for p in plans}
    # the bulk reference stroke, and at each height every agent NG's wall cells run (issue 30)
    assert agents == {("stroke", "bulk")} | {(a, f"h={h}") for h in ("1.5", "10")
                                             for a in ("stroke", "llm", "qlearning", "random", "ppo")}
    per_height = {a: sum(p.agent == a and p.group == "h=10" for p in plans) for a in ("llm", "ppo", "qlearning")}
    assert per_height == {"llm": 1, "ppo": 2, "qlearning": 2}  # the wall study's --runs 1, --q-runs learners
    ppo = [p for p in plans if p.agent == "ppo"]
    assert all(p.roc_levels == 0 and p.action_set == "all" and "-real-" in p.run_id for p in ppo)
    assert {json.loads(p.scene)["medium"] for p in plans} == {"bulk", "wall"}
    assert all(p.init == (1, 1) for p in plans)  # the paper's Purcell start (+, +)
    # NG's wall study is as before: its free reference and its LLM and PPO rows stay
    ng = build("wall", StudyOptions(heights=(10.0,), q_runs=1))
    assert {p.group for p in ng} >= {"free", "h=10"} and "llm" in {p.agent for p in ng}


@pytest.mark.slow  # a study: tables and programs of two models
def test_purcell_wall_study_rows_figure_and_picture(tmp_path):
    out = tmp_path / "pw"
    run_study("wall", StudyOptions(swimmers=("purcell",), heights=(1.5,), q_runs=1, steps=16), out=out)
    rows = [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]
    by = {(r["agent"], r["group"]): r for r in rows}
    assert by[("stroke", "bulk")]["per_cycle"] == pytest.approx(BULK_CYCLE, abs=1e-7)
    wall = by[("stroke", "h=1.5")]
    xi_t, xi_n = wall_rft.drag_coefficients(1.5)
    from tests.physics.test_wall_rft import cycles  # the test-side RK4 at the wall's ratio

    assert wall["per_cycle"] == pytest.approx(float(cycles([xi_n / xi_t])[0, 0]), rel=2e-7)
    assert wall["fate"] == "gliding" and wall["start_height"] == 1.5 and wall["medium"] == "wall"
    assert (out / "figures" / "wall.png").exists() and (out / "report.html").exists()
    # the picture: seen from above, in the swimmer's own plane (its y, not its height)
    t = track(wall)
    assert worlds.from_above(wall) and "above a wall" in t.world.describe() and not t.world.wall
    np.testing.assert_allclose(t.y[1:], wall["y"])
    assert np.abs(t.bodies[..., 1]).max() < 1.2  # links within a link length of the axis, not at h
