"""Regenerate README's scene-physics numbers (float64), so the text cannot drift from the code.

Prints, for the point-force default and for ``mobility="rpy"``:

* a lone swimmer's square-stroke cycle in the unbounded fluid;
* the wall table (X, tilt and height over the first cycle from tilt 0 at h = 3..50 a) and, for the point forces, the
  wall correction's local exponents (160..200, 200..400, 800..1600 a), a pure power-law
  (log-log least squares) fit over 20..200 a, and the far coefficients c (a/h)^3 of X and
  c (a/h)^4 of tilt and height at h = 1600 a;
* the pair table: change of the common speed per cycle from a lone swimmer's (second joint
  cycle; the front swimmer k quarter cycles ahead) at D = 30 and 60 a, and the local exponent
  at 180..240 a, in the unbounded fluid; the relative drift per cycle there;
* the relative drift per cycle of a pair above the wall (h = 10 a, D = 30 a): swimmers
  alternating (swimmer 1's move, then swimmer 2's, square strokes) and stroking together (k = 0).

And (``--purcell``, alone) Purcell's swimmer above a wall (``docs/scenes.md``): its
square stroke's displacement per cycle against the height of its plane, 1.5..1000 link lengths,
with the drag ratio xi_N / xi_T and the approach to the bulk 0.19124724.

Usage: ``python benchmarks/scene_tables.py [--mobility point|rpy|both] [--purcell]`` (a few
minutes: one compilation per table and mobility; ``--purcell`` about a minute, one table build
per height).
"""

from __future__ import annotations

import argparse

import jax
import jax.numpy as jnp
import numpy as np

from jswim.env import scene_rollout, scene_rollout_batch
from jswim.scenes import (
    Scene,
    batch_starts,
    scene_params,
    scene_reset,
    scene_step,
    scene_step_joint,
)

SQUARE = [(1, -1), (2, -1), (1, 1), (2, 1)]
WALL_TABLE = [3.0, 5.0, 7.0, 10.0, 20.0, 50.0]
FIT = [
    20.0,
    25.0,
    30.0,
    40.0,
    50.0,
    65.0,
    80.0,
    100.0,
    130.0,
    160.0,
    200.0,
]  # tests/physics/test_scene_physics.py's heights
FAR = [160.0, 200.0, 400.0, 800.0, 1600.0]
SEPARATIONS = np.array([30.0, 60.0, 180.0, 240.0])


def lone_cycle(mobility: str) -> float:
    return float(scene_rollout("ng", SQUARE, Scene(medium="free", mobility=mobility)).x[-1, 0])


def wall_cycles(mobility: str, heights: list[float]) -> dict[str, np.ndarray]:
    """X, tilt and height change over the first square cycle from each start height, tilt 0
    (what ``jswim.env.rollout_moves(..., scene=Scene(medium="wall", height=h))`` gives)."""
    params = scene_params(
        "ng", Scene(medium="wall", height=10.0, mobility=mobility), dtype=jnp.float64
    )
    h = np.asarray(heights)
    r = scene_rollout_batch(batch_starts(params, height=h), SQUARE)
    return {"x": r.x[:, 3, 0], "tilt": r.tilt[:, 3, 0], "z": r.z[:, 3, 0] - h}


def joint_cycles(
    mobility: str, medium: str, separations: np.ndarray, height: float = 10.0
) -> np.ndarray:
    """x of both swimmers after each of three joint square cycles, front one k moves ahead:
    shape (k = 0..3, D, 4, 2)."""
    params = scene_params(
        "ng",
        Scene(medium=medium, swimmers=2, separation=30.0, height=height, mobility=mobility),
        dtype=jnp.float64,
    )
    pb = batch_starts(params, separation=separations)
    axes = pb.replace(zeta=None, centre0=0, tilt0=0, arms0=None, obstacles=None)
    dofs = jnp.array([0, 1, 0, 1])
    rocs = jnp.array([-1.0, -1.0, 1.0, 1.0])
    key = jax.random.PRNGKey(0)

    def one(par, k):
        st = scene_reset(par)
        for j in range(3):  # the front swimmer alone, to phase k (a zero ROC does not move)
            st = scene_step(par, st, (1, dofs[j], jnp.where(j < k, rocs[j], 0.0)), key)[0]
        xs = [st.centre[:, 0]]
        for _ in range(3):
            for j in range(4):
                st = scene_step_joint(
                    par,
                    st,
                    jnp.stack([dofs[j], dofs[(j + k) % 4]]),
                    jnp.stack([rocs[j], rocs[(j + k) % 4]]),
                    key,
                )[0]
            xs.append(st.centre[:, 0])
        return jnp.stack(xs)

    over_d = jax.vmap(one, in_axes=(axes, None))
    return np.asarray(jax.jit(jax.vmap(over_d, in_axes=(None, 0)))(pb, jnp.arange(4)))


