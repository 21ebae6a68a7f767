"""The navigation study in a flow: budgets grow with Zermelo's least time, every row carries its
flow, whether the target is reachable, Zermelo's time and its own ratio to it, and an unreachable
target says so instead of timing out silently. Zermelo's times here are checked against the
uniform stream's closed form written out in the test."""

from __future__ import annotations

import json
import math

import pytest

from jswim.env.flows import SWIM_SPEED as V
from jswim.env.targets import target_from_dict
from jswim.results import as_run_rows
from jswim.studies.kinds import navigate
from jswim.studies.options import StudyOptions
from jswim.studies.specs import build

R = 0.25  # the success radius


def _plans(fraction, bearing, agents=("controller", "zermelo")):
    o = StudyOptions(flow="uniform", flows=(fraction,), bearings=(bearing,), agents=agents)
    return [p for p in build("navigate", o) if p.group.startswith("fixed")]


def _crab_time(fraction: float, bearing: float) -> float | None:
    """A uniform stream u = (0, f v) and a target 3 a away: the least T with
    |P - u T| = v T + r (a straight crab path), the smaller positive root."""
    px, py = 3 * math.cos(math.radians(bearing)), 3 * math.sin(math.radians(bearing))
    u = fraction * V
    a = u * u - V * V
    b = -2 * (py * u + V * R)
    c = px * px + py * py - R * R
    if abs(a) < 1e-15:
        return -c / b
    disc = b * b - 4 * a * c
    if disc < 0:
        return None
    roots = [(-b - math.sqrt(disc)) / (2 * a), (-b + math.sqrt(disc)) / (2 * a)]
    pos = [t for t in roots if t > 0]
    return min(pos) if pos else None


@pytest.mark.parametrize("fraction, bearing", [(0.9, 0.0), (0.5, 90.0), (0.5, 180.0)])
def test_the_budget_is_at_least_four_zermelo_times(fraction, bearing):
    best = _crab_time(fraction, bearing)
    plans = navigate.with_budgets(_plans(fraction, bearing))
    got = navigate.zermelo_path(plans[0].target, plans[0].flow).steps
    assert got == pytest.approx(best, rel=1e-6)
    budget = target_from_dict(json.loads(plans[0].target)).budget
    assert budget >= math.ceil(navigate.FLOW_BUDGET_FACTOR * best)
    assert all(p.steps == budget for p in plans)


@pytest.mark.slow  # compiles the world for two agents (~20 s)
def test_an_unreachable_target_says_so():
    # a cross stream of 1.2 v and a target straight ahead: no heading reaches it
    assert _crab_time(1.2, 0.0) is None
    plans = navigate.with_budgets(_plans(1.2, 0.0))
    assert navigate.zermelo_path(plans[0].target, plans[0].flow).steps is None
    rows = {p.agent: r for p in plans for r in navigate.baseline_rows([p])}
    for r in rows.values():
        assert r.reachable is False and r.zermelo_steps is None and r.zermelo_ratio is None
        assert r.flow_fraction == 1.2 and json.loads(r.flow)["kind"] == "uniform"
    assert rows["zermelo"].reached is False and rows["controller"].reached is False


