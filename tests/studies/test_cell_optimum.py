"""A navigation cell's optimum is one record: its ``optimal`` row. Every other row of the cell
reads its ``optimal_steps`` and ``time_ratio`` from it when a folder is read."""

from __future__ import annotations

import json

import pytest

from jswim.results import as_run_rows, read_runs
from jswim.results.optimum import with_cell_optimum
from jswim.results.row import RunRow
from jswim.results.store import StudyStore

T90 = json.dumps({"kind": "fixed", "distance": 3.0, "bearing": 90.0})
T0 = json.dumps({"kind": "fixed", "distance": 3.0, "bearing": 0.0})


def _rec(agent: str, steps: int | None, target: str = T90, **kw) -> dict:
    return {
        "run_id": f"{agent}-{target[-6:-1]}-{kw.get('init', '')}-{kw.get('seed', 0)}",
        "study": "navigate",
        "agent": agent,
        "swimmer": "purcell",
        "group": "g",
        "seed": kw.pop("seed", 0),
        "roc_levels": 2,
        "target": target,
        "reached": steps is not None,
        "success": steps is not None,
        "steps_to_target": steps,
        "optimal_steps": kw.pop("optimal_steps", None),
        "time_ratio": kw.pop("time_ratio", None),
        **kw,
    }


def test_every_row_of_a_cell_is_measured_against_its_optimal_row():
    rows = [
        _rec("controller", 150),
        _rec("llm", 180),
        _rec("random", None),
        _rec("optimal", 120, optimal_steps=120, time_ratio=1.0),
        _rec("zermelo", 58, zermelo_steps=57.5),
    ]
    got = {r["agent"]: r for r in with_cell_optimum(rows)}
    assert {r["optimal_steps"] for r in got.values()} == {120}
    assert got["controller"]["time_ratio"] == 1.25
    assert got["llm"]["time_ratio"] == 1.5
    assert got["random"]["time_ratio"] is None  # not reached: no ratio
    assert got["optimal"]["time_ratio"] == 1.0
    # Zermelo's point: his real-valued least time over the swimmer's
    assert got["zermelo"]["time_ratio"] == pytest.approx(57.5 / 120, abs=1e-6)
    # the same rule for typed rows, which stay typed
    typed = as_run_rows(rows)
    assert all(isinstance(r, RunRow) for r in typed)
    assert [r.time_ratio for r in typed] == [got[r.agent]["time_ratio"] for r in typed]


def test_cells_are_kept_apart_and_a_cell_without_an_optimal_row_keeps_its_own_columns():
    rows = [
        _rec("controller", 150),
        _rec("optimal", 100, optimal_steps=100),
        _rec("controller", 150, init="+-"),  # another start: another cell, no optimal row
        _rec("optimal", 90, target=T0, optimal_steps=90),
        _rec("llm", 99, target=T0),
        _rec("ppo", 120, target=T0, optimal_steps=77, time_ratio=9.9),  # stale: overridden
        {"run_id": "swim", "agent": "llm", "group": "s", "success": True},  # no target
    ]
    got = with_cell_optimum(rows)
    assert got[0]["time_ratio"] == 1.5
    assert got[2]["optimal_steps"] is None and got[2]["time_ratio"] is None
    assert got[4]["time_ratio"] == 1.1 and got[5]["optimal_steps"] == 90
    assert got[5]["time_ratio"] == pytest.approx(120 / 90, abs=1e-6)
    assert got[6] == rows[6]


def test_a_failed_optimal_row_or_one_that_found_no_way_gives_no_ratio():
    failed = _rec("optimal", None, status="aborted", error="boom")
    rows = [_rec("controller", 150, optimal_steps=140, time_ratio=1.07), failed]
    assert with_cell_optimum(rows)[0]["time_ratio"] == 1.07  # nothing to read: as stored
    none = _rec("optimal", None)  # the search found no way to the target
    got = with_cell_optimum([_rec("controller", 150), none])
    assert got[0]["optimal_steps"] is None and got[0]["time_ratio"] is None


def test_a_folder_reads_every_rows_ratio_from_the_optimal_row_written_last(tmp_path):
    with StudyStore(tmp_path / "f", "navigate", {"study": "navigate"}) as store:
        store.add_runs([_rec("controller", 150), _rec("llm", 200)])
        assert all(r["time_ratio"] is None for r in read_runs(tmp_path / "f"))
        store.add_runs([_rec("optimal", 100, optimal_steps=100)])
    got = {r["agent"]: r["time_ratio"] for r in read_runs(tmp_path / "f")}
    assert got == {"controller": 1.5, "llm": 2.0, "optimal": 1.0}
