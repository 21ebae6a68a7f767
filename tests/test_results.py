"""Study folders: atomic files, torn-line recovery, identity checks."""

import json

import pytest

from jswim.errors import ConfigError
from jswim.results import StudyStore, atomic_write, read_runs
from jswim.stats import mean_interval, wilson_interval


def test_torn_last_line_is_dropped_and_repaired(tmp_path):
    store = StudyStore(tmp_path / "s", "noise", {"a": 1})
    store.add_runs([{"run_id": "r1", "x": [0.1]}, {"run_id": "r2", "x": [0.2]}])
    with open(tmp_path / "s" / "runs.jsonl", "a") as fh:
        fh.write('{"run_id": "r3", "x": [0.')  # a kill in the middle of a write
    assert [r["run_id"] for r in read_runs(tmp_path / "s")] == ["r1", "r2"]
    store.add_runs([{"run_id": "r3", "x": [0.3]}, {"run_id": "r1", "x": [9.9]}])
    runs = read_runs(tmp_path / "s")
    assert [r["run_id"] for r in runs] == ["r1", "r2", "r3"]
    assert runs[0]["x"] == [0.1]  # a duplicate never replaces the first record
    lines = (tmp_path / "s" / "runs.jsonl").read_text().splitlines()
    assert all(json.loads(line) for line in lines)


def test_identity_mismatch_and_foreign_folders_are_refused(tmp_path):
    StudyStore(tmp_path / "s", "noise", {"zetas": [0, 1]})
    with pytest.raises(ConfigError, match="zetas"):
        StudyStore(tmp_path / "s", "noise", {"zetas": [0, 2]})
    with pytest.raises(ConfigError, match="'noise' study"):
        StudyStore(tmp_path / "s", "ablation", {"zetas": [0, 1]})
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("mine")
    with pytest.raises(ConfigError, match="not empty"):
        StudyStore(tmp_path / "other", "noise", {})
    StudyStore(tmp_path / "s", "noise", {"zetas": [0, 1]})  # same settings: resumes


def test_atomic_write_leaves_no_temporary_files(tmp_path):
    atomic_write(tmp_path / "f.txt", "one")
    atomic_write(tmp_path / "f.txt", "two")
    assert (tmp_path / "f.txt").read_text() == "two"
    assert [p.name for p in tmp_path.iterdir()] == ["f.txt"]


def test_finalize_writes_tables(tmp_path):
    store = StudyStore(tmp_path / "s", "curves", {})
    store.add_runs([{"run_id": "a", "agent": "llm", "x": [0.1, 0.2], "actions": [[1, 1], [2, -1]],
                     "progress": [0.1, 0.1], "stuck": [False, False]}])
    store.finalize()
    assert (tmp_path / "s" / "runs.csv").read_text().splitlines()[0] == "run_id,agent"
    import pyarrow.parquet as pq

    t = pq.read_table(tmp_path / "s" / "trajectories.parquet").to_pylist()
    assert [r["step"] for r in t] == [1, 2] and t[1]["action"] == "[2, -1]"


def test_wilson_interval_known_values():
    # 0 of 10: the interval is [0, 0.2775] (Wilson, z = 1.96).
    lo, hi = wilson_interval(0, 10)
    assert lo == 0.0 and hi == pytest.approx(0.2775, abs=1e-4)
    lo, hi = wilson_interval(5, 10)
    assert lo == pytest.approx(0.2366, abs=1e-4) and hi == pytest.approx(0.7634, abs=1e-4)


def test_mean_interval_covers_the_mean():
    m, lo, hi = mean_interval([1.0, 2.0, 3.0, 4.0])
    assert m == 2.5 and lo < m < hi
    assert mean_interval([7.0]) == (7.0, 7.0, 7.0)
