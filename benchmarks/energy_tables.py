"""Regenerate the energy and turning tables of docs/physics.md from jswim's code.

The square gait's work per cycle and Lighthill efficiency (exact work tables), the loops of the
K = 2 lattice of Purcell's swimmer with their rotation, displacement and work per cycle, and the
steering controller's steps to targets at several bearings. The block sits in docs/physics.md
between the markers below; ``--check`` exits 1 where the page differs, ``--write`` rewrites it.
The tests under tests/physics check the same quantities against independent computations
(tests/physics/test_dissipation.py, tests/physics/test_turning.py).

    python benchmarks/energy_tables.py            # print the block (~30 s on 2 shared cores)
    python benchmarks/energy_tables.py --check    # exit 1 where the page differs
    python benchmarks/energy_tables.py --write    # put the block on the page
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

PAGE = Path(__file__).resolve().parents[1] / "docs" / "physics.md"
BEGIN = "<!-- energy_tables.py: begin -->"
END = "<!-- energy_tables.py: end -->"

#: The controller's targets: distance and success radius (link lengths), bearings (degrees).
DISTANCE, RADIUS = 3.0, 0.25
BEARINGS = (0, 45, 90, 135, 180, -45, -90, -135)


def lighthill(displacement: float, work: float, steps: int) -> float:
    """``eta = C dX^2 / (T W)``: the work of towing the swimmer rigidly over the cycle's distance
    in the cycle's time, over the stroke's work; ``C`` = 3 (three straight links along their
    axis, ``3 xi_par a``; or three isolated spheres, ``3 x 6 pi mu a``), ``T = steps`` tau."""
    return 3.0 * displacement**2 / (steps * work)


def gait_rows() -> list[str]:
    from jswim.env.loops import loop_motion
    from jswim.swimmers.models import make_model
    from jswim.swimmers.turning import rectangle

    rows = [
        "| swimmer | dX per cycle | work per cycle | work per distance | Lighthill efficiency |",
        "|---|---|---|---|---|",
    ]
    cases = [
        ("Purcell, d_max = pi/3", make_model("purcell"), "xi_par a^3 / tau"),
        ("Purcell, d_max = pi/4", make_model("purcell", d_max=math.pi / 4), "xi_par a^3 / tau"),
        ("NG, (d_min, d_max) = (6, 10)", make_model("ng"), "6 pi mu a^3 / tau"),
    ]
    for name, model, unit in cases:
        start = (1, 1) if model.planar else (0, 0)
        other = (0, 0) if model.planar else (1, 1)
        motion = loop_motion(model, 1, rectangle(start, other, start))
        dx = motion.displacement
        rows.append(
            f"| {name} | {dx:.8f} a | {motion.work:.6f} {unit} | {motion.work / dx:.4f} | "
            f"{lighthill(dx, motion.work, motion.steps):.3e} |"
        )
    return rows


def _tie(value: float) -> float:
    """A sort key that mirror-image loops share: their equal values differ in the last bit from
    one CPU to another, which would reorder the table's rows."""
    return round(value, 10)


def loop_rows() -> list[str]:
    from jswim.env.loops import lattice_loops
    from jswim.swimmers.models import make_model

    model = make_model("purcell")
    names = {0: "-pi/3", 1: "0", 2: "pi/3"}
    rows = [
        "| loop (d1, d2), from the first vertex | rotation per cycle | displacement per cycle "
        "| work per cycle | turning radius |",
        "|---|---|---|---|---|",
    ]
    for m in sorted(
        lattice_loops(model, 2),
        key=lambda m: (-_tie(abs(m.rotation)), _tie(m.work), m.loop.vertices),
    ):
        path = " -> ".join(f"({names[i]}, {names[j]})" for i, j in m.loop.vertices)
        radius = "straight" if abs(m.rotation) < 1e-12 else f"{m.radius:.3f} a"
        rotation = 0.0 if abs(m.rotation) < 1e-12 else m.rotation
        rows.append(
            f"| {path} | {rotation:+.6f} rad | {m.displacement:.6f} a | {m.work:.5f} | {radius} |"
        )
    return rows


