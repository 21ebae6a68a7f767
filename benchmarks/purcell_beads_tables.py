"""Regenerate docs/scenes.md's tables for Purcell's swimmer near a wall in both models (float64).

* bead-count convergence of the non-local bead model (:mod:`jswim.swimmers.purcell_beads`): the
  square stroke's displacement per cycle X in the bulk and at h = 0.5 l, for m beads per link;
* X against the plane's height h in the bead model and in local resistive force theory
  (:mod:`jswim.swimmers.wall_rft`, ``wall_model="local-rft"``), each beside its own bulk value,
  with the bead model's per-cycle heave Z and pitch A_y (rad; positive: the leading end, +x,
  dips towards the wall);
* the far-field local exponent of the wall's effect, ``-d ln|X(h) - X_bulk| / d ln h`` between 20
  and 40 link lengths, in both models.

Usage: ``python benchmarks/purcell_beads_tables.py [--quick]`` (several minutes on two cores;
``--quick``: fewer beads and heights).
"""

from __future__ import annotations

import argparse
import math
import time

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp
import numpy as np

from jswim.swimmers import purcell_beads, wall_rft
from tests.physics.test_wall_rft import cycles

B = purcell_beads.BEAD_RADIUS  # l / b = 50, local RFT's tables at the same b


def bead_cycle(h: float, m: int, wall: bool = True) -> np.ndarray:
    return np.asarray(
        purcell_beads.square_cycle(jnp.asarray(h, jnp.float64), m=m, b=B, wall=wall, steps=16)
    )


def rft_cycle(h: float | None) -> float:
    ratio = 2.0 if h is None else float(np.divide(*wall_rft.drag_coefficients(h, B)[::-1]))
    return float(cycles([ratio])[0, 0])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true")
    quick = ap.parse_args().quick
    t0 = time.time()
    ms = (8, 16, 32) if quick else (16, 32, 64, 128)
    print(f"## Bead-count convergence (b = {B} l; X per cycle, link lengths)\n")
    print("| m per link | spacing / b | X bulk | X at h = 0.5 l | pitch A_y at 0.5 l |")
    print("|---|---|---|---|---|")
    for m in ms:
        bulk = bead_cycle(1.0, m, wall=False)
        near = bead_cycle(0.5, m)
        print(f"| {m} | {1 / m / B:.3g} | {bulk[0]:.6f} | {near[0]:.6f} | {near[5]:+.3e} |")
    m = purcell_beads.BEADS_PER_LINK if not quick else ms[-1]
    bulk = bead_cycle(1.0, m, wall=False)
    rft_bulk = rft_cycle(None)
    heights = (0.05, 0.1, 0.25, 0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 40.0)
    if quick:
        heights = (0.1, 0.5, 2.0, 20.0, 40.0)
    print(f"\n## X per cycle against h (bead model m = {m}, b = {B} l; local RFT b = {B} l)\n")
    print(f"bulk: beads {bulk[0]:.8f}, local RFT {rft_bulk:.8f}\n")
    print(
        "| h / l | beads X | beads X / bulk - 1 | heave Z | pitch A_y | local RFT X | RFT X / bulk - 1 |"
    )
    print("|---|---|---|---|---|---|---|")
    rows = {}
    for h in heights:
        bx = bead_cycle(h, m)
        rx = rft_cycle(h)
        rows[h] = (bx[0] - bulk[0], rx - rft_bulk)
        print(
            f"| {h:g} | {bx[0]:.6f} | {bx[0] / bulk[0] - 1:+.3e} | {bx[3]:+.2e} | {bx[5]:+.3e} "
            f"| {rx:.6f} | {rx / rft_bulk - 1:+.3e} |"
        )
    if 20.0 in rows and 40.0 in rows:
        for name, k in (("beads", 0), ("local RFT", 1)):
            d1, d2 = rows[20.0][k], rows[40.0][k]
            p = -math.log(abs(d2 / d1)) / math.log(2.0)
            print(f"\nfar-field local exponent, 20..40 l, {name}: {p:.3f} ({d1:+.3e} -> {d2:+.3e})")
    print(f"\n({time.time() - t0:.0f} s)")


if __name__ == "__main__":
    main()
