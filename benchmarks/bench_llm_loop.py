"""How close the batched LLM loop gets to the ideal wall time against a fixed-latency server.

R independent runs of S steps each talk to the fake server (:mod:`tests.fakeserver`), which
answers every request after L seconds. Run one after the other, the study would take R*S*L; with
every round's prompts in flight together it ideally takes S*L. The target is wall <= 1.2 * S*L.

A lockstep round costs about L + R*c, where c is this process's CPU time per request (httpx,
prompt, parsing; printed below), because every request of the round is built before the wait
and handled after it. ``--cohorts K`` splits the runs into K independently stepping cohorts so
one cohort's CPU work overlaps the others' waiting.

Run from the repository root: ``python benchmarks/bench_llm_loop.py [--runs 64 --steps 50
--latency 0.1]``. By default the server runs in its own process, as a real one would; ``--inprocess``
puts it on a thread of this process (then it competes for the GIL).
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

from jswim.agents.llm import LLMAgentConfig, LLMRunSpec, run_batch_async  # noqa: E402
from jswim.llm import ClientSettings, LLMClient  # noqa: E402
from tests.fakeserver import FakeServer, hash_reply  # noqa: E402


def specs(runs: int, steps: int, swimmer: str) -> list[LLMRunSpec]:
    # Noise makes every run's positions, hence prompts, differ; seeds keep them reproducible.
    return [LLMRunSpec(swimmer=swimmer, zeta=0.5, seed=k, n_steps=steps) for k in range(runs)]


async def study(url: str, runs: int, steps: int, swimmer: str, cohorts: int) -> tuple[float, float, list]:
    settings = ClientSettings(base_url=url, model="fake", max_concurrency=runs, timeout_s=30.0)
    # Every request must reach the server: no cache, no sharing of identical prompts.
    config = LLMAgentConfig(share_identical=False)
    async with LLMClient(settings) as client:
        await run_batch_async(specs(runs, 1, swimmer), client, config, cohorts=cohorts)  # compile
        t0, c0 = time.perf_counter(), time.process_time()
        results = await run_batch_async(specs(runs, steps, swimmer), client, config, cohorts=cohorts)
        return time.perf_counter() - t0, time.process_time() - c0, results


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=64, help="R, independent runs")
    ap.add_argument("--steps", type=int, default=50, help="S, steps per run")
    ap.add_argument("--latency", type=float, default=0.1, help="L, seconds per server answer")
    ap.add_argument("--swimmer", default="purcell")
    ap.add_argument("--cohorts", type=int, default=8,
                    help="independent lockstep cohorts (default 8; 1 = one env step per round)")
    ap.add_argument("--inprocess", action="store_true", help="serve from a thread of this process")
    args = ap.parse_args()
    R, S, L = args.runs, args.steps, args.latency

    if args.inprocess:
        srv = FakeServer(reply=hash_reply, latency=L).start()
        url, stop = srv.url, srv.stop
    else:
        proc = subprocess.Popen(
            [sys.executable, "-m", "tests.fakeserver", "--latency", str(L)], stdout=subprocess.PIPE, text=True, cwd=ROOT
        )
        url = proc.stdout.readline().strip()
        stop = proc.terminate
    try:
        wall, cpu, results = asyncio.run(study(url, R, S, args.swimmer, args.cohorts))
    finally:
        stop()

    calls = sum(r.usage.calls for r in results)
    failed = sum(r.failed_steps for r in results)
    ideal, sequential = S * L, R * S * L
    print(f"runs R={R}, steps S={S}, latency L={L:g} s, cohorts {args.cohorts}, "
          f"server {'in-process' if args.inprocess else 'subprocess'}")
    print(f"calls {calls}, failed steps {failed}, statuses {sorted({r.status for r in results})}")
    print(f"wall time          {wall:8.2f} s   ({calls / wall:.0f} calls/s)")
    print(f"ideal S*L          {ideal:8.2f} s   wall/ideal      = {wall / ideal:.3f}  (target <= 1.2)")
    print(f"sequential R*S*L   {sequential:8.2f} s   sequential/wall = {sequential / wall:.1f}x")
    print(f"overhead per round {(wall - ideal) / S * 1000:8.1f} ms   "
          f"(this process: {cpu / calls * 1e6:.0f} us CPU per call)")
    # Each round costs about L + R * c, with c the CPU per call spent in this process.
    c = cpu / calls
    print(f"=> wall/ideal <= 1.2 needs R <= 0.2 * L / c = {0.2 * L / c:.0f} runs at L = {L:g} s, "
          f"or L >= 5 * R * c = {5 * R * c:.2f} s at R = {R}")


if __name__ == "__main__":
    main()
