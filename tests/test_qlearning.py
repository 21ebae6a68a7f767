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
    format_table,
    greedy_rollout,
    summarize,
    train,
    train_batch,
)
from jswim.env import encode_action as act, make_params
from jswim.errors import ConfigError
from jswim.gait import best_cycles, judge, replay

B = 64  # learners per batch; one size keeps the number of compilations down
DIRECTIONS = np.repeat([1.0, -1.0], B // 2)
NEVER_EXPLORES = QConfig(epsilon=0.0, q_init=0.0)


def _keys(seed: int, n: int = B) -> jax.Array:
    return jax.random.split(jax.random.PRNGKey(seed), n)


def _batched(swimmer: str, **changes) -> object:
    return batch_params(make_params(swimmer), B, direction=DIRECTIONS, **changes)


@pytest.mark.parametrize("swimmer", ["purcell", "ng"])
@pytest.mark.parametrize("action_set", ["all", "shape-changing"])
def test_learned_greedy_policy_is_the_signature_cycle(swimmer, action_set):
    # 600 steps: with all six actions NG's learner needs more than 200 steps (see the docs).
    params = _batched(swimmer)
    run = train_batch(_keys(1), params, QConfig(action_set=action_set, steps=600))
    assert evaluate(run, params).learned.all()
    rollout = jax.vmap(lambda q, p, k: greedy_rollout(q, p, 16, action_set, k))
    actions = np.asarray(rollout(run.q, params, _keys(2)))
    verdict = judge(actions, params, horizon=16)
    assert verdict.learned.all() and verdict.success.all()
    model = params.model
    for d in (1, -1):
        best = list(best_cycles(model, d)[0].actions)
        shifts = [best[k:] + best[:k] for k in range(4)]
        for cycle in verdict.cycle[DIRECTIONS == d]:
            assert cycle.tolist() in shifts  # the square gait, run in the target direction


def test_first_index_ties_repeat_the_first_action_forever():
    # Every value starts at 0 and nothing explores: argmax picks action 0, (DOF 1, ROC -1).
    # It bends DOF 1 from (+, +) to its lower limit; from then on action 0 pushes against that
    # limit, earns exactly 0, leaves every value at 0, and is picked again, forever.
    params = _batched("ng")
    run = train_batch(_keys(3), params, NEVER_EXPLORES.replace(tie_break="first"))
    actions, x = np.asarray(run.actions), np.asarray(run.x)
    assert (actions == act(1, -1)).all()
    np.testing.assert_array_equal(x, np.repeat(x[:, :1], x.shape[1], axis=1))
    assert not evaluate(run, params).learned.any()


def test_random_ties_without_exploration_trap_ng_in_a_reciprocal_stroke():
    # With only shape-changing moves and no exploration, NG's learner follows the immediate
    # reward. Towards +x, from arms (long, long) shortening arm 2 pays +0.096 and lengthening it
    # again costs the least (-0.096 against -0.174 for moving arm 1), so it flaps arm 2 forever
    # (arm 1 towards -x): a reciprocal stroke that goes nowhere, as the scallop theorem says.
    params = _batched("ng")
    run = train_batch(_keys(4), params, NEVER_EXPLORES.replace(action_set="shape-changing"))
    tail, x = np.asarray(run.actions)[:, -20:], np.asarray(run.x)
    assert not evaluate(run, params).learned.any()
    for d, dof in ((1, 2), (-1, 1)):
        rows = tail[DIRECTIONS == d]
        assert set(np.unique(rows).tolist()) == {act(dof, -1), act(dof, 1)}
        assert (rows[:, 2:] == rows[:, :-2]).all() and (rows[:, 1:] != rows[:, :-1]).all()
    np.testing.assert_allclose(x[:, -1], x[:, -21], atol=1e-5)


@pytest.fixture(scope="module")
def ng_greedy_all():
    params = _batched("ng")
    return train_batch(_keys(5), params, NEVER_EXPLORES), params


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


def test_vmapped_learners_equal_individually_trained_ones():
    base = make_params("ng", init="random")
    zeta = np.array([0.0, 0.5, 1.0, 3.0])
    direction = np.array([1.0, -1.0, 1.0, -1.0])
    init = np.array([[1, 1], [0, 1], [-1, -1], [1, 0]])
    params = batch_params(base, 4, zeta=zeta, direction=direction, init=init)
    keys = _keys(6, 4)
    batch = train_batch(keys, params)
    for i in range(4):
        one = train(keys[i], base.replace(zeta=zeta[i], direction=direction[i], init=init[i]))
        np.testing.assert_array_equal(np.asarray(batch.actions[i]), np.asarray(one.actions))
        np.testing.assert_array_equal(np.asarray(batch.levels0[i]), np.asarray(one.levels0))
        np.testing.assert_allclose(np.asarray(batch.x[i]), np.asarray(one.x), rtol=1e-6, atol=1e-6)
        np.testing.assert_allclose(np.asarray(batch.q[i]), np.asarray(one.q), rtol=1e-5, atol=1e-6)


def test_schedules_are_optax_schedules_evaluated_at_the_step_count():
    # Learning rate 0: the table never moves. Exploration that decays linearly to 0 by step 10:
    # no random action after it.
    config = QConfig(learning_rate=optax.constant_schedule(0.0), epsilon=optax.linear_schedule(1.0, 0.0, 10), q_init=0.3)
    run = train_batch(_keys(7), _batched("purcell"), config)
    np.testing.assert_array_equal(np.asarray(run.q), 0.3)
    explored = np.asarray(run.explored)
    assert explored[:, 0].all() and not explored[:, 10:].any()


def test_rewards_are_target_direction_displacements():
    params = _batched("purcell", zeta=0.5)
    run = train_batch(_keys(8), params)
    x = np.concatenate([np.zeros((B, 1)), np.asarray(run.x)], axis=1)
    np.testing.assert_allclose(np.asarray(run.reward), DIRECTIONS[:, None] * np.diff(x, axis=1), atol=1e-5)


def test_summaries(ng_greedy_all):
    run, params = ng_greedy_all
    rows = summarize(run, params, evaluate(run, params), swimmer="ng", action_set="all")
    assert [r.direction for r in rows] == [1, -1] and all(r.n == B // 2 for r in rows)
    assert all(r.learned == 0.0 and r.median == np.inf for r in rows)
    assert "never" in format_table(rows)


@pytest.mark.parametrize(
    "changes",
    [{"action_set": "some"}, {"discount": 1.0}, {"steps": 0}, {"tie_break": "last"}, {"learning_rate": -1.0}],
)
def test_bad_configs_are_refused(changes):
    with pytest.raises(ConfigError):
        QConfig(**changes)
