"""The figures of ``jswim qlearn --out`` and ``jswim ensemble --out`` (see :mod:`jswim.viz.charts`)."""

from __future__ import annotations

import argparse
import csv
import io
from pathlib import Path
from typing import Any, Sequence

from jswim.results import atomic_write, writing


def qlearn_outputs(rows: Sequence[Any], args: argparse.Namespace) -> list[Path]:
    """``qlearn.png``/``.pdf`` (histograms) and ``qlearn.csv`` (the table) in ``args.out``."""
    from jswim.figures import plots
    from jswim.viz.charts import qlearn_figure

    out = Path(args.out)
    rate = "alpha 1" if args.learning_rate is None and args.lr_decay is None else \
        f"alpha {args.learning_rate if args.learning_rate is not None else 1:g}" + \
        (f" x {args.lr_decay:g}^t" if args.lr_decay is not None else "")
    title = (f"Q-learning baseline (tabular, {rate}, {args.steps} training steps, \u03b6 = {args.noise:g}, seed "
             f"{args.seed}): steps to learn over {args.seeds:,} learners per setting")
    paths = plots.save(qlearn_figure(rows, title), out, "qlearn")
    buf = io.StringIO()
    fields = [f for f in rows[0]._fields if f != "hist"] if rows else []
    w = csv.writer(buf)
    w.writerow(fields)
    for r in rows:
        w.writerow([getattr(r, f) for f in fields])
    with writing(out, "choose a writable --out folder"):
        atomic_write(out / "qlearn.csv", buf.getvalue())
    return paths + [out / "qlearn.csv"]


def ensemble_figure_files(stats: Sequence[Any], title: str, direction: int, folder: Path, stem: str) -> list[Path]:
    """The ensemble figure as ``STEM.png`` and ``STEM.pdf`` in ``folder``."""
    from jswim.figures import plots
    from jswim.viz.charts import ensemble_figure

    return plots.save(ensemble_figure(stats, title, direction), folder, stem)
