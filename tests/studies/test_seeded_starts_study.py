"""``jswim study navigate --starts N``: every agent runs from the same N seeded starts (heading
and shape), start 0 is the study's own (every run and number as without the option), and the
rows pool the starts in each cell; a folder grows by its starts."""

from __future__ import annotations

import json
from collections import defaultdict

import pytest

from jswim.results import as_run_rows, read_runs
from jswim.studies.kinds import navigate
from jswim.studies.kinds.navigate import START_SPREAD, nav_overview, seeded_start
from jswim.studies.options import StudyOptions
from jswim.studies.run import run_study
from jswim.studies.specs import build


def _start_of(plan) -> tuple[float, tuple]:
    return json.loads(plan.target).get("start_heading", 0.0), tuple(plan.init)


def test_one_start_is_the_study_as_before():
    base = StudyOptions(q_runs=2, flow="shear", flows=(0.5,))
    one = StudyOptions(q_runs=2, flow="shear", flows=(0.5,), starts=1)
    assert build("navigate", base) == build("navigate", one)
    for p in build("navigate", base):
        assert "start_heading" not in p.target and tuple(p.init) == (1, 1)


def test_every_agent_shares_each_start_and_start_zero_is_the_default():
    o = StudyOptions(q_runs=2, flow="shear", flows=(0.5,), starts=3, seed=7)
    plans = build("navigate", o)
    default = {
        p.run_id: p
        for p in build("navigate", StudyOptions(q_runs=2, flow="shear", flows=(0.5,), seed=7))
    }
    by_tag: dict[str, set] = defaultdict(set)
    agents: dict[str, set] = defaultdict(set)
    for p in plans:
        tag = next((t for t in p.run_id.split("-") if t in ("s1", "s2")), "s0")
        by_tag[tag].add(_start_of(p))
        agents[tag].add(p.agent)
        if tag == "s0":
            assert default[p.run_id] == p  # start 0: the very runs of the study without --starts
    assert all(len(starts) == 1 for starts in by_tag.values())  # one start per tag, every agent
    assert len({next(iter(s)) for s in by_tag.values()}) == 3  # three different starts
    assert "zermelo" in agents["s0"] and "zermelo" not in agents["s1"] | agents["s2"]
    assert agents["s1"] == agents["s0"] - {"zermelo"}
    # each cell's group pools its starts: the learners' 2 seeds from each of the 3 starts
    groups = defaultdict(int)
    for p in plans:
        if p.agent == "qlearning":
            groups[p.group] += 1
    assert set(groups.values()) == {6}


def test_seeded_starts_are_reproducible_and_spread_as_documented():
    starts = [seeded_start(3, i) for i in range(1, 400)]
    assert starts == [seeded_start(3, i) for i in range(1, 400)]
    assert seeded_start(3, 0) == (0.0, "++")
    headings = [h for h, _ in starts]
    assert max(abs(h) for h in headings) <= START_SPREAD
    assert min(headings) < -0.9 * START_SPREAD and max(headings) > 0.9 * START_SPREAD
    shapes = {s for _, s in starts}
    assert shapes == {"++", "+-", "-+", "--"}  # every corner of the shape square
    assert seeded_start(4, 1) != seeded_start(3, 1)  # the study seed draws them


@pytest.mark.slow  # three solves of the optimum and the mpc per start (~2 CPU-min)
def test_seeded_starts_run_every_agent_and_the_folder_grows(tmp_path):
    out = tmp_path / "nav"
    agents = ("controller", "mpc", "optimal", "random")
    o = dict(distances=(3.0,), bearings=(90.0,), q_runs=1, agents=agents, seed=5)
    run_study("navigate", StudyOptions(**o), None, out=out, progress=False)
    first = {r.run_id: r for r in as_run_rows(read_runs(out))}
    run_study("navigate", StudyOptions(**o, starts=2), None, out=out, progress=False)
    rows = as_run_rows(read_runs(out))
    for r in rows:  # start 0's runs were kept, not run again
        if r.run_id in first:
            assert r.steps_to_target == first[r.run_id].steps_to_target
    assert len(rows) == 2 * len(first)
    heading, shape = seeded_start(5, 1)
    signs = "".join(shape)
    by_start = defaultdict(list)
    for r in rows:
        spec = json.loads(r.target)
        by_start[(spec.get("start_heading", 0.0), r.init, r.group)].append(r)
    for (h, init, _group), g in by_start.items():
        assert (h, init) in ((0.0, "++"), (heading, signs))
        assert {r.agent for r in g} == set(agents)
        best = next(r for r in g if r.agent == "optimal")
        assert best.reached
        for r in g:  # the optimum of each start is never beaten from that start
            assert r.optimal_steps == best.steps_to_target
            if r.reached:
                assert r.steps_to_target >= best.steps_to_target
    table = nav_overview(rows)
    assert {row["n"] for row in table} == {2}  # every agent's two starts pooled in each cell
    assert navigate.target_kind("fixed d=3 b=90") == "fixed d=3 b=90"
