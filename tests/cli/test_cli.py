"""End to end: the jswim command against the fake server, resumable study folders, error paths."""

from __future__ import annotations

import json

import pyarrow.parquet as pq
import pytest

from jswim import cli
from jswim.results import read_metadata, read_runs
from jswim.studies import Backend, StudyOptions, run_study
from tests.fakeserver import FakeServer, hash_reply

FAST = ["--steps", "8", "--q-runs", "4", "--no-figures"]


@pytest.fixture(scope="module")
def server():
    with FakeServer(reply=hash_reply, latency=0.005) as srv:
        yield srv


def backend_args(srv):
    return ["--base-url", srv.url, "--model", "fake", "--api-key-env", "JSWIM_TEST_NO_KEY"]


def test_swim_writes_every_file(server, tmp_path, capsys, monkeypatch):
    out = tmp_path / "swim"
    key = "sk-test-" + "k3y" * 12  # a key is set, so its absence from the folder means something
    monkeypatch.setenv("JSWIM_TEST_KEY", key)
    args = ["--base-url", server.url, "--model", "fake", "--api-key-env", "JSWIM_TEST_KEY"]
    server.reset_counts()  # the module's server: count only this test's requests, in any order
    rc = cli.main(
        ["swim", "--steps", "8", "--runs", "2", "--q-runs", "4", "--out", str(out), *args]
    )
    assert rc == 0
    assert server.auth_headers and set(server.auth_headers) == {f"Bearer {key}"}  # it was used
    printed = capsys.readouterr()
    text = printed.out
    assert key not in printed.out + printed.err
    assert not any(key.encode() in p.read_bytes() for p in out.rglob("*") if p.is_file())
    assert "llm" in text and "qlearning" in text and "random" in text and str(out) in text
    for name in (
        "metadata.json",
        "runs.jsonl",
        "runs.parquet",
        "runs.csv",
        "trajectories.parquet",
        "figures/swim.png",
        "figures/swim.pdf",
    ):
        assert (out / name).is_file(), name
    runs = read_runs(out)
    assert sorted(r["agent"] for r in runs).count("llm") == 2 and len(runs) == 2 + 4 + 4
    assert len(list((out / "transcripts").glob("*.jsonl"))) == 2
    table = pq.read_table(out / "runs.parquet").to_pylist()
    assert {r["run_id"] for r in table} == {r["run_id"] for r in runs}
    traj = pq.read_table(out / "trajectories.parquet")
    assert traj.num_rows == 10 * 8
    meta = read_metadata(out)
    assert meta["status"] == "complete" and meta["identity"]["backend"]["model"] == "fake"
    assert "api_key" not in json.dumps(meta).lower().replace("api_key_env", "")


def test_study_noise_grid_has_every_run(server, tmp_path):
    out = tmp_path / "noise"
    rc = cli.main(
        [
            "study",
            "noise",
            "--swimmer",
            "purcell",
            "--zetas",
            "0,1.5",
            "--runs",
            "2",
            *FAST,
            "--out",
            str(out),
            *backend_args(server),
        ]
    )
    assert rc == 0
    runs = read_runs(out)
    assert len(runs) == 2 * (2 + 4 + 4)
    assert sorted({r["zeta"] for r in runs}) == [0.0, 1.5]
    assert all(len(r["x"]) == 8 for r in runs)


def _table(folder):
    # Accounting that depends on which runs had identical requests in flight together (shared
    # calls bill once) and on what a resume replayed; the runs themselves must be identical.
    drop = {
        "wall_s",
        "latency_s",
        "cache_hits",
        "billed_calls",
        "calls",
        "http_retries",
        "replayed_calls",
        "prompt_tokens",
        "completion_tokens",
        "cached_tokens",
        "cost_usd",
    }
    return sorted(
        tuple(sorted((k, json.dumps(v)) for k, v in r.items() if k not in drop))
        for r in read_runs(folder)
    )


@pytest.mark.slow  # a study interrupted and resumed end to end (21 s under load 8)
def test_interrupted_study_resumes_to_the_same_table(server, tmp_path):
    opts = StudyOptions(swimmers=("purcell",), zetas=(0.0, 2.0), runs=3, q_runs=3, steps=6, chunk=2)
    backend = Backend(base_url=server.url, model="fake", api_key_env="JSWIM_TEST_NO_KEY")
    full = run_study("noise", opts, backend, tmp_path / "full")

    calls = {"n": 0}

    def interrupt(phase, done, total, info=""):
        # Ctrl-C when the third of the six LLM runs has ended (the others are in progress).
        if phase == "llm" and "steps" in info:
            calls["n"] += 1
            if calls["n"] == 3:
                raise KeyboardInterrupt

    part = tmp_path / "part"
    with pytest.raises(KeyboardInterrupt):
        run_study("noise", opts, backend, part, progress=interrupt)
    n_partial = len(read_runs(part))
    assert 0 < n_partial < len(full.rows)
    resumed = run_study("noise", opts, backend, part)
    assert len(resumed.rows) == len(full.rows)
    assert _table(part) == _table(tmp_path / "full")


def test_error_paths_exit_2_with_one_line(server, tmp_path, capsys):
    cases = [
        (["swim", "--swimmer", "eel"], "unknown swimmer"),
        (["swim", "--steps", "-1"], "--steps"),
        (["swim", "--noise", "-0.5"], "--noise"),
        (["swim", "--prompt-file", str(tmp_path / "none.txt")], "--prompt-file"),
        (
            [
                "swim",
                "--base-url",
                "http://127.0.0.1:9/v1",
                "--model",
                "x",
                "--out",
                str(tmp_path / "u"),
            ],
            "cannot reach",
        ),
        (["swim", "--model", "gpt-4"], "--base-url"),
        (["swim", "--cohorts", "0"], "--cohorts"),
        (["swim", "--threads", "0"], "--threads"),
        (["study", "nosuch"], "invalid choice"),
        (["plot", str(tmp_path)], "not a jswim study folder"),
    ]
    for argv, word in cases:
        rc = run_cli(argv)
        err = capsys.readouterr().err.strip().splitlines()
        assert rc == 2, argv
        assert word in err[-1], (argv, err)
        assert "Traceback" not in "\n".join(err)


def run_cli(argv):
    """Exit status of ``jswim argv`` (argparse exits by SystemExit, commands return it)."""
    try:
        return cli.main(argv)
    except SystemExit as exc:
        return exc.code


def test_output_folder_of_another_study_is_refused(server, tmp_path, capsys):
    out = tmp_path / "f"
    assert (
        cli.main(
            [
                "study",
                "curves",
                "--swimmer",
                "purcell",
                "--runs",
                "1",
                *FAST,
                "--out",
                str(out),
                *backend_args(server),
            ]
        )
        == 0
    )
    rc = cli.main(
        [
            "study",
            "ablation",
            "--swimmer",
            "purcell",
            "--runs",
            "1",
            "--steps",
            "8",
            "--out",
            str(out),
            *backend_args(server),
        ]
    )
    assert rc == 2
    assert "holds a 'curves' study" in capsys.readouterr().err


def test_gaits_command_ranks_the_square_gait_first(capsys):
    assert cli.main(["gaits", "purcell", "--top", "3"]) == 0
    out = capsys.readouterr().out
    assert "+0.191247" in out.splitlines()[2]
