"""The multi-host path (docs/performance.md, "Several hosts"): two local processes joined by
``jax.distributed`` on 127.0.0.1, CPU collectives over gloo, two forced host devices each (four
devices in one mesh), run the ensemble and the Q-learning sweep; the numbers equal one process's
with two devices, bit for bit (noise is counter-based, so the split over devices and hosts does
not enter)."""

import pickle
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

WORKER = Path(__file__).with_name("multihost_worker.py")
ROOT = Path(__file__).resolve().parents[2]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _equal(a, b) -> None:
    assert a.keys() == b.keys()
    for k in a:
        x, y = np.asarray(a[k]), np.asarray(b[k])
        assert x.dtype == y.dtype and x.shape == y.shape, k
        # bit for bit, NaN where NaN
        assert x.tobytes() == y.tobytes(), (k, x, y)


@pytest.mark.slow
def test_two_processes_give_one_process_numbers_bit_for_bit(tmp_path):
    env = {"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin", "JAX_PLATFORMS": "cpu"}
    single = tmp_path / "single.pkl"
    subprocess.run(
        [sys.executable, str(WORKER), str(single)], env=env, check=True, timeout=900, cwd=ROOT
    )
    port = _free_port()
    multi = tmp_path / "multi.pkl"
    procs = [
        subprocess.Popen(
            [sys.executable, str(WORKER), str(multi), str(port), str(i)],
            env=env,
            cwd=ROOT,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            text=True,
        )
        for i in range(2)
    ]
    try:
        logs = [p.communicate(timeout=900)[0] for p in procs]
    finally:
        for p in procs:
            p.kill()
    assert all(p.returncode == 0 for p in procs), "\n".join(log[-3000:] for log in logs)
    a, b = pickle.loads(single.read_bytes()), pickle.loads(multi.read_bytes())
    assert (a["processes"], a["devices"]) == (1, 2)
    assert (b["processes"], b["devices"]) == (2, 4)
    assert len(a["ensemble"]) == len(b["ensemble"]) == 2
    for x, y in zip(a["ensemble"], b["ensemble"], strict=True):
        _equal(x, y)
    assert len(a["qlearn"]) == len(b["qlearn"]) == 4  # two directions x two noise levels
    for x, y in zip(a["qlearn"], b["qlearn"], strict=True):
        _equal(x, y)
    # and the sweep learned something (the check is not of two empty tables)
    assert max(s["learned"] for s in a["qlearn"]) > 0.5
