"""The cost cap is validated in one place (`jswim.studies.session.check_max_cost`), by the CLI and
by `run_study` alike: the same values pass and the same are refused, in one line."""

from __future__ import annotations

import math

import pytest

from jswim import cli
from jswim.errors import ConfigError
from jswim.studies import run_study
from jswim.studies.session import check_max_cost


@pytest.mark.parametrize("bad", [-1.0, math.nan, math.inf, "5", True])
def test_a_cap_that_is_not_dollars_is_refused(bad):
    with pytest.raises(ConfigError, match="--max-cost") as e:
        check_max_cost(bad)
    assert "\n" not in str(e.value)


def test_a_cap_in_dollars_passes():
    assert check_max_cost(None) is None
    assert check_max_cost(0) == 0.0 and check_max_cost(2.5) == 2.5


@pytest.mark.parametrize("bad", [math.inf, math.nan, -0.5])
def test_run_study_refuses_as_the_command_does(bad, tmp_path):
    # run_study accepted an infinite cap that the command refused
    with pytest.raises(ConfigError, match="--max-cost"):
        run_study("swim", out=tmp_path / "o", max_cost=bad)
    assert not (tmp_path / "o" / "runs.jsonl").exists()


@pytest.mark.parametrize("bad", ["inf", "nan", "-1"])
def test_the_command_refuses_in_one_line(bad, tmp_path, capsys):
    rc = cli.main(["swim", "--max-cost", bad, "--out", str(tmp_path / "o"), "--steps", "4"])
    err = capsys.readouterr().err
    assert rc == 2 and "Traceback" not in err
    assert [ln for ln in err.splitlines() if "error:" in ln] == [
        ln for ln in err.splitlines() if "--max-cost" in ln
    ]
