"""Hand-edited or damaged study folders stay readable, and a command that stops changes nothing.

Each case damages one record of a finished (or half-done) study run against the fake server:
every reader says, in one line naming the file and the line, that it skipped that record (and
exits 2 after showing the rest); a
resume pays for what the bad record held and nothing more; no command that stops on an error
changes the folder's status.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from jswim import cli
from tests.fakeserver import FakeServer, hash_reply

STEPS = 12
FAST = [
    "--steps",
    str(STEPS),
    "--runs",
    "2",
    "--q-runs",
    "0",
    "--swimmer",
    "purcell",
    "--direction",
    "+x",
    "--no-figures",
]


def swim_args(url: str, out: Path, *extra: str) -> list[str]:
    return ["swim", *FAST, "--out", str(out), "--base-url", url, "--model", "fake", *extra]


@pytest.fixture(scope="module")
def srv():
    with FakeServer(reply=hash_reply) as s:
        yield s


@pytest.fixture(scope="module")
def finished(srv, tmp_path_factory):
    """A complete two-run study folder (24 answered calls)."""
    out = tmp_path_factory.mktemp("done") / "study"
    assert cli.main(swim_args(srv.url, out)) == 0
    return out


def copy(folder: Path, tmp_path: Path) -> Path:
    out = tmp_path / "study"
    shutil.copytree(folder, out)
    return out


def status(folder: Path) -> str:
    return json.loads((folder / "metadata.json").read_bytes().decode("utf-8", "replace"))["status"]


def run(capsys, *argv: str) -> tuple[int, str]:
    rc = cli.main(list(argv))
    err = capsys.readouterr().err
    assert "Traceback" not in err, err
    return rc, err


def replace_line(path: Path, n: int, new: bytes) -> None:
    lines = path.read_bytes().split(b"\n")
    lines[n - 1] = new
    path.write_bytes(b"\n".join(lines))


def second_run_record(folder: Path) -> dict:
    return json.loads((folder / "runs.jsonl").read_text().splitlines()[1])


RUN_EDITS = {
    "non-utf8": lambda rec: (
        json.dumps(rec).replace('"llm"', '"ll\udcff"', 1).encode("utf-8", "surrogateescape")
    ),
    "empty-object": lambda rec: b"{}",
    "run-id-number": lambda rec: b'{"run_id": 5}',
    "run-id-list": lambda rec: b'{"run_id": [1]}',
    "final-x-text": lambda rec: json.dumps({**rec, "final_x": "abc"}).encode(),
}


@pytest.mark.parametrize("case", list(RUN_EDITS))
def test_a_bad_runs_line_is_skipped_with_one_line_and_the_resume_pays_nothing(
    case, finished, srv, tmp_path, capsys
):
    out = copy(finished, tmp_path)
    replace_line(out / "runs.jsonl", 2, RUN_EDITS[case](second_run_record(out)))
    for argv in (
        ["show", str(out)],
        ["compare", str(out), str(out)],
        [*swim_args(srv.url, out), "--dry-run"],
    ):
        rc, err = run(capsys, *argv)
        # A reader shows the rest and exits 2 (not the whole folder); the dry run plans it again.
        assert rc == (0 if "--dry-run" in argv else 2), err
        warned = [ln for ln in err.splitlines() if "runs.jsonl, line 2" in ln]
        assert warned and "skipped" in warned[0], err
        assert status(out) == "complete"
    srv.reset_counts()
    rc, err = run(capsys, *swim_args(srv.url, out))
    assert rc == 0, err
    assert srv.n_requests == 0  # the skipped run is redone from the journal: nothing paid twice
    assert status(out) == "complete"


@pytest.mark.slow
def test_every_reader_of_a_non_utf8_runs_line_warns_and_goes_on(finished, tmp_path, capsys):
    out = copy(finished, tmp_path)
    replace_line(out / "runs.jsonl", 2, RUN_EDITS["non-utf8"](second_run_record(out)))
    for argv in (
        ["plot", str(out)],
        ["report", str(out)],
        ["animate", str(out), "--max", "1", "--dpi", "20"],
    ):
        rc, err = run(capsys, *argv)
        assert rc == 2, err  # the other runs drawn, the skipped line said
        assert "runs.jsonl, line 2" in err
        assert status(out) == "complete"


def half_done(finished: Path, tmp_path: Path) -> Path:
    """The finished study with its second run (by run id, as :func:`edit_call` counts; the runs
    land in the order they finish) not recorded (its 12 calls journaled)."""
    out = copy(finished, tmp_path)
    lines = (out / "runs.jsonl").read_bytes().split(b"\n")
    second = sorted(json.loads(ln)["run_id"] for ln in lines if ln)[1]
    (out / "runs.jsonl").write_bytes(
        b"\n".join(ln for ln in lines if not ln or json.loads(ln)["run_id"] != second)
    )
    return out


def edit_call(out: Path, index: int, **fields) -> None:
    """Change the journal record of the second run's call ``index``."""
    path = out / "calls.jsonl"
    recs = [json.loads(ln) for ln in path.read_text().splitlines()]
    run2 = sorted({r["run"] for r in recs})[1]
    lines = path.read_text().splitlines()
    for i, r in enumerate(recs):
        if r["run"] == run2 and r["n"] == index:
            lines[i] = json.dumps({**r, **fields})
    path.write_text("\n".join(lines) + "\n")


