"""The continuous RL baseline (PPO) as rows of ``jswim study wall`` / ``pair``: its rows
with their fate and success columns, its metadata line, resume without retraining, and the one-line
refusal of an option the scene rows cannot honour."""

from __future__ import annotations

import json

import pytest

from jswim import cli
from jswim.agents import fidelity, ppo
from jswim.results import read_metadata, read_runs
from jswim.studies import StudyOptions, run_study
from jswim.studies import scene_studies

WALL = dict(heights=(3.0,), q_runs=2, steps=12, agents=("stroke", "ppo"))


@pytest.mark.slow  # one PPO compilation on the wall scene (~25 s under load) and the strokes'
def test_wall_ppo_rows_resume_without_retraining(tmp_path, monkeypatch, float32):
    out = tmp_path / "wall"
    seen = {"n": 0}

    def interrupt(phase, done, total, info=""):
        if phase == "stroke":
            seen["n"] += 1
            if seen["n"] == 2:  # both strokes stored, PPO not started
                raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_study("wall", StudyOptions(**WALL), None, out, progress=interrupt)
    assert read_metadata(out)["status"] == "interrupted"
    assert {r["agent"] for r in read_runs(out)} == {"stroke"}

    calls = {"n": 0}
    train = ppo.train

    def counted(*a, **k):
        calls["n"] += 1
        return train(*a, **k)

    monkeypatch.setattr(ppo, "train", counted)
    res = run_study("wall", StudyOptions(**WALL), None, out)
    assert calls["n"] == 1  # the strokes kept, the PPO cell trained once
    rows = {r["run_id"]: r for r in read_runs(out)}
    learners = [r for r in rows.values() if r["agent"] == "ppo"]
    assert [r["run_id"] for r in learners] == [
        "ppo-ng-px-i+--z0-real-h3-r0",
        "ppo-ng-px-i+--z0-real-h3-r1",
    ]
    for r in learners:
        assert r["group"] == "h=3" and r["roc_levels"] == 0 and r["start_height"] == 3.0
        assert r["fate"] in scene_studies.FATES and r["mean_height"] > 1.0
        assert isinstance(r["success"], bool) and isinstance(r["learned"], bool)
        assert len(r["actions"]) == 12 and all(
            1 <= d <= 2 and -1 <= roc <= 1 for d, roc in r["actions"]
        )
        assert any(roc != round(roc) for _, roc in r["actions"])  # real ROCs, not the lattice's
        assert len(r["heights"]) == len(r["contact"]) == len(r["xs"]) == 12 and r["y"] == [
            h[0] for h in r["heights"]
        ]
        # x is the mean of the swimmers' positions, progress its steps (the reward the learner had).
        assert r["x"] == pytest.approx([sum(v) / len(v) for v in r["xs"]], abs=1e-6)
        assert json.loads(r["scene"])["medium"] == "wall"
    meta = read_metadata(out)
    assert (
        fidelity.SCENE_PPO in meta["fidelity_deviations"]
        and fidelity.REAL_ROCS in meta["fidelity_deviations"]
    )
    table = {(s["agent"], s["group"]): s for s in meta["summary"]["scenes"]}
    assert table[("ppo", "h=3")]["n"] == 2 and table[("ppo", "h=3")]["fates"]
    stroke_speed = next(
        r["speed"] for r in rows.values() if r["agent"] == "stroke" and r["group"] == "h=3"
    )
    assert table[("ppo", "h=3")]["vs_stroke"] == pytest.approx(
        sum(r["speed"] for r in learners) / 2 / stroke_speed
    )
    assert {s["group"] for s in res.summary.to_dict("records") if s["agent"] == "ppo"} == {"h=3"}

    # A finished study run again trains nothing and changes no row.
    def refuse(*a, **k):
        raise AssertionError("a finished PPO run was trained again")

    monkeypatch.setattr(ppo, "train", refuse)
    again = run_study("wall", StudyOptions(**WALL), None, out)
    assert {r["run_id"]: r["actions"] for r in again.rows} == {
        k: r["actions"] for k, r in rows.items()
    }
    assert read_metadata(out)["status"] == "complete"


