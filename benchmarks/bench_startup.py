"""Start-up of the ``jswim`` command, before and after the persistent compilation cache, in one run.

Each number is the median wall time of fresh ``jswim`` processes (what a user waits for):

* ``jswim --help``;
* ``jswim swim --runs 1 --steps 12 --q-runs 0`` against a fake server that answers at once, so
  the time is jswim's own (imports, the step table, compilation, 12 LLM steps):
  - *before*: ``JSWIM_COMPILATION_CACHE=0``, every process compiles (what every run paid before);
  - *after, warm*: the cache filled by one earlier process (the second and later runs a user makes).

The cache goes into a fresh folder (``XDG_CACHE_HOME`` in a temporary directory), so the run
starts from nothing and leaves nothing behind. On a shared machine the load moves every number:
the script prints the load average next to them.

Usage: ``python benchmarks/bench_startup.py [--repeats 3] [--json out.json]``
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from tests.fakeserver import FakeServer, hash_reply  # noqa: E402


def timed(cmd: list[str], env: dict[str, str]) -> float:
    t0 = time.perf_counter()
    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({r.returncode}): {r.stderr.strip()[-400:]}")
    return wall


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3, help="processes per measurement (median)")
    ap.add_argument("--json", default=None, help="also write the numbers here")
    args = ap.parse_args()
    jswim = [sys.executable, "-m", "jswim.cli"]
    out: dict[str, float] = {}
    with tempfile.TemporaryDirectory() as tmp, FakeServer(reply=hash_reply) as srv:
        env = {**os.environ, "XDG_CACHE_HOME": str(Path(tmp) / "cache"), "PYTHONWARNINGS": "ignore"}
        env.pop("JAX_COMPILATION_CACHE_DIR", None)

        def swim(i: int, **extra: str) -> float:
            cmd = [*jswim, "swim", "--runs", "1", "--steps", "12", "--q-runs", "0", "--no-figures",
                   "--base-url", srv.url, "--model", "fake", "--api-key-env", "", "--out", f"{tmp}/run{i}"]
            return timed(cmd, {**env, **extra})

        out["help_s"] = statistics.median(timed([*jswim, "--help"], env) for _ in range(args.repeats))
        out["swim_before_s"] = statistics.median(swim(i, JSWIM_COMPILATION_CACHE="0") for i in range(args.repeats))
        out["swim_first_s"] = swim(100)  # fills the cache
        out["swim_warm_s"] = statistics.median(swim(200 + i) for i in range(args.repeats))
    out["load_average_1min"] = os.getloadavg()[0]
    out["cpus"] = os.cpu_count() or 0
    print(f"load average {out['load_average_1min']:.1f} on {out['cpus']} CPUs; median of {args.repeats} processes")
    print(f"jswim --help                                  {out['help_s']:6.2f} s")
    print(f"jswim swim --runs 1 --steps 12 (before, no cache) {out['swim_before_s']:6.2f} s")
    print(f"jswim swim ... first run (fills the cache)    {out['swim_first_s']:6.2f} s")
    print(f"jswim swim ... warm cache (after)             {out['swim_warm_s']:6.2f} s  "
          f"({out['swim_before_s'] / out['swim_warm_s']:.2f}x faster)")
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    main()
