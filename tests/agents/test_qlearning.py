"""Q-learning baseline: what it learns, how it fails, and that batching changes nothing."""

from __future__ import annotations

import jax
import numpy as np
import optax
import pytest

from jswim.agents.qlearning import (
    QConfig,
    batch_params,
    evaluate,
    greedy_rollout,
    train,
)
from jswim.env.swimmer_world import SwimmerWorld
from jswim.env import encode_action as act, make_params
from jswim.errors import ConfigError
from jswim.judging.gait import Criterion, best_cycles, judge, replay
from jswim.studies.qlearn import format_table, summarize

B = 64  # learners per batch; one size keeps the number of compilations down
DIRECTIONS = np.repeat([1.0, -1.0], B // 2)
NEVER_EXPLORES = QConfig(epsilon=0.0, q_init=0.0)


def _keys(seed: int, n: int = B) -> jax.Array:
    return jax.random.split(jax.random.PRNGKey(seed), n)


def _batched(swimmer: str, **changes) -> object:
    return batch_params(make_params(swimmer), B, direction=DIRECTIONS, **changes)


def _world(params) -> SwimmerWorld:
    """The paper's world of ``params``."""
    return SwimmerWorld(params.model, params.roc_levels)


def _greedy_actions(q: np.ndarray, levels0: np.ndarray, steps: int, action_set: str) -> np.ndarray:
    """Greedy policies of trained tables run from the start, in NumPy (no ties remain)."""
    b, n = levels0.shape
    levels, out = levels0.copy(), np.empty((b, steps), np.int64)
    roc, dof = np.arange(3 * n) % 3 - 1, np.arange(3 * n) // 3
    for t in range(steps):
        row = q[np.arange(b), levels @ (2 ** np.arange(n))]
        if action_set == "shape-changing":
            row = np.where(roc[None] == 1 - 2 * levels[:, dof], row, -np.inf)
        a = np.argmax(row, axis=1)
        k, r = dof[a], roc[a]
        levels[np.arange(b), k] = np.where(r > 0, 1, np.where(r < 0, 0, levels[np.arange(b), k]))
        out[:, t] = a
    return out


@pytest.mark.parametrize(
    "swimmer, action_set",
    [
        ("purcell", "all"),
        ("ng", "shape-changing"),
        # each case compiles a 600-step training run (~2.5 CPU-s): two in the fast tier, one per swimmer
        pytest.param("purcell", "shape-changing", marks=pytest.mark.slow),
        pytest.param("ng", "all", marks=pytest.mark.slow),
    ],
)
def test_learned_greedy_policy_is_the_signature_cycle(swimmer, action_set):
    # 600 steps: with all six actions NG's learner needs more than 200 steps (see the docs).
    params = _batched(swimmer)
    run = train(_world(params), params, _keys(1), QConfig(action_set=action_set, steps=600))
    assert evaluate(run, params).learned.all()
    actions = _greedy_actions(np.asarray(run.q), np.asarray(run.levels0), 16, action_set)
    verdict = judge(actions, params, criterion=Criterion(horizon=16))
    assert verdict.learned.all() and verdict.success.all()
    model = params.model
    for d in (1, -1):
        best = list(best_cycles(model, d)[0].actions)
        shifts = [best[k:] + best[:k] for k in range(4)]
        for cycle in verdict.cycle[d == DIRECTIONS]:
            assert cycle.tolist() in shifts  # the square gait, run in the target direction


def test_greedy_rollout_runs_the_greedy_policy():
    params = _batched("purcell")
    run = train(_world(params), params, _keys(1), QConfig(action_set="all", steps=600))
    rollout = jax.vmap(lambda q, p, k: greedy_rollout(q, p, 16, "all", k))
    actions = np.asarray(rollout(run.q, params, _keys(2)))
    np.testing.assert_array_equal(
        actions, _greedy_actions(np.asarray(run.q), np.asarray(run.levels0), 16, "all")
    )


@pytest.mark.slow  # compiles a training run with argmax ties (15 s under load 8)
def test_first_index_ties_repeat_the_first_action_forever():
    # Every value starts at 0 and nothing explores: argmax picks action 0, (DOF 1, ROC -1).
    # It bends DOF 1 from (+, +) to its lower limit; from then on action 0 pushes against that
    # limit, earns exactly 0, leaves every value at 0, and is picked again, forever.
    params = _batched("ng")
    run = train(_world(params), params, _keys(3), NEVER_EXPLORES.replace(tie_break="first"))
    actions, x = np.asarray(run.actions), np.asarray(run.x)
    assert (actions == act(1, -1)).all()
    np.testing.assert_array_equal(x, np.repeat(x[:, :1], x.shape[1], axis=1))
    assert not evaluate(run, params).learned.any()


@pytest.mark.slow  # compiles a training run without exploration (20 s under load 8)
def test_random_ties_without_exploration_trap_ng_in_a_reciprocal_stroke():
    # With only shape-changing moves and no exploration, NG's learner chases immediate reward.
    # Two of the four strokes of its cycle move it backwards, so it never completes one: it
    # settles on flapping a single arm back and forth (towards +x, from arms (long, long):
    # shortening arm 2 pays +0.096 and lengthening it again costs the least, -0.096), a
    # reciprocal stroke that goes nowhere, as the scallop theorem says.
    params = _batched("ng")
    run = train(
        _world(params), params, _keys(4), NEVER_EXPLORES.replace(action_set="shape-changing")
    )
    tail, x = np.asarray(run.actions)[:, -20:], np.asarray(run.x)
    assert not evaluate(run, params).learned.any()
    assert (tail[:, 2:] == tail[:, :-2]).all() and (tail[:, 1:] != tail[:, :-1]).all()  # period 2
    dof, roc = tail // 3, tail % 3 - 1
    assert (dof == dof[:, :1]).all() and (roc[:, 0] == -roc[:, 1]).all()  # one arm, back and forth
    np.testing.assert_allclose(x[:, -1], x[:, -21], atol=1e-9)  # no net displacement
    assert np.mean(dof[DIRECTIONS > 0, 0] == 1) > 0.5  # mostly arm 2 towards +x ...
    assert np.mean(dof[DIRECTIONS < 0, 0] == 0) > 0.5  # ... and arm 1 towards -x


@pytest.fixture(scope="module")
def ng_greedy_all():
    params = _batched("ng")
    return train(_world(params), params, _keys(5), NEVER_EXPLORES), params


@pytest.mark.slow  # compiles a training run without exploration (17 s under load 8)
def test_random_ties_without_exploration_leave_ng_standing_still(ng_greedy_all):
    # Offered all six actions, the same learner soon meets a shape where every move has cost it
    # displacement while holding (or pushing against a limit) has cost nothing: it stops.
    run, params = ng_greedy_all
    moved = replay(np.asarray(run.actions).T, params.model, np.asarray(run.levels0)).moved.T
    assert not moved[:, -50:].any()
    assert not evaluate(run, params).learned.any()


def test_ties_are_broken_uniformly(ng_greedy_all):
    # All values are equal at the first step, so the first action is uniform over the six.
    run, _ = ng_greedy_all
    counts = np.bincount(np.asarray(run.actions)[:, 0], minlength=6)
    assert counts.sum() == B and counts.min() >= 2 and counts.max() <= 25


@pytest.mark.slow  # trains learners one by one to compare with the vmapped batch (31 s under load 8)
def test_vmapped_learners_equal_individually_trained_ones():
    base = make_params("ng", init="random")
    zeta = np.array([0.0, 0.5, 1.0, 3.0])
    direction = np.array([1.0, -1.0, 1.0, -1.0])
    init = np.array([[1, 1], [0, 1], [-1, -1], [1, 0]])
    params = batch_params(base, 4, zeta=zeta, direction=direction, init=init)
    keys = _keys(6, 4)
    batch = train(_world(params), params, keys)
    for i in range(4):
        one = train(
            SwimmerWorld(base.model),
            base.replace(zeta=zeta[i], direction=direction[i], init=init[i]),
            keys[i],
        )
        np.testing.assert_array_equal(np.asarray(batch.actions[i]), np.asarray(one.actions))
        np.testing.assert_array_equal(np.asarray(batch.levels0[i]), np.asarray(one.levels0))
        np.testing.assert_allclose(np.asarray(batch.x[i]), np.asarray(one.x), rtol=1e-6, atol=1e-6)
        np.testing.assert_allclose(np.asarray(batch.q[i]), np.asarray(one.q), rtol=1e-5, atol=1e-6)


def test_optax_update_is_textbook_q_learning():
    # The NumPy implementation of the benchmark writes the update by hand,
    # Q(s, a) += alpha_t (r + gamma max Q(s') - Q(s, a)), with alpha_t read at step t; on the
    # same random numbers it must take the same actions and end with the same tables.
    from benchmarks.bench_qlearning import jax_uniforms, numpy_train

    params = _batched("purcell", zeta=0.5)
    config = QConfig(learning_rate=optax.linear_schedule(1.0, 0.2, 100))
    run = train(_world(params), params, _keys(9), config)
    ref = numpy_train(jax_uniforms(_keys(9), config.steps), params, config)
    np.testing.assert_array_equal(np.asarray(run.actions), ref["actions"])
    np.testing.assert_allclose(np.asarray(run.x), ref["x"], atol=1e-9)
    np.testing.assert_allclose(np.asarray(run.q), ref["q"], atol=1e-9)


@pytest.mark.slow  # compiles training under three schedules (20 s under load 8)
def test_schedules_are_optax_schedules_evaluated_at_the_step_count():
    # Learning rate 0: the table never moves. Exploration that decays linearly to 0 by step 10:
    # no random action after it.
    config = QConfig(
        learning_rate=optax.constant_schedule(0.0),
        epsilon=optax.linear_schedule(1.0, 0.0, 10),
        q_init=0.3,
    )
    run = train(_world(_batched("purcell")), _batched("purcell"), _keys(7), config)
    np.testing.assert_array_equal(np.asarray(run.q), 0.3)
    explored = np.asarray(run.explored)
    assert explored[:, 0].all() and not explored[:, 10:].any()


def test_x_is_the_environment_s_displacement_of_the_executed_actions():
    params = _batched("purcell", init=np.tile([1, 0], (B, 1)))
    run = train(_world(params), params, _keys(8))
    exact = replay(np.asarray(run.actions).T, params.model, np.asarray(run.levels0)).x[1:].T
    np.testing.assert_allclose(np.asarray(run.x), exact, atol=1e-9)


def test_summaries(ng_greedy_all):
    run, params = ng_greedy_all
    rows = summarize(run, params, evaluate(run, params), swimmer="ng", action_set="all")
    assert [r.direction for r in rows] == [1, -1] and all(r.n == B // 2 for r in rows)
    # Never-learned learners are counted, not turned into +inf steps (jswim.judging.stats.learn_stats).
    assert all(r.learned == 0.0 and r.n_learned == 0 and np.isnan(r.median) for r in rows)
    assert f"0 of {B // 2}" in format_table(rows)


@pytest.mark.parametrize(
    "changes",
    [
        {"action_set": "some"},
        {"discount": 1.0},
        {"steps": 0},
        {"tie_break": "last"},
        {"learning_rate": -1.0},
    ],
)
def test_bad_configs_are_refused(changes):
    with pytest.raises(ConfigError):
        QConfig(**changes)
