"""The paper's numbers, kept through refactors: reference arrays and study rows recorded once.

Every array a baseline makes on the paper's swimmers (Q-learning, the random policy, PPO, fixed
strokes; noise, both directions, ROC lattices K = 1 and 2) and every row and transcript of small
studies (LLM runs against the fake server, Q-learning, random, PPO, the stroke on a wall) were
recorded with the code before the learners' entry points were merged (``tests/data/reference/``,
written by ``python -m tests.agents.test_reference_arrays record``). The test computes them again
through today's entry points and asks for the same numbers. The wall study's rows were recorded
again when the scenes' default self-mobility became the exact one (docs/scenes.md says by how
much they moved); the code was otherwise the same.

On the machine that recorded them the arrays are bit-identical (the comparison is exact there).
Another CPU rounds differently in the last bit (docs/performance.md: the bulk swimmer's x was 1 ulp
off on an AMD EPYC; an Intel Xeon with AVX-512 builds the step tables a bit apart), and a run
carries that bit along: a coordinate that crosses zero keeps the absolute error of the numbers
around it (a billion ulp of a value of 1e-17), and PPO's training grows it to ~1e-13 of the
array's scale in 40 updates. So floats are compared to `REL_TOL` of each array's largest value
(of the value itself, at least 1, in study rows), or 8 ulp of it where the dtype is coarser: a
change to the physics or the learners moves them by far more. Integer arrays (actions, starts,
the verdicts), row columns that are not floats, and the transcripts' text are compared exactly.
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path
from typing import Any

import jax
import numpy as np
import pytest

import jswim
from jswim import env
from jswim.agents import ppo, qlearning, random_policy
from jswim.env import make_params
from jswim.results.row import ENERGY

DATA = Path(__file__).resolve().parents[1] / "data" / "reference"
ARRAYS = DATA / "arrays.npz"
STUDIES = DATA / "studies.json"
MAX_ULP = 8
#: How far a float may move from its recorded value, relative to its array's scale.
REL_TOL = 1e-12

pytestmark = pytest.mark.slow


def _keys(n: int, seed: int = 0) -> jax.Array:
    return jax.random.split(jax.random.PRNGKey(seed), n)


def _paper_batch(swimmer: str, n: int, roc_levels: int = 1) -> Any:
    """``n`` learners: both directions, noise 0 and 0.5, a corner start and a random one."""
    base = make_params(swimmer, **({} if roc_levels == 1 else {"roc_levels": roc_levels}))
    init = np.array([[1] * base.n_dof if i % 2 else [-1] * base.n_dof for i in range(n)], np.int32)
    return env.broadcast_params(
        base,
        n,
        zeta=np.array([0.0, 0.5] * (n // 2)),
        direction=np.array([1.0, 1.0, -1.0, -1.0] * (n // 4)),
        init=init,
    )


def compute_arrays() -> dict[str, np.ndarray]:
    """Every reference array, through the learners' entry points."""
    out: dict[str, np.ndarray] = {}

    def put(name: str, run: Any, fields: tuple[str, ...]) -> None:
        for f in fields:
            if getattr(run, f) is not None:  # y, orientation: recorded only when asked for
                out[f"{name}.{f}"] = np.asarray(getattr(run, f))

    q_fields = ("actions", "x", "explored", "q", "levels0", "y", "orientation")
    for swimmer, k in (("purcell", 1), ("ng", 1), ("purcell", 2)):
        params = _paper_batch(swimmer, 4, k)
        world = jswim.make(swimmer, **({} if k == 1 else {"roc_levels": k}))[0]
        cfg = qlearning.QConfig(steps=40)
        put(
            f"q.{swimmer}.K{k}",
            qlearning.train(world, params, _keys(4), cfg, pose=True),
            q_fields,
        )
        put(
            f"random.{swimmer}.K{k}",
            random_policy.run(world, params, _keys(4, 1), 40),
            ("actions", "x", "levels0", "y", "orientation"),
        )
    world, one = jswim.make("purcell", zeta=0.5, direction=-1)
    put(
        "q.one",
        qlearning.train(world, one, jax.random.PRNGKey(7), qlearning.QConfig(steps=30)),
        q_fields,
    )
    put(
        "q.shape-changing",
        qlearning.train(
            jswim.make("ng")[0],
            _paper_batch("ng", 4),
            _keys(4, 2),
            qlearning.QConfig(steps=30, action_set="shape-changing"),
        ),
        q_fields,
    )
    params = _paper_batch("purcell", 4)
    put(
        "ppo.purcell",
        ppo.train(jswim.make("purcell")[0], params, _keys(4, 3), ppo.PPOConfig(steps=32)),
        ("actions", "dof", "x", "dofs", "dofs0", "y", "orientation"),
    )
    # Fixed strokes: the square gait (and its time reverse) in the paper's world, through the one
    # rollout, noiseless and noisy.
    square = np.array([3, 0, 5, 2] * 5)  # D2 down, D1 down, D2 up, D1 up: the square from (+, +)
    for swimmer, zeta, direction in (("purcell", 0.0, 1), ("ng", 0.5, -1), ("purcell", 0.3, -1)):
        w, p = jswim.make(swimmer, zeta=zeta, direction=direction)
        tr = jswim.rollout(w, p, jax.random.PRNGKey(5), square)
        name = f"stroke.{swimmer}.z{zeta}.d{direction}"
        out[f"{name}.position"] = np.asarray(tr.obs.position)
        out[f"{name}.orientation"] = np.asarray(tr.obs.orientation)
        out[f"{name}.progress"] = np.asarray(tr.info.progress)
    return out


