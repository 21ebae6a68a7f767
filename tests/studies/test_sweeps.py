"""Sweeps over LLM settings as grid axes: --temperatures, --prompt-files, and `jswim study
temperature`; each extends a folder as --zetas does."""

from __future__ import annotations

import pytest

from jswim import cli
from jswim.errors import ConfigError
from jswim.results import read_metadata, read_runs
from jswim.studies.options import StudyOptions
from jswim.studies.specs import build
from tests.fakeserver import FakeServer, hash_reply

FAST = [
    "--steps",
    "4",
    "--runs",
    "1",
    "--swimmer",
    "purcell",
    "--no-figures",
    "--api-key-env",
    "JSWIM_TEST_NO_KEY",
]


def test_temperature_and_prompt_axes_name_runs_and_groups():
    plans = build(
        "curves",
        StudyOptions(
            runs=1,
            q_runs=1,
            swimmers=("purcell",),
            temperatures=(0.0, 0.5),
            prompt_files=("a.txt", "b.txt"),
        ),
    )
    llm = [p for p in plans if p.agent == "llm"]
    assert sorted((p.temperature, p.prompt_file) for p in llm) == [
        (0.0, "a.txt"),
        (0.0, "b.txt"),
        (0.5, "a.txt"),
        (0.5, "b.txt"),
    ]
    assert {p.group for p in llm} == {
        "T=0, prompt=a",
        "T=0, prompt=b",
        "T=0.5, prompt=a",
        "T=0.5, prompt=b",
    }
    assert len({p.seed for p in llm}) == 4  # each its own run seed (hash of the run id)
    assert [p.temperature for p in plans if p.agent != "llm"] == [
        None,
        None,
    ]  # baselines are not swept
    # The temperature study's own grid: both swimmers and directions, LLM runs only.
    t = build("temperature", StudyOptions(runs=1))
    assert {p.temperature for p in t} == {0.0, 0.25, 0.5, 0.75, 1.0} and {
        p.direction for p in t
    } == {1, -1}
    assert {p.swimmer for p in t} == {"purcell", "ng"} and {p.agent for p in t} == {"llm"}
    for bad in (
        {"temperatures": (0.0, 3.0)},
        {"temperatures": (0.5, 0.5)},
        {"prompt_files": ("x/a.txt", "y/a.txt")},
    ):
        with pytest.raises(ConfigError):
            StudyOptions(**bad)


def test_study_temperature_runs_end_to_end_and_temperatures_extend_the_folder(tmp_path, capsys):
    with FakeServer(reply=hash_reply) as srv:
        base = [
            "study",
            "temperature",
            *FAST,
            "--direction",
            "+x",
            "--out",
            str(tmp_path / "t"),
            "--base-url",
            srv.url,
            "--model",
            "fake",
        ]
        assert cli.main([*base, "--temperatures", "0,0.5"]) == 0
        first = {b.get("temperature") for b in srv.requests}
        seeds = [b.get("seed") for b in srv.requests if b.get("temperature") == 0.5]
        n_before = srv.n_requests
        assert (
            cli.main([*base, "--temperatures", "0,0.5,1"]) == 0
        )  # one more level: only its runs run
        added = srv.requests[n_before:]
    assert first == {0.0, 0.5} and {b["temperature"] for b in added} == {1.0} and len(added) == 4
    assert (
        len(seeds) == 4 and len(set(seeds)) == 4 and None not in seeds
    )  # T > 0: a seed per request
    rows = read_runs(tmp_path / "t")
    assert sorted(r["temperature"] for r in rows) == [0.0, 0.5, 1.0]
    assert {g["group"] for g in read_metadata(tmp_path / "t")["summary"]["groups"]} == {
        "T=0",
        "T=0.5",
        "T=1",
    }
    assert "T=1" in capsys.readouterr().out


def test_prompt_files_extend_a_folder(tmp_path):
    a, b = tmp_path / "short.txt", tmp_path / "long.txt"
    a.write_text("{S1} {S2} {S3} {S5}")
    b.write_text("{S1} {S2} {S3} {S4} {S5}")
    with FakeServer(reply=hash_reply) as srv:
        base = [
            "swim",
            *FAST,
            "--q-runs",
            "0",
            "--out",
            str(tmp_path / "o"),
            "--base-url",
            srv.url,
            "--model",
            "fake",
        ]
        with pytest.raises(SystemExit) as stop:  # swim takes no study axes: a usage error, exit 2
            cli.main([*base, "--prompt-files", str(a)])
        assert stop.value.code == 2
        assert cli.main(["study", "curves", *base[1:], "--prompt-files", str(a)]) == 0
        n = srv.n_requests
        assert cli.main(["study", "curves", *base[1:], "--prompt-files", f"{a},{b}"]) == 0
        later = srv.requests[n:]
    assert len(later) == 4 and all("long-term consequences" in str(r["messages"]) for r in later)
    groups = {r["group"] for r in read_runs(tmp_path / "o")}
    assert groups == {"prompt=short", "prompt=long"}


def test_samples_repeat_the_very_setting_each_with_its_own_id_and_seed():
    plans = build(
        "curves", StudyOptions(runs=2, q_runs=2, swimmers=("purcell",), init="cycle", samples=3)
    )
    llm = [p for p in plans if p.agent == "llm"]
    assert len(llm) == 6 and len({p.run_id for p in llm}) == 6 and len({p.seed for p in llm}) == 6
    by_run = {}
    for p in llm:
        by_run.setdefault(p.run_id.split("-sample")[0], []).append(p)
    # Each run's samples share its start (cycle: repeats 0 and 1 start from different corners).
    assert sorted(len(v) for v in by_run.values()) == [3, 3]
    assert all(len({p.init for p in v}) == 1 for v in by_run.values())
    assert len({v[0].init for v in by_run.values()}) == 2
    assert sorted(p.sample for p in llm) == [0, 0, 1, 1, 2, 2]
    # Sample 0 keeps the id the run had before --samples existed (a folder extends).
    one = {
        p.run_id
        for p in build(
            "curves", StudyOptions(runs=2, q_runs=2, swimmers=("purcell",), init="cycle")
        )
    }
    assert one <= {p.run_id for p in plans}
    assert sum(p.agent != "llm" for p in plans) == 4  # baselines: --q-runs, not sampled
    with pytest.raises(ConfigError, match="--samples"):
        StudyOptions(samples=0)


