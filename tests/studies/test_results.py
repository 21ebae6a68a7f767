"""Study folders: atomic files, torn-line recovery, identity checks."""

import json
import math
import os
import stat

import numpy as np
import pytest

import pandas as pd

from jswim import results
from jswim.errors import JswimError, ResultFolderError
from jswim.results import (
    StudyFolderError,
    StudyStore,
    atomic_write,
    load,
    read_metadata,
    read_runs,
)
from jswim.judging.stats import learn_stats, mean_interval, wilson_interval


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
    with pytest.raises(ResultFolderError, match="zetas"):
        StudyStore(tmp_path / "s", "noise", {"zetas": [0, 2]})
    with pytest.raises(ResultFolderError, match="'noise' study"):
        StudyStore(tmp_path / "s", "ablation", {"zetas": [0, 1]})
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "notes.txt").write_text("mine")
    with pytest.raises(ResultFolderError, match="not empty"):
        StudyStore(tmp_path / "other", "noise", {})
    StudyStore(tmp_path / "s", "noise", {"zetas": [0, 1]})  # same settings: resumes


def test_atomic_write_leaves_no_temporary_files(tmp_path):
    atomic_write(tmp_path / "f.txt", "one")
    atomic_write(tmp_path / "f.txt", "two")
    assert (tmp_path / "f.txt").read_text() == "two"
    assert [p.name for p in tmp_path.iterdir()] == ["f.txt"]


def test_finalize_writes_tables(tmp_path):
    store = StudyStore(tmp_path / "s", "curves", {})
    store.add_runs(
        [
            {
                "run_id": "a",
                "agent": "llm",
                "x": [0.1, 0.2],
                "actions": [[1, 1], [2, -1]],
                "progress": [0.1, 0.1],
                "stuck": [False, False],
            }
        ]
    )
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


def test_wilson_interval_holds_p_at_every_n_exactly_at_the_ends():
    # All of k = 0 and k = n: [0, x] and [x, 1] exactly (rounding put hi at 1 - 1.1e-16 for
    # 6 of 6, and lo at 2.8e-17 for 0 of 11: a leaderboard's error bar came out negative).
    for n in range(1, 201):
        assert wilson_interval(0, n)[0] == 0.0 and wilson_interval(n, n)[1] == 1.0
        for k in range(n + 1):
            lo, hi = wilson_interval(k, n)
            assert 0.0 <= lo <= k / n <= hi <= 1.0


def test_mean_interval_covers_the_mean():
    m, lo, hi = mean_interval([1.0, 2.0, 3.0, 4.0])
    assert m == 2.5 and lo < m < hi
    assert mean_interval([7.0]) == (7.0, 7.0, 7.0)


def test_folder_written_with_old_field_names_resumes_and_reads_under_new_names(tmp_path):
    # A folder from before the rename allowed -> action_set: identity, rows and metadata.
    folder = tmp_path / "old"
    folder.mkdir()
    meta = {
        "study": "swim",
        "status": "complete",
        "identity": {"study": "swim", "options": {"allowed": "all", "steps": 6}, "seed": 0},
    }
    (folder / "metadata.json").write_text(json.dumps(meta))
    (folder / "runs.jsonl").write_text(
        json.dumps({"run_id": "a", "allowed": "shape-changing"}) + "\n"
    )
    new_identity = {"study": "swim", "options": {"action_set": "all", "steps": 6}, "seed": 0}
    store = StudyStore(folder, "swim", new_identity)  # resumes: same settings under new names
    assert store.done_ids() == {"a"}
    assert (
        read_runs(folder)[0]["action_set"] == "shape-changing"
        and "allowed" not in read_runs(folder)[0]
    )
    assert read_metadata(folder)["identity"] == new_identity
    store.close()  # the session ends: its lock goes
    with pytest.raises(ResultFolderError, match="options"):  # a real difference is still refused
        StudyStore(
            folder,
            "swim",
            {**new_identity, "options": {"action_set": "shape-changing", "steps": 6}},
        )


def test_load_returns_the_runs_as_a_dataframe(tmp_path):
    store = StudyStore(tmp_path / "s", "curves", {})
    store.add_runs(
        [
            {"run_id": "a", "agent": "llm", "success": True},
            {"run_id": "b", "agent": "random", "success": False},
        ]
    )
    df = load(tmp_path / "s").runs
    assert (
        isinstance(df, pd.DataFrame)
        and list(df["run_id"]) == ["a", "b"]
        and df["success"].sum() == 1
    )
    with pytest.raises(JswimError, match="not a jswim study folder"):
        load(tmp_path)


