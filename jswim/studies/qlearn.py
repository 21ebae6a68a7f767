"""The Q-learning baseline's steps-to-learn distributions over many seeds (``jswim qlearn``).

Many independent learners per (swimmer, direction, zeta) are trained in vectorised calls
([`jswim.agents.qlearning.train`][jswim.agents.qlearning.train], sharded over every device) and judged by the shared
criterion, ``chunk`` learners at a time so that 10^6 seeds fit in bounded memory; steps to learn
are summarised by [`jswim.judging.stats.learn_stats`][jswim.judging.stats.learn_stats], the same statistic as the study tables.
"""

from __future__ import annotations

from typing import NamedTuple
from collections.abc import Callable, Sequence

import jax
import numpy as np

from jswim import sharding
from jswim.agents.defaults import paper_init
from jswim.agents.qlearning import QConfig, QRun, batch_params, evaluate, train
from jswim.env.swimmer_world import SwimmerWorld
from jswim.env import EnvParams, make_params, seed_key
from jswim.errors import check_count
from jswim.judging.gait import PAPER, Criterion, GaitReport
from jswim.judging.stats import learn_stats
from jswim.swimmers.models import make_model


class Summary(NamedTuple):
    """Steps-to-learn distribution and success of one group of learners."""

    swimmer: str
    direction: int
    zeta: float
    action_set: str
    n: int
    learned: float  # fraction that end in the qualifying stroke (within the run)
    success: float  # fraction meeting the success criterion (jswim.judging.gait.Criterion)
    n_learned: int  # learners that learned; the quartiles below are over these (jswim.judging.stats.learn_stats)
    q25: float  # NaN when none learned
    median: float
    q75: float
    mean_x_horizon: float  # mean displacement in the target direction after `horizon` steps
    mean_x_end: float  # ... and at the end of the run
    hist: tuple[
        int, ...
    ] = ()  # learners per steps-to-learn value: hist[k] learned at step k (hist[0] = 0)


class Outcomes(NamedTuple):
    """Per-learner verdicts: all a study keeps of a trained learner (arrays over learners)."""

    direction: np.ndarray  # float (B,)
    zeta: np.ndarray  # float (B,)
    learned: np.ndarray  # bool (B,)
    success: np.ndarray  # bool (B,)
    steps_to_learn: np.ndarray  # int (B,), -1 when never learned
    x_horizon: np.ndarray  # X after `horizon` steps
    x_end: np.ndarray  # X after the last step

    @staticmethod
    def of(
        run: QRun, params: EnvParams, report: GaitReport, horizon: int = PAPER.horizon
    ) -> Outcomes:
        x = np.asarray(run.x)
        h = min(horizon, x.shape[1]) - 1
        shape = report.learned.shape
        return Outcomes(
            np.broadcast_to(np.asarray(params.direction), shape),
            np.broadcast_to(np.asarray(params.zeta), shape),
            np.asarray(report.learned),
            np.asarray(report.success),
            np.asarray(report.steps_to_learn),
            x[:, h],
            x[:, -1],
        )

    @staticmethod
    def concat(parts: Sequence[Outcomes]) -> Outcomes:
        return Outcomes(*(np.concatenate(cols) for cols in zip(*parts)))


def summarize(
    run: QRun,
    params: EnvParams,
    report: GaitReport,
    *,
    swimmer: str,
    action_set: str,
    horizon: int = PAPER.horizon,
) -> list[Summary]:
    """One `Summary` per (direction, zeta) group of a batched run.

    Steps to learn follow [`jswim.judging.stats.learn_stats`][jswim.judging.stats.learn_stats], as in every study table: quartiles
    over the learners that learned, and the count of those that did (never-learned learners are
    counted, not turned into numbers). ``horizon`` is where ``mean_x_horizon`` is read.
    """
    return summarize_outcomes(
        Outcomes.of(run, params, report, horizon), swimmer=swimmer, action_set=action_set
    )


def summarize_outcomes(out: Outcomes, *, swimmer: str, action_set: str) -> list[Summary]:
    """[`summarize`][jswim.studies.report.summarize] from per-learner verdicts (e.g. gathered chunk by chunk)."""
    rows = []
    for d, z in sorted(
        set(zip(out.direction.tolist(), out.zeta.tolist())), key=lambda g: (-g[0], g[1])
    ):
        sel = (out.direction == d) & (out.zeta == z)
        stl = out.steps_to_learn[sel]
        ls = learn_stats(stl.tolist())  # -1 marks never learned
        hist = np.bincount(stl[stl >= 1]) if np.any(stl >= 1) else np.zeros(1, int)
        rows.append(
            Summary(
                swimmer,
                int(d),
                float(z),
                action_set,
                int(sel.sum()),
                float(out.learned[sel].mean()),
                float(out.success[sel].mean()),
                ls.learned,
                ls.q25,
                ls.median,
                ls.q75,
                float(np.mean(d * out.x_horizon[sel], dtype=np.float64)),
                float(np.mean(d * out.x_end[sel], dtype=np.float64)),
                tuple(int(v) for v in hist),
            )
        )
    return rows


