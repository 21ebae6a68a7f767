"""A new world through a study and its report page, unchanged: the toy swimmer of
tests/env/test_toy_world.py, registered by name (``jswim.register_world``), runs the wall study's
cells (its factory takes any scene and swims the same in it: it has no wall to feel) with every
agent: the stroke, the LLM (against the fake server), Q-learning, the random policy and PPO (issue
30); and the page and ``jswim animate`` draw it from what the protocol observes (its position and
DOFs: one sphere at the position, no outline of its own).

The numbers checked are the toy's area rule, independent of jswim: the square gait from (1, 1)
nets -1 per cycle toward +x (clockwise round the unit square), its time reverse +1; one move
sweeps at most half the unit square (|dx| <= 0.5).
"""

from __future__ import annotations

import json
import os
import re

import numpy as np
import pytest

import jswim
from jswim.env import registry
from jswim.errors import ConfigError
from jswim.studies.options import StudyOptions
from jswim.studies.run import run_study
from jswim.viz.page import run_payload, write_report
from jswim.viz.publish import report
from jswim.viz.tracks import track
from tests.browser import browser_or_skip, open_report_run
from tests.env.test_toy_world import ToyParams, ToyWorld
from tests.fakeserver import FakeServer

ARTIFACTS = os.environ.get("JSWIM_TEST_ARTIFACTS", "test-artifacts")
H, STEPS = 3.0, 12


def toy_factory(scene, *, zeta=0.0, direction=1, init=None):
    """The toy in any scene: its world and params."""
    if init is not None:
        raise ConfigError("the toy starts at (1, 1)")
    return ToyWorld(), ToyParams(float(zeta), float(direction))


#: The toy's square toward each target, as the next move from the shape (D1, D2) the last record
#: ends at: counter-clockwise (+1 per cycle) toward +x, clockwise (-1) toward -x.
TOWARD = {
    "positive": {"1, 1": "[1, -1]", "0, 1": "[2, -1]", "0, 0": "[1, 1]", "1, 0": "[2, 1]"},
    "negative": {"1, 1": "[2, -1]", "1, 0": "[1, -1]", "0, 0": "[2, 1]", "0, 1": "[1, 1]"},
}
PROMPTS: list[str] = []


def toy_reply(body):
    """The square toward the prompt's target from the shape its records report (the toy starts at
    (1, 1)); a shape the toy never takes (the DOFs written otherwise than as its observation's 0 and
    1) gets an invalid reply, so that run's steps fail."""
    text = "\n".join(str(m.get("content", "")) for m in body["messages"])  # a retry's too
    PROMPTS.append(text)
    after = re.findall(r"-> \(([\d., ]+)\)", text)  # the records', not the legend's "(D1, D2)"
    way = "positive" if "positive x direction" in text else "negative"
    return TOWARD[way].get(after[-1] if after else "1, 1", "[7, 7]")


def _toy_study(tmp_path_factory, name, agents):
    """Run the wall study's cells on the toy with these agents; yields (folder, result)."""
    jswim.register_world("toy", toy_factory)
    out = tmp_path_factory.mktemp(name) / "wall"
    o = StudyOptions(
        swimmers=("toy",),
        heights=(H,),
        directions=(1, -1),
        steps=STEPS,
        q_runs=1,
        runs=1,
        agents=agents,
    )
    try:
        with FakeServer(reply=toy_reply) as srv:
            res = run_study("wall", o, backend=srv.backend(), out=out)
        report(out, figures=False)  # the page alone (the publish step without figures)
        yield out, res
    finally:
        registry._REGISTERED.pop("toy", None)


@pytest.fixture(scope="module")
def toy_folder(tmp_path_factory):
    """The agents that compile nothing new (fast tier): the stroke, Q-learning and random."""
    yield from _toy_study(tmp_path_factory, "toy", ("stroke", "qlearning", "random"))


@pytest.fixture(scope="module")
def toy_learners(tmp_path_factory):
    """The LLM (fake server) and PPO on the toy: slow, as each compiles its own step group (about
    13 s on 2 cores)."""
    yield from _toy_study(tmp_path_factory, "toy-learners", ("llm", "ppo"))


