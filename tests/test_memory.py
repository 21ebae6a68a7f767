"""The run's memory (jswim.agents.memory): clearing rule, history, observed-progress summary."""

from __future__ import annotations

import math

from jswim.agents.memory import ClearingRule, History, MoveStats, render_summary, shape_key
from jswim.prompt import Action, HistoryRecord, SwimmerText

LO, HI = -math.pi / 3, math.pi / 3
PURCELL = SwimmerText(2, LO, HI, dof_decimals=3)


def rec(step: int) -> HistoryRecord:
    return HistoryRecord(step, (HI, HI), (LO, HI), Action(1, -1), 0.0, 0.0)


def test_clearing_rule():
    rule = ClearingRule()  # after 5 steps, last 4 below 0.01
    assert not rule.should_clear(4, [0.0] * 4)  # too early
    assert rule.should_clear(5, [0.0] * 5)
    assert not rule.should_clear(5, [0.0, 0.0, 0.0, 0.01, 0.0])  # sum 0.01 is not below
    assert rule.should_clear(6, [0.5, 0.004, 0.003, -0.002, 0.004])
    assert not rule.should_clear(9, [0.0] * 3)  # fewer than window steps since the last clear
    assert not ClearingRule(enabled=False).should_clear(10, [0.0] * 10)
    assert ClearingRule(min_steps=2, window=2, threshold=0.1).should_clear(2, [0.05, 0.04])


def test_history_clears_and_rebuilds():
    h = History()
    cleared = [h.add(rec(k), 0.0) for k in range(1, 13)]
    # Clears at step 5, then needs 4 fresh steps: 9, then 13 would be next.
    assert [k for k, c in enumerate(cleared, 1) if c] == [5, 9]
    assert h.n_clears == 2 and len(h.records) == 3 and h.records[0].step == 10
    h2 = History()
    for k in range(1, 13):
        h2.add(rec(k), 0.05)
    assert h2.n_clears == 0 and [r.step for r in h2.last(3)] == [10, 11, 12]


def test_summary_sentence_reports_observed_means_without_negative_numbers():
    stats = MoveStats()
    here = shape_key(PURCELL, (HI, HI))
    stats.add(here, Action(1, -1), 0.0123)
    stats.add(here, Action(1, -1), 0.0097)  # mean 0.011 -> 11 thousandths
    stats.add(here, Action(2, -1), -0.0052)
    stats.add(shape_key(PURCELL, (LO, HI)), Action(2, -1), 0.5)  # another shape: not reported here
    options = [Action(2, -1), Action(1, -1), Action(1, 0)]
    stats.add(here, Action(1, 0), 0.0)
    text = render_summary(PURCELL, stats, (HI, HI), options, +1)
    assert text.startswith("Observed so far from the current shape (D1, D2) = (1.047, 1.047):")
    assert "[2, -1] moved X 5 away from +x on average in 1 try" in text
    assert "[1, -1] moved X 11 toward +x on average in 2 tries" in text
    assert "[1, 0] left X unchanged in 1 try" in text
    assert text.index("[2, -1]") < text.index("[1, -1]") < text.index("[1, 0]")  # the options' order
    assert "-5" not in text and "500" not in text
    # Progress is recorded in the target direction and named after it; untried pairs are said so.
    text = render_summary(PURCELL, stats, (HI, HI), [Action(1, -1), Action(1, 1)], -1)
    assert "[1, -1] moved X 11 toward -x" in text and "[1, 1] not tried yet" in text
