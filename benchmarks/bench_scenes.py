"""Swimmer-steps per second of the scene environment, side by side in one run.

Rows (default dtype, float32; noisy, random arm and ROC +-1 each step; jitted, vmapped over the
batch and scanned over steps; compilation excluded):

* ``env table``: today's environment (``jswim.env.step_batch``, the exact corner table): the
  reference the rest is measured against;
* ``scene bulk``: ``scene_step`` in the ``"bulk"`` medium (the paper's closed form);
* ``wall, 1 swimmer``: one NG swimmer above Blake's wall at h = 10 a and 3.5 a (the defaults in
  float32: 4 Gauss nodes x adaptive Picard sweeps, 3 sweeps = 12 force-free solves per step at
  10 a, 4-6 sweeps at 3.5 a; unrolled elimination), and at h = 10 a with the numerics before
  adaptive sweeps (6 nodes x 5 fixed sweeps = 30 solves), for the ratio;
* ``free, 1 swimmer``: the unbounded fluid (one sweep through the body-frame response,
  :mod:`jswim.swimmers.bodyframe`);
* ``pair free`` / ``pair wall``: two swimmers, one moving per step, block Gauss-Seidel by swimmer
  (free: each swimmer through its response, factored once per node; wall: two unrolled
  one-swimmer solves per node and sweep);
* ``N spheres``: one swimmer and ``N - 3`` unit-sphere obstacles, N = 3, 6, 12, 24, in the free medium.

The load average is printed: the machine is shared. Usage:
``python benchmarks/bench_scenes.py [--batch 10000] [--steps 4] [--quick]``
"""

from __future__ import annotations

import argparse
import os

import jax
import jax.numpy as jnp

from jswim import env
from jswim.scenes import Scene, scene_params, scene_reset, scene_step

from bench_env import best_time


def scene_rate(scene: Scene, batch: int, steps: int, **kw) -> float:
    params = scene_params("ng", scene, zeta=0.1, **kw)
    states = jax.tree.map(lambda v: jnp.broadcast_to(v, (batch,) + v.shape), scene_reset(params))
    s = params.n_swimmers

    @jax.jit
    def run(states, key):
        def body(st, k):
            k1, k2, k3 = jax.random.split(k, 3)
            act = (
                jax.random.randint(k1, (batch,), 0, s),
                jax.random.randint(k2, (batch,), 0, 2),
                jnp.where(jax.random.bernoulli(k3, 0.5, (batch,)), 1.0, -1.0),
            )
            st, _ = jax.vmap(scene_step, in_axes=(None, 0, 0, 0))(
                params, st, act, jax.random.split(k, batch)
            )
            return st, None

        return jax.lax.scan(body, states, jax.random.split(key, steps))[0]

    return batch * steps / best_time(run, states, jax.random.PRNGKey(0), repeat=2)


def table_rate(batch: int, steps: int) -> float:
    params = env.make_params("ng", zeta=0.1)
    states = jax.vmap(env.reset, in_axes=(0, None))(
        jax.random.split(jax.random.PRNGKey(0), batch), params
    )

    @jax.jit
    def run(states, key):
        def body(st, k):
            a = jax.random.randint(k, (batch,), 0, params.n_actions)
            return env.step_batch(k, st, a, params)[0], None

        return jax.lax.scan(body, states, jax.random.split(key, steps))[0]

    return batch * steps / best_time(run, states, jax.random.PRNGKey(1), repeat=2)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--batch", type=int, default=10_000)
    ap.add_argument("--steps", type=int, default=4)
    ap.add_argument("--quick", action="store_true", help="batch 1000, 2 steps")
    a = ap.parse_args()
    batch, steps = (1000, 2) if a.quick else (a.batch, a.steps)
    print(
        f"load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; batch {batch}, {steps} steps, "
        f"dtype {jnp.result_type(float)}"
    )
    ref = table_rate(batch, steps)
    rows = [("env table (reference)", ref, "swimmer-steps/s")]
    rows.append(("scene bulk", scene_rate(Scene(), batch, steps), "swimmer-steps/s"))
    wall10 = Scene(medium="wall", height=10.0)
    rows.append(("wall, 1 swimmer, h = 10 a", scene_rate(wall10, batch, steps), "swimmer-steps/s"))
    rows.append(
        (
            "wall, 1 swimmer, h = 3.5 a",
            scene_rate(Scene(medium="wall", height=3.5), batch, steps),
            "swimmer-steps/s",
        )
    )
    rows.append(
        (
            "wall, h = 10 a, 6 nodes x 5 sweeps",
            scene_rate(wall10, batch, steps, nodes=6, sweeps=5),
            "swimmer-steps/s",
        )
    )
    rows.append(
        ("free, 1 swimmer", scene_rate(Scene(medium="free"), batch, steps), "swimmer-steps/s")
    )
    small = max(batch // 10, 100)
    rows.append(
        (
            "pair free, D = 30 a",
            scene_rate(Scene(medium="free", swimmers=2), small, steps),
            "pair-steps/s",
        )
    )
    rows.append(
        (
            "pair wall, D = 30 a, h = 10 a",
            scene_rate(Scene(medium="wall", swimmers=2), small, steps),
            "pair-steps/s",
        )
    )
    for n in (3, 6, 12, 24):
        obs = tuple((-40.0 + 30.0 * (i % 4), 40.0 + 30.0 * (i // 4), 1.0) for i in range(n - 3))
        rows.append(
            (
                f"N = {n} spheres (1 swimmer + {n - 3} obstacles, free)",
                scene_rate(Scene(medium="free", obstacles=obs), small, steps, sweeps=5),
                "scene-steps/s",
            )
        )
    width = max(len(r[0]) for r in rows)
    for name, rate, unit in rows:
        print(f"{name:<{width}}  {rate:12.4g} {unit:<16} {rate / ref:9.3g} x table")


if __name__ == "__main__":
    main()