def _check_toy_rows(rows):
    """What holds for every agent's row on the toy: no paper verdict, STEPS moves on D1 or D2, and
    no move sweeping more than half the unit square (|dx| <= 0.5)."""
    for r in rows:
        assert r["swimmer"] == "toy" and r["success"] is None  # no paper criterion for a new world
        dx = np.diff(np.r_[0.0, r["x"]])
        assert len(dx) == STEPS and np.all(np.abs(dx) <= 0.5 + 1e-6)
        assert len(r["actions"]) == STEPS and all(a[0] in (1, 2) for a in r["actions"])
        if r["agent"] == "ppo":  # real ROCs in [-1, 1], not only the lattice's
            assert all(-1.0 <= a[1] <= 1.0 for a in r["actions"])
            assert any(a[1] not in (-1.0, 0.0, 1.0) for a in r["actions"])
        else:
            assert all(a[1] in (-1, 0, 1) for a in r["actions"])


def test_register_world_and_make(toy_folder):
    env, params = jswim.make("toy", direction="-x")
    assert isinstance(env, ToyWorld) and params.direction == -1.0
    assert "toy" in registry.registered_worlds()
    with pytest.raises(ConfigError, match="new name"):
        jswim.register_world("ng", toy_factory)
    with pytest.raises(ConfigError, match="unknown swimmer 'nope'"):
        StudyOptions(swimmers=("nope",))


def test_square_stroke_from_the_start_corner():
    from jswim.studies.scene_studies import square

    # Purcell's square from (+, +) (D2 down, D1 down, D2 up, D1 up), NG's from (10, 6) (D2 up, D1
    # down, D2 down, D1 up); toward -x each one's time reverse. Codes (dof - 1) * 3 + roc + 1.
    assert square((1, 1), 1) == (3, 0, 5, 2) and square((1, 1), -1) == (0, 3, 2, 5)
    assert square((1, 0), 1) == (5, 0, 3, 2) and square((1, 0), -1) == (0, 5, 2, 3)


def test_toy_world_runs_a_study(toy_folder):
    out, res = toy_folder
    rows = {r["run_id"]: r for r in res.rows}
    # per direction: the free-fluid reference stroke, and at h = 3 every agent, one run each
    assert len(rows) == 2 * 4
    assert sorted(r["agent"] for r in rows.values() if r["direction"] == 1) == [
        "qlearning",
        "random",
        "stroke",
        "stroke",
    ]
    strokes = [r for r in rows.values() if r["agent"] == "stroke"]
    assert len(strokes) == 4
    for r in strokes:
        # the area rule: the square from (1, 1) nets -1 per cycle toward +x, its reverse +1
        assert r["per_cycle"] == pytest.approx(-1.0 * r["direction"], abs=1e-6)
        assert r["x"][-1] == pytest.approx(-STEPS / 4 * r["direction"], abs=1e-5)
    _check_toy_rows(rows.values())
    assert {(t["agent"], t["group"]) for t in res.summary.to_dict("records")} >= {
        ("stroke", f"h={H:g}"),
        ("qlearning", f"h={H:g}"),
    }
    saved = [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]
    assert {r["run_id"] for r in saved} == set(rows)


@pytest.mark.slow  # the LLM's and PPO's step groups compile (about 13 s on 2 cores)
def test_toy_learners_run_a_study(toy_learners):
    out, res = toy_learners
    rows = {r["run_id"]: r for r in res.rows}
    # per direction: the LLM and PPO at h = 3 (the free-fluid reference comes with the stroke agent)
    assert sorted(r["agent"] for r in rows.values() if r["direction"] == 1) == ["llm", "ppo"]
    _check_toy_rows(rows.values())
    saved = [json.loads(line) for line in (out / "runs.jsonl").read_text().splitlines()]
    assert {r["run_id"] for r in saved} == set(rows)


