"""The cost of one step of a school against N, beside the paper's environment.

Rows (default dtype, float32; noisy, a random swimmer, arm and ROC +-1 each step, as agents
move; jitted, vmapped over the batch, scanned over steps; compilation excluded): the env table
(``jswim.env.step_batch``, the reference measured in the same run), then a school of N NG
swimmers in the unbounded fluid, in a line D = 30 a apart and side by side D = 10 a apart, and
above a wall (line, h = 10 a). Each school row gives school-steps/s (one arm of one swimmer
moves; every swimmer responds), its ratio to the table's swimmer-steps/s, and the CPU seconds per
school-step over N^2 (the couplings are all pairs of swimmers).

The load average is printed: the machine is shared. Usage:
``python benchmarks/bench_schools.py [--batch 1000] [--steps 4] [--sizes 1,2,3,4,6,8]``
"""

from __future__ import annotations

import argparse
import os
import time

import jax.numpy as jnp

from jswim.scenes import Scene

from bench_scenes import scene_rate, table_rate


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--batch", type=int, default=1000)
    ap.add_argument("--steps", type=int, default=4)
    ap.add_argument("--sizes", default="1,2,3,4,6,8")
    ap.add_argument("--media", default="line,side,wall")
    a = ap.parse_args()
    sizes = [int(v) for v in a.sizes.split(",")]
    print(
        f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; batch {a.batch}, {a.steps} steps, "
        f"dtype {jnp.result_type(float)}",
        flush=True,
    )
    ref = table_rate(a.batch * 10, a.steps)
    print(f"env table (reference): {ref:.4g} swimmer-steps/s", flush=True)
    scenes = {
        "line": lambda n: Scene(medium="free", swimmers=n, separation=30.0),
        "side": lambda n: Scene(medium="free", swimmers=n, separation=10.0, formation="side"),
        "wall": lambda n: Scene(medium="wall", swimmers=n, separation=30.0, height=10.0),
    }
    print("| school | N | school-steps/s | x the env table | compile s |")
    print("|---|---|---|---|---|")
    for name in a.media.split(","):
        for n in sizes:
            t0 = time.perf_counter()
            rate = scene_rate(scenes[name](n), a.batch, a.steps)
            total = time.perf_counter() - t0
            print(f"| {name} | {n} | {rate:.3g} | {rate / ref:.2e} | {total:.0f} |", flush=True)


if __name__ == "__main__":
    main()
