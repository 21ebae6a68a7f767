"""Flow inputs outside the arithmetic (issue 61): every flow takes its sizes and speeds in ranges
that cannot give NaN, overflow or a division by zero (`jswim.env.flows.MAX_FLOW_SPEED`,
`MAX_FLOW_RATE`, `MIN_FLOW_LENGTH`, `MAX_FLOW_LENGTH`) and refuses the rest in one line naming
the range; `flow_from_dict` requires every field; the real numbers users hold keep working; and
at the corners of the ranges the flows' numbers, and a world's rollout, stay finite."""

from __future__ import annotations

import math
import warnings

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jswim
from jswim.env.flows import (
    MAX_FLOW_LENGTH,
    MAX_FLOW_RATE,
    MAX_FLOW_SPEED,
    MIN_FLOW_LENGTH,
    SWIM_SPEED,
    Poiseuille,
    Shear,
    TaylorGreen,
    Uniform,
    flow_from_dict,
    study_flow,
)
from jswim.errors import ConfigError
from jswim.scenes.ranges import ModelRangeWarning


def refused(make, *says: str) -> str:
    with pytest.raises(ConfigError) as err:
        make()
    text = str(err.value)
    assert "\n" not in text and len(text) < 400, text
    for s in says:
        assert s in text, text
    return text


# --- the issue's cases ---------------------------------------------------------------------

SPEED = f"{MAX_FLOW_SPEED:.4g}"  # 47.81 a per step


@pytest.mark.parametrize(
    ("make", "says"),
    [
        # accepted, then ZeroDivisionError in a rollout and NaN in zermelo
        (lambda: Poiseuille(1, 1e-300), ("half_width", "1..1e+06 a")),
        (lambda: TaylorGreen(0.01, 1e-300), ("cell", "1..1e+06 a")),
        # NaN positions with no warning (inf in float32)
        (lambda: Uniform((1e300, 0)), ("flow u", SPEED)),
        # warned, then NaN
        (lambda: Shear(1e300), ("rate", "-1..1 per step")),
        # OverflowError
        (lambda: Shear(10**400), ("rate", "-1..1 per step", "401 characters")),
        # silently still fluid; TypeError
        (lambda: flow_from_dict({"kind": "shear"}), ("'rate' is missing",)),
        (lambda: flow_from_dict({"kind": ["shear"]}), ("flow kind must be one of",)),
    ],
    ids=[
        "poiseuille",
        "taylor-green",
        "uniform",
        "shear 1e300",
        "shear 10**400",
        "no rate",
        "list",
    ],
)
def test_the_issue_s_cases_are_refused_in_one_line_naming_the_range(make, says):
    refused(make, *says)


# --- the same kinds, other cases -----------------------------------------------------------


@pytest.mark.parametrize(
    ("make", "says"),
    [
        # lengths: zero, negative, NaN, inf, too small, too large, a bool, an int past float
        (lambda: Poiseuille(0.01, 0.0), "half_width"),
        (lambda: Poiseuille(0.01, -3.0), "half_width"),
        (lambda: Poiseuille(0.01, float("nan")), "half_width"),
        (lambda: TaylorGreen(0.01, float("inf")), "cell"),
        (lambda: TaylorGreen(0.0, 0.999), "cell"),  # still fluid, but below a link
        (lambda: TaylorGreen(0.0, np.float32(2e6)), "cell"),
        (lambda: Poiseuille(0.0, 1e300), "half_width"),  # h^2 overflowed
        (lambda: Poiseuille(0.0, True), "half_width must be a number"),
        (lambda: TaylorGreen(0.0, 10**400), "cell"),
        # speeds: past the bound, each way; a bool; NaN of NumPy
        (lambda: Poiseuille(-48.0, 1e3), "u_max"),
        (lambda: TaylorGreen(np.float64(48.0), 1e3), "u0"),
        (lambda: Uniform((0.0, -1e6)), "flow u"),
        (lambda: Uniform((40.0, 40.0)), "speed |u|"),  # each part in range, |u| not
        (lambda: Uniform(np.array([np.nan, 0.0])), "flow u"),
        (lambda: Uniform((np.bool_(True), 0.0)), "flow u must be a number"),
        # rates: a shear, and the gradient a speed makes over a length
        (lambda: Shear(-1.0000001), "rate"),
        (lambda: Shear(np.float32(2.0)), "rate"),
        (lambda: Shear(jnp.float32(-5.0)), "rate"),
        (lambda: Poiseuille(0.6, 1.0), "2 |u_max| / half_width = 1.2"),
        (lambda: TaylorGreen(0.5, 1.0), "pi |u0| / cell = 1.571"),
        # a study's flow: the fraction and length that made it
        (lambda: study_flow("shear", 1e300), "shear flow at 1e+300 v on 3 a"),
        (lambda: study_flow("poiseuille", 1.0, 0.1), "half_width"),
        (lambda: study_flow(["shear"], 1.0), "flow kind"),
    ],
)
def test_sizes_and_speeds_outside_the_ranges_are_refused(make, says):
    refused(make, says)