def test_learn_stats_counts_never_learned_runs_instead_of_inventing_steps():
    # 3 of 5 learned at 4, 10 and 40 steps: the median is over those (10), not over 5 values
    # with two +inf (which would give 40) nor a silent 3-row median with no count.
    ls = learn_stats([4, None, 10, -1, 40])
    assert (ls.n, ls.learned, ls.median) == (5, 3, 10.0)
    assert ls.q25 == 7.0 and ls.q75 == 25.0  # linear interpolation between 4, 10, 40
    assert ls.label() == "10 [7-25], 3 of 5 learned"
    none = learn_stats([None, None])
    assert none.learned == 0 and math.isnan(none.median) and none.label() == "0 of 2 learned"


def test_every_file_gets_the_same_mode(tmp_path):
    store = StudyStore(tmp_path / "s", "noise", {})
    store.add_runs(
        [{"run_id": "a", "x": [0.1], "actions": [[1, 1]], "progress": [0.1], "stuck": [False]}]
    )
    store.finalize()
    modes = {
        p.name: stat.S_IMODE(p.stat().st_mode) for p in (tmp_path / "s").iterdir() if p.is_file()
    }
    assert {
        "metadata.json",
        "runs.jsonl",
        "runs.csv",
        "runs.parquet",
        "trajectories.parquet",
    } <= set(modes)
    assert set(modes.values()) == {results.FILE_MODE}, modes


@pytest.mark.parametrize(
    "umask, files, folders",
    [
        (
            0o022,
            0o600,
            0o700,
        ),  # the usual umask, nobody's choice: the owner alone (was 0644 before)
        (0o027, 0o600, 0o700),  # stricter: still the owner alone
        (0o002, 0o664, 0o775),  # lets the group write: a shared-group setup, honoured
        (0o007, 0o660, 0o770),
    ],
)
def test_study_folders_are_the_owner_s_unless_the_umask_shares_with_a_group(
    umask, files, folders, tmp_path
):
    from jswim._io.permissions import file_mode

    from jswim.studies import StudyOptions, run_study

    old = os.umask(umask)
    try:
        run_study(
            "noise",
            StudyOptions(agents=("random",), q_runs=2, zetas=(0.0,), steps=4),
            backend=None,
            out=tmp_path / "s",
        )
        assert os.umask(umask) == umask  # run_study set the process's umask back
    finally:
        os.umask(old)
    assert file_mode(umask) == files
    paths = [tmp_path / "s", *(tmp_path / "s").rglob("*")]
    assert {stat.S_IMODE(p.stat().st_mode) for p in paths if p.is_file()} == {files}
    assert {stat.S_IMODE(p.stat().st_mode) for p in paths if p.is_dir()} == {folders}


def test_a_rewritten_file_keeps_its_mode(tmp_path):
    atomic_write(tmp_path / "f", "one")
    os.chmod(tmp_path / "f", 0o640)
    atomic_write(tmp_path / "f", "two")
    assert stat.S_IMODE((tmp_path / "f").stat().st_mode) == 0o640


def test_json_files_are_strict_json(tmp_path):
    store = StudyStore(tmp_path / "s", "noise", {"zetas": [0.0, float("nan")]})
    store.add_runs(
        [
            {
                "run_id": "a",
                "final_x": float("nan"),
                "x": [float("inf"), np.float64("nan"), 1.0],
                "n": np.int64(3),
            }
        ]
    )
    store.finalize(summary={"median": float("nan"), "rows": [{"mean": float("-inf")}]})
    for name in ("metadata.json", "runs.jsonl"):
        text = (tmp_path / "s" / name).read_text()
        assert "NaN" not in text and "Infinity" not in text
        for chunk in [text] if name.endswith(".json") else text.splitlines():
            json.loads(chunk, parse_constant=lambda c: pytest.fail(f"{name} has {c}"))
    meta = read_metadata(tmp_path / "s")
    assert meta["summary"] == {"median": None, "rows": [{"mean": None}]}
    assert read_runs(tmp_path / "s")[0]["x"] == [None, None, 1.0]
    store.close()
    StudyStore(tmp_path / "s", "noise", {"zetas": [0.0, float("nan")]})  # still resumes


