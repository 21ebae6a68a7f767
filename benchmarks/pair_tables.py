"""Regenerate docs/scenes.md's pair and line-of-three tables (float64, unbounded fluid).

* Side-by-side pair (``formation="side"``: swimmer 2 at D above swimmer 1, both along x), each
  doing the square stroke at once, swimmer 2 ``k`` quarter cycles ahead (k = 0..3: it first makes
  k moves alone, then both move together). Per joint cycle: the change of the axes' distance
  (negative: attract), of the swimmers' x offset, and of the tilts; the phase is called
  ``attract`` or ``repel`` when the distance changes with one sign every cycle, ``oscillate`` when
  the per-cycle change is smaller than the within-cycle swing and changes sign.
* A line of three in phase (D = 30 a): the ends' x displacements per cycle and their difference,
  cycle by cycle.

Usage: ``python benchmarks/pair_tables.py [--cycles N]`` (a few minutes; one compilation per table).
"""

from __future__ import annotations

import argparse

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp
import numpy as np

from jswim.scenes import (
    Scene,
    batch_starts,
    scene_params,
    scene_reset,
    scene_step,
    scene_step_joint,
)

DOFS = jnp.array([0, 1, 0, 1])
ROCS = jnp.array([-1.0, -1.0, 1.0, 1.0])


def side_pair(spacings: list[float], cycles: int) -> np.ndarray:
    """Centres ``(k, D, 4 cycles + 1, 2, 2)`` at every joint step (from after the lead-in)."""
    params = scene_params(
        "ng",
        Scene(medium="free", swimmers=2, separation=float(spacings[0]), formation="side"),
        dtype=jnp.float64,
    )
    pb = batch_starts(params, separation=np.asarray(spacings, np.float64))
    axes = pb.replace(zeta=None, centre0=0, tilt0=0, arms0=None, obstacles=None)
    key = jax.random.PRNGKey(0)

    def one(par, k):
        st = scene_reset(par)
        for j in range(3):
            st = scene_step(par, st, (1, DOFS[j], jnp.where(j < k, ROCS[j], 0.0)), key)[0]

        def body(st, j):
            st = scene_step_joint(
                par,
                st,
                jnp.stack([DOFS[j % 4], DOFS[(j + k) % 4]]),
                jnp.stack([ROCS[j % 4], ROCS[(j + k) % 4]]),
                key,
            )[0]
            return st, (st.centre + st.centre_lo, st.tilt)

        c0 = st.centre + st.centre_lo
        _, (c, t) = jax.lax.scan(body, st, jnp.arange(4 * cycles))
        return jnp.concatenate([c0[None], c]), jnp.concatenate([st.tilt[None], t])

    f = jax.jit(jax.vmap(jax.vmap(one, in_axes=(axes, None)), in_axes=(None, 0)))
    c, t = f(pb, jnp.arange(4))
    return np.asarray(c), np.asarray(t)


def line_of_three(cycles: int, d: float = 30.0) -> np.ndarray:
    params = scene_params("ng", Scene(medium="free", swimmers=3, separation=d), dtype=jnp.float64)
    key = jax.random.PRNGKey(0)

    def body(st, j):
        st = scene_step_joint(params, st, jnp.full(3, DOFS[j % 4]), jnp.full(3, ROCS[j % 4]), key)[
            0
        ]
        return st, st.centre + st.centre_lo

    st = scene_reset(params)
    _, c = jax.jit(lambda s: jax.lax.scan(body, s, jnp.arange(4 * cycles)))(st)
    c0 = np.asarray(st.centre + st.centre_lo)
    return np.concatenate([c0[None], np.asarray(c)])  # (4 cycles + 1, 3, 2)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cycles", type=int, default=20)
    cycles = ap.parse_args().cycles
    spacings = [10.0, 30.0]
    c, t = side_pair(spacings, cycles)
    print(
        f"## Side-by-side pair, unbounded fluid, {cycles} joint cycles (swimmer 2 k quarter cycles ahead)\n"
    )
    print(
        "| D / a | k | d(distance) per cycle, mean (a) | first, last cycle | swing within a cycle | dx offset per cycle | d tilt_2 per cycle | verdict |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for i, d in enumerate(spacings):
        for k in range(4):
            gap = c[k, i, :, 1, 1] - c[k, i, :, 0, 1]  # z distance of the middle spheres
            per = np.diff(gap[::4])
            swing = float(np.max(np.ptp(gap[:-1].reshape(cycles, 4), axis=1)))
            dx = np.diff((c[k, i, :, 1, 0] - c[k, i, :, 0, 0])[::4]).mean()
            dt2 = np.diff(t[k, i, ::4, 1]).mean()
            if np.all(per < 0):
                verdict = "attract"
            elif np.all(per > 0):
                verdict = "repel"
            else:
                verdict = "oscillate"
            print(
                f"| {d:g} | {k} | {per.mean():+.3e} | {per[0]:+.2e}, {per[-1]:+.2e} | {swing:.2e} "
                f"| {dx:+.3e} | {dt2:+.2e} | {verdict} |"
            )
    n3 = min(cycles, 8)
    c3 = line_of_three(n3)
    xs = c3[::4, :, 0]
    per = np.diff(xs, axis=0)  # (cycles, 3)
    print("\n## Line of three in phase, D = 30 a: X per cycle of each swimmer (a)\n")
    print("| cycle | back | middle | front | front - back | change from the last cycle |")
    print("|---|---|---|---|---|---|")
    prev = 0.0
    for j, p in enumerate(per):
        diff = p[2] - p[0]
        print(
            f"| {j + 1} | {p[0]:.8f} | {p[1]:.8f} | {p[2]:.8f} | {diff:+.3e} | {diff - prev:+.2e} |"
        )
        prev = diff


if __name__ == "__main__":
    main()
