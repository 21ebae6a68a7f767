"""Every baseline takes a new world unchanged: the toy swimmer of tests/env/test_toy_world.py (a
few dozen lines implementing the protocol, never registered anywhere) runs through the tabular
Q-learner, the random policy, a fixed stroke and PPO, each one batched scan over runs.

The toy's physics is the area rule (a closed stroke nets minus the signed area it encloses), so
the numbers checked are independent of jswim: the square gait from (1, 1) goes -1 per cycle,
exactly, and its reverse +1.
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jswim.agents import ppo, qlearning, random_policy, strokes
from jswim.env.discretiser import Cells
from tests.env.test_toy_world import SQUARE, ToyParams, ToyWorld

B = 8


def _keys(seed: int, n: int = B) -> jax.Array:
    return jax.random.split(jax.random.PRNGKey(seed), n)


def test_toy_discretiser_is_the_joint_corner(float32):
    env = ToyWorld()
    cells = env.cells()
    assert type(cells) is Cells and cells.n_cells == 4
    state = env.reset(None, ToyParams())
    j = cells.positions(state, ToyParams())
    assert j.tolist() == [1, 1] and int(cells.cell(state, j, ToyParams())) == 3
    # From (1, 1) only ROC -1 changes the shape: codes 0 (DOF 1) and 3 (DOF 2).
    assert np.flatnonzero(cells.mask(j, ToyParams(), "shape-changing")).tolist() == [0, 3]


@pytest.mark.slow  # two compilations (~5 s idle, 23 s under load 14)
def test_toy_stroke_and_random_policy(float32):
    env, params = ToyWorld(), ToyParams()
    tr = strokes.play(env, params, _keys(0, 2), jnp.stack([SQUARE, SQUARE[::-1]]), 20)
    # The reverse from (1, 1) first pushes two DOFs against their limit (stuck), so its first cycle
    # only closes half the square: +0.5, then +1 per cycle.
    np.testing.assert_allclose(tr.obs.position[:, -1, 0, 0], [-5.0, 4.5], atol=1e-6)
    assert np.asarray(tr.info.stuck)[1, :2].tolist() == [True, True]
    run = random_policy.run(env, params, _keys(1), 40, "shape-changing", trace=True)
    assert run.actions.shape == (B, 40) and run.x.shape == (B, 40)
    # Every offered move changes the shape: no step is stuck and every step moves.
    assert bool(np.all(np.asarray(run.trace.info.moved))) and not bool(
        np.any(np.asarray(run.trace.info.stuck))
    )
    np.testing.assert_allclose(np.cumsum(run.trace.info.progress, 1), run.x, atol=1e-5)


@pytest.mark.slow  # compiles the Q-learner and PPO on a new world (51 s under load 14)
def test_toy_q_learner_finds_the_area_rule_stroke_and_ppo_trains(float32):
    env = ToyWorld()
    directions = np.repeat([1.0, -1.0], B // 2)
    params = ToyParams(0.0, jnp.asarray(directions, jnp.float32))
    run = qlearning.train(env, params, _keys(2), qlearning.QConfig(steps=120))
    assert run.q.shape == (B, 4, 6)
    # A learned stroke is the unit square, 4 moves for 1 a either way: over the last 40 steps,
    # 10 cycles, +10 in the target direction (-x: the clockwise square from (1, 1)).
    late = directions * (np.asarray(run.x)[:, -1] - np.asarray(run.x)[:, -41])
    assert np.sum(np.isclose(late, 10.0, atol=1e-4)) >= B - 1
    trained = ppo.train(env, ToyParams(), _keys(3, 2), ppo.PPOConfig(steps=64))
    assert trained.x.shape == (2, 64) and trained.dofs.shape == (2, 64, 2)
    np.testing.assert_allclose(np.cumsum(trained.progress, 1), trained.x, atol=1e-5)
