"""Learner-steps per second of the vmapped Q-learning baseline against vectorised NumPy.

Both sides run the same algorithm on the same environment: epsilon-greedy tabular Q-learning
(one uniform per step picks the branch and the action, ties broken at random), the exact step
table of the noisy swimmer, the TD update ``Q(s, a) += alpha (r + gamma max Q(s') - Q(s, a))``.
The NumPy version keeps every learner in arrays and loops in Python over steps only, never over
learners; fed the same uniforms it reproduces the JAX learners' actions exactly (checked below).

How it is measured: ``jax.jit(train)`` is compiled and run once per batch size before
timing (compilation excluded), then timed ``--repeat`` times with ``block_until_ready``; NumPy is
timed the same number of times. Each side draws its own random numbers inside the timed region.
The minimum over repeats is reported. Default: Purcell's swimmer, zeta = 0.5, default QConfig.

Usage: ``python benchmarks/bench_qlearning.py [--steps 200] [--repeat 5] [--swimmer ng]
[--action-set shape-changing] [--json out.json]``
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from typing import Any
from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np

from jswim.action_codes import ACTION_SETS
from jswim.agents import qlearning
from jswim.agents.defaults import default_rocs
from jswim.agents.qlearning import QConfig, batch_params, train
from jswim.env.swimmer_world import SwimmerWorld
from jswim.env import EnvParams, make_params, step_table, uniforms


def numpy_train(u: np.ndarray, params: EnvParams, config: QConfig) -> dict[str, np.ndarray]:
    """The Q-learning baseline in NumPy, all learners at once.

    Learners run along the last (contiguous) axis of every array, so each NumPy call is one
    vectorised pass over learners; Python loops over steps only.

    Parameters
    ----------
    u : float array (steps, B, 2)
        Uniforms in [0, 1): column 0 drives the agent, column 1 is the env's noise ``(Y + 1) / 2``.
    params : EnvParams
        Environment with leaves broadcast to B (see :func:`batch_params`); fixed initial levels.
    config : QConfig
        Hyperparameters; schedules are evaluated once for all steps before the loop.
    """
    steps, b, _ = u.shape
    dtype = u.dtype
    n = params.model.n_dof
    n_actions = 3 * n
    inc = step_table(params.model)[0].reshape(-1, 3)
    table = (
        np.concatenate([inc, np.cos(inc[:, 2:]), np.sin(inc[:, 2:])], axis=1).astype(dtype).T.copy()
    )
    t = np.arange(steps)
    eps = np.asarray(jax.vmap(qlearning._schedule(config.epsilon))(t), dtype)
    lr = np.asarray(jax.vmap(qlearning._schedule(config.learning_rate))(t), dtype)
    zeta = np.asarray(params.zeta, dtype)
    direction = np.asarray(params.direction, dtype)
    levels = np.array(np.asarray(params.init).T, np.int64)  # (n_dof, B)
    assert levels.min() >= 0, "numpy_train takes fixed initial levels"
    weights = (2 ** np.arange(n))[:, None]
    corner = (levels * weights).sum(0)
    roc_of = (np.arange(n_actions) % 3 - 1)[:, None]
    dof_of = np.arange(n_actions) // 3
    kth = qlearning._kth_true_table(n_actions)
    bit = (1 << np.arange(n_actions))[:, None]
    rocs = np.isin(np.arange(n_actions) % 3 - 1, default_rocs(params.model))[:, None]
    q = np.full((2**n, n_actions, b), config.q_init, dtype)  # (corner, action, learner)
    cols = np.arange(n_actions)[:, None]
    rows = np.arange(b)
    x = np.zeros(b, dtype)
    c, s = np.ones(b, dtype), np.zeros(b, dtype)
    out_a = np.empty((steps, b), np.int64)
    out_x = np.empty((steps, b), dtype)

    def offered(levels: np.ndarray) -> np.ndarray:
        if config.action_set == "all":
            return np.broadcast_to(rocs, (n_actions, b))
        return (roc_of == 1 - 2 * levels[dof_of]) & rocs

    mask = offered(levels)
    for k in range(steps):
        row = q[corner, cols, rows]  # (actions, B)
        best = np.where(mask, row, -np.inf).max(0)
        u0 = u[k, :, 0]
        explore = u0 < eps[k]
        with np.errstate(divide="ignore", invalid="ignore"):
            v = np.where(explore, u0 / max(eps[k], 1e-30), (u0 - eps[k]) / max(1.0 - eps[k], 1e-30))
        cand = np.where(explore, mask, mask & (row == best))
        count = cand.sum(0)
        pick = np.clip(np.floor(v * count).astype(np.int64), 0, np.maximum(count - 1, 0))
        action = kth[(cand * bit).sum(0) * n_actions + pick]
        # Environment step from the exact table.
        dof, roc = action // 3, action % 3 - 1
        level = levels[dof, rows]
        moved = roc == 1 - 2 * level
        idx = corner * n + dof
        factor = 1.0 + zeta * (2.0 * u[k, :, 1] - 1.0)
        tx, ty = table[0, idx] * moved, table[1, idx] * moved
        if params.model.planar:
            dx = (c * tx - s * ty) * factor
            tc, ts = np.where(moved, table[3, idx], 1.0), table[4, idx] * moved
            c, s = c * tc - s * ts, s * tc + c * ts
        else:
            dx = tx * factor
        x = x + dx
        levels[dof, rows] = np.where(moved, 1 - level, level)
        new_corner = (levels * weights).sum(0)
        # TD update of the visited entry.
        mask = offered(levels)
        future = np.where(mask, q[new_corner, cols, rows], -np.inf).max(0)
        target = direction * dx + config.discount * future
        q[corner, action, rows] += lr[k] * (target - q[corner, action, rows])
        corner = new_corner
        out_a[k], out_x[k] = action, x
    return dict(actions=out_a.T, x=out_x.T, q=np.moveaxis(q, -1, 0))


def jax_uniforms(keys: jax.Array, steps: int) -> np.ndarray:
    """The uniforms :func:`train` draws for these keys, time-major (steps, B, 2)."""
    dtype = jnp.result_type(float)
    runs = jax.vmap(lambda k: jax.random.split(k)[1])(keys)
    u = jax.vmap(lambda k: uniforms(k, (steps, 2), dtype))(runs)
    return np.asarray(jnp.swapaxes(u, 0, 1))


def best_time(fn: Callable[[], Any], repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        jax.block_until_ready(fn())
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--swimmer", default="purcell")
    ap.add_argument("--zeta", type=float, default=0.5)
    ap.add_argument("--action-set", default="all", choices=ACTION_SETS)
    ap.add_argument("--batches", type=int, nargs="+", default=[1, 10, 100, 1_000, 10_000])
    ap.add_argument("--json", help="also write the results here")
    args = ap.parse_args()

    config = QConfig(steps=args.steps, action_set=args.action_set)
    base = make_params(args.swimmer, zeta=args.zeta)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(
        f"jswim bench_qlearning | jax {jax.__version__} | {platform.processor() or platform.machine()} | "
        f"{os.cpu_count()} cores, load {load:.2f} | {args.swimmer}, zeta={args.zeta}, "
        f"{args.action_set} actions, {args.steps} steps | min of {args.repeat}, compilation excluded"
    )

    # The two implementations agree action for action on the same random numbers.
    keys = jax.random.split(jax.random.PRNGKey(1), 256)
    params = batch_params(base, 256)
    ref = numpy_train(jax_uniforms(keys, args.steps), params, config)
    run = train(SwimmerWorld(params.model), params, keys, config)
    same = float(np.mean(np.asarray(run.actions) == ref["actions"]))
    print(
        f"NumPy vs JAX on the same uniforms: {same:.4%} of 256 x {args.steps} actions identical, "
        f"max |X difference| {np.max(np.abs(np.asarray(run.x) - ref['x'])):.1e}\n"
    )

    header = (
        f"{'learners':>8} {'steps':>6} {'JAX s':>9} {'NumPy s':>9} {'JAX learner-steps/s':>20} "
        f"{'NumPy learner-steps/s':>22} {'ratio':>7}"
    )
    print(header)
    print("-" * len(header))
    rows = []
    rng = np.random.default_rng(0)
    dtype = np.dtype(jnp.result_type(float))
    for b in args.batches:
        keys = jax.random.split(jax.random.PRNGKey(0), b)
        params = batch_params(base, b)
        jax.block_until_ready(
            train(SwimmerWorld(params.model), params, keys, config)
        )  # compile for this batch size
        t_jax = best_time(
            lambda: train(SwimmerWorld(params.model), params, keys, config), args.repeat
        )
        t_np = best_time(
            lambda: numpy_train(rng.random((args.steps, b, 2), dtype=dtype), params, config),
            args.repeat,
        )
        work = b * args.steps
        rows.append(
            dict(
                learners=b,
                steps=args.steps,
                jax_s=t_jax,
                numpy_s=t_np,
                jax_rate=work / t_jax,
                numpy_rate=work / t_np,
                ratio=t_np / t_jax,
            )
        )
        print(
            f"{b:8,d} {args.steps:6d} {t_jax:9.4f} {t_np:9.4f} {work / t_jax:20,.0f} {work / t_np:22,.0f} "
            f"{t_np / t_jax:7.1f}"
        )
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(
                dict(load=load, config=repr(config), same_actions=same, rows=rows), fh, indent=2
            )


if __name__ == "__main__":
    main()