@pytest.mark.parametrize(
    "study, grid", [("wall", ["--heights", "5"]), ("pair", ["--separations", "30"])]
)
def test_roc_levels_are_refused_by_the_scene_studies(study, grid, tmp_path, capsys):
    # Their lattice rows are read and judged on the paper's ROCs and PPO's are real: a K would be dropped.
    out = tmp_path / "o"
    assert cli.main(["study", study, *grid, "--roc-levels", "2", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--roc-levels 2" in err[0] and "PPO runs real ROCs" in err[0]
    assert not out.exists()


def test_the_scene_table_compares_every_agent_with_the_best_stroke_of_its_scene():
    def row(agent, group, speed, d=30.0, direction=1):
        return {
            "scene": "{}",
            "agent": agent,
            "group": group,
            "direction": direction,
            "speed": speed,
            "separation": d,
            "medium": "free",
            "start_height": None,
        }

    rows = [
        row("stroke", "D=30, phase 0", 0.02),
        row("stroke", "D=30, phase 1", 0.025),
        row("ppo", "D=30", 0.001),
        row("ppo", "D=30", 0.004),
        row("qlearning", "D=30", 0.03),
        row("stroke", "D=60, phase 0", 0.0215),
        row("random", "D=60", -0.0043, d=60.0),
        row("ppo", "D=30", 0.01, direction=-1),
    ]  # no -x stroke: nothing to compare with
    rows[5]["separation"] = 60.0
    got = {
        (s["agent"], s["group"], s["direction"]): s["vs_stroke"]
        for s in scene_studies.scene_summary(rows)
    }
    assert got[("ppo", "D=30", 1)] == pytest.approx(0.0025 / 0.025)  # the fastest phase at that D
    assert got[("qlearning", "D=30", 1)] == pytest.approx(
        1.2
    )  # a faster joint stroke than two squares
    assert got[("stroke", "D=30, phase 0", 1)] == pytest.approx(0.8)
    assert got[("random", "D=60", 1)] == pytest.approx(-0.2)
    assert got[("ppo", "D=30", -1)] is None
    # Per cycle, like speed, reads in the target direction: a -x stroke going -0.17 a per cycle is +0.17.
    back = [dict(row("stroke", "alone", 0.043, d=None, direction=-1), per_cycle=-0.172)]
    assert scene_studies.scene_summary(back)[0]["per_cycle"] == pytest.approx(0.172)
    # Runs with no whole cycle (a pair's 6 steps) leave blanks, and the table says why.
    assert scene_studies.table_note(scene_studies.scene_summary(rows)) is None
    short = scene_studies.scene_summary(rows + [row("llm", "D=60", None, d=60.0)])
    assert "no whole stroke cycle" in scene_studies.table_note(
        short
    ) and "--steps" in scene_studies.table_note(short)


@pytest.mark.parametrize("study, extra", [("wall", {"heights": (5.0,)}), ("continuous", {})])
def test_ppo_runs_are_offered_every_move_whatever_the_action_set(study, extra):
    # --action-set restricts the lattice agents' (DOF, ROC) moves; PPO picks any arm and any real
    # ROC, so its plans say "all" (not a set it was never held to), and the others keep the option
    from jswim.studies import specs

    plans = specs.build(
        study,
        StudyOptions(
            action_set="shape-changing", q_runs=1, steps=8, agents=("random", "ppo"), **extra
        ),
    )
    by_agent = {}
    for p in plans:
        by_agent.setdefault(p.agent, set()).add(p.action_set)
    assert by_agent["ppo"] == {"all"}
    assert by_agent["random"] == {"shape-changing"}