@pytest.mark.slow  # every row's yardstick: the swimmer's optimum is searched (~10-50 s)
def test_every_row_carries_its_time_ratio():
    plans = navigate.with_budgets(_plans(0.5, 90.0, ("controller", "zermelo", "optimal")))
    built = [r for p in plans for r in navigate.baseline_rows([p])]
    # every row's optimum is its cell's optimal row's (as a folder's rows are read)
    rows = {r.agent: r for r in as_run_rows(built)}
    assert all(r.optimal_steps is None for r in built if r.agent != "optimal")
    best = _crab_time(0.5, 90.0)
    ctrl, zer = rows["controller"], rows["zermelo"]
    assert ctrl.reached and ctrl.reachable
    assert ctrl.zermelo_steps == pytest.approx(best, rel=1e-5)
    assert ctrl.zermelo_ratio == pytest.approx(ctrl.steps_to_target / best, rel=1e-5)
    assert ctrl.zermelo_ratio >= 1.0  # nothing beats the point steerer of the same speed here
    # the row's own time ratio is to the swimmer's optimum, which no agent beats
    assert ctrl.optimal_steps is not None
    assert ctrl.time_ratio == pytest.approx(ctrl.steps_to_target / ctrl.optimal_steps, rel=1e-5)
    assert ctrl.time_ratio >= 1.0
    # Zermelo's own row: its path ends within the radius, after ceil(T) steps
    assert zer.reached and zer.steps_to_target == math.ceil(best) and zer.actions == []
    assert math.hypot(zer.x[-1], zer.y[-1] - 3.0) < R + 1e-6
    assert zer.zermelo_ratio == pytest.approx(1.0)
    table = {(g["agent"], g["group"]): g for g in navigate.nav_summary(list(rows.values()))}
    g = table[("controller", ctrl.group)]
    assert g["flow_fraction"] == 0.5 and g["reachable"] and g["time_ratio"] == ctrl.time_ratio
    assert g["zermelo_ratio"] == ctrl.zermelo_ratio


@pytest.mark.slow  # every row's yardstick: the swimmer's optimum is searched (~10-50 s)
def test_zermelo_is_never_cut_by_steps():
    # --steps shortens the agents' runs, not the yardstick's (38.3 steps here, --steps 30)
    o = StudyOptions(flow="uniform", flows=(0.5,), bearings=(90.0,), agents=("zermelo",), steps=30)
    plans = [p for p in build("navigate", o) if p.group.startswith("fixed")]
    (row,) = navigate.baseline_rows(navigate.with_budgets(plans))
    assert row.reached and row.steps_to_target == math.ceil(_crab_time(0.5, 90.0)) > 30
    assert row.zermelo_ratio == pytest.approx(1.0)


@pytest.mark.slow  # every row's yardstick: the swimmer's optimum is searched (~10-50 s)
def test_the_llm_sees_the_local_flow_in_its_records(tmp_path):
    from jswim.llm.backend import Backend
    from jswim.llm.reference import completion
    from jswim.results import read_runs, read_transcript
    from jswim.studies.run import run_study
    from tests.fakeserver import FakeServer

    def rule(body: dict) -> str:
        return completion(body)["choices"][0]["message"]["content"]

    out = tmp_path / "nav-flow"
    opts = StudyOptions(
        flow="uniform", flows=(0.5,), bearings=(90.0,), agents=("llm", "zermelo"), steps=6
    )
    with FakeServer(reply=rule) as srv:
        run_study("navigate", opts, Backend(base_url=srv.url, model="fake"), out, progress=False)
    rows = read_runs(out)
    llm = next(r for r in rows if r["agent"] == "llm" and r["group"].startswith("fixed"))
    assert llm["flow_fraction"] == 0.5 and llm["reachable"] is True
    steps = [r for r in read_transcript(out, llm["run_id"]) if r.get("type") == "step"]
    # u = (0, 0.5 v) = (0, 0.0239) a per step everywhere: "flow (0, 23)" in every record shown
    assert "The fluid flows and carries the swimmer" in steps[1]["prompt"]
    assert "flow (0, 23), stuck" in steps[1]["prompt"]
    meta = json.loads((out / "metadata.json").read_text())
    assert any(d.startswith("background flow") for d in meta["fidelity_deviations"])