@pytest.mark.parametrize(
    "fields",
    [{"text": None}, {"usage": ["x", 1, 0, 0]}, {"cost_usd": "x"}, {"n": "3"}],
    ids=["null-text", "usage-text", "cost-text", "index-text"],
)
def test_a_journal_record_failing_validation_costs_that_one_call_only(
    fields, finished, srv, tmp_path, capsys
):
    out = half_done(finished, tmp_path)
    edit_call(out, 3, **fields)
    srv.reset_counts()
    rc, err = run(capsys, *swim_args(srv.url, out))
    assert rc == 0, err
    assert "calls.jsonl, line" in err and "skipped" in err
    assert srv.settle() == 1  # that call alone: the ones after it keep their numbers and replay
    assert status(out) == "complete"


def test_metadata_fields_of_the_wrong_type(finished, srv, tmp_path, capsys):
    out = copy(finished, tmp_path)
    meta = json.loads((out / "metadata.json").read_text())
    (out / "metadata.json").write_text(json.dumps({**meta, "summary": 5}))
    rc, err = run(capsys, "show", str(out))
    assert rc == 2 and "metadata.json: 'summary' is 5" in err, err
    rc, err = run(capsys, *swim_args(srv.url, out))  # the resume rewrites the summary
    assert rc == 0, err
    assert isinstance(json.loads((out / "metadata.json").read_text())["summary"], dict)

    (out / "metadata.json").write_text(json.dumps({**meta, "identity": "x"}))
    before = (out / "metadata.json").read_bytes()
    rc, err = run(capsys, "show", str(out))
    assert rc == 2 and "'identity' is 'x'" in err, err
    rc, err = run(capsys, *swim_args(srv.url, out))
    lines = [ln for ln in err.splitlines() if ln.startswith("jswim: error:")]
    assert rc == 2 and len(lines) == 1 and "metadata.json" in lines[0] and "identity" in lines[0]
    assert (out / "metadata.json").read_bytes() == before  # the status is not touched


def test_a_refused_resume_leaves_the_status_as_it_was(finished, srv, tmp_path, capsys):
    # A cost cap the calls could not reach is refused before any request: the folder that read
    # "stopped at the cost cap" (here: any status) still reads it.
    out = half_done(finished, tmp_path)
    meta = json.loads((out / "metadata.json").read_text())
    (out / "metadata.json").write_text(json.dumps({**meta, "status": "stopped at the cost cap"}))
    rc, err = run(
        capsys,
        *swim_args(
            srv.url,
            out,
            "--max-cost",
            "1",
            "--price-local",
            "--prices",
            str(prices_without(tmp_path)),
        ),
    )
    assert rc == 2 and "--prices" in err
    assert status(out) == "stopped at the cost cap"


def prices_without(tmp_path: Path) -> Path:
    p = tmp_path / "prices.toml"
    p.write_text('[prices]\n"other" = [1.0, 2.0]\n')
    return p


def test_a_torn_transcript_of_a_finished_run_says_what_is_lost(finished, srv, tmp_path, capsys):
    out = copy(finished, tmp_path)
    path = sorted((out / "transcripts").glob("*.jsonl"))[0]
    data = path.read_bytes()
    path.write_bytes(data[:-20])  # its end record torn
    srv.reset_counts()
    rc = cli.main(swim_args(srv.url, out))
    printed = capsys.readouterr()
    assert rc == 0 and srv.n_requests == 0
    said = [ln for ln in (printed.err + printed.out).splitlines() if path.name in ln]
    assert said and "not redone" in said[0] and "redone, no answered" not in said[0], said
    assert path.read_bytes() == data[: data[:-20].rfind(b"\n") + 1]  # cut back to whole records
