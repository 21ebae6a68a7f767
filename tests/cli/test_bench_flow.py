"""The ``navigate-flow`` bench suite: its part's command line (the navigation study with
``--flow uniform --flows 0,0.5,0.9``), a dry run pricing its grid (nothing sent, nothing
written), and a models file's own suites with the flow options, refused in one line where the
study would refuse them."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from jswim import cli
from jswim.bench import runner
from jswim.bench.models_file import parse_model_option
from jswim.bench.suites import SUITES, user_suite
from jswim.errors import ConfigError

FLOWS = (0.0, 0.5, 0.9)
#: The navigation study's targets (docs/navigation.md): 3 a at 0, 90, 180 degrees, a path and
#: a moving target.
TARGETS = 5


def test_the_suite_runs_the_navigation_study_in_a_uniform_cross_stream(tmp_path):
    suite = SUITES["navigate-flow"]
    (part,) = suite.parts
    assert (part.name, part.study, suite.seed) == ("navigate-flow", "navigate", 0)
    assert dict(part.options) == {"runs": 1, "flow": "uniform", "flows": FLOWS}
    assert part.args(0) == [
        *("study", "navigate", "--runs", "1", "--flow", "uniform"),
        *("--flows", "0.0,0.5,0.9", "--seed", "0"),
    ]
    # every job of the bench carries the flow: the model's, the reference rule's, the baselines'
    model = parse_model_option("base_url=http://127.0.0.1:9/v1,model=m")
    jobs = runner.plan([model], suite, tmp_path, prices_file=None, reference_url="http://r/v1")
    assert {j.kind for j in jobs} == {"llm", "reference", "baseline"}
    for j in jobs:
        i = j.argv.index("--flow")
        assert j.argv[i : i + 4] == ["--flow", "uniform", "--flows", "0.0,0.5,0.9"]
    assert suite.describe()["parts"][0]["options"]["flows"] == FLOWS  # bench.json's record


def test_dry_run_prices_every_target_at_every_flow_speed(tmp_path, capsys):
    out = tmp_path / "b"
    model = "base_url=http://127.0.0.1:9/v1,model=gpt-4o,price_local=true"
    argv = ["bench", "--suite", "navigate-flow", "--model", model, "--dry-run", "--out", str(out)]
    assert cli.main([*argv, "--runs", "1", "--steps", "12"]) == 0
    text = capsys.readouterr().out
    est = json.loads(text.strip().splitlines()[-1])
    assert est["suite"] == "navigate-flow" and "part(s) per model (navigate-flow)" in text
    # one LLM run of 12 steps per target and flow speed
    assert est["models"]["gpt-4o"]["calls"] == TARGETS * len(FLOWS) * 12
    assert est["models"]["gpt-4o"]["priced"] and est["total_usd"] > 0
    assert not Path(out).exists()  # nothing written


def _suite(options: dict, study: str = "navigate"):
    return user_suite("mine", {"study": study, "options": options}, "models.toml")


def test_a_models_file_suite_takes_the_flow_options():
    (part,) = _suite({"flow": "taylor-green", "flows": [0.5, 1.0], "runs": 2}).parts
    assert dict(part.options) == {"flow": "taylor-green", "flows": (0.5, 1.0), "runs": 2}
    assert part.args(0)[-6:] == ["--flows", "0.5,1.0", "--runs", "2", "--seed", "0"]


@pytest.mark.parametrize(
    "options, study, says",
    [
        ({"flow": "uniform"}, "curves", "the curves study has no use for flow"),
        ({"flows": [0.5]}, "noise", "the noise study has no use for flows"),
        ({"flows": [0.5]}, "navigate", "give its kind too"),
        ({"flow": "vortex"}, "navigate", "flow must be one of uniform, shear"),
        ({"flow": ["uniform"]}, "navigate", "flow must be one of"),
    ],
)
def test_a_models_file_suite_with_a_flow_its_study_refuses_is_one_line(options, study, says):
    with pytest.raises(ConfigError) as err:
        _suite(options, study)
    text = str(err.value)
    assert says in text and "models.toml" in text and "\n" not in text
