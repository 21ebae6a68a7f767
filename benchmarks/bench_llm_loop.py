"""How close the LLM loop gets to the wall time no scheduler can beat.

R independent runs of S steps each talk to the fake server (:mod:`tests.fakeserver`). Every run
waits for its own replies one after the other, so no schedule can finish before the slowest run's
own summed latency, ``bound = max_r sum_s d(r, s)``. That is the reference; the target is
``wall <= 1.1 * bound`` at R = 64, S = 50 with heavy-tailed latency.

Latency (the server's delay per request):

- ``--lognormal MEDIAN SIGMA`` (default 0.5 0.8): ``d = median * exp(sigma * N(0, 1))``, the
  normal draw seeded by the request's messages (:func:`tests.fakeserver.lognormal_latency`), so
  each (run, step) has its own reproducible delay and this script recomputes every delay from
  the prompts in the transcripts. Real APIs look like this: most calls quick, a few very slow.
- ``--latency L``: every answer after exactly L seconds (bound = S * L).

Also printed, from the same delays: what lockstep rounds (every run's call, then one step for
all) would have cost at the least, ``sum_s max_r d(r, s)``, and how many env calls the steps
took (steps per env call = how many replies landed together).

Run from the repository root: ``python benchmarks/bench_llm_loop.py [--runs 64 --steps 50
--lognormal 0.5 0.8]``. The server runs in its own process, as a real one would;
``--inprocess`` puts it on a thread of this process (then it competes for the GIL).
"""

from __future__ import annotations

import argparse
import asyncio
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))  # the fake server lives in tests/

from jswim.agents.llm import LLMAgentConfig, LLMDriver, LLMRunSpec
from jswim.llm import ClientSettings, LLMClient
from jswim.prompt import build_messages
from tests.fakeserver import FakeServer, hash_reply, lognormal_latency


def specs(runs: int, steps: int, swimmer: str) -> list[LLMRunSpec]:
    # Noise makes every run's positions, hence prompts, differ; seeds keep them reproducible.
    return [LLMRunSpec(swimmer=swimmer, zeta=0.5, seed=k, n_steps=steps) for k in range(runs)]


async def study(url: str, runs: int, steps: int, swimmer: str) -> tuple[float, float, list, int]:
    settings = ClientSettings(base_url=url, model="fake", max_concurrency=runs, timeout_s=60.0)
    # Every request must reach the server: no cache, no sharing of identical prompts.
    config = LLMAgentConfig(share_identical=False)
    async with LLMClient(settings) as client:
        # Compile the env step for this batch size first (a prompt the timed runs never send).
        await LLMDriver(specs(runs, 1, swimmer), client, config, transcripts=False).run()
        driver = LLMDriver(specs(runs, steps, swimmer), client, config)
        t0, c0 = time.perf_counter(), time.process_time()
        results = await driver.run()
        return (
            time.perf_counter() - t0,
            time.process_time() - c0,
            results,
            sum(g.n_steps for g in driver.groups),
        )


def delays(results: list, latency, system: str | None) -> list[list[float]]:
    """Each run's server delays, recomputed from the prompts it sent (first attempts only)."""
    out = []
    for r in results:
        out.append(
            [
                latency({"messages": build_messages(rec["prompt"], system)})
                for rec in r.transcript
                if rec.get("type") == "step"
            ]
        )
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=64, help="R, independent runs")
    ap.add_argument("--steps", type=int, default=50, help="S, steps per run")
    ap.add_argument(
        "--lognormal",
        type=float,
        nargs=2,
        default=(0.5, 0.8),
        metavar=("MEDIAN", "SIGMA"),
        help="heavy-tailed latency (default 0.5 s median, sigma 0.8)",
    )
    ap.add_argument("--latency", type=float, default=None, help="fixed latency in seconds instead")
    ap.add_argument("--seed", type=int, default=0, help="seed of the lognormal delays")
    ap.add_argument("--swimmer", default="purcell")
    ap.add_argument("--inprocess", action="store_true", help="serve from a thread of this process")
    args = ap.parse_args()
    R, S = args.runs, args.steps
    if args.latency is not None:
        fixed = args.latency
        latency = lambda body: fixed
        server_args = ["--latency", str(fixed)]
        what = f"fixed {fixed:g} s"
    else:
        median, sigma = args.lognormal
        latency = lognormal_latency(median, sigma, seed=args.seed)
        server_args = ["--lognormal", str(median), str(sigma), "--latency-seed", str(args.seed)]
        what = f"lognormal, median {median:g} s, sigma {sigma:g}"

    if args.inprocess:
        srv = FakeServer(reply=hash_reply, latency=latency).start()
        url, stop = srv.url, srv.stop
    else:
        proc = subprocess.Popen(
            [sys.executable, "-m", "tests.fakeserver", *server_args],
            stdout=subprocess.PIPE,
            text=True,
            cwd=ROOT,
        )
        url = proc.stdout.readline().strip()
        stop = proc.terminate
    try:
        wall, cpu, results, env_calls = asyncio.run(study(url, R, S, args.swimmer))
    finally:
        stop()

    d = delays(results, latency, LLMAgentConfig().system)
    calls = sum(r.usage.calls for r in results)
    steps = sum(r.steps for r in results)
    per_run = [sum(x) for x in d]
    bound = max(per_run)
    lockstep = sum(max(x[s] for x in d if s < len(x)) for s in range(max(len(x) for x in d)))
    mean_d = sum(per_run) / max(sum(len(x) for x in d), 1)
    print(
        f"runs R={R}, steps S={S}, latency {what}, server {'in-process' if args.inprocess else 'subprocess'}"
    )
    print(
        f"calls {calls}, steps {steps}, failed steps {sum(r.failed_steps for r in results)}, "
        f"statuses {sorted({r.status for r in results})}"
    )
    print(
        f"mean delay per call {mean_d:.3f} s; runs' summed delays {min(per_run):.1f}-{bound:.1f} s"
    )
    print(f"wall time                 {wall:8.2f} s   ({calls / wall:.0f} calls/s)")
    print(
        f"bound (slowest run's sum) {bound:8.2f} s   wall/bound = {wall / bound:.3f}  (target <= 1.1)"
    )
    print(
        f"lockstep rounds, at least {lockstep:8.2f} s   = {lockstep / bound:.2f} x bound "
        f"({lockstep / (S * mean_d):.1f} x the mean delay per step)"
    )
    print(
        f"env calls {env_calls} for {steps} steps ({steps / max(env_calls, 1):.1f} steps per call); "
        f"this process: {cpu / calls * 1e6:.0f} us CPU per call, {cpu:.1f} s in all"
    )


if __name__ == "__main__":
    main()