def test_samples_extend_a_folder_resume_and_pool_into_the_row(tmp_path, capsys):
    out = tmp_path / "s"
    with FakeServer(reply=hash_reply) as srv:
        base = [
            "study",
            "curves",
            *FAST,
            "--q-runs",
            "0",
            "--direction",
            "+x",
            "--temperature",
            "0.7",
            "--out",
            str(out),
            "--base-url",
            srv.url,
            "--model",
            "fake",
        ]
        assert cli.main(base) == 0
        n1 = srv.n_requests
        assert (
            cli.main([*base, "--samples", "3"]) == 0
        )  # two more samples of the one run: only theirs run
        added = srv.requests[n1:]
        n3 = srv.n_requests
        capsys.readouterr()
        assert cli.main([*base, "--samples", "3"]) == 0  # nothing left to do: no call
        again = capsys.readouterr()
        assert srv.n_requests == n3
    assert n1 == 4 and len(added) == 8
    seeds = [b["seed"] for b in srv.requests]
    assert len(set(seeds)) == len(seeds) == 12  # T > 0: every sample's every request its own seed
    meta = read_metadata(out)
    assert meta["grid"]["samples"] == 3 and meta["n_planned"] == 3
    (group,) = meta["summary"]["groups"]
    assert group["n"] == 3 and group["samples"] == 3
    assert sorted(r["sample"] for r in read_runs(out)) == [0, 1, 2]
    assert "3 runs already done" in again.err
    # A resume that ran nothing says so, never the earlier session's calls as this session's.
    assert "LLM calls: none this session" in again.out and "sent, 0 replayed" not in again.out
    assert cli.main(["show", str(out)]) == 0
    shown = capsys.readouterr().out
    header = next(ln for ln in shown.splitlines() if "samples" in ln and "success" in ln)
    row = next(ln for ln in shown.splitlines() if ln.startswith("llm"))
    cells = dict(zip(header.split(), row.split()))
    assert cells["samples"] == "3" and cells["n"] == "3"


def test_prompt_files_are_known_by_their_bytes(tmp_path, capsys):
    import json

    a = tmp_path / "short.txt"
    a.write_text("{S1} {S2} {S3} {S5}")
    out = tmp_path / "o"
    with FakeServer(reply=hash_reply) as srv:

        def study(path, *more):
            return cli.main(
                [
                    "study",
                    "curves",
                    *FAST,
                    "--q-runs",
                    "0",
                    "--direction",
                    "+x",
                    "--out",
                    str(out),
                    "--base-url",
                    srv.url,
                    "--model",
                    "fake",
                    "--prompt-files",
                    str(path),
                    *more,
                ]
            )

        assert study(a) == 0
        meta = read_metadata(out)
        rec = meta["prompt_files"]["short"]
        assert rec["file"] == "short.txt" and len(rec["sha256"]) == 16
        n = srv.n_requests
        capsys.readouterr()
        # The same bytes under the same name elsewhere: the same setting, resumed (no call).
        same = tmp_path / "copy" / "short.txt"
        same.parent.mkdir()
        same.write_bytes(a.read_bytes())
        assert study(same) == 0 and srv.n_requests == n
        # An edited file, or another file of that name: refused in one line before anything runs.
        a.write_text("{S1} {S2} {S3} {S4} {S5}")
        other = tmp_path / "other" / "short.txt"
        other.parent.mkdir()
        other.write_text("{S3} {S5}")
        for path in (a, other):
            capsys.readouterr()
            assert study(path) == 2
            err = [ln for ln in capsys.readouterr().err.strip().splitlines() if "warning" not in ln]
            assert (
                len(err) == 1
                and "prompt=short made with another text" in err[0]
                and rec["sha256"] in err[0]
            )
            assert "rename the file" in err[0] and "Traceback" not in err[0]
            assert study(path, "--dry-run") == 2  # the dry run refuses alike
        assert srv.n_requests == n and read_metadata(out)["n_planned"] == meta["n_planned"]
        assert read_metadata(out)["status"] == "complete"
        # Renamed: a new setting in the same folder.
        renamed = tmp_path / "short2.txt"
        renamed.write_bytes(a.read_bytes())
        assert study(f"{same},{renamed}") == 0 and srv.n_requests == n + 4
        assert set(read_metadata(out)["prompt_files"]) == {"short", "short2"}
        # A folder made before the records resumes (its file trusted by name) and records it then.
        m = json.loads((out / "metadata.json").read_text())
        del m["prompt_files"]
        (out / "metadata.json").write_text(json.dumps(m))
        assert study(a) == 0 and srv.n_requests == n + 4
        assert read_metadata(out)["prompt_files"]["short"]["sha256"] != rec["sha256"]
    assert {r["group"] for r in read_runs(out)} == {"prompt=short", "prompt=short2"}


def test_swim_takes_samples_too():
    from jswim import cli as c
    from jswim.cli.options import options

    args = c.build_parser().parse_args(["swim", "--samples", "3", "--runs", "2"])
    plans = build("swim", options(args, "swim"))
    assert sum(p.agent == "llm" for p in plans) == 6
