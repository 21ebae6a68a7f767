"""Regenerate docs/scenes.md's sphere-wall tables (float64): the self-mobility models and the NG
swimmer's fates above the wall.

* the self-mobility factors, ``"exact"`` against ``"rpb"`` (:func:`jswim.swimmers.mobility.wall_self_factors`);
* the first-cycle wall table (X, tilt and height change from tilt 0) under both;
* the fate map: start height h0 (a) against start tilt (rad, nose up), each start run for
  ``--cycles`` square cycles under both self-mobility models. A fate is ``trapped`` when a step
  is refused for contact (a sphere within 0.1 a of the wall: the model's wall is reached; the
  cycle it came at is printed after ``T``), ``escaping`` when the middle sphere ends above
  :data:`ESCAPE_HEIGHT` and still rising (there the wall turns it by ~1e-6 rad a cycle),
  ``gliding`` otherwise, printed with the range of heights over the run's second half; ``.``
  marks a start that already touches the wall;
* the wall study's fate map: its own start (the paper's NG arms (10, 6)), stroke
  (:func:`jswim.studies.scene_studies.stroke_codes`), dtype (float32) and fate rule
  (:func:`jswim.studies.scene_studies.fate`) at its default horizon (``SPECS["wall"].steps``),
  height against start tilt, with the final height, and the cycle at which each start first
  reaches twice its height (what a longer horizon would call escaped).

Usage: ``python benchmarks/wall_fates_tables.py [--cycles N]`` (a few minutes: one compilation
per model).
"""

from __future__ import annotations

import argparse
import time

import jax

jax.config.update("jax_enable_x64", True)

import jax.numpy as jnp
import numpy as np

from jswim.action_codes import decode_action
from jswim.env import scene_rollout_batch
from jswim.scenes import Scene, batch_starts, scene_params
from jswim.studies.options import StudyOptions
from jswim.studies.plans import initial
from jswim.studies.scene_grids import wall_start_clears
from jswim.studies.scene_studies import fate as study_fate, stroke_codes
from jswim.studies.specs import SPECS
from jswim.swimmers.mobility import wall_self_factors

SQUARE = [(1, -1), (2, -1), (1, 1), (2, 1)]
HEIGHTS = (1.2, 1.5, 2.0, 3.0, 5.0, 7.0, 10.0, 15.0)
TILTS = (-0.3, -0.15, -0.05, 0.0, 0.05, 0.15, 0.3)
WALL_TABLE = (1.2, 1.5, 2.0, 3.0, 5.0, 10.0)
ESCAPE_HEIGHT = 30.0
STUDY_HEIGHTS = (1.2, 1.5, 2.0, 3.0, 5.0, 7.0, 10.0, 15.0, 20.0, 50.0)
STUDY_TILTS = (-0.3, -0.15, 0.0, 0.15, 0.3, 0.5, 0.6, 0.8, 1.0)
DOUBLING_CYCLES = 400  # how far the doubling cycle is looked for


def factor_table() -> None:
    print("## Self-mobility above the wall: exact against RPB\n")
    print(
        "| h / a | parallel exact | parallel RPB | RPB / exact | normal exact | normal RPB | RPB / exact |"
    )
    print("|---|---|---|---|---|---|---|")
    for h in (1.01, 1.05, 1.1, 1.2, 1.5, 2.0, 3.0, 5.0, 10.0):
        pe, ne = (float(v) for v in wall_self_factors(np.float64(1 / h), "exact"))
        pr, nr = (float(v) for v in wall_self_factors(np.float64(1 / h), "rpb"))
        print(
            f"| {h:g} | {pe:.5f} | {pr:.5f} | {pr / pe:.4f} | {ne:.5f} | {nr:.5f} | {nr / ne:.4f} |"
        )


def first_cycle(model: str) -> dict[str, np.ndarray]:
    p = scene_params(
        "ng", Scene(medium="wall", height=10.0, self_mobility=model), dtype=jnp.float64
    )
    h = np.asarray(WALL_TABLE)
    r = scene_rollout_batch(batch_starts(p, height=h), SQUARE)
    return {"x": r.x[:, 3, 0], "tilt": r.tilt[:, 3, 0], "z": r.z[:, 3, 0] - h}


