"""Each study's ``--help`` names that study's defaults and offers only what it accepts: an option
the study refuses is not listed (and still refused, in one line), a default the study changes is
the one its help names."""

from __future__ import annotations

import argparse

import pytest

from jswim import cli
from jswim.studies.kinds.navigate import NAV_ROC_LEVELS
from jswim.studies import get, names
from jswim.studies.flags import FLAGS


def study_parser(name: str) -> argparse.ArgumentParser:
    top = cli.build_parser()
    sub = next(a for a in top._actions if isinstance(a, argparse._SubParsersAction))
    if name == "swim":
        return sub.choices["swim"]
    study = sub.choices["study"]
    names = next(a for a in study._actions if isinstance(a, argparse._SubParsersAction))
    return names.choices[name]


def flag_help(parser: argparse.ArgumentParser, flag: str) -> str | None:
    """The help of ``flag`` as ``--help`` prints it (``None``: not listed)."""
    for action in parser._actions:
        if flag in action.option_strings:
            return None if action.help == argparse.SUPPRESS else action.help
    raise AssertionError(f"{flag} is not an option")


@pytest.mark.parametrize("study", [s for s in names() if get(s).command == "study"])
def test_an_option_the_study_refuses_is_not_in_its_help(study, capsys):
    parser = study_parser(study)
    usage = parser.format_usage()
    refused = [f.names[0] for f in FLAGS if f.field in get(study).ignores]
    for flag in refused:
        assert flag_help(parser, flag) is None, f"jswim study {study} --help offers {flag}"
        assert f"[{flag} " not in usage, f"jswim study {study}'s usage line offers {flag}"


@pytest.mark.parametrize("study", [s for s in names() if get(s).command == "study"])
def test_the_counts_help_names_this_study_s_defaults(study):
    parser, spec = study_parser(study), get(study)
    runs, q_runs = flag_help(parser, "--runs"), flag_help(parser, "--q-runs")
    if runs is not None:
        assert f"(default {spec.runs})" in runs
    if q_runs is not None:
        assert f"(default {spec.q_runs})" in q_runs


def test_navigate_help_names_its_own_lattice_and_swimmer():
    parser = study_parser("navigate")
    roc = flag_help(parser, "--roc-levels")
    assert f"default {NAV_ROC_LEVELS}" in roc and "default 1" not in roc
    swimmer = flag_help(parser, "--swimmer")
    assert "purcell" in swimmer and "ng" not in swimmer.replace("turns", "")
    assert flag_help(parser, "--direction") is None
    assert "lowers it" in flag_help(parser, "--x-min")


def test_continuous_help_names_its_grid_of_k():
    roc = flag_help(study_parser("continuous"), "--roc-levels")
    assert "default 1,2,5,10" in roc


def test_swim_keeps_every_run_option():
    # the paper's main job refuses nothing: each of these is listed with its help
    parser = study_parser("swim")
    for flag in ("--direction", "--n-ht", "--noise", "--init", "--q-runs", "--runs"):
        assert flag_help(parser, flag), flag


@pytest.mark.parametrize(
    "argv, says",
    [
        (["study", "navigate", "--direction=-x"], "--direction"),
        (["study", "school", "--runs", "2"], "--runs"),
        (["study", "history", "--n-ht", "3"], "--n-ht"),
    ],
)
def test_an_unlisted_option_is_still_refused_in_one_line(argv, says, capsys, tmp_path):
    rc = cli.main([*argv, "--out", str(tmp_path / "o"), "--dry-run"])
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if "error:" in ln]
    assert rc == 2 and len(lines) == 1 and says in lines[0] and "Traceback" not in err


def test_jswim_study_help_names_every_study(capsys):
    with pytest.raises(SystemExit):
        cli.main(["study", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    nested = [s for s in names() if get(s).command == "study"]
    assert {"school", "navigate"} <= set(nested)  # the two the listing used to leave out
    assert "NAME " + ", ".join(nested) in text


@pytest.mark.parametrize("swimmer", ["ng", "both"])
def test_navigate_refuses_a_swimmer_it_cannot_steer_in_one_line(swimmer, capsys, tmp_path):
    assert cli.main(["study", "navigate", "--swimmer", swimmer, "--out", str(tmp_path / "f")]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "steers Purcell's swimmer only" in err
