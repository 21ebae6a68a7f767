"""The shared success criterion: best cycles, replay, and the verdict on runs."""

from __future__ import annotations

import math

import numpy as np
import pytest

from jswim.env import decode_action, encode_action as act, make_params, rollout_moves
from jswim.errors import ConfigError
from jswim.judging.gait import best_cycles, best_per_step, judge, replay

HOLD = act(1, 0)


def _signature(swimmer: str, direction: int) -> tuple[list[int], tuple[int, ...]]:
    best = best_cycles(make_params(swimmer).model, direction)[0]
    return list(best.actions), best.start


def _runs(rows: list[list[int]]) -> np.ndarray:
    return np.array(rows, np.int32)


@pytest.mark.parametrize("swimmer, per_cycle", [("purcell", 0.19124724), ("ng", 0.15626494)])
@pytest.mark.parametrize("direction", [1, -1])
def test_best_cycle_is_the_square_gait_and_the_only_one_that_qualifies(
    swimmer, per_cycle, direction
):
    cycles = best_cycles(make_params(swimmer).model, direction)
    best = cycles[0]
    assert best.period == 4
    assert sorted(d for d, _ in best.moves) == [1, 1, 2, 2]  # each DOF forth and back
    assert all(roc != 0 for _, roc in best.moves)
    assert best.displacement == pytest.approx(per_cycle, rel=1e-7)  # DESIGN.md reference values
    assert abs(best.rotation) < 1e-12
    # Every other cycle is reciprocal (goes nowhere) or goes the wrong way.
    assert all(c.per_step < 1e-9 for c in cycles[1:])


def test_reversed_direction_reverses_the_best_cycle():
    model = make_params("ng").model
    plus, minus = best_cycles(model, 1)[0], best_cycles(model, -1)[0]
    flipped = [act(d, -r) for d, r in reversed(plus.moves)]  # same loop, run backwards
    rotations = [tuple(flipped[k:] + flipped[:k]) for k in range(4)]
    assert minus.actions in rotations
    assert best_per_step(model, -1) == pytest.approx(best_per_step(model, 1))


@pytest.mark.parametrize(
    "swimmer", ["purcell", "ng", pytest.param("nlink", marks=pytest.mark.slow)]
)  # nlink: 3.5 CPU-s
def test_replay_matches_the_environment(swimmer):
    # The four-link swimmer starts turned (symmetric about x), so its replay must carry the start
    # orientation through every step, not only the first.
    n = make_params(swimmer).model.n_dof
    actions = np.random.default_rng(1).integers(0, 3 * n, (6, 40))
    for init in [(1,) * n, (1, 0) + (1,) * (n - 2)]:
        moves = [[decode_action(int(a)) for a in row] for row in actions]
        env = rollout_moves(swimmer, moves, init=init)
        rp = replay(actions.T, make_params(swimmer).model, np.tile(init, (6, 1)))
        np.testing.assert_allclose(rp.x[1:].T, np.asarray(env.x), atol=1e-6)
        assert np.array_equal(~rp.moved.T & (actions % 3 != 1), np.asarray(env.stuck))


@pytest.mark.parametrize("swimmer", ["purcell", "ng"])
@pytest.mark.parametrize("direction", [1, -1])
def test_verdicts_on_constructed_runs(swimmer, direction):
    cyc, start = _signature(swimmer, direction)
    params = make_params(swimmer, direction=direction, init=start)
    wrong = [act(d, -r) for d, r in reversed([decode_action(a) for a in cyc])]
    t = 60
    runs = _runs(
        [
            (cyc * 15)[:t],  # 0: from the first step
            ([HOLD] * 7 + cyc * 15)[:t],  # 1: after 7 idle steps
            [HOLD] * (t - 12) + cyc * 3,  # 2: exactly three cycles, at the very end
            [HOLD] * (t - 11) + cyc * 2 + cyc[:3],  # 3: not quite three cycles
            (cyc * 15)[: t - 1] + [HOLD],  # 4: fails at the last step
            (wrong * 15)[:t],  # 5: the cycle backwards
            ([act(1, 1), act(1, -1)] * 30)[:t],  # 6: reciprocal, period 2
            [HOLD] * 38 + (cyc * 6)[: t - 38],  # 7: three cycles done at step 50
            [HOLD] * 39 + (cyc * 6)[: t - 39],  # 8: done at step 51: learned, too late
        ]
    )
    r = judge(runs, params)
    assert r.learned.tolist() == [True, True, True, False, False, False, False, True, True]
    # Counted from 1 as in the paper: the stroke from the first action is learned in 1 step.
    assert r.steps_to_learn.tolist() == [1, 8, 49, -1, -1, -1, -1, 39, 40]
    assert r.stroke_start.tolist() == [0, 7, 48, -1, -1, -1, -1, 38, 39]
    assert r.success.tolist() == [True, True, False, False, False, False, False, True, False]
    assert set(r.period[r.learned].tolist()) == {4}
    np.testing.assert_allclose(r.fraction[r.learned], 1.0, rtol=1e-9)
    for row in np.flatnonzero(r.learned):
        got = r.cycle[row, :4].tolist()
        assert got in [cyc[k:] + cyc[:k] for k in range(4)]


