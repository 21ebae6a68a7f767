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
    assert len(plain) == 25 and not any(p.flow or p.agent == "zermelo" for p in plain)
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
