"""``jswim ensemble``: a stroke or Q-policy over many noisy swimmers, X/a statistics per step,
and with ``--out`` the table (CSV) and a figure of mean X/a with quantile bands."""

from __future__ import annotations

import argparse
import csv
import time
from pathlib import Path
from typing import Any
from collections.abc import Sequence

from jswim.action_codes import decode_action
from jswim.cli import base
from jswim.studies import flags
from jswim.console import Progress
from jswim.errors import ConfigError, check_zeta


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "ensemble",
        help="a stroke or policy over many noisy swimmers: X/a statistics per step",
        description="Run one stroke (default: the signature gait) or the greedy policy of a "
        "trained Q-learner over N noisy swimmers per noise level zeta, on every "
        "device, in bounded chunks; print mean, spread, quantiles of X/a per step "
        "and the fraction of swimmers still moving forward.",
    )
    p.add_argument(
        "--swimmer",
        default="purcell",
        choices=flags.SWIMMERS,
        help="purcell, ng, nlink or nsphere (default purcell)",
    )
    p.add_argument(
        "--direction",
        type=flags.direction,
        default=(1,),
        metavar="DIR",
        help="+x or -x (default +x)",
    )
    p.add_argument(
        "--policy",
        default="signature",
        metavar="POLICY",
        help="signature (the best closed cycle), qlearn (greedy policy of one trained Q-learner), "
        "or moves such as '2,-1 1,-1 2,1 1,1' (DOF,ROC pairs repeated)",
    )
    p.add_argument(
        "--init",
        default=None,
        metavar="LEVELS",
        help="start configuration as signs, e.g. ++, or random (default: the stroke's start; ++ "
        "for qlearn and given moves)",
    )
    p.add_argument(
        "--n", type=int, default=100_000, help="swimmers per noise level (default 100000)"
    )
    p.set_defaults(command_main=main)
    if base.outlined(p):
        return
    from jswim.studies.options import DEFAULT_ZETAS  # lazy: the grids load JAX (not for --help)

    p.add_argument(
        "--zetas",
        type=flags.floats,
        default=DEFAULT_ZETAS,
        metavar="Z1,Z2,...",
        help="noise levels (default the paper's 0,0.5,...,3)",
    )
    p.add_argument("--steps", type=int, default=50, help="steps per swimmer (default 50)")
    p.add_argument(
        "--every", type=int, default=1, metavar="K", help="report every K-th step (default 1)"
    )
    p.add_argument(
        "--window",
        type=int,
        default=None,
        metavar="W",
        help="'moving forward' means X/a grew over the last W steps (default: the stroke's period)",
    )
    p.add_argument(
        "--seed",
        type=int,
        default=0,
        help="seed (default 0); each noise level's noise comes from (seed, zeta), and --policy qlearn "
        "trains its learner with it",
    )
    p.add_argument(
        "--chunk",
        type=int,
        default=1 << 20,
        metavar="N",
        help="swimmers simulated at once (default 1048576); bounds memory",
    )
    p.add_argument(
        "--rows", type=int, default=12, metavar="R", help="reported steps printed per noise level"
    )
    p.add_argument(
        "--out",
        default=None,
        metavar="FILE.csv|FOLDER",
        help="also write every reported step to this CSV and a figure of mean X/a with quantile bands "
        "beside it (FILE.png, .pdf); a folder gets ensemble.csv and ensemble.png",
    )


