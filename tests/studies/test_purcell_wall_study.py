"""``jswim study wall --swimmer purcell``: its cells, rows, figure and pictures."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from jswim.studies.options import StudyOptions
from jswim.studies.specs import build
from jswim.studies.run import run_study
from jswim.swimmers import wall_rft
from jswim.viz import worlds
from jswim.viz.publish import report
from jswim.viz.tracks import track
from tests.fakeserver import FakeServer

BULK_CYCLE = 0.19124724  # DESIGN.md


def test_purcell_cells_run_every_agent_at_each_height():
    plans = build("wall", StudyOptions(swimmers=("purcell",), heights=(1.5, 10.0), q_runs=2))
    agents = {(p.agent, p.group) for p in plans}
    # the bulk reference stroke, and at each height every agent NG's wall cells run
    assert agents == {("stroke", "bulk")} | {
        (a, f"h={h}")
        for h in ("1.5", "10")
        for a in ("stroke", "llm", "qlearning", "random", "ppo")
    }
    per_height = {
        a: sum(p.agent == a and p.group == "h=10" for p in plans)
        for a in ("llm", "ppo", "qlearning")
    }
    assert per_height == {
        "llm": 1,
        "ppo": 2,
        "qlearning": 2,
    }  # the wall study's --runs 1, --q-runs learners
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
    run_study(
        "wall",
        StudyOptions(
            swimmers=("purcell",),
            heights=(1.5,),
            q_runs=1,
            steps=16,
            agents=("stroke", "qlearning", "random"),
        ),
        out=out,
    )  # LLM, PPO rows: below
    report(out)  # the publish step: the figures and report.html, drawn from the folder
    rows = [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]
    by = {(r["agent"], r["group"]): r for r in rows}
    assert by[("stroke", "bulk")]["per_cycle"] == pytest.approx(BULK_CYCLE, abs=1e-7)
    wall = by[("stroke", "h=1.5")]
    xi_t, xi_n = wall_rft.drag_coefficients(1.5)
    from tests.physics.test_wall_rft import cycles  # the test-side RK4 at the wall's ratio

    assert wall["per_cycle"] == pytest.approx(float(cycles([xi_n / xi_t])[0, 0]), rel=2e-7)
    assert wall["fate"] == "gliding" and wall["start_height"] == 1.5 and wall["medium"] == "wall"
    # the world says how it is drawn: a plane 1.5 link lengths above the wall (its Scenery)
    assert wall["plane_height"] == 1.5 and "plane_height" not in by[("stroke", "bulk")]
    assert (out / "figures" / "wall.png").exists() and (out / "report.html").exists()
    # the picture: seen from above, in the swimmer's own plane (its y, not its height)
    t = track(wall)
    assert worlds.from_above(wall) and "above a wall" in t.world.describe() and not t.world.wall
    np.testing.assert_allclose(t.y[1:], wall["y"])
    assert np.abs(t.bodies[..., 1]).max() < 1.2  # links within a link length of the axis, not at h


#: Purcell's square toward +x from (+, +) (D2 down, D1 down, D2 up, D1 up): the next move from the
#: signs of the shape the last record ends at.
NEXT = {(1, 1): "[2, -1]", (1, -1): "[1, -1]", (-1, -1): "[2, 1]", (-1, 1): "[1, 1]"}
PROMPTS: list[str] = []


def square_reply(body):
    """The square from the shape the prompt's records report (the start (+, +) before any)."""
    text = "\n".join(str(m.get("content", "")) for m in body["messages"])
    PROMPTS.append(text)
    after = re.findall(r"-> \(([-\d., ]+)\)", text)  # the records', not the legend's "(D1, D2)"
    shape = tuple(int(np.sign(float(v))) for v in after[-1].split(", ")) if after else (1, 1)
    return NEXT.get(shape, "[7, 7]")


@pytest.mark.slow  # a study: tables and programs of a new model, the LLM's step group and PPO (~30 s of CPU)
def test_purcell_wall_llm_and_ppo_rows(tmp_path):
    h = 1.5
    out = tmp_path / "pw-agents"
    with FakeServer(reply=square_reply) as srv:
        run_study(
            "wall",
            StudyOptions(
                swimmers=("purcell",),
                heights=(h,),
                q_runs=1,
                runs=1,
                steps=16,
                agents=("stroke", "llm", "ppo"),
            ),
            srv.backend(),
            out=out,
        )
    rows = [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]
    by = {(r["agent"], r["group"]): r for r in rows}
    assert set(by) == {("stroke", "bulk"), ("stroke", "h=1.5"), ("llm", "h=1.5"), ("ppo", "h=1.5")}
    xi_t, xi_n = wall_rft.drag_coefficients(h)
    from tests.physics.test_wall_rft import cycles  # the test-side RK4 at the wall's ratio

    assert by[("stroke", "h=1.5")]["per_cycle"] == pytest.approx(
        float(cycles([xi_n / xi_t])[0, 0]), rel=2e-7
    )
    for agent in ("llm", "ppo"):
        r = by[(agent, "h=1.5")]
        # the scene's columns; the plane is fixed, so the height is the start's throughout
        assert (
            r["medium"] == "wall" and json.loads(r["scene"])["height"] == h and r["n_swimmers"] == 1
        )
        assert r["start_height"] == r["mean_height"] == h and r["fate"] == "gliding"
        assert np.all(np.asarray(r["heights"]) == h) and len(r["heights"]) == 16
        assert isinstance(
            r["success"], bool
        )  # judged by the paper's criterion (a registered world's: None)
    llm = by[("llm", "h=1.5")]
    # The reply followed the records' shapes: the square itself, so the LLM's run is the stroke's,
    # displacement for displacement, and a success.
    np.testing.assert_allclose(llm["x"], by[("stroke", "h=1.5")]["x"], rtol=1e-9)
    assert llm["success"] and llm["failed_steps"] == 0
    # Purcell's prompt: its hinge angles' range, no height in the records (the plane is fixed)
    assert all("D1 and D2 each stay in [-1.047, 1.047]" in p and ", H " not in p for p in PROMPTS)
    ppo = by[("ppo", "h=1.5")]
    assert all(d in (1, 2) and -1.0 <= roc <= 1.0 for d, roc in ppo["actions"])
    assert any(roc not in (-1.0, 0.0, 1.0) for _, roc in ppo["actions"])