#: Learners trained and judged at once by `study`: bounds its memory (~10 kB per learner
#: at 200 steps, most of it the judge's replay) whatever ``n_seeds`` is.
STUDY_CHUNK = 65_536


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
    chunk: int = STUDY_CHUNK,
    progress: Callable[[int, int], None] | None = None,
) -> list[Summary]:
    """Train ``n_seeds`` learners per (swimmer, direction, zeta) and summarise each group.

    Parameters
    ----------
    config : QConfig
        Hyperparameters shared by every learner.
    swimmers, directions, zetas : sequences
        The grid; one batched call per swimmer and chunk covers all its directions and noise
        levels.
    n_seeds : int
        Learners per group (10^6 and more: learners are trained and judged ``chunk`` at a time,
        each chunk sharded over every device, and only their verdicts are kept).
    init : sequence of int or str, optional
        Initial configuration (default: each swimmer's paper start,
        `jswim.agents.defaults.paper_init`: Purcell (+, +), NG (10, 6)); ``"random"``
        draws one per learner.
    seed : int
        Seed of the whole study. Learner ``i`` of a swimmer gets key ``i`` of one split, so the
        results depend neither on ``chunk`` nor on the device count.
    criterion : Criterion
        The success criterion (default: the paper's).
    chunk : int
        Learners per chunk (default `STUDY_CHUNK`).
    progress : callable, optional
        ``progress(done, total)`` after every chunk, in learners over the whole study.

    Returns
    -------
    list of Summary
        One row per (swimmer, direction, zeta).

    Raises
    ------
    ConfigError
        ``n_seeds`` or ``chunk`` not a count in ``1..2**31 - 1`` ([`jswim.errors.check_count`][jswim.errors.check_count]).
    """
    n_seeds, chunk = check_count("seeds", n_seeds), check_count("chunk", chunk)
    rows: list[Summary] = []
    key = seed_key(seed)
    grid = [(d, z) for d in directions for z in zetas]
    total, done = len(swimmers) * len(grid) * n_seeds, 0
    for swimmer in swimmers:
        base = make_params(swimmer, init=paper_init(make_model(swimmer)) if init is None else init)
        world = SwimmerWorld(base.model)
        d_arr = np.repeat([g[0] for g in grid], n_seeds).astype(float)
        z_arr = np.repeat([g[1] for g in grid], n_seeds).astype(float)
        key, sub = jax.random.split(key)
        keys = jax.random.split(sub, d_arr.size)
        parts = []
        for start, stop in sharding.chunks(d_arr.size, chunk):
            params = batch_params(
                base, stop - start, direction=d_arr[start:stop], zeta=z_arr[start:stop]
            )
            # on several hosts each process holds its own block: gather them before judging
            run = sharding.to_host(train(world, params, keys[start:stop], config))
            report = evaluate(run, params, criterion=criterion)
            parts.append(Outcomes.of(run, params, report, criterion.horizon))
            done += stop - start
            if progress is not None:
                progress(done, total)
        rows += summarize_outcomes(
            Outcomes.concat(parts), swimmer=swimmer, action_set=config.action_set
        )
    return rows


def format_table(rows: Sequence[Summary]) -> str:
    """Plain-text table of summaries."""

    def num(v: float) -> str:
        return "-" if not np.isfinite(v) else f"{v:g}"

    head = (
        f"{'swimmer':8} {'dir':>3} {'zeta':>4} {'actions':14} {'n':>6} {'learned':>15} {'success':>7} "
        f"{'q25':>5} {'median':>6} {'q75':>5} {'X@50':>7} {'X@end':>7}"
    )
    lines = [head, "-" * len(head)]
    for r in rows:
        lines.append(
            f"{r.swimmer:8} {'+x' if r.direction > 0 else '-x':>3} {r.zeta:4g} {r.action_set:14} {r.n:6d} "
            f"{f'{r.n_learned} of {r.n}':>15} {r.success:7.3f} {num(r.q25):>5} {num(r.median):>6} {num(r.q75):>5} "
            f"{r.mean_x_horizon:7.3f} {r.mean_x_end:7.3f}"
        )
    lines.append(
        "q25/median/q75: steps to learn over the learners that learned (jswim.judging.stats.learn_stats), counted "
        "from 1 as in the paper: the step at which the final stroke starts"
    )
    return "\n".join(lines)
