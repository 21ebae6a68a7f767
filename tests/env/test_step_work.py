"""Work in every step: `StepInfo.work` against independent quadratures and the physics page.

The references are the direct quadratures of f.u along discretised links (and the exactly
force-free sphere solve) of tests/physics/test_dissipation.py, written in NumPy from the
definitions, and the square gait's work per cycle that docs/physics.md prints.
"""

from __future__ import annotations

import math

import jax
import numpy as np
import pytest

import jswim
from jswim.env.base import StepInfo
from jswim.env.work import lighthill_efficiency, step_work
from jswim.results.row import RunRow
from jswim.studies.rows import energy_columns
from tests.physics.test_dissipation import gauss_work, rft_reference, spheres_reference

#: The square gait's work per cycle and its Lighthill efficiency (docs/physics.md, "Energy and
#: turning"): Purcell d_max = pi/3 in xi_par a^3/tau, NG in 6 pi mu a^3/tau.
PAGE_WORK = {"purcell": 3.749661, "ng": 49.077991}
PAGE_DX = {"purcell": 0.19124724, "ng": 0.15626494}
PAGE_EFFICIENCY = {"purcell": 7.316e-3, "ng": 3.732e-4}

#: D2 down, D1 down, D2 up, D1 up from (+, +): the square gait's codes in the paper's world.
SQUARE = [3, 0, 5, 2]


def _richardson_power(d, rate):
    """Purcell's power by direct f.u quadrature (200 and 400 segments per link, extrapolated)."""
    return (4 * rft_reference(d, rate, m_seg=400)[1] - rft_reference(d, rate, m_seg=200)[1]) / 3


@pytest.mark.parametrize("swimmer", ["purcell", "ng"])
def test_square_gait_work_per_cycle_from_a_rollout_is_the_pages(swimmer):
    world, params = jswim.make(swimmer)
    tr = jswim.rollout(world, params, 0, np.array(SQUARE * 3))
    work = np.asarray(tr.info.work)
    assert work.dtype == np.float64
    per_cycle = work.reshape(3, 4).sum(1)
    np.testing.assert_allclose(per_cycle, PAGE_WORK[swimmer], rtol=1e-5)
    x = float(np.asarray(tr.obs.position)[-1, 0, 0])
    eta = lighthill_efficiency(x / 3, float(per_cycle[0]), 4, 3)
    np.testing.assert_allclose(eta, PAGE_EFFICIENCY[swimmer], rtol=1e-3)


def test_square_gait_work_in_float32_rounds_the_float64(float32):
    world, params = jswim.make("purcell")
    work = np.asarray(jswim.rollout(world, params, 0, np.array(SQUARE)).info.work)
    assert work.dtype == np.float32
    np.testing.assert_allclose(work.sum(), PAGE_WORK["purcell"], rtol=1e-6)


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_corner_steps_work_against_direct_quadrature_of_f_dot_u(dtype):
    """Each of four corner steps (one stuck) against Gauss quadrature of the independently
    discretised RFT power along the step's path."""
    codes = [3, 2, 0, 5]  # D2 down, D1 up at its limit (stuck), D1 down, D2 up
    with jax.enable_x64(dtype == "float64"):
        world, params = jswim.make("purcell")
        work = np.asarray(jswim.rollout(world, params, 0, np.array(codes)).info.work)
    model = params.model
    span = model.hi - model.lo
    levels, ref = [1, 1], []
    for code in codes:
        k, sign = code // 3, code % 3 - 1
        d0 = np.array([model.lo + span * v for v in levels])
        if (sign > 0 and levels[k] == 1) or (sign < 0 and levels[k] == 0):
            ref.append(0.0)
            continue
        rate = np.zeros(2)
        rate[k] = sign * span
        ref.append(gauss_work(_richardson_power, d0, rate, 1.0, nodes=12))
        levels[k] = 1 - levels[k]
    assert work[1] == 0.0
    np.testing.assert_allclose(work, ref, rtol=1e-6 if dtype == "float32" else 1e-8, atol=1e-9)


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_lattice_and_float_roc_steps_work_is_step_work(dtype):
    """K = 2 lattice steps (a clipped push included) and float ROC steps (one clipped at its
    limit mid-step) equal `step_work` of the step's ROC vector from its start shape, and a
    clipped float ROC step equals the independent quadrature over the time it moves."""
    with jax.enable_x64(dtype == "float64"):
        world, params = jswim.make("purcell", roc_levels=2)
        # DOF 1 by -2/2 (to lo), DOF 2 by -1/2, DOF 1 by +2/2 (to hi), DOF 2 by +2/2 (clipped: moves 1/2)
        codes = np.array([0, 6, 4, 9])
        tr = jswim.rollout(world, params, 0, codes)
        work = np.asarray(tr.info.work)
        shapes = [np.array([1.0, 1.0]), np.array([0.0, 1.0]), np.array([0.0, 0.5])]
        shapes.append(np.array([1.0, 0.5]))
        rocs = [np.array([-1.0, 0.0]), np.array([0.0, -0.5]), np.array([1.0, 0.0])]
        rocs.append(np.array([0.0, 1.0]))
        want = [float(step_work(params.model, s, r)) for s, r in zip(shapes, rocs)]
        np.testing.assert_allclose(work, want, rtol=1e-6 if dtype == "float32" else 1e-12)

        world, params = jswim.make("purcell", init=(1, 0))
        rocs = np.array([[0.0, 0.5], [0.0, 0.8], [-0.3, 0.0]])  # 0.5 of the range, then clipped
        work = np.asarray(jswim.rollout(world, params, 0, rocs).info.work)
    model = params.model
    span = model.hi - model.lo
    ref = [
        gauss_work(
            _richardson_power, np.array([model.hi, model.lo]), np.array([0, 0.5 * span]), 1.0
        ),
        # 0.5 of the range left at ROC 0.8: it moves for 0.5 / 0.8 of the step
        gauss_work(
            _richardson_power,
            np.array([model.hi, model.lo + 0.5 * span]),
            np.array([0, 0.8 * span]),
            0.5 / 0.8,
        ),
        gauss_work(
            _richardson_power, np.array([model.hi, model.hi]), np.array([-0.3 * span, 0]), 1.0
        ),
    ]
    np.testing.assert_allclose(work, ref, rtol=1e-6 if dtype == "float32" else 1e-8)


