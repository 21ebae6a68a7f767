"""The run's memory: the history records since the last clear, the paper's clearing rule, and the
observed-progress statistics behind the summary sentence (a variant; off in the paper's protocol).

Text of a record line lives in :mod:`jswim.prompt` (:class:`~jswim.prompt.HistoryRecord`); this
module decides which records the model still sees.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

from jswim.prompt import Action, HistoryRecord, SwimmerText, format_dof


@dataclass(frozen=True)
class ClearingRule:
    """The paper's history clearing scheme.

    After each step, once at least ``min_steps`` steps have run in total and ``window`` steps have
    run since the last clear, the history is erased if the displacement in the target direction
    summed over the last ``window`` steps is below ``threshold``. The records are then rebuilt
    from the following steps. Counting only steps since the last clear keeps one bad stretch from
    clearing again at every step.
    """

    min_steps: int = 5
    window: int = 4
    threshold: float = 0.01
    enabled: bool = True

    def should_clear(self, n_steps: int, progress_since_clear: Sequence[float]) -> bool:
        """Whether to clear now.

        Parameters
        ----------
        n_steps : int
            Steps executed so far in the run (including the one just taken).
        progress_since_clear : sequence of float
            ``direction * dX`` of each step since the last clear (or the start), oldest first.
        """
        if not self.enabled or n_steps < self.min_steps or len(progress_since_clear) < self.window:
            return False
        return math.fsum(progress_since_clear[-self.window :]) < self.threshold


@dataclass
class History:
    """Records since the last clear, plus the progress the clearing rule looks at."""

    rule: ClearingRule = field(default_factory=ClearingRule)
    records: list[HistoryRecord] = field(default_factory=list)
    progress: list[float] = field(default_factory=list)
    n_steps: int = 0
    n_clears: int = 0

    def add(self, record: HistoryRecord, progress: float) -> bool:
        """Append a step; clear if the rule says so. Returns whether it cleared."""
        self.records.append(record)
        self.progress.append(float(progress))
        self.n_steps += 1
        if self.rule.should_clear(self.n_steps, self.progress):
            self.records.clear()
            self.progress.clear()
            self.n_clears += 1
            return True
        return False

    def last(self, n: int) -> list[HistoryRecord]:
        """The last ``n`` records (all when fewer)."""
        return self.records[-n:] if n > 0 else []


# Observed-progress summary (a variant; off in the paper's protocol)

#: The summary sentence; ``{shape}`` is the current DOF values, ``{moves}`` the items below.
SUMMARY_SENTENCE = "Observed so far from the current shape ({dof_names}) = ({shape}): {moves}."
SUMMARY_TRIED = "{action} moved X {amount} {way} {direction} on average in {count} {tries}"
SUMMARY_STILL = "{action} left X unchanged in {count} {tries}"
SUMMARY_UNTRIED = "{action} not tried yet"


def shape_key(sw: SwimmerText, dof_values: Sequence[float]) -> tuple[str, ...]:
    """The shape as the prompt shows it (DOF values at the prompt's precision)."""
    return tuple(format_dof(v, sw.dof_decimals) for v in dof_values)


@dataclass
class MoveStats:
    """Observed progress of every (shape, action) pair of one run so far.

    Only what the run executed and saw (noise included) goes in; nothing is predicted.
    """

    totals: dict[tuple[tuple[str, ...], Action], tuple[float, int]] = field(default_factory=dict)

    def add(self, shape: tuple[str, ...], action: Action, progress: float) -> None:
        """Count one executed step; ``progress`` is its displacement in the target direction."""
        total, count = self.totals.get((shape, action), (0.0, 0))
        self.totals[(shape, action)] = (total + float(progress), count + 1)

    def mean(self, shape: tuple[str, ...], action: Action) -> tuple[float, int] | None:
        """``(mean progress, count)``, or ``None`` when the pair was never tried."""
        got = self.totals.get((shape, action))
        return None if got is None else (got[0] / got[1], got[1])


def render_summary(
    sw: SwimmerText, stats: MoveStats, dof_values: Sequence[float], options: Sequence[Action], direction: int
) -> str:
    """The summary sentence for the actions in ``options`` (in that order) from the current shape.

    Mean progress is rounded to whole thousandths of ``a`` (the unit of X in the prompt) and said
    as a distance toward or away from the target direction, so no number is negative.
    """
    shape = shape_key(sw, dof_values)
    target = "+x" if direction == 1 else "-x"
    items = []
    for a in options:
        got = stats.mean(shape, a)
        if got is None:
            items.append(SUMMARY_UNTRIED.format(action=a.text()))
            continue
        mean, count = got
        amount = round(abs(mean) * 1000)
        tries = "try" if count == 1 else "tries"
        if amount == 0:
            items.append(SUMMARY_STILL.format(action=a.text(), count=count, tries=tries))
        else:
            way = "toward" if mean > 0 else "away from"
            items.append(SUMMARY_TRIED.format(action=a.text(), amount=amount, way=way, direction=target,
                                              count=count, tries=tries))
    return SUMMARY_SENTENCE.format(dof_names=", ".join(sw.names), shape=", ".join(shape), moves="; ".join(items))