def alternating_wall_drift(mobility: str) -> float:
    """Relative drift per cycle (second cycle) of a pair above the wall, h = 10 a, D = 30 a,
    the swimmers alternating moves of their square strokes."""
    moves = [(s, d, k) for d, k in SQUARE for s in (1, 2)] * 2
    r = scene_rollout(
        "ng",
        moves,
        Scene(medium="wall", height=10.0, swimmers=2, separation=30.0, mobility=mobility),
    )
    sep = r.x[:, 1] - r.x[:, 0]
    return float(sep[15] - sep[7])


def local_exponent(h1: float, h2: float, c1: float, c2: float) -> float:
    return float(np.log(c1 / c2) / np.log(h2 / h1))


PURCELL_SQUARE = [(2, -1), (1, -1), (2, 1), (1, 1)]  # from the paper's start (+, +), toward +x
PURCELL_HEIGHTS = [1.5, 2.0, 3.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 1000.0]


def purcell_wall_table() -> None:
    """Purcell's square stroke per cycle above a wall, through ``scene_rollout`` (float64)."""
    from jswim.env import rollout_moves
    from jswim.swimmers.wall_rft import LINK_RADIUS, drag_coefficients

    bulk = float(rollout_moves("purcell", PURCELL_SQUARE).x[-1])
    per, ratio = [], []
    for h in PURCELL_HEIGHTS:
        per.append(
            float(scene_rollout("purcell", PURCELL_SQUARE, Scene(medium="wall", height=h)).x[-1, 0])
        )
        xi_t, xi_n = drag_coefficients(h)
        ratio.append(float(xi_n / xi_t))
    print(
        f"== Purcell's swimmer above a wall (link radius {LINK_RADIUS:g} l), square stroke from (+, +)"
    )
    print("| h / l | " + " | ".join(f"{h:g}" for h in PURCELL_HEIGHTS) + " | bulk |")
    print("|---|" + "---|" * (len(PURCELL_HEIGHTS) + 1))
    print("| xi_N / xi_T | " + " | ".join(f"{r:.6f}" for r in ratio) + " | 2 |")
    print("| X per cycle (l) | " + " | ".join(f"{v:.8f}" for v in per) + f" | {bulk:.8f} |")
    print("| X - bulk (l) | " + " | ".join(f"{v - bulk:+.3e}" for v in per) + " | 0 |")
    print(
        "| h (X - bulk) (l^2) | "
        + " | ".join(f"{h * (v - bulk):.5f}" for h, v in zip(PURCELL_HEIGHTS, per))
        + " | |"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--mobility", choices=("point", "rpy", "both"), default="both")
    ap.add_argument("--purcell", action="store_true", help="only Purcell's swimmer above a wall")
    args = ap.parse_args()
    if args.purcell:
        with jax.enable_x64(True):
            purcell_wall_table()
        return
    mobs = ("point", "rpy") if args.mobility == "both" else (args.mobility,)
    with jax.enable_x64(True):
        res = {}
        for mob in mobs:
            free = lone_cycle(mob)
            heights = WALL_TABLE + (FIT + FAR if mob == "point" else [])
            wall = wall_cycles(mob, heights)
            pair = joint_cycles(mob, "free", SEPARATIONS)
            d = pair[:, :, 2] - pair[:, :, 1]  # second cycle, (k, D, swimmer)
            common = d.mean(-1) - free
            res[mob] = (free, wall, common, d)
            print(f"== mobility {mob}")
            print(f"lone swimmer, unbounded fluid: {free:.11f} a per cycle")
            print("| h / a | " + " | ".join(f"{h:g}" for h in WALL_TABLE) + " |")
            for name, unit in (
                ("x", "X per cycle (a)"),
                ("tilt", "tilt per cycle (rad)"),
                ("z", "height per cycle (a)"),
            ):
                fmt = "{:.8f}" if name == "x" else "{:+.2e}"
                print(
                    f"| {unit} | "
                    + " | ".join(fmt.format(v) for v in wall[name][: len(WALL_TABLE)])
                    + " |"
                )
            if mob == "point":
                n0 = len(WALL_TABLE)
                fit_h, far_h = np.asarray(FIT), np.asarray(FAR)
                fit = {k: wall[k][n0 : n0 + len(FIT)] for k in wall}
                far = {k: wall[k][n0 + len(FIT) :] for k in wall}
                dx_fit, dx_far = fit["x"] - free, far["x"] - free
                for i, j in ((0, 1), (1, 2), (3, 4)):
                    print(
                        f"local exponents {far_h[i]:g}..{far_h[j]:g} a: X {local_exponent(far_h[i], far_h[j], dx_far[i], dx_far[j]):.4f}, "
                        f"tilt {local_exponent(far_h[i], far_h[j], far['tilt'][i], far['tilt'][j]):.4f}"
                    )
                px = -np.polyfit(np.log(fit_h), np.log(np.abs(dx_fit)), 1)[0]
                pt = -np.polyfit(np.log(fit_h), np.log(np.abs(fit["tilt"])), 1)[0]
                print(
                    f"pure power law over 20..200 a (the tests' 11 heights, log-log least squares): X {px:.3f}, tilt {pt:.3f}"
                )
                h = far_h[-1]
                print(
                    f"at h = {h:g} a: X - free = {dx_far[-1] * h**3:.2f} (a/h)^3, tilt {far['tilt'][-1] * h**4:.1f} (a/h)^4, "
                    f"height {far['z'][-1] * h**4:.2f} (a/h)^4"
                )
            print("pair, change of the common speed per cycle (free): k = 0..3")
            for i, dd in enumerate(SEPARATIONS[:2]):
                print(
                    f"| D = {dd:g} a | "
                    + " | ".join(f"{common[k, i]:+.3e}" for k in range(4))
                    + " |"
                )
            exps = [
                f"{local_exponent(SEPARATIONS[2], SEPARATIONS[3], common[k, 2], common[k, 3]):.2f}"
                if np.all(np.sign(common[k]) == np.sign(common[k, 0]))
                else "(sign change)"
                for k in range(4)
            ]
            print("| local exponent, D = 180..240 a | " + " | ".join(exps) + " |")
            print(
                f"relative drift per cycle, free, max over D and k: {np.abs(d[..., 1] - d[..., 0]).max():.2e} a"
            )
            wall_pair = joint_cycles(mob, "wall", np.array([30.0]))
            wd = wall_pair[0, 0, 2] - wall_pair[0, 0, 1]
            print(
                f"wall h = 10 a, D = 30 a: relative drift per cycle, alternating {alternating_wall_drift(mob):+.3e} a, "
                f"together (k = 0) {wd[1] - wd[0]:+.3e} a"
            )
        if len(mobs) == 2:
            (f0, w0, c0, _), (f1, w1, c1, _) = res["point"], res["rpy"]
            print("== rpy minus point")
            print(f"lone swimmer: {f1 - f0:+.4e} a per cycle ({(f1 - f0) / f0:+.2%})")
            n0 = len(WALL_TABLE)
            for name in ("x", "tilt", "z"):
                print(
                    f"| {name} | "
                    + " | ".join(f"{v:+.2e}" for v in (w1[name][:n0] - w0[name][:n0]))
                    + " |"
                )
            for i, dd in enumerate(SEPARATIONS[:2]):
                print(
                    f"| common speed change, D = {dd:g} a | "
                    + " | ".join(f"{c1[k, i] - c0[k, i]:+.2e}" for k in range(4))
                    + " |"
                )


if __name__ == "__main__":
    main()
