"""The Q-learning baseline's steps-to-learn distributions over many seeds (``jswim qlearn``).

Many independent learners per (swimmer, direction, zeta) are trained in one vectorised call
(:func:`jswim.agents.qlearning.train_batch`) and judged by the shared criterion; steps to learn
are summarised by :func:`jswim.stats.learn_stats`, the same statistic as the study tables.
"""

from __future__ import annotations

from typing import NamedTuple, Sequence

import jax
import numpy as np

from jswim.agents.qlearning import QConfig, QRun, batch_params, evaluate, train_batch
from jswim.env import EnvParams, make_params
from jswim.gait import PAPER, Criterion, GaitReport
from jswim.stats import learn_stats


class Summary(NamedTuple):
    """Steps-to-learn distribution and success of one group of learners."""

    swimmer: str
    direction: int
    zeta: float
    action_set: str
    n: int
    learned: float  # fraction that end in the qualifying stroke (within the run)
    success: float  # fraction meeting the success criterion (jswim.gait.Criterion)
    n_learned: int  # learners that learned; the quartiles below are over these (jswim.stats.learn_stats)
    q25: float  # NaN when none learned
    median: float
    q75: float
    mean_x_horizon: float  # mean displacement in the target direction after `horizon` steps
    mean_x_end: float  # ... and at the end of the run


def summarize(
    run: QRun, params: EnvParams, report: GaitReport, *, swimmer: str, action_set: str,
    horizon: int = PAPER.horizon,
) -> list[Summary]:
    """One :class:`Summary` per (direction, zeta) group of a batched run.

    Steps to learn follow :func:`jswim.stats.learn_stats`, as in every study table: quartiles
    over the learners that learned, and the count of those that did (never-learned learners are
    counted, not turned into numbers). ``horizon`` is where ``mean_x_horizon`` is read.
    """
    direction = np.broadcast_to(np.asarray(params.direction), report.learned.shape)
    zeta = np.broadcast_to(np.asarray(params.zeta), report.learned.shape)
    x = np.asarray(run.x)
    h = min(horizon, x.shape[1]) - 1
    rows = []
    for d, z in sorted(set(zip(direction.tolist(), zeta.tolist())), key=lambda g: (-g[0], g[1])):
        sel = (direction == d) & (zeta == z)
        ls = learn_stats(report.steps_to_learn[sel].tolist())  # -1 marks never learned
        rows.append(
            Summary(
                swimmer, int(d), float(z), action_set, int(sel.sum()),
                float(report.learned[sel].mean()), float(report.success[sel].mean()),
                ls.learned, ls.q25, ls.median, ls.q75,
                float(np.mean(d * x[sel, h])), float(np.mean(d * x[sel, -1])),
            )
        )
    return rows


def study(
    config: QConfig = QConfig(),
    *,
    swimmers: Sequence[str] = ("purcell", "ng"),
    directions: Sequence[int] = (1, -1),
    zetas: Sequence[float] = (0.0,),
    n_seeds: int = 1000,
    init: Sequence[int] | str | None = None,
    seed: int = 0,
    criterion: Criterion = PAPER,
) -> list[Summary]:
    """Train ``n_seeds`` learners per (swimmer, direction, zeta) and summarise each group.

    Parameters
    ----------
    config : QConfig
        Hyperparameters shared by every learner.
    swimmers, directions, zetas : sequences
        The grid; one batched call per swimmer covers all its directions and noise levels.
    n_seeds : int
        Learners per group.
    init : sequence of int or str, optional
        Initial configuration (default (+, +)); ``"random"`` draws one per learner.
    seed : int
        Seed of the whole study.
    criterion : Criterion
        The success criterion (default: the paper's).

    Returns
    -------
    list of Summary
        One row per (swimmer, direction, zeta).
    """
    rows: list[Summary] = []
    key = jax.random.PRNGKey(seed)
    for swimmer in swimmers:
        base = make_params(swimmer, init=init)
        grid = [(d, z) for d in directions for z in zetas]
        d_arr = np.repeat([g[0] for g in grid], n_seeds).astype(float)
        z_arr = np.repeat([g[1] for g in grid], n_seeds).astype(float)
        params = batch_params(base, d_arr.size, direction=d_arr, zeta=z_arr)
        key, sub = jax.random.split(key)
        run = train_batch(jax.random.split(sub, d_arr.size), params, config)
        report = evaluate(run, params, criterion=criterion)
        rows += summarize(run, params, report, swimmer=swimmer, action_set=config.action_set,
                          horizon=criterion.horizon)
    return rows


def format_table(rows: Sequence[Summary]) -> str:
    """Plain-text table of summaries."""

    def num(v: float) -> str:
        return "-" if not np.isfinite(v) else f"{v:g}"

    head = f"{'swimmer':8} {'dir':>3} {'zeta':>4} {'actions':14} {'n':>6} {'learned':>15} {'success':>7} " \
           f"{'q25':>5} {'median':>6} {'q75':>5} {'X@50':>7} {'X@end':>7}"
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(
            f"{r.swimmer:8} {'+x' if r.direction > 0 else '-x':>3} {r.zeta:4g} {r.action_set:14} {r.n:6d} "
            f"{f'{r.n_learned} of {r.n}':>15} {r.success:7.3f} {num(r.q25):>5} {num(r.median):>6} {num(r.q75):>5} "
            f"{r.mean_x_horizon:7.3f} {r.mean_x_end:7.3f}"
        )
    lines.append("q25/median/q75: steps to learn over the learners that learned (jswim.stats.learn_stats)")
    return "\n".join(lines)
