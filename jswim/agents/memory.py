"""The run's memory: the history records since the last clear, the paper's clearing rule, and the
observed-progress statistics behind the summary sentence (a variant; off in the paper's protocol).

Text of a record line lives in [`jswim.prompt`][jswim.prompt] ([`HistoryRecord`][jswim.prompt.HistoryRecord]); this
module decides which records the model still sees.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from collections.abc import Sequence

from jswim.errors import ConfigError
from jswim.prompt import Action, HistoryRecord, SwimmerText, format_dof


@dataclass(frozen=True)
class ClearingRule:
    """The history clearing scheme (paper: "when the swimmer's displacement within the last few
    steps falls below a threshold, such as 0.01, we erase ... the entire record"; the numbers
    are the authors' code's, per swimmer, in `jswim.agents.defaults.default_clearing`).

    After each step the history is erased when all of these hold:

    - at least ``min_steps`` steps have run in the run;
    - at least ``min_records`` records were added since the last clear (or the start);
    - the displacement in the target direction summed over the run's last ``window`` steps
      (all of them when fewer; the window may reach back past a clear, as in the code),
      rounded to ``decimals`` when given, is below ``threshold``.

    Summing ``direction * dX`` and comparing with ``threshold`` is the code's two tests in one:
    ``sum dX < 0.01`` toward +x, ``sum dX > -0.01`` toward -x (rounding is symmetric).
    Counting records since the last clear keeps one bad stretch from clearing at every step.

    Attributes
    ----------
    min_steps : int
        Steps that must have run before any clear (the code: from step 6).
    min_records : int
        Records since the last clear before another clear (6).
    window : int
        Steps summed (three-DOF 4, four-link 40, four-sphere 5).
    threshold : float
        In units of ``a`` (three-DOF 0.01, four-DOF 0.05).
    decimals : int or None
        Round the sum to this many decimals before comparing (three-DOF and four-sphere: 3);
        ``None``: no rounding (four-link).
    enabled : bool
        ``False`` never clears.
    """

    min_steps: int = 6
    min_records: int = 6
    window: int = 4
    threshold: float = 0.01
    decimals: int | None = 3
    enabled: bool = True

    def __post_init__(self) -> None:
        if self.window < 1 or self.min_records < 0 or self.min_steps < 0:
            raise ConfigError(
                f"a clearing rule needs window >= 1, min_records >= 0 and min_steps >= 0, got {self}"
            )

    def should_clear(self, n_steps: int, n_records: int, progress: Sequence[float]) -> bool:
        """Whether to clear now.

        Parameters
        ----------
        n_steps : int
            Steps executed so far in the run (including the one just taken).
        n_records : int
            Records added since the last clear (or the start), the one just taken included.
        progress : sequence of float
            ``direction * dX`` of the run's steps so far (at least its last ``window``), oldest first.
        """
        if not self.enabled or n_steps < self.min_steps or n_records < self.min_records:
            return False
        total = math.fsum(progress[-self.window :])
        if self.decimals is not None:
            total = round(total, self.decimals)
        return total < self.threshold

    def describe(self) -> str:
        """One line for metadata and tables."""
        if not self.enabled:
            return "never"
        rounding = f", rounded to {self.decimals} decimals," if self.decimals is not None else ""
        return (
            f"from step {self.min_steps}, with >= {self.min_records} records since the last clear: clear "
            f"when the last {self.window} displacements toward the target sum{rounding} to < {self.threshold:g}"
        )


@dataclass
class History:
    """Records since the last clear, plus the run's progress the clearing rule looks at.

    Records are numbered as the model sees them: the index restarts at 1 after each clear
    (the authors' code), whatever step of the run they come from.
    """

    rule: ClearingRule = field(default_factory=ClearingRule)
    records: list[HistoryRecord] = field(default_factory=list)
    progress: list[float] = field(default_factory=list)  # the run's, every step (never cleared)
    n_steps: int = 0
    n_clears: int = 0

    def add(self, record: HistoryRecord, progress: float) -> bool:
        """Append a step (renumbered as the next record since the last clear); clear if the rule
        says so. Returns whether it cleared."""
        self.records.append(replace(record, step=len(self.records) + 1))
        self.progress.append(float(progress))
        self.n_steps += 1
        if self.rule.should_clear(self.n_steps, len(self.records), self.progress):
            self.records.clear()
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
    sw: SwimmerText,
    stats: MoveStats,
    dof_values: Sequence[float],
    options: Sequence[Action],
    direction: int,
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
            items.append(
                SUMMARY_TRIED.format(
                    action=a.text(),
                    amount=amount,
                    way=way,
                    direction=target,
                    count=count,
                    tries=tries,
                )
            )
    return SUMMARY_SENTENCE.format(
        dof_names=", ".join(sw.names), shape=", ".join(shape), moves="; ".join(items)
    )
