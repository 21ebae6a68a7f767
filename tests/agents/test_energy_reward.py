"""The baselines' energy-aware reward: ``progress - lambda x work``."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jswim
from jswim.agents import ppo, qlearning
from jswim.agents.rewards import energy_reward
from jswim.errors import ConfigError


@pytest.mark.parametrize("dtype", ["float64", "float32"])
def test_the_reward_is_progress_minus_lambda_times_work(dtype):
    with jax.enable_x64(dtype == "float64"):
        world, params = jswim.make("purcell", roc_levels=2, zeta=0.3)
        info = jswim.rollout(world, params, 1, np.array([0, 6, 4, 9, 2, 1])).info
        assert energy_reward(0.0)(info) is info.progress
        got = np.asarray(energy_reward(0.25)(info))
        progress, work = np.asarray(info.progress), np.asarray(info.work)
    assert np.any(work > 0) and np.any(work == 0)
    np.testing.assert_array_equal(got, progress - np.asarray(0.25, progress.dtype) * work)


@pytest.mark.parametrize("weight", [-0.1, float("nan"), float("inf"), "1"])
def test_a_bad_energy_weight_is_refused(weight):
    with pytest.raises(ConfigError, match="energy_weight"):
        qlearning.QConfig(energy_weight=weight)
    with pytest.raises(ConfigError, match="energy_weight"):
        ppo.PPOConfig(energy_weight=weight)


@pytest.mark.slow
def test_pricing_work_makes_q_learning_spend_less():
    """On the K = 2 lattice the unpriced learners settle on the full square gait (19.6
    xi_par a^3/tau per a); at lambda = 0.05 they swim slower strokes that spend about a fifth of
    its work over the last 200 steps."""
    world, params = jswim.make("purcell", roc_levels=2)
    keys = jax.random.split(jax.random.PRNGKey(0), 8)
    spent = {}
    for weight in (0.0, 0.05):
        config = qlearning.QConfig(steps=600, energy_weight=weight)
        run = qlearning.train(world, params, keys, config, trace=True)
        spent[weight] = np.asarray(run.trace.info.work, np.float64)[:, -200:].sum(1)
    assert np.all(spent[0.05] < 0.5 * spent[0.0])


@pytest.mark.slow
def test_ppo_with_an_energy_price_records_progress_not_the_priced_reward():
    world, params = jswim.make("purcell")
    keys = jax.random.split(jax.random.PRNGKey(3), 2)
    run = ppo.train(world, params, keys, ppo.PPOConfig(steps=16, energy_weight=1.0), trace=True)
    np.testing.assert_array_equal(np.asarray(run.progress), np.asarray(run.trace.info.progress))
    assert np.all(np.isfinite(np.asarray(run.trace.info.work)))


@pytest.mark.parametrize(
    "number", [np.float32(0.25), jnp.float32(0.25), np.array(0.25)], ids=["np", "jnp", "0-d"]
)
def test_a_learners_config_holds_a_numpy_number_as_the_plain_number(number):
    # Configs are static (hashed into jit's cache): one config, one compilation, whatever the
    # array type of the number it was given; integers stay integers, floats are not rounded.
    for config in (qlearning.QConfig, ppo.PPOConfig):
        made = config(energy_weight=number, steps=np.int64(40), learning_rate=number)
        same = config(energy_weight=0.25, steps=40, learning_rate=0.25)
        assert made == same and hash(made) == hash(same)
        assert type(made.steps) is int and type(made.energy_weight) is float
    with pytest.raises(ConfigError, match="steps"):
        qlearning.QConfig(steps=np.float64(40.0))  # a whole float is not a step count
    with pytest.raises(ConfigError, match="energy_weight"):
        ppo.PPOConfig(energy_weight=np.bool_(True))