def fates(model: str, cycles: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    hh, tt = np.meshgrid(HEIGHTS, TILTS, indexing="ij")
    valid = hh.ravel() - 10.0 * np.abs(np.sin(tt.ravel())) - 1.0 >= 0.1  # end spheres clear
    p = scene_params(
        "ng", Scene(medium="wall", height=10.0, self_mobility=model), dtype=jnp.float64
    )
    r = scene_rollout_batch(batch_starts(p, height=hh.ravel(), tilt=tt.ravel()), SQUARE * cycles)
    z = r.z[:, :, 0]
    contact = np.asarray(r.contact).reshape(z.shape[0], -1)
    first = np.where(contact.any(1), contact.argmax(1) // 4, -1)
    tail = z[:, -1] - z[:, -cycles // 10 * 4]
    late = z[:, z.shape[1] // 2 :]
    fate = np.where(
        ~valid,
        ".",
        np.where(first >= 0, "T", np.where((z[:, -1] > ESCAPE_HEIGHT) & (tail > 0), "E", "G")),
    )
    lo, hi = late.min(1), late.max(1)
    return (
        fate.reshape(hh.shape),
        first.reshape(hh.shape),
        np.stack([lo, hi, z[:, -1]], -1).reshape(*hh.shape, 3),
    )


def study_fate_map() -> None:
    """The wall study's own runs of the square stroke over (height, tilt), float32, its fate
    rule at its default horizon; and the first cycle each start reaches twice its height."""
    steps = SPECS["wall"].steps
    init = initial("paper", 0, "ng")
    codes = stroke_codes("square", 1, 4, 1)
    moves = [tuple(int(v) for v in decode_action(int(c))) for c in codes]
    starts = [
        (h, t) for h in STUDY_HEIGHTS for t in STUDY_TILTS if t == 0.0 or wall_start_clears(h, t)
    ]
    p = scene_params("ng", Scene(medium="wall", height=10.0), dtype=jnp.float32, init=init)
    hh, tt = (np.array(v) for v in zip(*starts))
    cycles = max(DOUBLING_CYCLES, steps // 4)
    r = scene_rollout_batch(batch_starts(p, height=hh, tilt=tt), moves * cycles)
    z = np.asarray(r.z[:, :, 0], np.float64)
    contact = np.asarray(r.contact).reshape(z.shape[0], -1)
    cells = {}
    for i, (h, t) in enumerate(starts):
        f, _ = study_fate(z[i, :steps], h, contact[i, :steps])
        up = np.nonzero(z[i, 3::4] >= 2.0 * h)[0]
        touched = np.nonzero(contact[i])[0]
        twice = (
            "-" if not up.size or (touched.size and touched[0] // 4 <= up[0]) else f"{up[0] + 1}"
        )
        cells[h, t] = f"{f[0].upper()} {z[i, steps - 1]:.3g} / {twice}"
    defaults = StudyOptions()
    print(
        f"\n## The wall study's fates at its default horizon ({steps} steps = {steps // 4} square cycles), "
        "float32, its start (arms 10, 6) (fate T/E/G, final height / first cycle at twice the start height, "
        f"- none within {cycles}; . the start touches the wall; * the default grid)\n"
    )
    print("| h0 \\ tilt0 | " + " | ".join(f"{t:+g}" for t in STUDY_TILTS) + " |")
    print("|---|" + "---|" * len(STUDY_TILTS))
    for h in STUDY_HEIGHTS:
        row = []
        for t in STUDY_TILTS:
            mark = "*" if h in defaults.heights and t in defaults.tilts else ""
            row.append(cells[h, t] + mark if (h, t) in cells else ".")
        print(f"| {h:g} | " + " | ".join(row) + " |")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--cycles", type=int, default=1200)
    ap.add_argument("--models", default="exact,rpb", help="self-mobility models of the fate maps")
    ap.add_argument("--study-only", action="store_true", help="only the wall study's fate map")
    args = ap.parse_args()
    cycles = args.cycles
    t0 = time.time()
    if args.study_only:
        study_fate_map()
        print(f"\n({time.time() - t0:.0f} s)")
        return
    factor_table()
    for model in ("exact", "rpb"):
        w = first_cycle(model)
        print(f"\n## First square cycle above the wall, self_mobility={model!r}\n")
        print("| h / a | " + " | ".join(f"{h:g}" for h in WALL_TABLE) + " |")
        print("|---|" + "---|" * len(WALL_TABLE))
        print("| X (a) | " + " | ".join(f"{v:.6f}" for v in w["x"]) + " |")
        print("| tilt (rad) | " + " | ".join(f"{v:+.3e}" for v in w["tilt"]) + " |")
        print("| height (a) | " + " | ".join(f"{v:+.3e}" for v in w["z"]) + " |")
    for model in args.models.split(","):
        fate, first, zend = fates(model, cycles)
        print(
            f"\n## Fate map, {cycles} cycles, self_mobility={model!r} (T: trapped at cycle; E: escaping, final height; G: gliding, heights over the second half)\n"
        )
        print("| h0 \\ tilt0 | " + " | ".join(f"{t:+g}" for t in TILTS) + " |")
        print("|---|" + "---|" * len(TILTS))
        for i, h in enumerate(HEIGHTS):
            cells = []
            for j in range(len(TILTS)):
                f = fate[i, j]
                lo, hi, end = zend[i, j]
                cells.append(
                    {"T": f"T{first[i, j]}", "E": f"E {end:.3g}", ".": "."}.get(
                        f, f"G {lo:.3g}-{hi:.3g}"
                    )
                )
            print(f"| {h:g} | " + " | ".join(cells) + " |")
    study_fate_map()
    print(f"\n({time.time() - t0:.0f} s)")


if __name__ == "__main__":
    main()
