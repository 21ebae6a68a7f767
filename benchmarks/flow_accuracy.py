"""How far the flow tables' steps are from the RK4 reference, over many random starts.

A Purcell swimmer plays the paper's square gait on the corner table in each study flow
(`jswim.env.flows.study_flow`: shear and Poiseuille on the targets' scale of 3 a, Taylor-Green
cells of 6 a and 20 a), at 0.5 and 0.9 of the swimming speed, from ``--starts`` random starts
(place uniform in [-6, 6]^2 a, heading uniform, one of the gait's four corners, so any phase of
the cycle), all in one vmapped batch, float64. The same steps go once through the tables
(`jswim.env.flow_steps`) and once through the RK4 reference (`jswim.env.flow_steps.Integrated`,
16 RK4 pieces per step). Per start: the error of the centroid (``a``, Euclidean) and of the
orientation (rad) after one step, and the largest along ``--steps`` steps; printed as the median
and the maximum over the starts (docs/physics.md, "Background flows").

``--jeffery`` measures a straight swimmer held in shear (Jeffery's orbit: ``cot(phi)`` grows by
the rate each step): one step through the tables and through the reference from ``--starts``
random angles, against the exact ``arccot(cot(phi) + rate)``.

``--clipped`` measures what a clipped push (a K = 2 push past a limit: fast, then held) would
move if its move were instead spread over the whole step (the rule before issue 60), per step.

Usage: ``python benchmarks/flow_accuracy.py [--starts 256] [--steps 200] [--jeffery]
[--clipped] [--only tg6-0.9,...]`` (minutes: one compile of the unrolled RK4 step per flow).
"""

from __future__ import annotations

import argparse
import time

import jax
import jax.numpy as jnp
import numpy as np

import jswim
from jswim.env.flow_steps import Integrated
from jswim.env.flows import Shear, study_flow
from jswim.env.state import start_state
from jswim.env.stepping import advance

jax.config.update("jax_enable_x64", True)  # the measurement in float64

#: The study flows measured: name -> (kind, length), each at 0.5 and 0.9 of the swimming speed.
KINDS = {
    "shear": ("shear", 3.0),
    "poiseuille": ("poiseuille", 3.0),
    "tg6": ("taylor-green", 3.0),
    "tg20": ("taylor-green", 10.0),
}
FLOWS = {
    f"{name}-{f}": (kind, length, f) for name, (kind, length) in KINDS.items() for f in (0.5, 0.9)
}

#: The square gait's corners (levels of DOF 1, 2) in its order and the code that leaves each:
#: (1,1) DOF 2 down, (1,0) DOF 1 down, (0,0) DOF 2 up, (0,1) DOF 1 up (`tests/env`'s SQUARE).
CORNERS = np.array([[1, 1], [1, 0], [0, 0], [0, 1]])
SQUARE = np.array([3, 0, 5, 2])

#: Half-width of the box the starts are drawn in (a): the Poiseuille channel's half-width.
BOX = 6.0


def _starts(model, n: int, seed: int, hold: tuple[float, ...] | None = None):
    """``n`` random start states (float64) and each one's gait phase."""
    rng = np.random.default_rng(seed)
    phase = rng.integers(0, 4, n)
    xy = rng.uniform(-BOX, BOX, (n, 2))
    theta = rng.uniform(-np.pi, np.pi, n)
    levels = np.asarray(hold, float)[None].repeat(n, 0) if hold else CORNERS[phase]

    def one(lv, p, th):
        st = start_state(model, lv, jnp.float64)
        zero = jnp.zeros((), jnp.float64)
        return st._replace(
            x=p[0], y=p[1], theta=th, cos=jnp.cos(th), sin=jnp.sin(th), theta_lo=zero,
            cos_lo=zero, sin_lo=zero,
        )  # fmt: skip

    states = jax.vmap(one)(jnp.asarray(levels, jnp.float64), jnp.asarray(xy), jnp.asarray(theta))
    return states, phase, theta


def _trajectories(params, states, actions):
    """Centroids (B, T, 2) and orientations (B, T) after each of ``actions`` (B, T)."""

    def run(st, acts):
        def body(s, a):
            s, _ = advance(s, a, jnp.zeros(()), params)
            return s, (jnp.stack([s.x + s.x_lo, s.y + s.y_lo]), s.theta + s.theta_lo)

        return jax.lax.scan(body, st, acts)[1]

    return jax.jit(jax.vmap(run))(states, jnp.asarray(actions))