def test_a_stuck_move_inside_a_repeating_pattern_disqualifies_it():
    cyc, start = _signature("purcell", 1)
    params = make_params("purcell", init=start)
    # Replace the cycle's last move by the same DOF pushed the wrong way: it is stuck, and the
    # shape no longer returns to its start.
    d, roc = decode_action(cyc[-1])
    bad = cyc[:-1] + [act(d, -roc)]
    assert not judge(_runs([bad * 12]), params).learned[0]


def test_direction_and_init_may_be_batched():
    cyc, start = _signature("ng", 1)
    actions = _runs([cyc * 10, cyc * 10])
    params = make_params("ng", init=start).replace(direction=np.array([1.0, -1.0]))
    assert judge(actions, params).learned.tolist() == [True, False]
    # From the opposite corner the first two moves push against limits; the stroke starts after.
    params = make_params("ng").replace(init=np.array([start, [1 - v for v in start]]))
    assert judge(actions, params).steps_to_learn.tolist() == [1, 3]


def test_purcell_from_a_bent_start_still_qualifies_at_the_rotated_speed():
    # Started from (1, 0), the swimmer's body frame is turned by the orientation the square gait
    # has at that corner, so the gait advances at cos(0.6001) of the best speed along x.
    cyc, start = _signature("purcell", 1)
    model = make_params("purcell").model
    corners = replay(np.array([cyc]).T, model, np.array([start])).corner[:4, 0].tolist()
    k = corners.index(1)  # the cycle's step that starts from levels (1, 0)
    shifted = cyc[k:] + cyc[:k]
    r = judge(_runs([shifted * 12]), make_params("purcell", init=(1, 0)))
    assert r.learned[0] and r.steps_to_learn[0] == 1
    assert r.fraction[0] == pytest.approx(math.cos(0.6001), abs=1e-3)


def test_one_dimensional_actions_are_one_run():
    cyc, start = _signature("purcell", -1)
    r = judge(np.array(cyc * 4), make_params("purcell", direction=-1, init=start))
    assert r.learned.shape == (1,) and r.learned[0]


def test_random_start_needs_the_actual_levels():
    cyc, start = _signature("ng", 1)
    params = make_params("ng", init="random")
    with pytest.raises(ConfigError):
        judge(_runs([cyc * 5]), params)
    assert judge(_runs([cyc * 5]), params, levels0=np.array([start])).learned[0]


def test_bad_actions_are_refused():
    params = make_params("purcell")
    with pytest.raises(ConfigError):
        judge(_runs([[0, 6, 1]]), params)
    with pytest.raises(ConfigError):
        judge(np.zeros((2, 3), float), params)


def test_three_dof_cycles_use_the_same_code_path():
    model = make_params("nsphere").model
    cycles = best_cycles(model, 1)
    best = cycles[0]
    assert best.per_step > 0 and best.period <= 8
    assert all(c.per_step <= best.per_step + 1e-12 for c in cycles)
    params = make_params("nsphere", init=best.start)
    r = judge(_runs([[act(1, 0)] * 5 + list(best.actions) * 6]), params)
    assert r.learned[0] and r.steps_to_learn[0] == 6 and r.period[0] == best.period  # after 5 holds


@pytest.mark.parametrize("swimmer", ["purcell", "ng"])
def test_runs_without_steps_are_judged_not_learned(swimmer):
    # A run the server failed at its first request has no executed action.
    r = judge(np.zeros((2, 0), np.int64), make_params(swimmer))
    assert r.learned.tolist() == [False, False] and r.success.tolist() == [False, False]
    assert r.steps_to_learn.tolist() == [-1, -1]


def test_the_criterion_says_when_runs_are_shorter_than_its_horizon():
    from jswim.judging.gait import Criterion

    assert "within 50 steps," in Criterion().describe()
    assert "within 50 steps," in Criterion().describe(steps=60)
    assert "within 50 steps (these runs have 20)," in Criterion().describe(steps=20)
