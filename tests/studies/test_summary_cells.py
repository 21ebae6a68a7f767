"""Summary cells at small n: no quartiles from fewer than 4 runs that learned, no bootstrap interval
from fewer than 3 runs (as a referee reads the table)."""

from __future__ import annotations

from jswim.bench.leaderboard import steps_text
from jswim.studies.overview import SUMMARY_NOTE, _learn_cell, _x_cell


def cell(n, learned, med=1.5, q25=1.25, q75=1.75):
    return {
        "n": n,
        "learned": learned,
        "steps_to_learn_median": med,
        "steps_to_learn_q25": q25,
        "steps_to_learn_q75": q75,
        "mean_x": 0.1432,
        "mean_x_lo": 0.05,
        "mean_x_hi": 0.2,
    }


def test_steps_to_learn_print_the_median_alone_below_four_runs():
    assert (
        _learn_cell(cell(2, 2)) == "med 1.5"
    )  # was 1.25/1.5/1.75: interpolation between two values
    assert _learn_cell(cell(10, 4, 17, 12, 30)) == "12/17/30"
    assert _learn_cell(cell(10, 0)) == "-"
    row = {"learned": 2, "n": 10, "steps_median": 1.5, "steps_q25": 1.25, "steps_q75": 1.75}
    assert steps_text(row) == "1.5 (2 of 10)"


def test_bootstrap_interval_is_not_printed_for_one_or_two_runs_and_the_note_says_so():
    assert _x_cell(cell(2, 0)) == "+0.143 [n<3]"
    assert _x_cell(cell(3, 0)) == "+0.143 [+0.05,+0.20]"
    assert "[n<3]" in SUMMARY_NOTE and "median alone below 4" in SUMMARY_NOTE
