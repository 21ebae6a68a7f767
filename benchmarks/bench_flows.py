"""Swimmer-steps per second of the navigation world in a background flow, against still fluid,
measured side by side in one run.

The world is ``jswim.make("purcell", roc_levels=2, target=FixedTarget(3.0, 90.0), flow=...)``;
``--batch`` swimmers (4,096) step together for ``--steps`` random K = 2 codes in one jitted scan
(``env.step`` vmapped, default dtype, compilation excluded; best of three). Still fluid reads each
step from the exact lattice table; a uniform flow adds ``u`` to it; the other flows add what the
flow tables give for the step's row (`jswim.env.flow_steps`: one flow evaluation and small
contractions; "taylor-green 6" is the study's cell of 6 a, whose rows hold more harmonics). ``--reference`` also times those flows through the RK4 reference the tables
replace (`jswim.env.flow_steps.Integrated`: 16 pieces per step, each evaluating the body's RFT
response; minutes to compile). The ratio is each world's rate over the still-fluid rate of this
run.

Usage: ``python benchmarks/bench_flows.py [--batch 4096] [--steps 50] [--reference]
[--json out.json]``
"""

from __future__ import annotations

import argparse
import json
import platform
import time

import jax
import jax.numpy as jnp

import jswim
from jswim.env.flow_steps import Integrated
from jswim.env.flows import Poiseuille, Shear, TaylorGreen, Uniform
from jswim.env.targets import FixedTarget

FLOWS = {
    "still": None,
    "uniform": Uniform((0.024, 0.0)),
    "shear": Shear(0.005),
    "poiseuille": Poiseuille(0.024, 10.0),
    "taylor-green": TaylorGreen(0.024, 20.0),
    # the study flow (`study_flow("taylor-green", 0.9)`): cells of 6 a need 7 harmonics, not 5
    "taylor-green 6": TaylorGreen(0.043, 6.0),
}


def rate(flow, batch: int, steps: int) -> float:
    env, params = jswim.make("purcell", roc_levels=2, target=FixedTarget(3.0, 90.0), flow=flow)

    @jax.jit
    def run(key):
        states = jax.vmap(env.reset, in_axes=(0, None))(jax.random.split(key, batch), params)
        actions = jax.random.randint(key, (steps, batch), 0, env.n_actions)

        def body(s, a):
            s, _ = jax.vmap(env.step, in_axes=(None, 0, 0, None))(key, s, a, params)
            return s, None

        return jax.lax.scan(body, states, actions)[0]

    key = jax.random.PRNGKey(0)
    jax.block_until_ready(run(key))
    best = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        jax.block_until_ready(run(key))
        best = min(best, time.perf_counter() - t0)
    return batch * steps / best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--batch", type=int, default=4096)
    ap.add_argument("--steps", type=int, default=50)
    ap.add_argument("--reference", action="store_true", help="also time the RK4 reference")
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    worlds = dict(FLOWS)
    if args.reference:
        worlds.update(
            {f"{k} (rk4)": Integrated(f) for k, f in FLOWS.items() if k not in ("still", "uniform")}
        )
    rates = {name: rate(flow, args.batch, args.steps) for name, flow in worlds.items()}
    print(f"{'world':<20} {'swimmer-steps/s':>16} {'x still':>8}")
    for name, r in rates.items():
        print(f"{name:<20} {r:16.3g} {r / rates['still']:8.3f}")
    if args.json:
        out = {
            "batch": args.batch,
            "steps": args.steps,
            "machine": platform.machine(),
            "devices": [str(d) for d in jax.devices()],
            "dtype": str(jnp.result_type(float)),
            "rates": rates,
            "ratio_to_still": {k: v / rates["still"] for k, v in rates.items()},
        }
        with open(args.json, "w") as f:
            json.dump(out, f, indent=2)


if __name__ == "__main__":
    main()