def gait_errors(flow, starts: int = 256, steps: int = 200, seed: int = 0) -> dict[str, np.ndarray]:
    """Per start: the centroid (a) and orientation (rad) errors of the table world against the
    RK4 reference after one step and the largest along ``steps`` steps of the square gait."""
    _, params = jswim.make("purcell", flow=flow)
    _, ref_params = jswim.make("purcell", flow=Integrated(flow))
    states, phase, _ = _starts(params.model, starts, seed)
    actions = SQUARE[(phase[:, None] + np.arange(steps)[None]) % 4]
    fast = _trajectories(params, states, actions)
    ref = _trajectories(ref_params, states, actions)
    dpos = np.linalg.norm(np.asarray(fast[0]) - np.asarray(ref[0]), axis=-1)
    dang = np.abs(np.asarray(fast[1]) - np.asarray(ref[1]))
    return dict(pos1=dpos[:, 0], ang1=dang[:, 0], pos=dpos.max(1), ang=dang.max(1))


def jeffery_errors(
    rate: float, starts: int = 256, seed: int = 1, reference: bool = True
) -> dict[str, np.ndarray]:
    """A straight Purcell swimmer (the K = 2 lattice's centre) held one step in ``Shear(rate)``
    from random angles: the error of its new angle (rad) and of the growth of ``cot(phi)`` (the
    exact growth is ``rate``), through the tables and (``reference``) the RK4 reference."""
    out = {}
    flows = [("tables", Shear(rate))] + [("rk4", Integrated(Shear(rate)))] * reference
    for label, flow in flows:
        _, params = jswim.make("purcell", roc_levels=2, flow=flow)
        states, _, _ = _starts(params.model, starts, seed, hold=(0.5, 0.5))
        hold = np.full((starts, 1), 2)  # DOF 1, k = 0
        _, angle = _trajectories(params, states, hold)
        phi1 = np.asarray(angle[:, 0])
        phi0 = np.asarray(states.theta)
        exact = np.arctan2(1.0, 1.0 / np.tan(phi0) + rate)  # arccot, then the right branch
        exact = exact + np.pi * np.round((phi0 - exact) / np.pi)
        out[f"{label} angle"] = np.abs(phi1 - exact)
        out[f"{label} cot"] = np.abs(1.0 / np.tan(phi1) - 1.0 / np.tan(phi0) - rate)
        out["phi0"] = phi0
    return out


def clipped_gap(flow, starts: int = 256, seed: int = 2) -> dict[str, np.ndarray]:
    """Per start, one K = 2 push past a limit (ROC 1 from the lattice's middle: half a range,
    then held), stepped by the RK4 reference fast-then-held and spread over the whole step: how
    far the two rules put the centroid (a) and the orientation (rad)."""
    from jswim.env.stepping import flow_step

    _, params = jswim.make("purcell", roc_levels=2, flow=flow)
    model = params.model
    rng = np.random.default_rng(seed)
    pose = np.stack(
        [
            rng.uniform(-BOX, BOX, starts),
            rng.uniform(-BOX, BOX, starts),
            rng.uniform(-np.pi, np.pi, starts),
        ],
        -1,
    )
    dof = rng.integers(0, 2, starts)
    other = rng.integers(0, 3, starts) / 2.0
    up = rng.integers(0, 2, starts).astype(bool)
    s0 = np.where(dof[:, None] == np.arange(2), 0.5, other[:, None])
    s1 = s0.copy()
    s1[np.arange(starts), dof] = np.where(up, 1.0, 0.0)

    def both(a, b, p):
        held = flow_step(model, flow, a, b, p, duration=0.5)
        spread = flow_step(model, flow, a, b, p)
        return held - spread

    gap = np.asarray(jax.jit(jax.vmap(both))(jnp.asarray(s0), jnp.asarray(s1), jnp.asarray(pose)))
    return dict(pos=np.hypot(gap[:, 0], gap[:, 1]), ang=np.abs(gap[:, 2]))


def _line(name: str, values: dict[str, np.ndarray], keys) -> str:
    return f"{name:16s} " + "  ".join(
        f"{k} {np.median(values[k]):.1e} / {values[k].max():.1e}" for k in keys
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--starts", type=int, default=256)
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--only", default="", help="comma-separated flows (e.g. tg6-0.9)")
    ap.add_argument("--jeffery", action="store_true")
    ap.add_argument("--clipped", action="store_true")
    args = ap.parse_args()
    names = [n for n in FLOWS if not args.only or n in args.only.split(",")]
    print(f"median / max over {args.starts} random starts (float64)")
    for name in names:
        kind, length, f = FLOWS[name]
        flow = study_flow(kind, f, length)
        t0 = time.perf_counter()
        if args.clipped:
            print(_line(name, clipped_gap(flow, args.starts), ("pos", "ang")), flush=True)
            continue
        err = gait_errors(flow, args.starts, args.steps)
        print(
            _line(name, err, ("pos1", "ang1", "pos", "ang"))
            + f"  ({time.perf_counter() - t0:.0f} s)",
            flush=True,
        )
    if args.jeffery:
        for rate in (0.01, 0.05):
            err = jeffery_errors(rate, args.starts)
            keys = ("tables angle", "tables cot", "rk4 angle", "rk4 cot")
            print(_line(f"jeffery {rate}", err, keys), flush=True)


if __name__ == "__main__":
    main()
