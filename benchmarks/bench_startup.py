"""Start-up of the ``jswim`` command: the code before a change and after it, in one run.

Each number is the median wall time (and CPU time) of fresh ``jswim`` processes, what a user
waits for:

* ``jswim --help``;
* ``jswim swim --runs 1 --steps 12 --q-runs 0 --no-figures`` against a fake server that answers at
  once, so the time is jswim's own (imports, the step table, compilation, 12 LLM steps, the
  folder's files):
  - *no cache*: ``JSWIM_COMPILATION_CACHE=0``, every process compiles;
  - *warm*: the compilation cache filled by one earlier process (a user's second and later runs).

``--before DIR`` also measures the code checked out in ``DIR`` (``git worktree add DIR REV``) with
``--before-python`` (default: this interpreter; give the old virtual environment's to measure
its dependencies too), the two sides alternating so that a change in the machine's load hits
both alike. Python writes its bytecode cache as it does for users (this benchmark drops
``PYTHONDONTWRITEBYTECODE``), into the temporary folder, filled by one untimed import first. The
compilation, table and bytecode caches all go into a fresh temporary folder, so nothing is left
behind. On a shared machine the load moves every number: the load average is printed with them.

Usage: ``python benchmarks/bench_startup.py [--repeats 3] [--before DIR [--before-python PY]]
[--json out.json]``
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

from tests.fakeserver import FakeServer, hash_reply

ROOT = Path(__file__).resolve().parents[1]


def timed(cmd: list[str], env: dict[str, str], cwd: Path) -> tuple[float, float]:
    """Wall and CPU seconds (user + system) of one process."""
    before = os.times()
    t0 = time.perf_counter()
    r = subprocess.run(cmd, env=env, cwd=cwd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    after = os.times()
    if r.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({r.returncode}): {r.stderr.strip()[-400:]}")
    return wall, (after.children_user - before.children_user) + (
        after.children_system - before.children_system
    )


class Side:
    """One version of the code: its interpreter, source folder and caches."""

    def __init__(self, name: str, python: str, src: Path, tmp: Path, url: str) -> None:
        self.name, self.python, self.src, self.url = name, python, src, url
        self.tmp = tmp / name
        base = {
            k: v
            for k, v in os.environ.items()
            if k not in ("PYTHONDONTWRITEBYTECODE", "JAX_COMPILATION_CACHE_DIR")
        }
        self.env = {
            **base,
            "XDG_CACHE_HOME": str(self.tmp / "cache"),
            "PYTHONPYCACHEPREFIX": str(self.tmp / "pyc"),
            "PYTHONPATH": str(src),
            "PYTHONWARNINGS": "ignore",
        }
        self.n = 0
        self.times: dict[str, list[tuple[float, float]]] = {}

    def warm_bytecode(self) -> None:
        timed(
            [self.python, "-c", "import jax.numpy, jswim.cli, jswim.studies.run, jswim.agents.llm"],
            self.env,
            self.src,
        )

    def run(self, what: str, *args: str, **extra: str) -> None:
        self.n += 1
        if what == "help":
            cmd = [self.python, "-m", "jswim.cli", "--help"]
        else:
            cmd = [
                self.python,
                "-m",
                "jswim.cli",
                "swim",
                "--runs",
                "1",
                "--steps",
                "12",
                "--q-runs",
                "0",
                "--no-figures",
                "--base-url",
                self.url,
                "--model",
                "fake",
                "--api-key-env",
                "",
                "--out",
                str(self.tmp / f"run{self.n}"),
            ]
        self.times.setdefault(what, []).append(timed(cmd, {**self.env, **extra}, self.src))

    def median(self, what: str) -> tuple[float, float]:
        got = self.times[what]
        return statistics.median(w for w, _ in got), statistics.median(c for _, c in got)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3, help="processes per measurement (median)")
    ap.add_argument("--before", default=None, help="a checkout of the code before the change")
    ap.add_argument("--before-python", default=sys.executable, help="the interpreter for --before")
    ap.add_argument("--json", default=None, help="also write the numbers here")
    args = ap.parse_args()
    load0 = os.getloadavg()[0]
    with tempfile.TemporaryDirectory() as tmp, FakeServer(reply=hash_reply) as srv:
        sides = [Side("after", sys.executable, ROOT, Path(tmp), srv.url)]
        if args.before:
            sides.insert(
                0,
                Side("before", args.before_python, Path(args.before).resolve(), Path(tmp), srv.url),
            )
        for s in sides:
            s.warm_bytecode()
        plan = [("help", {}), ("no cache", {"JSWIM_COMPILATION_CACHE": "0"})]
        for what, extra in plan:
            for _ in range(args.repeats):
                for s in sides:
                    s.run(what, **extra)
        for s in sides:
            s.run("first (fills the cache)")
        for _ in range(args.repeats):
            for s in sides:
                s.run("warm")
    load1 = os.getloadavg()[0]
    print(
        f"load average {load0:.1f} at the start, {load1:.1f} at the end, on {os.cpu_count()} CPUs; "
        f"median of {args.repeats} processes, wall s (CPU s)"
    )
    rows = ["help", "no cache", "first (fills the cache)", "warm"]
    labels = {
        "help": "jswim --help",
        "no cache": "swim, no compilation cache",
        "first (fills the cache)": "swim, first run (fills the cache)",
        "warm": "swim, warm",
    }
    print(f"{'':36s}" + "".join(f"{s.name:>18s}" for s in sides))
    out: dict[str, object] = {
        "load_average_start": load0,
        "load_average_end": load1,
        "cpus": os.cpu_count() or 0,
    }
    for r in rows:
        cells = []
        for s in sides:
            w, c = s.median(r)
            out[f"{s.name}:{r}"] = {"wall_s": w, "cpu_s": c}
            cells.append(f"{w:8.2f} ({c:5.2f})")
        print(f"{labels[r]:36s}" + "".join(f"{c:>18s}" for c in cells))
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=2) + "\n")


if __name__ == "__main__":
    main()