@pytest.mark.parametrize(
    ("data", "says"),
    [
        ({}, "'kind' is missing"),
        ({"rate": 0.1}, "'kind' is missing"),
        ({"kind": "vortex", "rate": 0.1}, "flow kind must be one of"),
        ({"kind": 3}, "flow kind must be one of"),
        ({"kind": None}, "flow kind must be one of"),
        ({"kind": "poiseuille", "u_max": 0.01}, "'half_width' is missing"),
        ({"kind": "taylor-green", "cell": 6.0}, "'u0' is missing"),
        ({"kind": "uniform"}, "'u' is missing"),
        ({"kind": "shear", "rate": 0.1, "speed": 1.0}, "no field 'speed'"),
        ({"kind": "shear", "rate": 0.1, 1: 2}, "no field 1"),
        ({"kind": "shear", "rate": "0.1"}, "flow rate must be a number"),
        ({"kind": "shear", "rate": None}, "flow rate must be a number"),
        ({"kind": "shear", "rate": True}, "flow rate must be a number"),
        ({"kind": "shear", "rate": [0.1]}, "flow rate must be a number"),
        ({"kind": "shear", "rate": 1e300}, "-1..1 per step"),
        ({"kind": "uniform", "u": "ab"}, "(ux, uy)"),
        ({"kind": "uniform", "u": [0.01]}, "(ux, uy)"),
        ({"kind": "uniform", "u": {"x": 0.0, "y": 0.0}}, "(ux, uy)"),
        ({"kind": "poiseuille", "u_max": 0.01, "half_width": 0.5}, "half_width"),
        ([("kind", "shear")], "a flow must be a mapping"),
        ('{"kind": "shear", "rate": 0.1}', "a flow must be a mapping"),
    ],
)
def test_flow_from_dict_requires_every_field_and_nothing_else(data, says):
    refused(lambda: flow_from_dict(data), says)


# --- what stays accepted -------------------------------------------------------------------

#: Each flow at the corners of its ranges.
CORNERS = [
    Uniform((MAX_FLOW_SPEED, 0.0)),
    Uniform((0.0, -MAX_FLOW_SPEED)),
    Shear(MAX_FLOW_RATE),
    Shear(-MAX_FLOW_RATE),
    Poiseuille(MAX_FLOW_RATE * MIN_FLOW_LENGTH / 2, MIN_FLOW_LENGTH),
    Poiseuille(MAX_FLOW_SPEED, MAX_FLOW_LENGTH),
    Poiseuille(-MAX_FLOW_SPEED, 2 * MAX_FLOW_SPEED / MAX_FLOW_RATE),
    TaylorGreen(MAX_FLOW_RATE * MIN_FLOW_LENGTH / math.pi, MIN_FLOW_LENGTH),
    TaylorGreen(MAX_FLOW_SPEED, MAX_FLOW_LENGTH),
    TaylorGreen(0.0, MIN_FLOW_LENGTH),
]


def test_the_real_numbers_users_hold_and_the_study_flows_are_taken():
    assert Shear(np.float32(0.5)) == Shear(0.5)
    assert Poiseuille(np.float64(0.1), np.int64(4)) == Poiseuille(0.1, 4.0)
    assert TaylorGreen(jnp.float32(0.25), jnp.int32(1)) == TaylorGreen(0.25, 1.0)
    assert Uniform(np.array([0.5, 0.0], np.float32)) == Uniform((0.5, 0.0))
    assert Shear(np.array(-1.0)) == Shear(-1.0)  # a 0-d array at the bound
    for flow in CORNERS:  # round trip at the corners
        assert flow_from_dict(flow.to_dict()) == flow
    # every --flows speed of the study (up to 2 v) stays well inside the ranges
    for kind in ("uniform", "shear", "poiseuille", "taylor-green"):
        flow = study_flow(kind, 2.0)
        assert flow.speed <= 2 * SWIM_SPEED + 1e-12 and flow.max_gradient < 0.06
        assert study_flow(kind, 1e-300).speed < 1e-300  # a tiny fraction is a tiny flow


@pytest.mark.parametrize("dtype", ["float32", "float64"])
def test_at_the_corners_every_flow_s_numbers_stay_finite(dtype):
    # velocity, gradient and hessian across the targets' range (1e4 a) and far beyond it
    line = np.linspace(-1e4, 1e4, 401)
    x = np.concatenate([np.stack([line, line[::-1]], -1), [[1e6, -1e6], [0.5, 0.25]]])
    with jax.enable_x64(dtype == "float64"):
        pts = jnp.asarray(x, dtype)
        for flow in CORNERS:
            for part in (flow.velocity, flow.gradient, flow.hessian):
                out = np.asarray(part(pts))
                assert out.dtype == dtype and np.isfinite(out).all(), (flow, part.__name__)
            assert math.isfinite(flow.max_gradient) and flow.max_gradient <= MAX_FLOW_RATE


@pytest.mark.slow  # three flow tables built, eight worlds compiled (~60 s on a busy core)
@pytest.mark.parametrize("dtype", ["float32", "float64"])
def test_a_world_at_the_corners_of_the_ranges_stays_finite(dtype):
    # Beyond the tables' range (a gradient of 0.1) jswim.make warns, as before; at the ranges'
    # corners a world's 600 steps stay finite, in the default float32 and in float64. Past them
    # they did not: a shear of 10 a step was NaN within 400 steps, Uniform((1e300, 0)) at once.
    actions = jnp.asarray(np.random.default_rng(0).integers(0, 6, 600))
    for flow in (
        Uniform((MAX_FLOW_SPEED, 0.0)),
        Shear(MAX_FLOW_RATE),
        Poiseuille(MAX_FLOW_RATE / 2, MIN_FLOW_LENGTH),
        TaylorGreen(MAX_FLOW_RATE / math.pi, MIN_FLOW_LENGTH),
    ):
        with warnings.catch_warnings(), jax.enable_x64(dtype == "float64"):
            warnings.simplefilter("ignore", ModelRangeWarning)
            env, params = jswim.make("purcell", flow=flow)
            obs = jswim.rollout(env, params, jax.random.PRNGKey(0), actions).obs
        assert obs.position.dtype == dtype
        assert np.isfinite(np.asarray(obs.position)).all(), flow
        assert np.isfinite(np.asarray(obs.orientation)).all(), flow
