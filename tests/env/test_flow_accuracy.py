"""The flow tables' documented accuracy, from random starts (benchmarks/flow_accuracy.py, whose
functions these are): the square gait through the tables against the RK4 reference, and Jeffery's
orbit through the tables at random angles. Each asserts a bound of 2 x the maximum docs/physics.md
("Background flows") states for 256 starts, so a broken table fails while the measured spread
passes."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from jswim.env.flows import study_flow

_spec = importlib.util.spec_from_file_location(
    "flow_accuracy", Path(__file__).resolve().parents[2] / "benchmarks" / "flow_accuracy.py"
)
flow_accuracy = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(flow_accuracy)

#: docs/physics.md's maxima over 256 starts, Taylor-Green cells of 6 a at 0.9 v (the worst):
#: one step (a, rad), 200 steps (a, rad).
TG6_09 = {"pos1": 1.2e-5, "ang1": 2.1e-5, "pos": 4.7e-3, "ang": 1.1e-3}

#: Jeffery's orbit through the tables at rate 0.05: the largest error of the new angle (rad).
JEFFERY_05 = 4.2e-5


@pytest.mark.slow  # compiles the unrolled RK4 step of the corner world in a Taylor-Green cell
def test_two_hundred_steps_from_random_starts_stay_within_twice_the_documented_error():
    err = flow_accuracy.gait_errors(study_flow("taylor-green", 0.9), starts=24, steps=200)
    for key, bound in TG6_09.items():
        assert err[key].max() < 2 * bound, (key, err[key].max())
    # and the spread is real: the starts are not all on a stagnation point or a zero line
    assert np.median(err["pos"]) > 1e-5


@pytest.mark.slow  # builds and compiles the shear world's K = 2 tables
def test_jeffery_s_orbit_through_the_tables_at_random_angles():
    err = flow_accuracy.jeffery_errors(0.05, starts=64, reference=False)
    assert err["tables angle"].max() < 2 * JEFFERY_05, err["tables angle"].max()
