"""Reading studies back: tables that never cut a cell, show and compare (read-only)."""

from __future__ import annotations

import io
import json

import pytest

from jswim import console
from jswim.studies import overview
from jswim.errors import ConfigError, ResultFolderError
from jswim.results import read_metadata
from jswim.studies import StudyOptions, run_study
from tests.fakeserver import FakeServer, hash_reply

COLS = [
    console.Column("agent", False),
    console.Column("group", False),
    console.Column("n"),
    console.Column("success p [95% CI]"),
    console.Column("X/a end [95% CI]"),
]
ROWS = [
    ["qlearning", "zeta=0", "10", "1.00 [0.72,1.00]", "+1.491 [+1.43,+1.56]"],
    ["qlearning", "zeta=0.5", "10", "0.90 [0.60,0.98]", "+1.200 [+1.10,+1.30]"],
]


def test_plain_table_keeps_every_cell_whole():
    text = console.plain_table(COLS, ROWS, "noise")
    for row in ROWS:
        for cell in row:
            assert cell in text
    assert "zeta=0.5" in text and "\u2026" not in text


def test_narrow_terminal_wraps_columns_into_blocks_and_cuts_nothing():
    text = console.plain_table(COLS, ROWS, width=50)
    assert max(len(line) for line in text.splitlines()) <= 50
    for row in ROWS:
        for cell in row:
            assert cell in text
    # the label columns are repeated in every block
    assert text.count("zeta=0.5") == 2 and text.count("agent") == 2


def test_print_table_to_a_log_is_plain_text_at_full_width():
    buf = io.StringIO()  # not a terminal
    wide = ROWS + [
        [
            "qlearning",
            "a-very-long-group-label-" * 6,
            "10",
            "0.10 [0.00,0.40]",
            "+0.001 [-0.01,+0.01]",
        ]
    ]
    console.print_table(COLS, wide, "t", file=buf)
    assert "a-very-long-group-label-" * 6 in buf.getvalue()
    assert "\x1b[" not in buf.getvalue()  # no terminal escapes in a log


def test_progress_in_a_log_is_one_line_per_update_with_the_info():
    buf = io.StringIO()
    with console.Progress(file=buf, interval=3600) as p:
        p.update("Q-learning", 10, 40, "")
        p.update("Q-learning", 11, 40, "")  # within the interval: not printed
        p.update("LLM runs", 10, 40, "steps 100/1500 · ETA 2m10s")
        p.update("LLM runs", 40, 40, "", final=True)
    lines = buf.getvalue().splitlines()
    assert len(lines) == 3 and "\r" not in buf.getvalue()
    assert lines[0].endswith("Q-learning: 10/40 runs (25%)")
    assert "ETA 2m10s" in lines[1] and "40/40 runs (100%)" in lines[2]


def test_eta_and_durations():
    assert console.eta(30.0, 0.25) == "1m30s"
    assert console.eta(0.0, 0.0) is None
    assert console.format_duration(3725) == "1h02m"


@pytest.fixture(scope="module")
def folders(small_swim_study, tmp_path_factory):
    root = tmp_path_factory.mktemp("studies")
    with FakeServer(reply=hash_reply, latency=0.001) as srv:
        backend = srv.backend()
        run_study(
            "swim",
            StudyOptions(swimmers=("purcell",), directions=(1,), steps=8, runs=2, q_runs=3, seed=1),
            backend,
            root / "b",
        )
    return small_swim_study, root / "b"  # a: Purcell and NG toward +x and -x, 8 steps


def _snapshot(folder):
    return sorted((str(p), p.stat().st_mtime_ns, p.stat().st_size) for p in folder.rglob("*"))


def test_show_prints_status_table_and_cost_without_writing(folders, capsys):
    a, _ = folders
    before = _snapshot(a)
    text = overview.show_text(a)
    assert _snapshot(a) == before
    assert text.startswith(f"study swim in {a}: complete")
    assert "model: fake" in text and "LLM usage:" in text
    # A fake server on 127.0.0.1 with no list price: the one wording, with the reason (not "$0.0000").
    assert (
        "cost not priced (a server on this machine or the LAN, with no list price for its model); $0 counted"
        in text
    )
    assert "no figures yet" in text  # run_study draws nothing
    for agent in ("llm", "qlearning", "random"):
        assert f"\n{agent}" in text


def test_show_marks_an_unfinished_study(folders, tmp_path):
    a, _ = folders
    part = tmp_path / "part"
    part.mkdir()
    meta = json.loads((a / "metadata.json").read_text())
    meta.update(status="running", n_planned=28)
    (part / "metadata.json").write_text(json.dumps(meta))
    (part / "runs.jsonl").write_text(
        "".join(line + "\n" for line in (a / "runs.jsonl").read_text().splitlines()[:5])
    )
    text = overview.show_text(part)
    # "running" with no live session holding the folder: its session died without a word
    assert (
        "UNFINISHED: 5 of 28 runs done (status running, but no live session holds the folder"
        in text
    )