def _study_rows(tmp: Path) -> dict[str, Any]:
    """Rows and transcripts of small studies: LLM (fake server), Q-learning, random, PPO, stroke."""
    from jswim.studies.options import StudyOptions
    from jswim.studies.run import run_study
    from tests.fakeserver import FakeServer, hash_reply

    studies = {
        "noise": StudyOptions(
            swimmers=("purcell", "ng"),
            zetas=(0.0, 0.5),
            directions=(1, -1),
            runs=1,
            q_runs=2,
            steps=16,
            agents=("llm", "qlearning", "random"),
        ),
        "continuous": StudyOptions(
            swimmers=("purcell",),
            directions=(1,),
            roc_levels_grid=(1, 2),
            runs=1,
            q_runs=1,
            steps=16,
            agents=("llm", "qlearning", "random", "ppo"),
        ),
        "wall": StudyOptions(
            swimmers=("ng",),
            heights=(3.0,),
            directions=(1,),
            runs=1,
            q_runs=1,
            steps=12,
            agents=("stroke", "qlearning", "random"),
        ),
    }
    out: dict[str, Any] = {}
    with FakeServer(reply=hash_reply) as srv:
        for name, o in studies.items():
            folder = tmp / name
            run_study(name, o, backend=srv.backend(), out=folder)
            rows = [json.loads(line) for line in (folder / "runs.jsonl").read_text().splitlines()]
            transcripts = {
                p.name: [_stable(json.loads(line)) for line in p.read_text().splitlines()]
                for p in sorted((folder / "transcripts").glob("*.jsonl"))
            }
            out[name] = {
                "rows": sorted(rows, key=lambda r: r["run_id"]),
                "transcripts": transcripts,
            }
    return out


#: Transcript fields that differ between two sessions of the same study (the fake server's port,
#: the replies' timing).
VOLATILE = frozenset({"base_url", "latency_s", "wall_s", "elapsed_s", "started", "finished"})


def _stable(obj: Any) -> Any:
    """``obj`` without the :data:`VOLATILE` keys, at any depth."""
    if isinstance(obj, dict):
        return {k: _stable(v) for k, v in obj.items() if k not in VOLATILE}
    if isinstance(obj, list):
        return [_stable(v) for v in obj]
    return obj


def _same_float(a: float, b: float) -> bool:
    if a == b or (math.isnan(a) and math.isnan(b)):
        return True
    return abs(a - b) <= REL_TOL * max(abs(a), abs(b), 1.0)


#: Row columns added since the reference was recorded: new numbers, not changed ones (a
#: recorded row lacks them; every other column must stay as recorded).
ADDED = frozenset(ENERGY)


def _diff(path: str, got: Any, want: Any, found: list[str]) -> None:
    """Append to ``found`` where ``got`` differs from ``want`` (floats to `REL_TOL`)."""
    if isinstance(want, dict) and isinstance(got, dict):
        for k in sorted(set(want) | set(got)):
            if k in ADDED and k not in want:
                continue
            if k not in got or k not in want:
                found.append(f"{path}.{k}: only in {'recorded' if k in want else 'computed'}")
            else:
                _diff(f"{path}.{k}", got[k], want[k], found)
    elif isinstance(want, list) and isinstance(got, list):
        if len(want) != len(got):
            found.append(f"{path}: length {len(got)} != {len(want)}")
        for i, (g, w) in enumerate(zip(got, want)):
            _diff(f"{path}[{i}]", g, w, found)
    elif isinstance(want, float) and isinstance(got, (int, float)) and not isinstance(got, bool):
        if not _same_float(float(got), want):
            found.append(f"{path}: {got!r} != {want!r}")
    elif got != want:
        found.append(f"{path}: {str(got)[:80]!r} != {str(want)[:80]!r}")


def both_dtypes(compute: Any) -> dict[str, np.ndarray]:
    """``compute()`` in float64 (the suite's x64) and in float32 (users' default), names prefixed."""
    out = {f"f64.{k}": v for k, v in compute().items()}
    with jax.enable_x64(False):
        out.update({f"f32.{k}": v for k, v in compute().items()})
    return out


def test_reference_arrays_are_unchanged():
    want = dict(np.load(ARRAYS))
    got = both_dtypes(compute_arrays)
    assert sorted(got) == sorted(want)
    for name in sorted(want):
        g, w = got[name], want[name]
        assert g.dtype == w.dtype and g.shape == w.shape, name
        if np.issubdtype(w.dtype, np.floating):
            scale = max(float(np.max(np.abs(w), initial=0.0)), float(np.finfo(w.dtype).tiny))
            tol = max(REL_TOL, MAX_ULP * float(np.finfo(w.dtype).eps)) * scale
            worst = float(np.max(np.abs(g.astype(np.float64) - w), initial=0.0))
            assert worst <= tol, f"{name}: off by {worst:.3g} (> {tol:.3g}; scale {scale:.3g})"
        else:
            np.testing.assert_array_equal(g, w, err_msg=name)


def test_reference_study_rows_and_transcripts_are_unchanged(tmp_path):
    want = json.loads(STUDIES.read_text())
    got = json.loads(json.dumps(_study_rows(tmp_path)))
    found: list[str] = []
    _diff("", got, want, found)
    assert not found, "\n".join(found[:40])


def record(tmp: Path) -> None:
    """Write the reference files (run once, with the code whose numbers are the reference)."""
    DATA.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(ARRAYS, **both_dtypes(compute_arrays))
    STUDIES.write_text(json.dumps(_study_rows(tmp), indent=0, sort_keys=True) + "\n")


if __name__ == "__main__" and sys.argv[1:] == ["record"]:
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        record(Path(d))
