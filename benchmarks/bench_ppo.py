"""The continuous-action RL baseline (jswim.agents.ppo): training time and steps to learn.

For each swimmer and target direction, ``--seeds`` PPO learners (default config, 200 steps,
the paper's start) are trained in one jitted, vmapped call and judged by
:func:`jswim.agents.ppo.evaluate` (real-valued strokes: a return to the same shape within 0.1 %
of the range, >= 1/2 of the square gait's speed, 3 cycles; steps to learn by
:func:`jswim.judging.stats.learn_stats`). Timing: the first call of a swimmer includes compilation and
is reported apart; the other direction runs on the compiled program (``block_until_ready``).
References measured in the same run and reported as ratios: the same number of continuous
environment steps alone (random one-DOF ROCs, one jitted scan of vmapped steps), and the tabular
Q-learner (``qlearning.train``, same seeds and steps). CPU seconds (all threads of the
process) are printed beside wall seconds: on a loaded machine they bound what an idle one needs.

The machine is shared: the load average is printed with the numbers.

Usage: ``python benchmarks/bench_ppo.py [--seeds 1000] [--swimmers purcell,ng] [--json out.json]``
"""

from __future__ import annotations

import argparse
import json
import os
import time

import jax
import jax.numpy as jnp
import numpy as np

from jswim import env
from jswim.agents import ppo, qlearning
from jswim.env.swimmer_world import SwimmerWorld
from jswim.agents.defaults import paper_init
from jswim.judging.stats import learn_stats


def _timed(fn, *args):
    """Result, wall seconds; the process's CPU seconds (all threads) go to ``_timed.cpu``."""
    t0, c0 = time.perf_counter(), time.process_time()
    out = jax.block_until_ready(fn(*args))
    _timed.cpu = time.process_time() - c0
    return out, time.perf_counter() - t0


@jax.jit
def _env_only(params, keys, u):
    states = jax.vmap(env.reset)(keys, params)
    n = params.model.n_dof

    def body(s, u):
        dof = jnp.minimum((u[:, 0] * n).astype(jnp.int32), n - 1)
        a = jnp.where(jnp.arange(n)[None] == dof[:, None], 2 * u[:, 1:2] - 1, 0.0)
        s, info = jax.vmap(lambda s, a, p: env.advance(s, a, 0.0, p))(s, a, params)
        return s, info.progress

    return jax.lax.scan(body, states, u)[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=1000)
    ap.add_argument("--swimmers", default="purcell,ng")
    ap.add_argument("--json")
    args = ap.parse_args()
    cfg = ppo.PPOConfig()
    rows = []
    print(
        f"PPO baseline, {args.seeds} seeds x {cfg.steps} steps; {os.cpu_count()} CPUs, "
        f"load average at start {os.getloadavg()[0]:.1f}"
    )
    for swimmer in args.swimmers.split(","):
        model = env.make_params(swimmer).model
        for i, direction in enumerate((1, -1)):
            params = env.broadcast_params(
                env.make_params(swimmer, direction=direction, init=paper_init(model)), args.seeds
            )
            keys = jax.random.split(jax.random.PRNGKey(i), args.seeds)
            run, wall = _timed(ppo.train, SwimmerWorld(params.model), params, keys, cfg)
            cpu = _timed.cpu
            report = ppo.evaluate(run, params)
            ls = learn_stats(report.steps_to_learn.tolist())
            x = np.asarray(run.progress, np.float64)
            row = {
                "swimmer": swimmer,
                "direction": direction,
                "seeds": args.seeds,
                "wall_s": wall,
                "cpu_s": cpu,
                "compiled_in_call": i == 0,
                "learned": ls.learned,
                "q25": ls.q25,
                "median": ls.median,
                "q75": ls.q75,
                "success": float(report.success.mean()),
                "mean_X_200": float(x.sum(1).mean()),
                "mean_X_last50": float(x[:, -50:].sum(1).mean()),
                "load": os.getloadavg()[0],
            }
            if i == 1:  # references on the compiled programs (each warmed up first)
                u = jax.random.uniform(jax.random.PRNGKey(9), (cfg.steps, args.seeds, 2))
                _env_only(params, keys, u).block_until_ready()
                _, row["env_only_s"] = _timed(_env_only, params, keys, u)
                qcfg = qlearning.QConfig(steps=cfg.steps)
                qlearning.train(SwimmerWorld(params.model), params, keys, qcfg)
                _, row["qlearning_s"] = _timed(
                    qlearning.train, SwimmerWorld(params.model), params, keys, qcfg
                )
                q = qlearning.train(SwimmerWorld(params.model), params, keys, qcfg)
                row["qlearning_learned"] = learn_stats(
                    qlearning.evaluate(q, params).steps_to_learn.tolist()
                ).label()
            rows.append(row)
            extra = (
                f"; env steps alone {row['env_only_s']:.2f} s (x{wall / row['env_only_s']:.1f}), Q-learning "
                f"{row['qlearning_s']:.2f} s (x{wall / row['qlearning_s']:.0f}; {row['qlearning_learned']})"
                if i == 1
                else " (includes compilation)"
            )
            print(
                f"{swimmer:7} {'+x' if direction > 0 else '-x'}  {wall:6.1f} s wall, {cpu:6.1f} s CPU{extra}\n"
                f"         steps to learn {ls.label()}; success {row['success']:.3f}; mean X after 200 steps "
                f"{row['mean_X_200']:.3f}, over the last 50 {row['mean_X_last50']:.3f}; load {row['load']:.1f}",
                flush=True,
            )
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(rows, fh, indent=1)


if __name__ == "__main__":
    main()
