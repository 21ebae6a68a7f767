"""A navigation study's and a target's bad input is one line and exit 2 (a ``ConfigError`` in
Python), never a traceback, and never silently changed: each case is an example of a kind
(numbers past what the dtype holds, empty list items, values the study would change behind the
user's back, strings where numbers go, non-finite values)."""

from __future__ import annotations

import math

import pytest

from jswim import cli
from jswim.env.targets import FixedTarget, MovingTarget, Waypoints
from jswim.errors import MAX_COUNT, ConfigError


def refused(capsys, tmp_path, *args: str) -> str:
    try:
        rc = cli.main([*args, "--out", str(tmp_path / "o"), "--dry-run"])
    except SystemExit as e:  # argparse's own refusal (a usage line, then one error line)
        rc = e.code
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = [ln for ln in err.splitlines() if "error:" in ln]
    assert rc == 2 and len(lines) == 1, err
    assert not (tmp_path / "o" / "runs.jsonl").exists()
    return lines[0]


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--distances", "1e9", "--train-episodes", "1"], "--distances"),  # int32 overflow before
        (["--distances", "-3"], "--distances"),
        (["--distances", "nan"], "--distances"),
        (["--bearings", "1e30"], "--bearings"),
        (["--bearings", "inf"], "--bearings"),
        (["--train-episodes", "99999999999"], "--train-episodes"),
        (["--roc-levels", "1"], "--roc-levels"),  # the study would run K = 2 behind the user's back
        (["--distances", "3,,6"], "empty items"),
        (["--bearings", "0,,90"], "empty items"),
        (["--distances", "abc"], "--distances"),
        (["--starts", "0"], "--starts"),
        (["--starts", "-2"], "--starts"),
        (["--starts", "99999999999"], "--starts"),
        (["--starts", "2.5"], "--starts"),
    ],
)
def test_navigate_refuses_in_one_line(capsys, tmp_path, args, says):
    assert says in refused(capsys, tmp_path, "study", "navigate", *args)


@pytest.mark.parametrize(
    ("study", "args"),
    [
        ("noise", ["--zetas", "0,,1"]),
        ("wall", ["--heights", "3,,10"]),
        ("school", ["--school-sizes", "1,,3"]),
    ],
)
def test_every_study_refuses_empty_list_items(capsys, tmp_path, study, args):
    assert "empty items" in refused(capsys, tmp_path, "study", study, *args)


@pytest.mark.parametrize(
    "make",
    [
        lambda: FixedTarget("3"),  # a string is not coerced to 3.0
        lambda: FixedTarget(True),
        lambda: FixedTarget(3.0, 90.0, budget=10**12),  # past int32: was a raw OverflowError
        lambda: FixedTarget(3.0, budget=MAX_COUNT + 1),
        lambda: FixedTarget(3.0, math.inf),
        lambda: FixedTarget(3.0, 1e30),
        lambda: FixedTarget(1e9),
        lambda: FixedTarget(3.0, radius=float("nan")),
        lambda: Waypoints(((2.0, "1"),)),
        lambda: MovingTarget(3.0, 90.0, velocity=(math.nan, 0.0)),
    ],
)
def test_targets_refuse_with_a_config_error(make):
    with pytest.raises(ConfigError) as e:
        make()
    assert "\n" not in str(e.value)


def test_targets_keep_what_is_valid():
    t = FixedTarget(3, 90, budget=MAX_COUNT)
    assert (t.distance, t.bearing, t.budget) == (3.0, 90.0, MAX_COUNT)
    assert isinstance(t.distance, float)


@pytest.mark.parametrize("study", ["curves", "noise", "wall"])
def test_other_studies_refuse_seeded_starts(capsys, tmp_path, study):
    line = refused(capsys, tmp_path, "study", study, "--starts", "3")
    assert "--starts" in line
