"""The swimmer's own optimum: wall time of `jswim.agents.optimal.solve` for one target in each flow.

    python benchmarks/bench_optimal.py                 # the four flows at 0.5 v, 90-degree target
    python benchmarks/bench_optimal.py --fraction 0.9 --bearing 180
    python benchmarks/bench_optimal.py --compile-cache # twice: the second loads the compiled
                                                       #   programs (the jswim command's cache)
    python benchmarks/bench_optimal.py --study         # + a navigate study with and without
                                                       #   the optimal and mpc rows

Each line: the flow, the optimum's steps and lower bound, the steering controller's steps, the
model-predictive agent's steps (``--mpc``), and the seconds each took (the first solve includes
compiling the still-fluid time to go and the search; the table says which). ``--study`` runs
``jswim study navigate`` (no LLM) on one flow speed twice, each in a fresh process: once as it
was before the optimum (no ``optimal`` or ``mpc`` agent: no optimum is searched) and once as it
is, and prints the ratio of their wall times (the issue's budget: at most 1.5).
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time

import jswim
from jswim import compile_cache
from jswim.agents import mpc, optimal, steering
from jswim.env.flows import study_flow
from jswim.env.navigation import summarise
from jswim.env.targets import FixedTarget

FLOWS = ("uniform", "shear", "poiseuille", "taylor-green")


def _solve_all(
    fraction: float, bearing: float, with_mpc: bool, beam: int = optimal.BEAM_WIDTH
) -> float:
    total = 0.0
    print(
        f"target 3 a at {bearing:g} degrees, flows at {fraction:g} v, K = 2, float32, beam {beam}"
    )
    print(f"{'flow':14s} {'optimal':>7s} {'lower':>5s} {'ctrl':>5s} {'mpc':>5s} {'solve s':>8s}")
    for kind in FLOWS:
        env, params = jswim.make(
            "purcell",
            roc_levels=2,
            target=FixedTarget(3.0, bearing),
            flow=study_flow(kind, fraction),
        )
        t = time.perf_counter()
        best = optimal.solve(env, params, beam=beam)
        dt = time.perf_counter() - t
        total += dt
        ctrl = summarise(env, params, steering.run(env, params, 0))[0]
        m = "-"
        if with_mpc:
            ep = summarise(env, params, jswim.rollout(env, params, 0, mpc.run(env, params, 0)))[0]
            m = str(ep.steps) if ep.reached else "n"
        print(
            f"{kind:14s} {best.steps if best.steps else 'n':>7} {best.lower:>5d} "
            f"{ctrl.steps if ctrl.reached else 'n':>5} {m:>5s} {dt:8.1f}"
        )
    print(f"all four: {total:.1f} s (the issue's budget: 60 s on 2 cores)")
    return total


def _arm(name: str, fraction: float) -> float:
    """One arm of ``--study``, in this process: the study with (``with``) or without
    (``without``) the ``optimal`` and ``mpc`` agents; its wall time (s)."""
    from jswim.studies.options import ALL_AGENTS, MPC_AGENT, OPTIMAL_AGENT, StudyOptions
    from jswim.studies.run import run_study

    dropped = (OPTIMAL_AGENT, MPC_AGENT, "llm") if name == "without" else ("llm",)
    agents = tuple(a for a in ALL_AGENTS if a not in dropped)
    out = tempfile.mkdtemp(prefix="bench-optimal-")
    opts = StudyOptions(flow="shear", flows=(fraction,), bearings=(90.0,), agents=agents)
    t = time.perf_counter()
    run_study("navigate", opts, None, out, progress=False)
    wall = time.perf_counter() - t
    shutil.rmtree(out, ignore_errors=True)
    return wall


def _study(fraction: float) -> None:
    """``--study``: each arm in a fresh process (nothing compiled by one is reused by the
    other), one after the other."""
    walls = {}
    for name in ("without", "with"):
        cmd = [sys.executable, __file__, "--arm", name, "--fraction", str(fraction)]
        out = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
        walls[name] = float(out.split()[-1])
        print(
            f"navigate study, shear {fraction:g} v, 3 targets, {name} optimal/mpc: {walls[name]:.0f} s"
        )
    print(f"with / without: {walls['with'] / walls['without']:.2f} (the issue's budget: 1.5)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fraction", type=float, default=0.5)
    ap.add_argument("--bearing", type=float, default=90.0)
    ap.add_argument("--mpc", action="store_true", help="also run the model-predictive agent")
    ap.add_argument("--study", action="store_true", help="also time a study with and without")
    ap.add_argument("--beam", type=int, default=optimal.BEAM_WIDTH, help="the optimum's beam width")
    ap.add_argument(
        "--compile-cache",
        action="store_true",
        help="keep compiled programs on disk as the jswim command does (jswim.compile_cache): "
        "run twice, the second run loads what the first compiled",
    )
    ap.add_argument("--arm", choices=("with", "without"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.arm:  # one arm of --study, run by it in a fresh process
        print(f"{_arm(args.arm, args.fraction):.3f}")
        return
    if args.compile_cache:
        print(f"compile cache: {compile_cache.enable()}")
    _solve_all(args.fraction, args.bearing, args.mpc, args.beam)
    if args.study:
        _study(args.fraction)


if __name__ == "__main__":
    main()
