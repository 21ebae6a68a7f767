"""Small statistics for study summaries: proportions and means with confidence intervals."""

from __future__ import annotations

import math
from typing import NamedTuple
from collections.abc import Sequence

import numpy as np


def wilson_interval(successes: int, n: int, z: float = 1.96) -> tuple[float, float]:
    """Wilson score interval of a proportion (95% by default); ``(nan, nan)`` when ``n == 0``.

    Unlike the normal approximation it stays inside [0, 1] and is sensible at p = 0 or 1, which
    is where small LLM studies (10 runs per level) often land.
    """
    if n <= 0:
        return (math.nan, math.nan)
    p = successes / n
    den = 1.0 + z * z / n
    centre = (p + z * z / (2 * n)) / den
    half = z * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n)) / den
    # The interval holds p (exactly 0 at k = 0 and 1 at k = n); rounding alone can put the bound
    # 1e-16 on the wrong side (n = 6, 11, 21, ...), which an error bar of p - lo would draw negative.
    return (min(p, max(0.0, centre - half)), max(p, min(1.0, centre + half)))


def mean_interval(
    values: Sequence[float], level: float = 0.95, n_boot: int = 2000, seed: int = 0
) -> tuple[float, float, float]:
    """Mean and a percentile-bootstrap interval (approximate; exact for no small sample).

    Returns ``(mean, lo, hi)``; with fewer than two finite values the interval is the mean itself.
    """
    x = _finite(values)
    if x.size == 0:
        return (math.nan, math.nan, math.nan)
    m = float(x.mean())
    if x.size < 2:
        return (m, m, m)
    rng = np.random.default_rng(seed)
    boots = x[rng.integers(0, x.size, (n_boot, x.size))].mean(axis=1)
    a = (1 - level) / 2
    return (m, float(np.quantile(boots, a)), float(np.quantile(boots, 1 - a)))


def median_interval(
    values: Sequence[float], level: float = 0.95, n_boot: int = 2000, seed: int = 0
) -> tuple[float, float, float]:
    """Median and a percentile-bootstrap interval (approximate; coarse for small samples).

    Returns ``(median, lo, hi)``; with fewer than two finite values the interval is the median
    itself, nan with none.
    """
    x = _finite(values)
    if x.size == 0:
        return (math.nan, math.nan, math.nan)
    m = float(np.median(x))
    if x.size < 2:
        return (m, m, m)
    rng = np.random.default_rng(seed)
    boots = np.median(x[rng.integers(0, x.size, (n_boot, x.size))], axis=1)
    a = (1 - level) / 2
    return (m, float(np.quantile(boots, a)), float(np.quantile(boots, 1 - a)))


def quartiles(values: Sequence[float]) -> tuple[float, float, float]:
    """25th, 50th and 75th percentiles of the finite values (nan if none)."""
    x = _finite(values)
    if x.size == 0:
        return (math.nan, math.nan, math.nan)
    q = np.quantile(x, [0.25, 0.5, 0.75])
    return (float(q[0]), float(q[1]), float(q[2]))


class LearnStats(NamedTuple):
    """Steps to learn over a group of runs: the one definition every table uses.

    Runs that never learned are not numbers of steps: they are counted (``n - learned``), never
    turned into +inf and never silently dropped. The quartiles are over the runs that learned
    (NaN when none did), so a table reads "median 16 [13-18], 97 of 100 learned".
    """

    n: int  # runs in the group
    learned: int  # runs that learned (ended in the qualifying stroke)
    q25: float
    median: float
    q75: float

    def label(self) -> str:
        """``"16 [13-18], 97 of 100 learned"`` (``"0 of 4 learned"`` when none did)."""
        head = (
            ""
            if self.learned == 0
            else f"{_num(self.median)} [{_num(self.q25)}-{_num(self.q75)}], "
        )
        return f"{head}{self.learned} of {self.n} learned"


def learn_stats(steps_to_learn: Sequence[float | None]) -> LearnStats:
    """[`LearnStats`][jswim.judging.stats.LearnStats] of one group; ``None`` (or a negative value, the judge's -1, or a
    non-finite one) marks a run that never learned.

    Values are counted as the paper counts them, from 1 (`jswim.judging.gait.GaitReport.steps_to_learn`:
    the step at which the final stroke starts; 1 = the stroke from the first action).
    """
    done = [float(v) for v in steps_to_learn if v is not None and math.isfinite(v) and v >= 0]
    q = quartiles(done)
    return LearnStats(len(steps_to_learn), len(done), *q)


def _finite(values: Sequence[float | None]) -> np.ndarray:
    return np.asarray([v for v in values if v is not None and math.isfinite(v)], float)


def _num(v: float) -> str:
    return f"{v:g}"
