"""Why a real swimmer can beat Zermelo's point steerer: the body averages the flow over its links.

Zermelo's steerer (`jswim.agents.zermelo`) is a point that feels the flow at its centre. Purcell's
swimmer is three links 3 a long, each element dragged by the flow at its own place (resistive
force theory), so it is carried by the flow averaged over its body
(`jswim.swimmers.flow_response.flow_velocity`), which differs from the flow at its centroid
where the flow curves over a body length. Up a Taylor-Green cell's axis against the flow
(``u = (u0 sin kx, 0)``, ``u0 < 0``, ``k = pi / cell``) a straight rod along the axis feels
``sin(k l) / (k l)`` of the centroid's flow (``l = 1.5 a`` its half-length): 0.900 in cells of
6 a, 0.991 in cells of 20 a.

For each case: the steering controller's steps to ``FixedTarget(D, 0)`` (radius 0.25) in
``TaylorGreen(-f v, cell)``, Zermelo's least time and their ratio; along the controller's path,
the flow that carries its centroid (the body's rigid response, moved to the centroid) over the
flow at its centroid, along the axis: the median per step and the ratio of their sums over the
path.

Usage: ``python benchmarks/body_flow.py`` (a minute or two: one compile per case).
"""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np

import jswim
from jswim.agents import steering
from jswim.agents.zermelo import zermelo
from jswim.env.flows import SWIM_SPEED, TaylorGreen
from jswim.env.navigation import summarise
from jswim.env.state import corner_values
from jswim.env.targets import FixedTarget
from jswim.swimmers.flow_response import flow_velocity

jax.config.update("jax_enable_x64", True)

#: (flow speed over v, cell a, target distance a): the issue's case first.
CASES = [(0.7, 6.0, 3.0), (0.5, 6.0, 3.0), (0.6, 6.0, 3.0), (0.8, 6.0, 3.0), (0.85, 6.0, 3.0)]
CASES += [(0.9, 6.0, 3.0)]
CASES += [(0.7, 20.0, 10.0), (0.9, 20.0, 10.0)]


def carried(model, flow, frac, x, y, theta):
    """The centroid's velocity from the flow alone (the body's rigid response, ``a / tau``) and
    the flow at the centroid, lab frame, (2,) each."""
    d = corner_values(model, frac)
    off = model.centroid_offset(d)
    c, s = jnp.cos(theta), jnp.sin(theta)
    arm = jnp.stack([c * off[0] - s * off[1], s * off[0] + c * off[1]])
    ref = jnp.stack([x - arm[0], y - arm[1], theta])
    u = flow_velocity(d, ref, flow.velocity, model.xi_ratio, 6)
    body = u[:2] + u[2] * jnp.stack([-arm[1], arm[0]])
    return body, flow.velocity(jnp.stack([x, y]))


def case(fraction: float, cell: float, distance: float) -> dict[str, float]:
    flow = TaylorGreen(-fraction * SWIM_SPEED, cell)
    target = FixedTarget(distance, 0.0, budget=4000)
    env, params = jswim.make("purcell", roc_levels=2, target=target, flow=flow)
    traj = steering.run(env, params, 0)
    summary = summarise(env, params, traj)[0]
    z = zermelo(flow, target)
    sw = traj.state.swimmer
    n = summary.steps
    model = params.swimmer.model
    body, point = jax.vmap(lambda f, x, y, t: carried(model, flow, f, x, y, t))(
        *(jnp.asarray(v)[:n] for v in (sw.frac, sw.x + sw.x_lo, sw.y + sw.y_lo, sw.theta))
    )
    bx, px = np.asarray(body[:, 0]), np.asarray(point[:, 0])
    keep = np.abs(px) > 0.05 * abs(flow.u0)  # per step only where the flow is not near zero
    rod = math.sin(1.5 * math.pi / cell) / (1.5 * math.pi / cell)
    return dict(
        reached=summary.reached,
        steps=n,
        zermelo=z.steps,
        ratio=n / z.steps if z.steps else float("nan"),
        median=float(np.median(bx[keep] / px[keep])),
        summed=float(bx.sum() / px.sum()),
        rod=rod,
    )


def main() -> None:
    print("flow    cell  D   controller  Zermelo  ratio  body/centroid flow (median, summed)  rod")
    for f, cell, dist in CASES:
        r = case(f, cell, dist)
        print(
            f"-{f} v  {cell:4.0f}  {dist:3.0f}  {r['steps']:5d} {'' if r['reached'] else '(not)'}"
            f"  {r['zermelo']:8.1f}  {r['ratio']:.3f}  {r['median']:.3f}  {r['summed']:.3f}"
            f"  {r['rod']:.3f}",
            flush=True,
        )


if __name__ == "__main__":
    main()
