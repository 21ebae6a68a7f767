"""``jswim qlearn``: the Q-learning baseline's steps-to-learn distributions over many learners,
and with ``--out`` their histograms (``qlearn.png``, ``.pdf``) and table (``qlearn.csv``)."""

from __future__ import annotations

import argparse
import csv
import io
import math
import time
from pathlib import Path
from typing import Any
from collections.abc import Sequence

from jswim.action_codes import ACTION_SETS
from jswim.cli import base
from jswim.studies import flags
from jswim.console import Progress
from jswim.errors import ConfigError, check_zeta


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "qlearn",
        help="Q-learning steps-to-learn distributions",
        description="Train many independent Q-learners on-device and summarise steps-to-learn.",
    )
    p.add_argument(
        "--swimmer",
        type=flags.swimmers,
        default=("purcell", "ng"),
        metavar="NAME",
        help="purcell, ng, both, or a comma-separated list (default both)",
    )
    p.add_argument(
        "--direction",
        type=flags.direction,
        default=(1, -1),
        metavar="DIR",
        help="target direction: +x, -x or both (default both)",
    )
    p.add_argument("--seeds", type=int, default=1000, help="learners per setting (default 1000)")
    p.add_argument(
        "--steps", type=int, default=200, help="training steps per learner (default 200)"
    )
    p.add_argument(
        "--noise",
        type=float,
        default=0.0,
        metavar="ZETA",
        help="noise level zeta >= 0 of the environment (default 0)",
    )
    p.add_argument(
        "--action-set",
        default="both",
        choices=(*ACTION_SETS, "both"),
        help="actions the learner may take: all six (the paper's), only the shape-changing moves, "
        "or both in turn (default both)",
    )
    p.add_argument(
        "--learning-rate",
        type=float,
        default=None,
        metavar="ALPHA",
        help="learning rate alpha in (0, 1] (default 1.0, exact for the noiseless swimmer; smaller "
        "under noise), the start value when --lr-decay is given",
    )
    p.add_argument(
        "--lr-decay",
        type=float,
        default=None,
        metavar="FACTOR",
        help="exponential learning-rate schedule: alpha_t = max(ALPHA * FACTOR**t, --lr-min), "
        "FACTOR in (0, 1] (default: constant alpha)",
    )
    p.add_argument(
        "--lr-min",
        type=float,
        default=0.0,
        metavar="ALPHA_MIN",
        help="floor of the decaying learning rate (default 0)",
    )
    p.add_argument("--seed", type=int, default=0, help="seed of the learners (default 0)")
    p.add_argument(
        "--chunk",
        type=int,
        default=None,
        metavar="N",
        help="learners trained and judged at once (default 65536); bounds memory for --seeds 1000000",
    )
    p.add_argument(
        "--out",
        default=None,
        metavar="FOLDER",
        help="also write a histogram of steps to learn (qlearn.png, .pdf) and the table (qlearn.csv) here",
    )
    p.set_defaults(command_main=main)


def main(args: argparse.Namespace) -> int:
    from jswim.agents.qlearning import QConfig  # lazy: JAX loads only for commands that run
    from jswim.studies import qlearn  # lazy: as above

    base.check_counts(args, "seeds", "steps", "chunk")
    check_zeta(args.noise, "--noise")
    rate = _learning_rate(args)
    sets = ACTION_SETS if args.action_set == "both" else (args.action_set,)
    if args.out is not None:
        base.check_out_folder(args.out)
    every: list[Any] = []
    for action_set in sets:
        t0 = time.perf_counter()
        cfg = QConfig(
            steps=args.steps,
            action_set=action_set,
            **({"learning_rate": rate} if rate is not None else {}),
        )
        with Progress() as bar:
            rows = qlearn.study(
                cfg,
                swimmers=args.swimmer,
                directions=args.direction,
                zetas=(args.noise,),
                n_seeds=args.seeds,
                seed=args.seed,
                chunk=args.chunk or qlearn.STUDY_CHUNK,
                progress=lambda done, total: bar.update(
                    f"Q-learners ({action_set})",
                    done,
                    total,
                    base.eta(t0, done, total),
                    final=done == total,
                    unit="learners",
                ),
            )
        print(qlearn.format_table(rows))
        print(f"({action_set}: {time.perf_counter() - t0:.1f} s including compilation)\n")
        every += rows
    if args.out is not None:
        for path in qlearn_outputs(every, args):
            if path.suffix != ".pdf":
                print(f"{'figure' if path.suffix == '.png' else 'table'}: {path}")
    return 0


def _learning_rate(args: argparse.Namespace) -> Any:
    """``--learning-rate`` / ``--lr-decay`` / ``--lr-min`` as a number or an optax schedule (``None``:
    QConfig's default)."""
    alpha = args.learning_rate
    if alpha is not None and not (math.isfinite(alpha) and 0 < alpha <= 1):
        raise ConfigError(f"--learning-rate must lie in (0, 1], got {alpha}")
    if args.lr_decay is None:
        if args.lr_min:
            raise ConfigError("--lr-min is the floor of a decaying rate; give --lr-decay too")
        return alpha
    import optax  # lazy: only for a schedule

    start = 1.0 if alpha is None else alpha
    if not (math.isfinite(args.lr_decay) and 0 < args.lr_decay <= 1):
        raise ConfigError(f"--lr-decay must lie in (0, 1], got {args.lr_decay}")
    if not (math.isfinite(args.lr_min) and 0 <= args.lr_min <= start):
        raise ConfigError(
            f"--lr-min must lie in [0, {start:g}] (the start rate), got {args.lr_min}"
        )
    return optax.exponential_decay(
        start, transition_steps=1, decay_rate=args.lr_decay, end_value=args.lr_min or None
    )


def qlearn_outputs(rows: Sequence[Any], args: argparse.Namespace) -> list[Path]:
    """``qlearn.png``/``.pdf`` (histograms) and ``qlearn.csv`` (the table) in ``args.out``."""
    from jswim.figures.panels import save  # lazy: matplotlib only when asked
    from jswim.results import atomic_write, writing  # lazy: start-up (NumPy)
    from jswim.viz.charts import qlearn_figure  # lazy: matplotlib only when asked

    out = Path(args.out)
    rate = (
        "alpha 1"
        if args.learning_rate is None and args.lr_decay is None
        else f"alpha {args.learning_rate if args.learning_rate is not None else 1:g}"
        + (f" x {args.lr_decay:g}^t" if args.lr_decay is not None else "")
    )
    title = (
        f"Q-learning baseline (tabular, {rate}, {args.steps} training steps, \u03b6 = {args.noise:g}, seed "
        f"{args.seed}): steps to learn over {args.seeds:,} learners per setting"
    )
    paths = save(qlearn_figure(rows, title), out, "qlearn")
    buf = io.StringIO()
    fields = [f for f in rows[0]._fields if f != "hist"] if rows else []
    w = csv.writer(buf)
    w.writerow(fields)
    w.writerows([getattr(r, f) for f in fields] for r in rows)
    with writing(out, "choose a writable --out folder"):
        atomic_write(out / "qlearn.csv", buf.getvalue())
    return paths + [out / "qlearn.csv"]
