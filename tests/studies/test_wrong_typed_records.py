"""Records of the wrong type in a study folder (a hand edit, damage) never crash a command: a run
record whose scene fields or tracks have the wrong type or shape is skipped with one warning
(and run again by the resume, which ends with the folder's status said), wrong-typed LLM totals
are ignored, a NaN track still draws the report."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import pytest

from jswim import cli
from jswim.results import read_runs
from jswim.results.schema import run_problem
from tests.fakeserver import FakeServer, hash_reply

SWIM = ["--model", "fake", "--q-runs", "0", "--steps", "4"]
SWIM += ["--swimmer", "purcell", "--direction", "+x", "--no-figures", "--runs"]


def swim(url: str, out: Path, runs: int = 2) -> list[str]:
    return ["swim", "--base-url", url, *SWIM, str(runs), "--out", str(out)]


@pytest.fixture(scope="module")
def study(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("wrong") / "S"
    with FakeServer(reply=hash_reply) as srv:
        assert cli.main(swim(srv.url, out)) == 0
    return out


def edited(study: Path, tmp_path: Path, edit) -> Path:
    out = tmp_path / "S"
    shutil.copytree(study, out)
    lines = (out / "runs.jsonl").read_text().splitlines()
    first = json.loads(lines[0])
    edit(first)
    lines[0] = json.dumps(first)
    (out / "runs.jsonl").write_text("\n".join(lines) + "\n")
    return out


CASES = {
    "heights text": ("heights", "x"),
    "heights ragged": ("heights", [["a"], [1.0]]),
    "contact number": ("contact", 5),
    "n_swimmers text": ("n_swimmers", "two"),
    "separation text": ("separation", "far"),
    "per_cycle list": ("per_cycle", [1]),
    "medium number": ("medium", 3),
    "orientation short": ("orientation", [0.0]),
}


@pytest.mark.parametrize("field, value", CASES.values(), ids=CASES.keys())
def test_a_scene_field_of_the_wrong_type_is_no_run_record(field, value):
    row = {"run_id": "r", "agent": "llm", "group": "", "steps": 4, "x": [0.1, 0.2, 0.3, 0.4]}
    row[field] = value
    assert run_problem(row) is not None
    good = {"run_id": "r", "agent": "llm", "group": "", "steps": 2, "x": [0.1, 0.2]}
    good["heights"] = [[1.0], [2.0]]
    assert run_problem({**good, "contact": [False, True], "n_swimmers": 1}) is None
    assert run_problem({**good, "contact": [[False], [True]]}) is None


@pytest.mark.parametrize("field, value", [CASES["heights text"], CASES["separation text"]])
def test_show_report_plot_and_resume_skip_a_wrong_typed_record(
    study, tmp_path, capsys, field, value
):
    out = edited(study, tmp_path, lambda r: r.update({field: value}))
    for cmd in (["show", str(out)], ["report", str(out)], ["plot", str(out)]):
        assert cli.main(cmd) == 2, cmd  # the rest shown; 2: not the whole folder (issue 61)
        err = capsys.readouterr().err
        assert "skipped" in err and "Traceback" not in err
    with FakeServer(reply=hash_reply) as srv:
        assert cli.main(swim(srv.url, out)) == 0
        assert srv.n_requests == 0  # the skipped run is run again from the call journal
    assert len(read_runs(out)) == 2
    assert json.loads((out / "metadata.json").read_text())["status"] == "complete"


def test_a_nan_orientation_still_draws_the_report(study, tmp_path, capsys):
    out = edited(study, tmp_path, lambda r: r.update(orientation=[math.nan] * len(r["x"])))
    assert cli.main(["report", str(out)]) == 0
    assert "Traceback" not in capsys.readouterr().err and (out / "report.html").exists()


@pytest.mark.parametrize(
    "totals",
    [{"requests": "x", "sessions": [1]}, {"faults": 5, "sessions": 1}, {"wall_s": math.nan}, []],
    ids=["text", "faults number", "nan", "a list"],
)
def test_wrong_typed_llm_totals_neither_crash_show_nor_the_resume(study, tmp_path, capsys, totals):
    out = tmp_path / "S"
    shutil.copytree(study, out)
    meta = json.loads((out / "metadata.json").read_text())
    if isinstance(totals, dict):
        meta["llm_totals"].update(totals)
    else:
        meta["llm_totals"] = totals
    (out / "metadata.json").write_text(json.dumps(meta))
    assert cli.main(["show", str(out)]) == 2  # the rest shown, the totals' fields said
    err = capsys.readouterr().err
    assert "Traceback" not in err and "llm_totals" in err
    with FakeServer(reply=hash_reply) as srv:
        assert cli.main(swim(srv.url, out, runs=3)) == 0  # one more run: a session is recorded
    assert json.loads((out / "metadata.json").read_text())["status"] == "complete"


def test_a_transcript_replaced_by_a_folder_is_named_as_such(study, tmp_path, capsys):
    out = tmp_path / "S"
    shutil.copytree(study, out)
    one = sorted((out / "transcripts").iterdir())[0]
    one.unlink()
    one.mkdir()
    with FakeServer(reply=hash_reply) as srv:
        assert cli.main(swim(srv.url, out, runs=3)) == 2
    err = capsys.readouterr().err
    assert "a folder stands where this file goes" in err and "writable --out" not in err


def test_school_refuses_the_options_of_an_llm(tmp_path, capsys):
    for extra in (["--runs", "2"], ["--base-url", "http://127.0.0.1:9/v1", "--model", "m"]):
        assert cli.main(["study", "school", *extra, "--out", str(tmp_path / "x")]) == 2
        err = capsys.readouterr().err
        assert "no use for" in err and "no LLM" in err and not (tmp_path / "x").exists()


def test_an_empty_model_name_is_refused(tmp_path, capsys):
    code = cli.main(
        [
            "swim",
            "--base-url",
            "http://127.0.0.1:9/v1",
            "--model",
            " ",
            "--out",
            str(tmp_path / "x"),
        ]
    )
    assert code == 2 and "--model" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["runs.jsonl", "calls.jsonl", "requests.jsonl", "metadata.json"])
def test_a_fifo_in_place_of_a_record_file_is_one_line_not_a_hang(study, tmp_path, capsys, name):
    import os

    out = tmp_path / "S"
    shutil.copytree(study, out)
    (out / name).unlink()
    os.mkfifo(out / name)
    with FakeServer(reply=hash_reply) as srv:
        assert cli.main(swim(srv.url, out, runs=3)) == 2
        assert srv.n_requests == 0
    err = capsys.readouterr().err
    assert "not a regular file" in err and "Traceback" not in err
    code = cli.main(["show", str(out)])  # returns: the readers never wait on a FIFO
    assert code == (2 if name in ("runs.jsonl", "metadata.json") else 0)