def main(args: argparse.Namespace) -> int:
    import numpy as np  # lazy: start-up

    from jswim.env import make_params  # lazy: JAX loads only for commands that run
    from jswim.studies import ensemble  # lazy: as above

    base.check_counts(args, "n", "steps", "every", "chunk", "rows")
    ensemble.check_every(args.every, args.steps)
    if len(args.direction) != 1:
        raise ConfigError("--direction takes +x or -x here")
    if not args.zetas:
        raise ConfigError("--zetas must list noise levels >= 0")
    for z in args.zetas:
        check_zeta(z, "--zetas")
    if args.out and Path(args.out).suffix.lower() != ".csv":
        base.check_out_folder(args.out)
    elif args.out and not Path(args.out).resolve().parent.is_dir():
        raise ConfigError(f"--out {args.out}: no such folder {str(Path(args.out).parent)!r}")
    params = make_params(args.swimmer, direction=args.direction[0])
    start = None
    if args.policy == "signature":
        policy, start = ensemble.signature_policy(params)
    elif args.policy == "qlearn":
        policy = None
    else:
        policy = ensemble.stroke_policy(parse_moves(args.policy, params.n_dof), label=args.policy)
    init = args.init if args.init is not None else start
    params = make_params(args.swimmer, direction=args.direction[0], init=init)
    if policy is None:
        policy = ensemble.learned_policy(params, seed=args.seed)
    t0 = time.perf_counter()
    with Progress() as bar:
        stats = ensemble.run(
            policy,
            params,
            n=args.n,
            zetas=args.zetas,
            steps=args.steps,
            every=args.every,
            window=args.window,
            seed=args.seed,
            chunk=args.chunk,
            progress=lambda done, total: bar.update(
                "ensemble",
                done,
                total,
                base.eta(t0, done, total),
                final=done == total,
                unit="swimmer-steps",
            ),
        )
    wall = time.perf_counter() - t0
    start_txt = (
        "".join("+" if v else "-" for v in np.asarray(params.init))
        if np.all(np.asarray(params.init) >= 0)
        else "random"
    )
    moves = (
        " ".join("[{}, {}]".format(*decode_action(int(a))) for a in policy.actions)
        if policy.kind == "stroke"
        else ""
    )
    print(
        f"{params.model.label} swimmer, {policy.label}{' ' + moves if moves else ''}, start {start_txt}, target "
        f"{'+x' if args.direction[0] > 0 else '-x'}: {args.n:,} swimmers per noise level, {args.steps} steps"
    )
    print(ensemble.format_table(stats, args.rows))
    total = args.n * len(args.zetas) * (args.steps // args.every * args.every)
    print(
        f"{total:,} swimmer-steps in {wall:.1f} s ({total / wall:,.0f}/s, compilation included); "
        f"quantiles to within the histogram bin ({max(float(s.resolution.max()) for s in stats):.2g} a at most); "
        f"forward: X/a grew over the last {args.window or policy.period} steps"
    )
    if args.out:
        csv_path = (
            Path(args.out)
            if Path(args.out).suffix.lower() == ".csv"
            else Path(args.out) / "ensemble.csv"
        )
        rows = ensemble.to_rows(stats)
        try:
            csv_path.parent.mkdir(parents=True, exist_ok=True)
            with open(csv_path, "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=list(rows[0]))
                w.writeheader()
                w.writerows(rows)
        except OSError as exc:
            raise ConfigError(f"--out {args.out}: {exc.strerror or exc}") from None
        print(f"table: {csv_path}")
        title = (
            f"{params.model.label} swimmer, {policy.label}{' ' + moves if moves else ''}, start {start_txt}: "
            f"{args.n:,} swimmers per \u03b6"
        )
        for path in ensemble_figure_files(
            stats, title, args.direction[0], csv_path.parent, csv_path.stem
        ):
            if path.suffix == ".png":
                print(f"figure: {path}")
    return 0


def parse_moves(text: str, n_dof: int) -> list[int]:
    """'2,-1 1,-1 2,1 1,1' -> action indices (validated)."""
    from jswim.env import validate_actions  # lazy: JAX loads only for commands that run

    try:
        pairs = [tuple(int(v) for v in item.split(",")) for item in text.replace(";", " ").split()]
    except ValueError:
        raise ConfigError(
            f"--policy: expected signature, qlearn or DOF,ROC pairs like '2,-1 1,-1', got {text!r}"
        ) from None
    if not pairs or any(len(p) != 2 for p in pairs):
        raise ConfigError(
            f"--policy: expected DOF,ROC pairs like '2,-1 1,-1 2,1 1,1', got {text!r}"
        )
    return [int(a) for a in validate_actions(pairs, n_dof)]


def ensemble_figure_files(
    stats: Sequence[Any], title: str, direction: int, folder: Path, stem: str
) -> list[Path]:
    """The ensemble figure as ``STEM.png`` and ``STEM.pdf`` in ``folder``."""
    from jswim.figures.panels import save  # lazy: matplotlib only when asked
    from jswim.viz.charts import ensemble_figure  # lazy: as above

    return save(ensemble_figure(stats, title, direction), folder, stem)
