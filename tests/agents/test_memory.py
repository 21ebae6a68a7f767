"""The run's memory (jswim.agents.memory): clearing rule, history, observed-progress summary."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jswim.agents.defaults import default_clearing
from jswim.agents.memory import ClearingRule, History, MoveStats, render_summary, shape_key
from jswim.prompt import Action, HistoryRecord, SwimmerText
from jswim.swimmers.models import make_model

LO, HI = -math.pi / 3, math.pi / 3
PURCELL = SwimmerText(2, LO, HI, dof_decimals=3)


def rec(step: int) -> HistoryRecord:
    return HistoryRecord(step, (HI, HI), (LO, HI), Action(1, -1), 0.0, 0.0)


def test_clearing_rule_three_dof_follows_the_authors_code():
    # fidelity.md: only from step 6 with >= 6 records since the last clear; the last 4
    # displacements summed, rounded to 3 decimals, < 0.01 toward +x (> -0.01 toward -x).
    for name in ("purcell", "ng"):
        rule = default_clearing(make_model(name))
        assert (rule.min_steps, rule.min_records, rule.window, rule.threshold, rule.decimals) == (
            6,
            6,
            4,
            0.01,
            3,
        )
    rule = default_clearing(make_model("purcell"))
    assert not rule.should_clear(5, 5, [0.0] * 5)  # step 5: too early
    assert rule.should_clear(6, 6, [0.0] * 6)
    assert not rule.should_clear(12, 5, [0.0] * 12)  # only 5 records since the last clear
    # Only the last 4 count: a big early step does not keep the history.
    assert rule.should_clear(6, 6, [0.5, 0.5, 0.002, 0.002, 0.002, 0.002])
    # Rounded to 3 decimals first: 0.0096 -> 0.010 is not below 0.01; 0.0094 -> 0.009 is.
    assert not rule.should_clear(6, 6, [0.0, 0.0, 0.0024, 0.0024, 0.0024, 0.0024])
    assert rule.should_clear(6, 6, [0.0, 0.0, 0.00235, 0.00235, 0.00235, 0.00235])
    # Toward -x the code's test is sum dX > -0.01: the rule gets direction * dX (see the env test
    # below for where that product comes from), so dX = -0.0024 per step is progress +0.0024 and
    # rounds to 0.010, not below; dX = +0.0024 (away from the target) is progress -0.0024: clear.
    direction = -1
    assert not rule.should_clear(6, 6, [direction * -0.0024] * 6)
    assert rule.should_clear(6, 6, [direction * 0.0024] * 6)
    assert rule.should_clear(6, 6, [direction * -0.00235] * 6)  # sum dX = -0.0094 -> -0.009 > -0.01
    assert not ClearingRule(enabled=False).should_clear(10, 10, [0.0] * 10)


def test_clearing_rule_four_dof_per_swimmer():
    link = default_clearing(make_model("nlink"))  # last 40 steps, 0.05, no rounding
    sphere = default_clearing(make_model("nsphere"))  # last 5 steps, 0.05, rounded
    assert (link.window, link.threshold, link.decimals, link.min_records) == (40, 0.05, None, 6)
    assert (sphere.window, sphere.threshold, sphere.decimals, sphere.min_records) == (5, 0.05, 3, 6)
    assert link.should_clear(6, 6, [0.008] * 6)  # 0.048 over the 6 steps there are
    assert not link.should_clear(6, 6, [0.01] * 6)  # 0.06
    # The window is the run's last 40 steps, reaching back past a clear (as the code's).
    assert link.should_clear(46, 6, [0.05] + [0.0] * 45)  # step 1 has left the window
    assert not link.should_clear(40, 6, [0.05] + [0.0] * 39)  # 0.05 is not below
    assert not link.should_clear(
        12, 6, [0.01] * 6 + [0.0] * 6
    )  # the 6 steps before the clear count
    assert sphere.should_clear(6, 6, [1.0] + [0.0098] * 5)  # the last 5 only: 0.049
    assert not sphere.should_clear(6, 6, [0.0] + [0.01] * 5)  # 0.05 is not below


@pytest.mark.parametrize("direction", [1, -1])
def test_history_keeps_a_run_that_swims_toward_its_target_and_clears_one_that_swims_away(direction):
    # The env's progress (direction * dX) feeds the clearing rule: the best cycle toward the target
    # (~0.19 a per 4 steps) never clears; the same moves with the target reversed clear at step 6.
    from jswim import env
    from jswim.judging import gait

    model = make_model("purcell")
    best = gait.best_cycles(model, direction)[0]
    moves = list(best.moves) * 3
    toward = env.rollout_moves("purcell", moves, direction=direction, init=best.start)
    away = env.rollout_moves("purcell", moves, direction=-direction, init=best.start)
    dx = np.diff(np.concatenate([[0.0], np.asarray(toward.x, np.float64)]))
    assert direction * dx.sum() > 0.5  # the cycle swims toward the target (3 cycles of ~0.19)
    np.testing.assert_allclose(toward.progress, direction * dx, atol=1e-12)
    np.testing.assert_allclose(away.progress, -direction * dx, atol=1e-12)
    kept, dropped = History(default_clearing(model)), History(default_clearing(model))
    for k, (p_toward, p_away) in enumerate(zip(toward.progress, away.progress), 1):
        kept.add(rec(k), float(p_toward))
        dropped.add(rec(k), float(p_away))
    assert kept.n_clears == 0 and len(kept.records) == len(moves)
    assert dropped.n_clears == 2  # at steps 6 and 12


def test_history_clears_rebuilds_and_renumbers():
    h = History(default_clearing(make_model("purcell")))
    cleared = [h.add(rec(k), 0.0) for k in range(1, 15)]
    # Stuck from the start: clears at step 6, then after 6 fresh records at step 12.
    assert [k for k, c in enumerate(cleared, 1) if c] == [6, 12]
    # The record index restarts at 1 after each clear (the authors' code).
    assert h.n_clears == 2 and [r.step for r in h.records] == [1, 2]
    h2 = History(default_clearing(make_model("purcell")))
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
    assert (
        text.index("[2, -1]") < text.index("[1, -1]") < text.index("[1, 0]")
    )  # the options' order
    assert "-5" not in text and "500" not in text
    # Progress is recorded in the target direction and named after it; untried pairs are said so.
    text = render_summary(PURCELL, stats, (HI, HI), [Action(1, -1), Action(1, 1)], -1)
    assert "[1, -1] moved X 11 toward -x" in text and "[1, 1] not tried yet" in text