def k4_rows() -> list[str]:
    """The K = 4 lattice's 100 rectangles, summarised: those that turn most per cycle and most per
    unit work (one orientation each; values in multiples of pi/6)."""
    from jswim.env.loops import lattice_loops
    from jswim.swimmers.models import make_model

    model = make_model("purcell")
    motions = [m for m in lattice_loops(model, 4) if abs(m.rotation) > 1e-12]
    names = {0: "-pi/3", 1: "-pi/6", 2: "0", 3: "pi/6", 4: "pi/3"}
    rows = [
        "| K = 4 loop, from the first vertex | rotation per cycle | displacement per cycle "
        "| work per cycle | rotation per work |",
        "|---|---|---|---|---|",
    ]

    def first_each_way(key: Any) -> list[Any]:  # the first clockwise loop, then anticlockwise
        ranked = sorted(motions, key=lambda m: (key(m), m.loop.vertices))
        return [next(m for m in ranked if (m.rotation > 0) == sign) for sign in (False, True)]

    most = first_each_way(lambda m: -_tie(abs(m.rotation)))
    thrifty = first_each_way(lambda m: -_tie(abs(m.rotation) / m.work))
    for m in most + thrifty:
        path = " -> ".join(f"({names[i]}, {names[j]})" for i, j in m.loop.vertices)
        rows.append(
            f"| {path} | {m.rotation:+.6f} rad | {m.displacement:.6f} a | {m.work:.5f} "
            f"| {abs(m.rotation) / m.work:.4f} |"
        )
    return rows


def controller_rows() -> list[str]:
    import jax.numpy as jnp

    from jswim.env import make_params
    from jswim.env.loops import steer, steering_budget, steering_plan

    params = make_params("purcell", roc_levels=2)
    angles = np.radians(BEARINGS)
    targets = jnp.asarray(np.stack([DISTANCE * np.cos(angles), DISTANCE * np.sin(angles)], -1))
    rows = [
        "| bearing | backward allowed: steps (budget) | work | work per distance "
        "| turning only: steps (budget) | work | work per distance |",
        "|---|---|---|---|---|---|---|",
    ]
    cells: dict[bool, list[str]] = {}
    for reverse in (True, False):
        plan = steering_plan(params.model, 2, reverse=reverse)
        budgets = [steering_budget(params.model, DISTANCE, a, reverse=reverse) for a in angles]
        run = steer(params, plan, targets, max(budgets), RADIUS)
        out = []
        for i, budget in enumerate(budgets):
            steps = int(run.steps[i])
            work = float(np.sum(np.asarray(run.work[i, :steps], np.float64)))
            reached = f"{steps} ({budget})" if 0 < steps <= budget else f"not reached ({budget})"
            out.append(f"{reached} | {work:.2f} | {work / (DISTANCE - RADIUS):.2f}")
        cells[reverse] = out
    for i, b in enumerate(BEARINGS):
        rows.append(f"| {b:+d} deg | {cells[True][i]} | {cells[False][i]} |")
    return rows


def block() -> str:
    lines = [BEGIN, ""]
    lines += gait_rows()
    lines += ["", *loop_rows(), "", *k4_rows(), "", *controller_rows(), "", END]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--check", action="store_true", help="exit 1 where the page differs")
    ap.add_argument("--write", action="store_true", help="put the block on docs/physics.md")
    a = ap.parse_args(argv)
    new = block()
    print(new)
    text = PAGE.read_text()
    if BEGIN not in text or END not in text:
        print(f"{PAGE.name} has no {BEGIN} ... {END} block", file=sys.stderr)
        return 1 if a.check else 0
    rest = text.split(BEGIN, 1)[1]
    old = BEGIN + rest.split(END, 1)[0] + END
    if a.write:
        PAGE.write_text(text.replace(old, new))
        return 0
    if a.check and old != new:
        print(f"{PAGE.name} differs from the code's numbers", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
