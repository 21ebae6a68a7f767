"""The tables of docs/scenes.md "Schools": a school's speed against N and D (float64).

N NG swimmers in the unbounded fluid (medium ``"free"``), in a line or side by side D apart, each
doing the square stroke at the same time and in phase (``scene_step_joint``: every swimmer moves
the same arm at once). Per cycle (the second, from the start's arms (10, 10)): the school's mean
displacement along x (its speed), each swimmer's, and its change from a lone swimmer's
0.17209143957 a. One compilation per (N, formation), the spacings batched (``batch_starts``).

Usage: ``python benchmarks/school_tables.py [--sizes 1,2,3,4,5] [--line 30,60,120] [--side 5,10,30]``
(prints markdown tables; about 2 minutes on 2 cores).
"""

from __future__ import annotations

import argparse

import jax
import jax.numpy as jnp
import numpy as np

jax.config.update("jax_enable_x64", True)

from jswim.scenes import (
    Scene,
    batch_starts,
    scene_params,
    scene_reset,
    scene_step_joint,
)

SQUARE = [(1, -1), (2, -1), (1, 1), (2, 1)]  # from (10, 10): d1 short, d2 short, d1 long, d2 long
LONE = (
    0.17209143957  # one swimmer's cycle in the unbounded fluid (tests: independent collinear solve)
)


def school_cycles(
    n: int, formation: str, spacings: list[float], cycles: int = 2
) -> dict[str, np.ndarray]:
    """Per-cycle displacement ``(B, S, 2)`` and tilt change ``(B, S)`` of each swimmer over the last
    of ``cycles`` in-phase square cycles, for each spacing."""
    scene = Scene(medium="free", swimmers=n, separation=float(spacings[0]), formation=formation)
    params = scene_params("ng", scene, dtype=jnp.float64)
    if n > 1:
        params = batch_starts(params, separation=np.asarray(spacings, np.float64))
    else:
        params = batch_starts(params, height=np.full(len(spacings), scene.height))
    dofs = jnp.asarray([[d - 1] * n for d, _ in SQUARE] * cycles, jnp.int32)
    rocs = jnp.asarray([[float(k)] * n for _, k in SQUARE] * cycles, jnp.float64)

    def one(centre0, tilt0):
        p = params.replace(centre0=centre0, tilt0=tilt0)

        def body(st, a):
            st, _ = scene_step_joint(p, st, a[0], a[1], jax.random.PRNGKey(0))
            return st, (st.centre, st.centre_lo, st.tilt)

        return jax.lax.scan(body, scene_reset(p), (dofs, rocs))[1]

    hi, lo, tilt = jax.jit(jax.vmap(one))(params.centre0, params.tilt0)
    pos = np.asarray(hi, np.float64) + np.asarray(
        lo, np.float64
    )  # (B, T, S, 2), arms back at (10, 10)
    end, start = 4 * cycles - 1, 4 * cycles - 5
    before = pos[:, start] if start >= 0 else np.asarray(params.centre0, np.float64)
    return {
        "disp": pos[:, end] - before,
        "tilt": np.asarray(tilt)[:, end] - np.asarray(tilt)[:, start],
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    num = lambda kind: lambda s: [kind(v) for v in s.split(",")]
    ap.add_argument("--sizes", type=num(int), default=[1, 2, 3, 4, 5])
    ap.add_argument("--line", type=num(float), default=[30.0, 60.0, 120.0])
    ap.add_argument("--side", type=num(float), default=[5.0, 10.0, 30.0])
    a = ap.parse_args()
    for formation, spacings in (("line", a.line), ("side", a.side)):
        rows = {n: school_cycles(n, formation, spacings) for n in a.sizes}
        print(
            f"\n{formation}: the school's speed (mean X per cycle, a), change from a lone swimmer's {LONE}"
        )
        print("| N | " + " | ".join(f"D = {d:g} a" for d in spacings) + " |")
        print("|---|" + "---|" * len(spacings))
        for n, r in rows.items():
            mean = r["disp"][..., 0].mean(-1)
            print(f"| {n} | " + " | ".join(f"{m:.8f} ({m - LONE:+.2e})" for m in mean) + " |")
        print(
            f"\n{formation}: each swimmer's X per cycle minus the school's (front last / top last), and max |dz|, |dtilt|"
        )
        for n, r in rows.items():
            for i, d in enumerate(spacings):
                dx = r["disp"][i, :, 0] - r["disp"][i, :, 0].mean()
                print(
                    f"N={n} D={d:g}: dx-mean {np.array2string(dx, precision=3, floatmode='fixed')}, "
                    f"dz {np.array2string(r['disp'][i, :, 1], precision=3)}, dtilt {np.array2string(r['tilt'][i], precision=3)}"
                )


if __name__ == "__main__":
    main()
