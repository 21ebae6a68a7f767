"""Swimmer-steps per second of the vectorised environment against a plain Python loop.

Three JAX paths, each jitted, batched and scanned over steps (compilation excluded):

* ``table/step_batch``: the exact step table, noise for the whole batch drawn from one key;
* ``table/vmap(step)``: the gymnax-style ``jax.vmap(step)`` with one key per swimmer;
* ``integrator``: every step integrated from scratch (Chebyshev degree 16, float64,
  ~1e-14 relative per cycle), the path for strokes that do not follow the table.

The reference is what a plain script does: one swimmer at a time, RK4 with 300 substeps per step
on the paper's closed-form velocities (NumPy scalars). All numbers come from this run.

Usage: ``python benchmarks/bench_env.py [--quick] [--steps 100] [--json out.json]``
"""

from __future__ import annotations

import argparse
import json
import math
import os
import platform
import time

import jax
import jax.numpy as jnp
import numpy as np

from jswim import env
from jswim.integrate import integrate_stroke
from jswim.swimmers import purcell


def best_time(fn, *args, repeat: int = 3) -> float:
    """Minimum wall time of ``fn(*args)`` over ``repeat`` runs, after one warm-up (compilation)."""
    jax.block_until_ready(fn(*args))
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        jax.block_until_ready(fn(*args))
        times.append(time.perf_counter() - t0)
    return min(times)


def table_runner(params: env.EnvParams, batch: int, steps: int, per_swimmer_keys: bool):
    def run(key):
        keys = jax.random.split(key, batch)
        states = jax.vmap(env.reset, in_axes=(0, None))(keys, params)
        actions = jax.random.randint(key, (steps, batch), 0, params.n_actions)

        def body(s, inp):
            k, a = inp
            if per_swimmer_keys:
                s, _ = jax.vmap(env.step, in_axes=(0, 0, 0, None))(jax.random.split(k, batch), s, a, params)
            else:
                s, _ = env.step_batch(k, s, a, params)
            return s, None

        s, _ = jax.lax.scan(body, states, (jax.random.split(key, steps), actions))
        return s.x

    return jax.jit(run)


def integrator_runner(params: env.EnvParams, batch: int, steps: int):
    model = params.model

    def one_step(levels, pose, action):
        dof, roc = action // 3, action % 3 - 1
        level = levels[dof]
        moved = ((roc == 1) & (level == 0)) | ((roc == -1) & (level == 1))
        rate = jax.nn.one_hot(dof, model.n_dof, dtype=pose.dtype) * roc * moved
        d0 = env.corner_values(model, levels.astype(pose.dtype))
        pose = integrate_stroke(model, d0, rate, model.duration, pose)
        return levels.at[dof].set(jnp.where(moved, 1 - level, level)), pose

    def run(key):
        actions = jax.random.randint(key, (steps, batch), 0, params.n_actions)
        levels = jnp.ones((batch, model.n_dof), jnp.int32)
        pose = jnp.zeros((batch, 3))

        def body(carry, a):
            return jax.vmap(one_step)(carry[0], carry[1], a), None

        (levels, pose), _ = jax.lax.scan(body, (levels, pose), actions)
        return pose

    return jax.jit(run)


def python_reference(n_steps: int, d_max: float, substeps: int = 300, seed: int = 0) -> float:
    """Seconds per swimmer-step of a plain one-swimmer RK4 loop (300 substeps per step)."""
    rng = np.random.default_rng(seed)
    d = np.array([d_max, d_max])
    pose = np.zeros(3)
    duration = 2 * d_max
    h = duration / substeps
    t0 = time.perf_counter()
    for _ in range(n_steps):
        k, roc = int(rng.integers(2)), int(rng.choice([-1, 1]))
        target = d_max if roc > 0 else -d_max
        if d[k] != target:
            rate = np.zeros(2)
            rate[k] = roc
            for i in range(substeps):
                t = i * h
                f = lambda tt, p: purcell.velocity(d + rate * tt, rate, p[2], xp=np)
                k1 = f(t, pose)
                k2 = f(t + h / 2, pose + h / 2 * k1)
                k3 = f(t + h / 2, pose + h / 2 * k2)
                k4 = f(t + h, pose + h * k3)
                pose = pose + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
            d[k] = target
        # a move into the limit costs nothing, as in the env
    return (time.perf_counter() - t0) / n_steps


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--quick", action="store_true", help="smaller batches and fewer steps")
    ap.add_argument("--steps", type=int, default=100, help="steps per swimmer in the table paths")
    ap.add_argument("--zeta", type=float, default=1.0, help="noise level (the noisy env)")
    ap.add_argument("--json", help="also write the results here")
    args = ap.parse_args()

    batches = [1, 100, 10_000] if args.quick else [1, 10, 100, 1_000, 10_000, 100_000]
    params = env.make_params("purcell", zeta=args.zeta)
    print(f"jswim bench_env | jax {jax.__version__} | {platform.processor() or platform.machine()} "
          f"| {os.cpu_count()} cores | noisy Purcell, zeta={args.zeta}, d_max=pi/3")

    ref_steps = 4 if args.quick else 12
    ref = python_reference(ref_steps, math.pi / 3)
    ref_rate = 1.0 / ref
    print(f"plain Python reference (RK4, 300 substeps, one swimmer): {ref_rate:,.1f} steps/s "
          f"({ref_steps} steps timed)\n")

    rows = []
    header = f"{'path':20s} {'dtype':8s} {'batch':>8s} {'steps':>6s} {'seconds':>9s} {'steps/s':>14s} {'x Python':>10s}"
    print(header)
    print("-" * len(header))

    def report(path, dtype, batch, steps, seconds):
        rate = batch * steps / seconds
        rows.append(dict(path=path, dtype=dtype, batch=batch, steps=steps, seconds=seconds,
                         steps_per_s=rate, ratio_vs_python=rate / ref_rate))
        print(f"{path:20s} {dtype:8s} {batch:8,d} {steps:6d} {seconds:9.4f} {rate:14,.0f} {rate / ref_rate:10,.0f}")

    key = jax.random.PRNGKey(0)
    for per_key in (False, True):
        name = "table/vmap(step)" if per_key else "table/step_batch"
        for b in batches:
            steps = args.steps if b >= 1000 else args.steps * 10
            report(name, "float32", b, steps, best_time(table_runner(params, b, steps, per_key), key))
    with jax.enable_x64(True):
        params64 = env.make_params("purcell", zeta=args.zeta)
        for b in batches:
            if b > 10_000 and args.quick:
                continue
            steps = 10 if b >= 10_000 else 50
            report("integrator", "float64", b, steps, best_time(integrator_runner(params64, b, steps), key, repeat=2))
    # The four-DOF swimmers (four links, four spheres) on the same paths, at the largest batch.
    b4 = batches[-1]
    for sw in ("nlink", "nsphere"):
        p4 = env.make_params(sw, zeta=args.zeta)
        report(f"{sw}4 table/batch", "float32", b4, args.steps, best_time(table_runner(p4, b4, args.steps, False), key))
    with jax.enable_x64(True):
        for sw in ("nlink", "nsphere"):
            p4 = env.make_params(sw, zeta=args.zeta)
            b = min(b4, 10_000)
            report(f"{sw}4 integrator", "float64", b, 10, best_time(integrator_runner(p4, b, 10), key, repeat=2))
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(dict(reference_steps_per_s=ref_rate, rows=rows), fh, indent=2)


if __name__ == "__main__":
    main()