def test_ng_step_work_against_the_force_free_sphere_solve():
    world, params = jswim.make("ng")
    work = np.asarray(jswim.rollout(world, params, 0, np.array([3])).info.work)
    model = params.model
    span = model.hi - model.lo
    ref = gauss_work(
        lambda d, r: spheres_reference(d, r)[1],
        np.array([model.hi, model.hi]),
        np.array([0.0, -span]),
        1.0,
    )
    # NG moves its spheres by the paper's formula, within 0.4 % of the exactly force-free solve
    # (docs/physics.md), so the two works agree to that order, as in tests/physics
    np.testing.assert_allclose(work[0], ref, rtol=5e-3)


def test_work_does_not_depend_on_the_noise():
    quiet = jswim.make("purcell")
    noisy = jswim.make("purcell", zeta=0.5)
    codes = np.array(SQUARE * 2)
    a = np.asarray(jswim.rollout(*quiet, 3, codes).info.work)
    b = np.asarray(jswim.rollout(*noisy, 3, codes).info.work)
    np.testing.assert_array_equal(a, b)


def test_a_scene_world_does_not_count_work():
    from jswim.scenes import Scene

    world, params = jswim.make("ng", Scene(medium="wall", height=4.0))
    work = np.asarray(jswim.rollout(world, params, 0, np.array([3, 0])).info.work)
    assert np.all(np.isnan(work))


def test_step_info_without_work_says_not_counted():
    info = StepInfo(np.zeros((1, 2)), 0.0, False, False, False, math.inf)
    assert math.isnan(info.work)
    assert StepInfo._fields[-1] == "work"


def test_energy_columns_of_a_row():
    cols = energy_columns("purcell", -0.5, [1.0, 0.0, 2.0])
    assert cols["energy"] == 3.0
    assert cols["energy_per_distance"] == 6.0
    assert cols["efficiency"] == pytest.approx(3 * 0.25 / (3 * 3.0))
    assert energy_columns("purcell", 0.0, [1.0])["energy_per_distance"] is None
    assert energy_columns("purcell", 0.2, [0.0, 0.0])["efficiency"] is None
    assert set(energy_columns("ng", 0.2, [1.0, math.nan]).values()) == {None}
    assert set(energy_columns("ng", 0.2, None).values()) == {None}


def test_an_old_row_without_energy_reads_none():
    row = RunRow.from_dict(
        {
            "run_id": "a",
            "agent": "random",
            "swimmer": "purcell",
            "direction": 1,
            "init": "++",
            "zeta": 0.0,
            "seed": 0,
            "n_ht": None,
            "drop": "",
            "action_set": "all",
            "group": "g",
            "variant": "",
            "steps": 1,
            "final_x": 0.1,
            "signed_final_x": 0.1,
            "success": False,
            "learned": False,
            "steps_to_learn": None,
            "period": 0,
            "roc_levels": 1,
            "x": [0.1],
            "actions": [[1, -1]],
            "progress": [0.1],
        }
    )
    assert row.energy is None and row["energy_per_distance"] is None and row.efficiency is None
    assert "energy" in row.to_dict()
