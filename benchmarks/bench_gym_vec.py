"""Steps per second of the Gymnasium door: one environment against ``gym.make_vec`` (the vector
entry point, one jitted vmapped JAX step for every env), and the gymnax door scanned inside JIT.

* ``single``: ``gym.make(id)``, one ``env.step(action)`` per Python call (random actions);
* ``make_vec``: ``gym.make_vec(id, num_envs=N)``, one ``envs.step(actions)`` per call for N envs
  (actions, observations and rewards cross to NumPy every step, as a Gymnasium user gets them);
* ``gymnax scan``: ``jswim.gymnax.make(name)``, ``jax.vmap(env.step)`` over N envs inside a
  ``lax.scan`` of ``--scan`` steps (PureJaxRL's setting: nothing leaves the device).

Compilation is excluded (one warm-up each); each figure is the best of ``--repeat`` timings.
Speed-ups are against ``single`` of the same run. CPU time is reported beside wall time (the
machine is shared; wall time under load overstates).

Usage: ``python benchmarks/bench_gym_vec.py [--id jswim/Purcell-v0] [--num-envs 4096]
[--single-steps 2000] [--vec-steps 200] [--scan 200] [--json out.json]``
"""

from __future__ import annotations

import argparse
import importlib
import json
import os
import platform
import time

import gymnasium as gym
import jax
import numpy as np

import jswim.gym


def timed(fn, repeat: int) -> tuple[float, float]:
    """``(wall, cpu)`` seconds: the best of ``repeat`` runs of ``fn()`` by wall time."""
    best = (np.inf, np.inf)
    for _ in range(repeat):
        w, c = time.perf_counter(), time.process_time()
        fn()
        best = min(best, (time.perf_counter() - w, time.process_time() - c))
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--id", default="jswim/Purcell-v0")
    ap.add_argument("--num-envs", type=int, default=4096)
    ap.add_argument("--single-steps", type=int, default=2000)
    ap.add_argument("--vec-steps", type=int, default=200)
    ap.add_argument("--scan", type=int, default=200)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    n = args.num_envs
    rows = []

    env = gym.make(args.id)
    env.reset(seed=0)
    env.action_space.seed(0)
    acts = [env.action_space.sample() for _ in range(args.single_steps)]
    for a in acts[:10]:
        env.step(a)  # compile

    def single():
        for a in acts:
            env.step(a)

    w, c = timed(single, args.repeat)
    base = args.single_steps / w
    rows.append(("single (gym.make)", 1, args.single_steps / w, args.single_steps / c))

    envs = gym.make_vec(args.id, num_envs=n)
    assert isinstance(envs.unwrapped, jswim.gym.JswimVectorEnv)
    envs.reset(seed=0)
    envs.action_space.seed(0)
    vacts = [envs.action_space.sample() for _ in range(args.vec_steps)]
    envs.step(vacts[0])  # compile

    def vec():
        for a in vacts:
            envs.step(a)

    w, c = timed(vec, args.repeat)
    rows.append((f"make_vec (num_envs={n})", n, n * args.vec_steps / w, n * args.vec_steps / c))

    try:
        jswim_gymnax = importlib.import_module("jswim.gymnax")
    except ImportError:  # the gymnax extra is not installed: that row is left out
        jswim_gymnax = None
    if jswim_gymnax is not None:
        genv, params = jswim_gymnax.make(args.id.removeprefix("jswim/"))
        space = genv.action_space(params)

        @jax.jit
        def rollout(key):
            _obs, state = jax.vmap(genv.reset, in_axes=(0, None))(jax.random.split(key, n), params)

            def body(carry, k):
                state, total = carry
                ka, ks = jax.random.split(k)
                a = jax.vmap(space.sample)(jax.random.split(ka, n))
                _, state, r, *_ = jax.vmap(genv.step, in_axes=(0, 0, 0, None))(
                    jax.random.split(ks, n), state, a, params
                )
                return (state, total + r.sum()), None

            (_, total), _ = jax.lax.scan(body, (state, 0.0), jax.random.split(key, args.scan))
            return total

        jax.block_until_ready(rollout(jax.random.PRNGKey(0)))
        w, c = timed(lambda: jax.block_until_ready(rollout(jax.random.PRNGKey(1))), args.repeat)
        rows.append((f"gymnax scan (vmap {n})", n, n * args.scan / w, n * args.scan / c))

    print(
        f"{args.id}; {platform.machine()}, {os.cpu_count()} cores, jax {jax.__version__}, "
        f"load {os.getloadavg()[0]:.1f}"
    )
    print(f"{'path':32s} {'steps/s (wall)':>16s} {'steps/CPU-s':>14s} {'x single':>10s}")
    for name, _, sw, sc in rows:
        print(f"{name:32s} {sw:16,.0f} {sc:14,.0f} {sw / base:10,.0f}")
    if args.json:
        with open(args.json, "w") as f:
            json.dump(
                [
                    {"path": r[0], "num_envs": r[1], "steps_per_s": r[2], "steps_per_cpu_s": r[3]}
                    for r in rows
                ],
                f,
                indent=1,
            )


if __name__ == "__main__":
    main()