@pytest.mark.slow  # every row's yardstick: the swimmer's optimum is searched (~10-50 s)
def test_compare_sets_flow_studies_side_by_side_with_their_zermelo_columns(tmp_path):
    from jswim.studies.overview import compare_text, show_text
    from jswim.studies.run import run_study

    opts = StudyOptions(
        flow="uniform", flows=(0.5,), bearings=(90.0,), agents=("controller", "zermelo")
    )
    for name in ("a", "b"):
        run_study("navigate", opts, None, tmp_path / name, progress=False)
    text = compare_text([tmp_path / "a", tmp_path / "b"])
    header = next(line for line in text.splitlines() if "time ratio" in line)
    assert "Zermelo" in header and "study" in header
    zermelo = next(line for line in text.splitlines() if " zermelo " in f" {line} ")
    # Zermelo's own row: its least time (38.3 steps here) and a time ratio of 1
    assert f"{_crab_time(0.5, 90.0):.1f}" in zermelo and "1.00" in zermelo
    # `jswim show` names the flow among the settings, as the page does
    settings = next(line for line in show_text(tmp_path / "a").splitlines() if "settings" in line)
    assert settings.endswith("flow uniform at 0.5 v (the swimming speed)")


@pytest.mark.slow  # a study with the optimum and mpc: minutes
def test_no_agent_beats_the_swimmers_optimum_in_any_cell(tmp_path):
    from jswim.results import as_run_rows, read_runs
    from jswim.studies.run import run_study

    opts = StudyOptions(
        flow="shear",
        flows=(0.0, 0.5),
        bearings=(90.0,),
        agents=("controller", "optimal", "mpc", "random", "qlearning"),
        q_runs=2,
        train_episodes=20,
    )
    run_study("navigate", opts, None, tmp_path / "f", progress=False)
    rows = as_run_rows(read_runs(tmp_path / "f"))
    cells: dict[str, list] = {}
    for r in rows:
        cells.setdefault(r.group, []).append(r)
    assert len(cells) == 6  # three targets at two flow speeds
    for group, g in cells.items():
        (best,) = [r for r in g if r.agent == "optimal"]
        # the optimum's row is its replayed sequence: reached exactly at its own steps
        assert best.reached and best.steps_to_target == best.optimal_steps, group
        for r in g:
            assert r.optimal_steps == best.optimal_steps
            if r.reached:
                assert r.steps_to_target >= best.steps_to_target, (group, r.agent)
                assert r.time_ratio == pytest.approx(r.steps_to_target / best.optimal_steps)


@pytest.mark.slow  # trains the learners briefly and replays every row (~1-2 min)
def test_every_rows_actions_replay_its_path_in_a_rotating_flow():
    """A row's actions, replayed through the world from its start, give its recorded path (they
    seed the cell's optimum): in Taylor-Green at 0.9 v pushes are clipped at the shape's limits,
    and such a push is another step than the shorter move the DOFs' change reads as."""
    import jax.numpy as jnp
    import numpy as np

    import jswim
    from jswim.action_codes import encode_action
    from jswim.env.flows import flow_from_dict

    o = StudyOptions(
        flow="taylor-green",
        flows=(0.9,),
        agents=("qlearning", "ppo", "controller", "random"),
        q_runs=4,
        train_episodes=4,
    )
    plans = [p for p in navigate.with_budgets(build("navigate", o)) if p.group.startswith("path")]
    rows = [r for p in plans for r in navigate.baseline_rows([p])]
    assert {r.agent for r in rows} == {"qlearning", "ppo", "controller", "random"}
    env, params = jswim.make(
        "purcell",
        roc_levels=2,
        target=target_from_dict(json.loads(rows[0].target)),
        flow=flow_from_dict(json.loads(rows[0].flow)),
    )
    for r in rows:
        codes = [encode_action(dof, round(roc), 2) for dof, roc in r.actions]
        assert all(float(roc) == round(float(roc)) for _, roc in r.actions), r.run_id
        trace = jswim.rollout(env, params, 0, jnp.asarray(codes, jnp.int32))
        xy = np.cumsum(np.asarray(trace.info.displacement, np.float64).reshape(-1, 2), axis=0)
        dev = np.hypot(xy[:, 0] - np.asarray(r.x), xy[:, 1] - np.asarray(r.y)).max()
        assert dev < 1e-4, (r.run_id, dev)
