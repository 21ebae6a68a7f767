"""Swimmer-steps per second of the vectorised environment against a plain Python loop.

Three JAX paths, each jitted, batched and scanned over steps (compilation excluded):

* ``table/step_batch``: the exact step table, noise for the whole batch drawn from one key;
* ``table/vmap(step)``: the gymnax-style ``jax.vmap(step)`` with one key per swimmer;
* ``integrator``: every step integrated from scratch (Chebyshev degree 16, float64,
  ~1e-14 relative per cycle), the path for strokes that do not follow the table.

``--continuous`` instead times one-DOF continuous steps side by side in one run, noisy,
default dtype (float32), batch ``--batch`` (10^5): random DOF and real ROC in [-1, 1] on the
motion table (``cont/table``) and through the integrator (``cont/integrator``, degree 24), integer
codes on the K = 5 lattice (``lattice/K=5``), and the corner table (``corner``, the paper's codes).

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
                s, _ = jax.vmap(env.step, in_axes=(0, 0, 0, None))(
                    jax.random.split(k, batch), s, a, params
                )
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


def continuous_runner(params: env.EnvParams, batch: int, steps: int, kind: str):
    """Scan of ``env.step_batch`` over ``steps`` steps: ``kind`` ``"corner"`` / ``"lattice"``
    (integer codes) or ``"rocs"`` (a random DOF at a real ROC in [-1, 1] per swimmer and step)."""

    def run(key):
        states = jax.vmap(env.reset, in_axes=(0, None))(jax.random.split(key, batch), params)
        if kind == "rocs":
            dof = jax.random.randint(key, (steps, batch), 0, params.n_dof)
            roc = jax.random.uniform(
                jax.random.fold_in(key, 1), (steps, batch), minval=-1.0, maxval=1.0
            )
            actions = jax.nn.one_hot(dof, params.n_dof) * roc[..., None]
        else:
            actions = jax.random.randint(key, (steps, batch), 0, params.n_actions)

        def body(s, inp):
            k, a = inp
            s, _ = env.step_batch(k, s, a, params)
            return s, None

        s, _ = jax.lax.scan(body, states, (jax.random.split(key, steps), actions))
        return s.x

    return jax.jit(run)


def continuous(args) -> None:
    from jswim.env import stepping

    b = args.batch
    print(
        f"jswim bench_env --continuous | jax {jax.__version__} | {os.cpu_count()} cores | noisy Purcell, "
        f"zeta={args.zeta}, float32, batch {b:,d}"
    )
    key = jax.random.PRNGKey(0)
    rows = []
    cases = [
        ("corner", "corner", 1, args.steps),
        ("lattice/K=5", "lattice", 5, args.steps),
        ("cont/table", "rocs", 1, args.steps),
        ("cont/integrator", "rocs", 1, max(1, args.steps // 10)),
    ]
    for name, kind, big_k, steps in cases:
        stepping.STEP_METHOD = "integrator" if name == "cont/integrator" else "table"
        params = env.make_params("purcell", zeta=args.zeta, roc_levels=big_k)
        t0 = time.perf_counter()
        fn = continuous_runner(params, b, steps, kind)
        jax.block_until_ready(fn(key))
        compile_s = time.perf_counter() - t0
        sec = best_time(fn, key, repeat=args.repeat)
        rows.append(
            dict(
                path=name,
                batch=b,
                steps=steps,
                seconds=sec,
                steps_per_s=b * steps / sec,
                first_call_s=compile_s,
            )
        )
    stepping.STEP_METHOD = "table"
    base = {r["path"]: r["steps_per_s"] for r in rows}
    print(
        f"{'path':18s} {'steps/s':>14s} {'x integrator':>13s} {'x corner':>9s} {'first call s':>13s}"
    )
    for r in rows:
        print(
            f"{r['path']:18s} {r['steps_per_s']:14,.0f} {r['steps_per_s'] / base['cont/integrator']:13.1f} "
            f"{r['steps_per_s'] / base['corner']:9.2f} {r['first_call_s']:13.1f}"
        )
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(dict(rows=rows), fh, indent=2)


def main() -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--quick", action="store_true", help="smaller batches and fewer steps")
    ap.add_argument("--steps", type=int, default=100, help="steps per swimmer in the table paths")
    ap.add_argument("--zeta", type=float, default=1.0, help="noise level (the noisy env)")
    ap.add_argument("--json", help="also write the results here")
    ap.add_argument(
        "--continuous", action="store_true", help="time continuous one-DOF steps (see above)"
    )
    ap.add_argument("--batch", type=int, default=100_000, help="batch of --continuous")
    ap.add_argument(
        "--repeat", type=int, default=3, help="timed repeats of --continuous (best kept)"
    )
    args = ap.parse_args()
    if args.continuous:
        continuous(args)
        return

    batches = [1, 100, 10_000] if args.quick else [1, 10, 100, 1_000, 10_000, 100_000]
    params = env.make_params("purcell", zeta=args.zeta)
    print(
        f"jswim bench_env | jax {jax.__version__} | {platform.processor() or platform.machine()} "
        f"| {os.cpu_count()} cores | noisy Purcell, zeta={args.zeta}, d_max=pi/3"
    )

    ref_steps = 4 if args.quick else 12
    ref = python_reference(ref_steps, math.pi / 3)
    ref_rate = 1.0 / ref
    print(
        f"plain Python reference (RK4, 300 substeps, one swimmer): {ref_rate:,.1f} steps/s "
        f"({ref_steps} steps timed)\n"
    )

    rows = []
    header = f"{'path':20s} {'dtype':8s} {'batch':>8s} {'steps':>6s} {'seconds':>9s} {'steps/s':>14s} {'x Python':>10s}"
    print(header)
    print("-" * len(header))

    def report(path, dtype, batch, steps, seconds):
        rate = batch * steps / seconds
        rows.append(
            dict(
                path=path,
                dtype=dtype,
                batch=batch,
                steps=steps,
                seconds=seconds,
                steps_per_s=rate,
                ratio_vs_python=rate / ref_rate,
            )
        )
        print(
            f"{path:20s} {dtype:8s} {batch:8,d} {steps:6d} {seconds:9.4f} {rate:14,.0f} {rate / ref_rate:10,.0f}"
        )

    key = jax.random.PRNGKey(0)
    for per_key in (False, True):
        name = "table/vmap(step)" if per_key else "table/step_batch"
        for b in batches:
            steps = args.steps if b >= 1000 else args.steps * 10
            report(
                name, "float32", b, steps, best_time(table_runner(params, b, steps, per_key), key)
            )
    with jax.enable_x64(True):
        params64 = env.make_params("purcell", zeta=args.zeta)
        for b in batches:
            if b > 10_000 and args.quick:
                continue
            steps = 10 if b >= 10_000 else 50
            report(
                "integrator",
                "float64",
                b,
                steps,
                best_time(integrator_runner(params64, b, steps), key, repeat=2),
            )
    # The four-DOF swimmers (four links, four spheres) on the same paths, at the largest batch.
    b4 = batches[-1]
    for sw in ("nlink", "nsphere"):
        p4 = env.make_params(sw, zeta=args.zeta)
        report(
            f"{sw}4 table/batch",
            "float32",
            b4,
            args.steps,
            best_time(table_runner(p4, b4, args.steps, False), key),
        )
    with jax.enable_x64(True):
        for sw in ("nlink", "nsphere"):
            p4 = env.make_params(sw, zeta=args.zeta)
            b = min(b4, 10_000)
            report(
                f"{sw}4 integrator",
                "float64",
                b,
                10,
                best_time(integrator_runner(p4, b, 10), key, repeat=2),
            )
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(dict(reference_steps_per_s=ref_rate, rows=rows), fh, indent=2)


if __name__ == "__main__":
    main()
