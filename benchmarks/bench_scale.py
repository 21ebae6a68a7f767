"""Scaling over devices: swimmer-steps/s and Q-learner-steps/s against device count and batch size.

Three paths, each measured with the batch axis spread over the first 1, 2, 4, ... devices
(``jswim.sharding.limit``), the one-device figure measured in the same run as the reference:

* ``step_batch``: noisy Purcell swimmers (zeta = 1, float32 state, drift-free positions) stepped by
  ``env.step_batch`` inside one jitted scan over steps, the square gait as actions;
* ``ensemble``: ``jswim.studies.ensemble.run`` (the signature gait over N noisy swimmers, statistics
  every step, in chunks): what ``jswim ensemble`` does;
* ``qlearning``: ``qlearning.train``, 200 steps per learner, NG, all six actions.

Compilation is excluded (one warm-up call); each figure is the best of ``--repeat`` runs.
``--memory N`` also runs the ensemble at N swimmers per noise level and reports the process's
peak resident memory (``ru_maxrss``) against the state bytes of one chunk.

CPU: force host devices to see the sharded code path (they share the same cores, so expect no
speed-up, only the cost of the split)::

    XLA_FLAGS=--xla_force_host_platform_device_count=4 python benchmarks/bench_scale.py

GPU (one short run; targets on one GPU: >= 1e9 swimmer-steps/s at 1e7+ swimmers, >= 1e9
learner-steps/s at 1e6 learners)::

    python benchmarks/bench_scale.py --gpu --json bench_scale_gpu.json

Usage: ``python benchmarks/bench_scale.py [--quick | --gpu] [--memory N] [--json out.json]``
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import jax
import jax.numpy as jnp

from jswim import env, sharding
from jswim.agents import qlearning
from jswim.env.swimmer_world import SwimmerWorld
from jswim.studies import ensemble

SQUARE = jnp.asarray([env.encode_action(*m) for m in [(2, -1), (1, -1), (2, 1), (1, 1)]], jnp.int32)


def best_time(fn, repeat: int) -> float:
    jax.block_until_ready(fn())
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        jax.block_until_ready(fn())
        times.append(time.perf_counter() - t0)
    return min(times)


def step_batch_runner(batch: int, steps: int):
    params = env.make_params("purcell", zeta=1.0)
    size = sharding.padded_size(batch)
    states = jax.vmap(lambda lv: env.start_state(params.model, lv))(jnp.ones((size, 2), jnp.int32))
    states = sharding.shard(states)

    @jax.jit
    def run(states, key):
        def body(s, t):
            a = jnp.broadcast_to(SQUARE[t % 4], (size,))
            s, _ = env.step_batch(jax.random.fold_in(key, t), s, a, params)
            return s, None

        return jax.lax.scan(body, states, jnp.arange(steps))[0].x

    key = jax.random.PRNGKey(0)
    return lambda: run(states, key), size * steps


#: Swimmers per ensemble chunk (``--gpu`` raises it: a GPU wants more work per kernel launch).
CHUNK = [1 << 20]


def ensemble_runner(batch: int, steps: int):
    params = env.make_params("purcell", init=(0, 0))
    policy = ensemble.stroke_policy([5, 2, 3, 0])
    run = lambda: (
        ensemble.run(policy, params, n=batch, zetas=(1.0,), steps=steps, chunk=CHUNK[0])[0].mean
    )
    return run, batch * steps


def qlearning_runner(batch: int, steps: int):
    params = qlearning.batch_params(env.make_params("ng"), sharding.padded_size(batch))
    keys = sharding.shard(jax.random.split(jax.random.PRNGKey(0), sharding.padded_size(batch)))
    params = sharding.shard(params)
    config = qlearning.QConfig(steps=steps)
    return (
        lambda: qlearning.train(SwimmerWorld(params.model), params, keys, config).x
    ), sharding.padded_size(batch) * steps


def device_counts() -> list[int]:
    total = len(jax.devices())
    counts = [1]
    while counts[-1] * 2 <= total:
        counts.append(counts[-1] * 2)
    if counts[-1] != total:
        counts.append(total)
    return counts


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="small batches (a smoke test)")
    ap.add_argument(
        "--gpu", action="store_true", help="GPU sizes: 1e6..3e7 swimmers, 1e5..1e6 learners"
    )
    ap.add_argument(
        "--steps", type=int, default=None, help="steps per measurement (default 20, 200 for Q)"
    )
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument(
        "--paths",
        default="step_batch,ensemble,qlearning",
        help="comma-separated subset; '' with --memory for the memory figure alone",
    )
    ap.add_argument(
        "--memory",
        type=int,
        default=0,
        metavar="N",
        help="also run the ensemble at N swimmers and report peak RSS (e.g. 10000000)",
    )
    ap.add_argument("--json", default=None)
    args = ap.parse_args()

    if args.gpu:
        CHUNK[0] = 1 << 23
        sizes = {
            "step_batch": [1_000_000, 10_000_000, 30_000_000],
            "ensemble": [10_000_000, 30_000_000],
            "qlearning": [100_000, 1_000_000],
        }
    elif args.quick:
        sizes = {"step_batch": [10_000], "ensemble": [10_000], "qlearning": [1_000]}
    else:
        sizes = {
            "step_batch": [100_000, 1_000_000],
            "ensemble": [1_000_000],
            "qlearning": [10_000, 100_000],
        }
    runners = {
        "step_batch": step_batch_runner,
        "ensemble": ensemble_runner,
        "qlearning": qlearning_runner,
    }
    print(
        f"jax {jax.__version__}, backend {jax.default_backend()}, {len(jax.devices())} device(s): "
        f"{jax.devices()[0].device_kind}; {os.cpu_count()} CPU cores; {platform.machine()}"
    )
    print(
        f"{'path':11s} {'batch':>11s} {'devices':>7s} {'steps':>6s} {'seconds':>9s} {'steps/s':>15s} {'vs 1 dev':>8s}"
    )
    rows = []
    for path in [p for p in args.paths.split(",") if p]:
        steps = args.steps or (200 if path == "qlearning" else 20)
        for batch in sizes[path]:
            ref = None
            for ndev in device_counts():
                with sharding.limit(ndev):
                    fn, work = runners[path](batch, steps)
                    seconds = best_time(fn, args.repeat)
                rate = work / seconds
                ref = rate if ref is None else ref
                rows.append(
                    dict(
                        path=path,
                        batch=batch,
                        devices=ndev,
                        steps=steps,
                        seconds=seconds,
                        rate=rate,
                        vs_one=rate / ref,
                    )
                )
                print(
                    f"{path:11s} {batch:11,d} {ndev:7d} {steps:6d} {seconds:9.4f} {rate:15,.0f} {rate / ref:8.2f}",
                    flush=True,
                )
    result = {
        "jax": jax.__version__,
        "backend": jax.default_backend(),
        "device_kind": jax.devices()[0].device_kind,
        "devices": len(jax.devices()),
        "cpu_count": os.cpu_count(),
        "rows": rows,
    }
    if args.memory:
        n, steps = args.memory, 10
        chunk = CHUNK[0]
        t0 = time.perf_counter()
        ensemble.run(
            ensemble.stroke_policy([5, 2, 3, 0]),
            env.make_params("purcell", init=(0, 0)),
            n=n,
            zetas=(1.0,),
            steps=steps,
            chunk=chunk,
        )
        wall = time.perf_counter() - t0
        peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20  # KiB -> GiB
        state = chunk * 52 / 2**30
        print(
            f"memory: ensemble of {n:,} swimmers x {steps} steps in chunks of {chunk:,}: {wall:.1f} s, "
            f"peak RSS {peak:.2f} GiB (chunk state {state:.3f} GiB; the whole population's would be "
            f"{n * 52 / 2**30:.2f} GiB)"
        )
        result["memory"] = dict(n=n, steps=steps, chunk=chunk, seconds=wall, peak_rss_gib=peak)
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
