"""A navigation study in a flow: bad ``--flow``/``--flows`` input is one line and exit 2, a flow
option on another study is refused, and still-fluid folders keep their identity and runs."""

from __future__ import annotations

import pytest

from jswim import cli
from jswim.errors import ConfigError
from jswim.studies.options import StudyOptions
from jswim.studies.run import identity
from jswim.studies.specs import build


def refused(capsys, tmp_path, *args: str) -> str:
    try:
        rc = cli.main([*args, "--out", str(tmp_path / "o"), "--dry-run"])
    except SystemExit as e:  # argparse's own refusal
        rc = e.code
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = [ln for ln in err.splitlines() if "error:" in ln]
    assert rc == 2 and len(lines) == 1, err
    return lines[0]


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--flow", "vortex"], "--flow"),  # not a kind
        (["--flows", "0.5"], "--flow KIND"),  # speeds without a kind
        (["--flow", "shear", "--flows", "-0.5"], "--flows"),
        (["--flow", "shear", "--flows", "3"], "--flows"),  # past the largest fraction
        (["--flow", "uniform", "--flows", "nan"], "--flows"),
        (["--flow", "uniform", "--flows", "inf"], "--flows"),
        (["--flow", "shear", "--flows", "1e300"], "--flows"),  # huge: a NaN world (issue 61)
        (["--flow", "poiseuille", "--flows", "0.5,1e400"], "--flows"),  # inf after parsing
        (["--flow", "taylor-green", "--flows", "2.000001"], "--flows"),
        (["--flow", "uniform", "--flows", "0,,1"], "empty items"),
        (["--flow", "uniform", "--flows", "fast"], "--flows"),
        (["--train-episodes", "0"], "--train-episodes"),  # a zero was dropped for the default
    ],
)
def test_navigate_refuses_bad_flows_in_one_line(capsys, tmp_path, args, says):
    assert says in refused(capsys, tmp_path, "study", "navigate", *args)


def test_another_study_refuses_a_flow():
    with pytest.raises(ConfigError, match="--flow"):
        build("curves", StudyOptions(flow="uniform"))
    with pytest.raises(ConfigError, match="--flows"):
        StudyOptions(flows=(0.2,))


def test_still_fluid_keeps_its_runs_and_its_identity():
    plain = build("navigate", StudyOptions())
    # five targets, each: one LLM run, 16 seeds of Q-learning, PPO and the random policy, and
    # one run each of the controller, mpc and the optimum
    assert len(plain) == 5 * (1 + 3 * 16 + 3)
    assert not any(p.flow or p.agent == "zermelo" for p in plain)
    ident = identity("navigate", StudyOptions(), None)["options"]
    assert "flow" not in ident and "flows" not in ident
    # a flow changes the identity; its speeds are a grid size (the folder grows with them)
    a = identity("navigate", StudyOptions(flow="uniform"), None)
    b = identity("navigate", StudyOptions(flow="uniform", flows=(0.0, 1.2)), None)
    assert a["options"]["flow"] == "uniform" and a == b


def test_a_flow_grid_crosses_every_target_with_every_speed_and_adds_zermelo():
    plans = build("navigate", StudyOptions(flow="shear", flows=(0.0, 0.5), bearings=(90.0,)))
    assert {p.flow_fraction for p in plans} == {0.0, 0.5}
    assert sum(p.agent == "zermelo" for p in plans) == 2 * 3  # 3 targets at 2 speeds
    assert len({p.run_id for p in plans}) == len(plans)
    assert all(p.flow for p in plans)
    # speed 0 is still fluid, written as a uniform stream of speed 0
    assert {p.flow for p in plans if p.flow_fraction == 0.0} == {
        '{"kind": "uniform", "u": [0.0, 0.0]}'
    }


def test_a_target_given_twice_is_one_target():
    # --bearings 90,90 and --distances 3,3.0 ended in an assertion traceback (duplicate run ids)
    once = build("navigate", StudyOptions(bearings=(90.0,)))
    assert [p.run_id for p in build("navigate", StudyOptions(bearings=(90.0, 90.0)))] == [
        p.run_id for p in once
    ]
    twice = StudyOptions(distances=(3.0, 3), bearings=(0.0, 0))
    assert twice.distances == (3.0,) and twice.bearings == (0.0,)


def test_a_flow_past_zermelo_s_work_bound_is_one_line(capsys, tmp_path):
    # Taylor-Green at 2 v needs 2 RK4 steps a step; a target 1000 a away, a horizon of 83,704
    # steps: 167,408 RK4 steps, past MAX_RK4_STEPS (it took minutes; now refused when planned)
    line = refused(
        capsys,
        tmp_path,
        *("study", "navigate", "--flow", "taylor-green", "--flows", "2", "--distances", "1000"),
    )
    assert "MAX_RK4_STEPS" in line and "1e+03 a away" in line
