"""The command end to end with a damaged flow table (issue 61): a small ``jswim study navigate
--flow shear`` whose cached ``flow-*.npz`` is cut to its first row exits 0, says so in one
``jswim: warning:`` line, gives the numbers of the run with a clean cache and writes the rebuilt
table back. The damage kinds one by one: tests/env/test_table_damage.py."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]

#: The smallest navigation study in a shear flow the command runs: one target distance and
#: bearing, no LLM run, one baseline run each trained for one episode.
ARGS = [
    *("study", "navigate", "--flow", "shear", "--flows", "0.5", "--runs", "0", "--q-runs", "1"),
    *("--train-episodes", "1", "--steps", "20", "--distances", "3", "--bearings", "90"),
    "--no-figures",
]


def _study(out: Path, cache: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "JSWIM_TABLE_CACHE": str(cache), "PYTHONPATH": str(ROOT)}
    return subprocess.run(
        [sys.executable, "-m", "jswim", *ARGS, "--out", str(out)],
        env=env,
        capture_output=True,
        text=True,
        timeout=900,
    )


def _rows(folder: Path) -> list[dict]:
    rows = [json.loads(line) for line in (folder / "runs.jsonl").read_text().splitlines()]
    return sorted(rows, key=lambda r: (r["group"], r["agent"], r["run_id"]))


def _notes(done: subprocess.CompletedProcess) -> list[str]:
    """The lines that mention a table (the command's other warnings: the short --steps)."""
    return [line for line in done.stderr.splitlines() if "table" in line]


def _table_lines(done: subprocess.CompletedProcess) -> list[str]:
    """The printed summary, less the wall time and the folder's name."""
    lines = done.stdout.split("results:")[0].splitlines()
    return [re.sub(r" in [0-9.]+ s$", "", line) for line in lines]


def _cut_to_first_row(path: Path) -> None:  # the damage, the entry's record kept
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files}
    arrays["rows"] = arrays["rows"][:1]
    path.unlink()
    with open(path, "wb") as fh:
        np.savez(fh, **arrays)


# slow: two small navigation studies in fresh processes (a minute or more each)
@pytest.mark.slow
def test_a_damaged_flow_table_does_not_change_the_study(tmp_path):
    cache = tmp_path / "tables"
    clean = _study(tmp_path / "clean", cache)
    assert clean.returncode == 0, clean.stderr[-2000:]
    assert not _notes(clean)
    entries = sorted(cache.glob("flow-*.npz"))
    assert entries
    for entry in entries:
        _cut_to_first_row(entry)

    damaged = _study(tmp_path / "damaged", cache)
    assert damaged.returncode == 0, damaged.stderr[-2000:]
    assert "Traceback" not in damaged.stderr
    notes = _notes(damaged)
    assert len(notes) == len(entries), damaged.stderr
    for note, entry in zip(sorted(notes), entries):
        assert note.startswith("jswim: warning: cached flow table ") and str(entry) in note
        assert "damaged ('rows' has shape (1, " in note and note.endswith("not used, rebuilt")
    assert _rows(tmp_path / "damaged") == _rows(tmp_path / "clean")
    assert _table_lines(damaged) == _table_lines(clean)
    for entry in entries:  # written back whole (a later run reads it in silence: the env tests)
        with np.load(entry) as data:
            assert data["rows"].shape[0] > 1