def test_compare_lists_settings_present_in_all(folders):
    a, b = folders
    text = overview.compare_text([a, b])
    assert text.splitlines()[0].startswith(f"[1] {a.name} (fake): study swim, complete")
    body = [line for line in text.splitlines() if line.startswith(("llm", "qlearning", "random"))]
    # b has Purcell toward +x only: 3 settings in common, each shown for both studies: one row per
    # study, or one row naming both ([1][2]) where a baseline's numbers agree (seeds 0 and 1 can
    # give the random policy's 3 runs the same summary: they did in a from-scratch install, jax 0.10.2)
    assert {line.split()[0] for line in body} == {"llm", "qlearning", "random"}
    assert sum(line.split()[3].count("[") for line in body) == 3 * 2
    assert all(line.split()[3] in ("[1]", "[2]") for line in body if line.startswith("llm"))
    assert all(" purcell " in line and " +x " in line for line in body)
    assert "9 setting(s) not present in every study are left out" in text
    with pytest.raises(ConfigError, match="at least two"):
        overview.compare_table([a])
    with pytest.raises(ResultFolderError, match="not a jswim study folder"):
        overview.compare_table([a, a.parent])


def test_groups_read_in_the_grids_order_not_the_order_runs_finished(tmp_path, capsys):
    import random

    from jswim import cli
    from tests.fakeserver import FakeServer, hash_reply

    out = tmp_path / "h"
    with FakeServer(reply=hash_reply) as srv:
        args = [
            "study",
            "history",
            "--n-hts",
            "10,2,1",
            "--runs",
            "1",
            "--steps",
            "4",
            "--swimmer",
            "purcell",
            "--direction",
            "+x",
            "--no-figures",
            "--out",
            str(out),
            "--base-url",
            srv.url,
            "--model",
            "fake",
        ]
        assert cli.main(args) == 0
        # Runs land as they finish (concurrency scrambles them): shuffle the file to say so.
        lines = (out / "runs.jsonl").read_text().splitlines()
        for seed in range(10):
            random.Random(seed).shuffle(lines)
            if next(json.loads(ln)["group"] for ln in lines) != "n_ht=10":
                break
        (out / "runs.jsonl").write_text("\n".join(lines) + "\n")
        capsys.readouterr()
        assert cli.main(args) == 0  # the resumed session's table
        printed = capsys.readouterr().out
    assert read_metadata(out)["group_order"] == ["n_ht=10", "n_ht=2", "n_ht=1"]

    def groups(text):
        return [
            w
            for ln in text.splitlines()
            if ln.startswith("llm")
            for w in ln.split()
            if w.startswith("n_ht=")
        ]

    assert groups(printed) == ["n_ht=10", "n_ht=2", "n_ht=1"]  # as --n-hts gave them
    assert cli.main(["show", str(out)]) == 0
    assert groups(capsys.readouterr().out) == ["n_ht=10", "n_ht=2", "n_ht=1"]
    # A folder from before the order was recorded: one swept number in its numeric order.
    meta = json.loads((out / "metadata.json").read_text())
    del meta["group_order"]
    (out / "metadata.json").write_text(json.dumps(meta))
    assert cli.main(["show", str(out)]) == 0
    assert groups(capsys.readouterr().out) == ["n_ht=1", "n_ht=2", "n_ht=10"]


def test_a_fixed_stroke_s_row_says_fixed_not_how_many_learned():
    from jswim.studies.overview import summary_table

    base = dict(
        swimmer="ng", direction=1, n=1, success_rate=1.0, success_lo=0.21, success_hi=1.0,
        mean_x=0.8, learned=1, steps_to_learn_median=1.0, failed_steps=0, tokens_per_step=None,
    )  # fmt: skip
    cols, rows = summary_table([dict(base, agent="stroke"), dict(base, agent="qlearning")])
    at = {c.header: i for i, c in enumerate(cols)}
    learned, learn = at["learned"], at["learn q25/med/q75"]
    assert rows[0][learned] == "fixed" and rows[0][learn] == "-"
    assert rows[1][learned] == "1 of 1" and rows[1][learn] == "med 1"


def test_a_mean_that_rounds_to_zero_is_printed_without_a_minus_sign():
    from jswim.studies.overview import _fmt

    assert _fmt(-1e-9, "+.3f") == "+0.000" and _fmt(-0.0004, ".3f") == "0.000"
    assert _fmt(-0.0006, "+.3f") == "-0.001"
