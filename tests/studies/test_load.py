"""jswim.load: a study folder as pandas DataFrames (runs; trajectories with x, y, orientation)."""

from __future__ import annotations

import numpy as np
import pytest

from jswim.results import load, read_runs


@pytest.fixture(scope="module")
def folders(small_swim_study):
    return (
        small_swim_study,
    )  # Purcell and NG toward +x and -x, 8 steps; 1 + 3 + 3 runs per setting


def _snapshot(folder):
    return sorted((str(p), p.stat().st_mtime_ns, p.stat().st_size) for p in folder.rglob("*"))


def test_load_returns_runs_and_trajectories(folders):
    (a,) = folders
    before = _snapshot(a)
    s = load(a)
    assert _snapshot(a) == before  # read-only
    runs = read_runs(a)
    assert (
        len(s.runs) == len(runs) == 2 * 2 * (1 + 3 + 3)
        and s.name == "swim"
        and s.status == "complete"
    )
    assert {"run_id", "agent", "swimmer", "direction", "success", "signed_final_x"} <= set(
        s.runs.columns
    )
    t = s.trajectories
    assert len(t) == len(runs) * 8
    assert {"x", "y", "orientation", "target_x", "dof", "roc", "step"} <= set(t.columns)
    one = runs[0]
    rows = t[t.run_id == one["run_id"]].sort_values("step")
    assert rows.step.tolist() == list(range(1, 9))
    assert np.allclose(rows.x, one["x"]) and np.allclose(
        rows.target_x, one["direction"] * np.asarray(one["x"])
    )
    assert rows.dof.tolist() == [a[0] for a in one["actions"]]
    # y and orientation are recorded for every agent: replaying a run's actions through the
    # noiseless environment gives the same pose at every step
    from jswim import env

    for r in [
        next(r for r in runs if r["agent"] == a and r["swimmer"] == "purcell")
        for a in ("llm", "qlearning", "random")
    ]:
        tr = t[t.run_id == r["run_id"]].sort_values("step")
        ref = env.rollout_moves(
            "purcell",
            r["actions"],
            init=[int(c == "+") for c in r["init"]],
            direction=r["direction"],
        )
        assert np.allclose(tr.x, ref.x, atol=1e-9) and np.allclose(tr.y, ref.y, atol=1e-9)
        assert np.allclose(tr.orientation, ref.orientation, atol=1e-9)
    assert t[t.swimmer == "purcell"].orientation.abs().max() > 0.1  # the body turns within a stroke
    assert (t[t.swimmer == "ng"][["y", "orientation"]] == 0).all().all()  # spheres on a line
    import pyarrow.parquet as pq

    written = pq.read_table(a / "trajectories.parquet").to_pandas()
    assert {"y", "orientation"} <= set(written.columns) and written.orientation.notna().all()
    # the final target-direction displacement of every run matches its summary field
    last = t[t.step == 8].set_index("run_id").target_x
    assert np.allclose(last.loc[s.runs.run_id].to_numpy(), s.runs.signed_final_x.to_numpy())