@pytest.mark.parametrize("how", ["read-only", "under-a-file"])
def test_a_folder_that_cannot_be_written_is_one_line_error(tmp_path, how):
    # A read-only parent stops everyone but root; a parent that is a file stops root too (CI runs
    # as root), so the second case always runs and the first wherever it means something.
    if how == "read-only" and os.geteuid() == 0:
        pytest.skip("root writes into read-only folders; the under-a-file case covers root")
    parent = tmp_path / "ro"
    if how == "read-only":
        parent.mkdir()
        parent.chmod(0o555)
        cause = "Permission denied"
    else:
        parent.write_text("a file, not a folder")
        cause = "Not a directory"
    try:
        with pytest.raises(StudyFolderError) as err:
            StudyStore(parent / "study", "noise", {})
        msg = str(err.value)
        assert "\n" not in msg and str(parent / "study") in msg and cause in msg and "--out" in msg
    finally:
        if parent.is_dir():
            parent.chmod(0o755)


def test_a_folder_that_stops_being_writable_is_one_line_error(tmp_path):
    folder = tmp_path / "s"
    store = StudyStore(folder, "noise", {})
    # The folder replaced by a file (a path no one, root included, can write into).
    folder.rename(tmp_path / "moved")
    folder.write_text("not a folder any more")
    with pytest.raises(StudyFolderError, match="cannot write") as err:
        store.add_runs([{"run_id": "a"}])
    assert "\n" not in str(err.value)
    with pytest.raises(StudyFolderError, match="cannot write"):
        store.set_status("interrupted")


def test_set_status_records_the_status(tmp_path):
    store = StudyStore(tmp_path / "s", "noise", {})
    assert read_metadata(tmp_path / "s")["status"] == "running"
    store.set_status("interrupted", n_runs=0)
    meta = read_metadata(tmp_path / "s")
    assert meta["status"] == "interrupted" and meta["n_runs"] == 0


def test_unwritable_paths_are_one_line_errors(tmp_path, monkeypatch):
    (tmp_path / "file").write_text("x")
    with pytest.raises(StudyFolderError, match="cannot write") as err:
        StudyStore(tmp_path / "file" / "study", "noise", {})  # a file where a folder should be
    assert "\n" not in str(err.value)

    def refuse(src, dst):
        raise PermissionError(13, "Permission denied", str(dst))

    store = StudyStore(tmp_path / "s", "noise", {})
    monkeypatch.setattr(os, "replace", refuse)  # a read-only folder, as root sees it too
    with pytest.raises(StudyFolderError) as err:
        store.finalize()
    assert str(err.value).startswith(
        f"cannot write {tmp_path / 's'}"
    ) and "Permission denied" in str(err.value)
    assert not [p for p in (tmp_path / "s").iterdir() if p.name.endswith(".tmp")]


@pytest.mark.parametrize(
    "rows",
    [
        [
            {"run_id": "a", "n": 1, "x": 0.5, "ok": True, "note": None, "mixed": 1},
            {"run_id": "b", "n": 2, "x": None, "ok": False, "note": None, "mixed": 2.25},
        ],
        [
            {"run_id": "a", "late": None, "n": None},
            {"run_id": "b", "late": "text", "n": 3},
        ],  # values first seen late
        [{"run_id": "a", "odd": [1, 2]}],  # not a scalar column: pyarrow's own conversion
    ],
)
def test_tables_are_typed_as_pyarrow_s_own_conversion_types_them(rows):
    import pyarrow as pa

    ours, theirs = results.arrow_table(rows), pa.Table.from_pylist(rows)
    assert ours.schema == theirs.schema
    assert ours.to_pylist() == theirs.to_pylist()
    assert results.arrow_table([]).num_rows == 0


def test_writing_a_study_s_tables_does_not_import_pandas(tmp_path):
    # pyarrow imports pandas (~0.4 s) on any conversion from Python objects; the session's end
    # must not pay it (start-up stays light). A fresh interpreter, so nothing is loaded yet.
    import subprocess
    import sys

    code = (
        "import sys; from jswim import results; "
        f"results.write_tables({str(tmp_path)!r}, [{{'run_id': 'r', 'agent': 'llm', 'x': [0.1, 0.2], 'success': True}}]); "
        "print('pandas' in sys.modules); "
        "import pyarrow.parquet as pq; "  # reading a table back imports pandas itself
        f"assert pq.read_table({str(tmp_path / 'trajectories.parquet')!r}).num_rows == 2"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True
    ).stdout
    assert out.strip() == "False"