@pytest.mark.slow  # the LLM's step group compiles
def test_toy_llm_runs_read_the_toy_world(toy_learners):
    out, res = toy_learners
    llm = {r["direction"]: r for r in res.rows if r["agent"] == "llm"}
    assert set(llm) == {1, -1}
    for d, r in llm.items():
        # The reply followed the shapes the records gave, so the run is the toy's square toward
        # the target: +1 per cycle by the area rule (0.5 at a cycle's first and last moves).
        assert r["failed_steps"] == 0 and r["success"] is None
        np.testing.assert_allclose(
            np.asarray(r["x"]) * d,
            np.repeat(np.arange(1, 4), 4) - [0.5, 0.5, 0.5, 0.0] * 3,
            atol=1e-6,
        )
    # The prompt is the toy's: its two DOFs over the world's range [0, 1] and records of its observed
    # shapes (the paper's swimmers' ranges are [-1.047, 1.047] and [6, 10]).
    toy = [p for p in PROMPTS if "D1 and D2 each stay in [0, 1]" in p]
    assert len(toy) == len(PROMPTS) == 2 * STEPS
    assert any("(1, 1) [1, -1] -> (0, 1), X" in p for p in toy) and any(
        "(1, 1) [2, -1] -> (1, 0), X" in p for p in toy
    )
    first = json.loads(
        (out / "transcripts" / f"{llm[1]['run_id']}.jsonl").read_text().splitlines()[0]
    )
    assert first["spec"]["swimmer"] == "toy" and first["levels0"] == [1, 1]


@pytest.mark.slow  # PPO's training compiles
def test_toy_ppo_learns_on_the_toy_world(toy_learners):
    _out, res = toy_learners
    for r in (r for r in res.rows if r["agent"] == "ppo"):
        assert r["success"] is None and r["period"] == 0  # no paper criterion for a new world
        # the recorded x is the area rule's on the recorded moves, replayed here from (1, 1)
        f, x = np.ones(2), 0.0
        for (dof, roc), xr in zip(r["actions"], r["x"]):
            f1 = f.copy()
            f1[dof - 1] = np.clip(f1[dof - 1] + roc, 0.0, 1.0)
            mid, dd = (f + f1) / 2, f1 - f
            x, f = x + 0.5 * (mid[0] * dd[1] - mid[1] * dd[0]), f1
            assert xr == pytest.approx(x, abs=1e-5)


def test_toy_run_pictured_from_the_protocol(toy_folder):
    out, res = toy_folder
    row = next(
        r
        for r in res.rows
        if r["agent"] == "stroke" and r["group"] == f"h={H:g}" and r["direction"] == 1
    )
    t = track(row)
    p = run_payload(t)
    # one sphere per swimmer at its observed position (above the wall at h), the DOFs in [0, 1]
    assert p["n_swimmers"] == 1 and p["wall"] and p["dof_names"] == ["D1", "D2"] and not p["planar"]
    assert np.shape(p["bodies"]) == (STEPS + 1, 1, 1, 2)
    np.testing.assert_allclose(np.asarray(p["pos"])[:, 0, 0], np.r_[0.0, row["x"]], atol=1e-6)
    np.testing.assert_allclose(np.asarray(p["pos"])[:, 0, 1], H)
    # the square's corners: (1, 1) -> (1, 0) -> (0, 0) -> (0, 1) -> (1, 1)
    np.testing.assert_allclose(np.asarray(p["dofs"])[:5], [[1, 1], [1, 0], [0, 0], [0, 1], [1, 1]])
    assert (out / "report.html").exists()


@pytest.mark.slow
def test_toy_page_in_chromium(toy_folder):
    out, res = toy_folder
    run = next(r["run_id"] for r in res.rows if r["agent"] == "stroke" and r["group"] == f"h={H:g}")
    page = write_report(out, figures="none")
    with browser_or_skip(height=1100) as b:
        open_report_run(b, page, run)
        drawn = b.eval("window.jswimReport.drawn()")
        # inside the sphere (half a radius right of its centre, off the centre's cross): its white fill
        inside = b.eval(
            "(() => { var d = window.jswimReport.data(), q = d.pos[window.jswimReport.step()][0],"
            "p = window.jswimReport.toCanvas(q[0] + 0.5, q[1] + 0.5), c = document.getElementById('swim');"
            "return Array.from(c.getContext('2d').getImageData(p[0], p[1], 1, 1).data).slice(0, 3); })()"
        )
        start = b.eval("document.getElementById('step').textContent")
        b.screenshot(os.path.join(ARTIFACTS, "report-toy-world.png"))
        assert b.errors == []
    assert drawn == 1 and inside == [255, 255, 255]
    assert "D1" in start and "D2" in start
