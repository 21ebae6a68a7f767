"""The gymnax door (jswim.gymnax): gymnax's spaces and bounds (those of the Gymnasium door), params
with max_steps_in_episode, gymnax's four standard wrappers, and a PureJaxRL-structured PPO that
learns Purcell's square gait through FlattenObservationWrapper and LogWrapper."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

pytest.importorskip("gymnax")
from gymnax.environments import environment, spaces

import jswim.gymnax
from jswim.errors import ConfigError

SQUARE_CODES = [3, 0, 5, 2]
#: Purcell's square gait over a 200-step episode: 50 cycles of 0.19124724 (docs/design.md).
SQUARE_RETURN = 50 * 0.19124724


def test_make_gives_env_and_params_with_gymnax_spaces():
    env, params = jswim.gymnax.make("Purcell-v0")
    assert isinstance(env, environment.Environment)
    assert params.max_steps_in_episode == 200
    assert isinstance(env.action_space(params), spaces.Discrete)
    assert isinstance(env.observation_space(params), spaces.Box)
    env.extra = 1  # not frozen: wrappers may set attributes
    env, params = jswim.gymnax.make("jswim/NGPair-v0", max_steps_in_episode=7, history=2)
    assert params.max_steps_in_episode == 7
    box = env.observation_space(params)
    assert box.shape == (4 + 2 + 4,) and bool(jnp.all(jnp.isfinite(box.low)))
    env, params = jswim.gymnax.make("PurcellContinuous-v0")
    assert isinstance(env.action_space(params), spaces.Box)
    with pytest.raises(ConfigError, match="Purcell-v0"):
        jswim.gymnax.make("Purcel-v0")
    with pytest.raises(ConfigError, match="valid"):
        jswim.gymnax.make("Purcell-v0", height=3.0)


def test_bounds_match_the_gymnasium_door():
    gym = pytest.importorskip("gymnasium")
    import jswim.gym

    for name in ("Purcell-v0", "NGWall-v0", "NGSchool-v0"):
        env, params = jswim.gymnax.make(name)
        box = env.observation_space(params)
        ref = gym.make(f"jswim/{name}").observation_space
        np.testing.assert_array_equal(np.asarray(box.low), ref.low)
        np.testing.assert_array_equal(np.asarray(box.high), ref.high)


@pytest.mark.slow
def test_gymnax_wrappers_take_the_door(float32):
    from gymnax.wrappers.gym import GymnaxToGymWrapper, GymnaxToVectorGymWrapper
    from gymnax.wrappers.purerl import FlattenObservationWrapper, LogWrapper

    env, params = jswim.gymnax.make("Purcell-v0", max_steps_in_episode=4)
    wrapped = LogWrapper(FlattenObservationWrapper(env))
    _obs, state = jax.vmap(wrapped.reset, in_axes=(0, None))(
        jax.random.split(jax.random.PRNGKey(0), 3), params
    )

    def body(state, inp):
        k, code = inp
        obs, state, reward, _term, truncated, info = jax.vmap(
            wrapped.step, in_axes=(0, 0, 0, None)
        )(jax.random.split(k, 3), state, jnp.full((3,), code), params)
        return state, (reward, truncated, info["returned_episode_returns"], obs)

    codes = jnp.asarray(SQUARE_CODES * 2)
    _, (reward, truncated, returns, obs) = jax.lax.scan(
        body, state, (jax.random.split(jax.random.PRNGKey(1), 8), codes)
    )
    assert reward.dtype == jnp.float32 and obs.dtype == jnp.float32
    np.testing.assert_array_equal(np.asarray(truncated)[:, 0], [0, 0, 0, 1, 0, 0, 0, 1])
    # gymnax's logger sums the rewards of each episode: one square cycle, the reference value
    np.testing.assert_allclose(np.asarray(returns)[3], 0.19124724, rtol=1e-5)
    np.testing.assert_array_equal(np.asarray(obs)[3], np.ones((3, 2)))  # reset to the start

    g = GymnaxToGymWrapper(env, params, seed=0)
    assert g.observation_space.shape == (2,) and g.action_space.n == 6
    g.reset()
    rewards = [float(g.step(c)[1]) for c in SQUARE_CODES]
    assert sum(rewards) == pytest.approx(0.19124724, rel=1e-5)
    assert g.render().shape == (360, 480, 3)

    v = GymnaxToVectorGymWrapper(env, 4, params, seed=0)
    obs, _ = v.reset()
    assert obs.shape == (4, 2) and v.observation_space.shape == (4, 2)
    _obs, reward, *_ = v.step(jnp.full((4,), SQUARE_CODES[0]))
    assert np.all(np.asarray(reward) != 0)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["Purcell-v0", "PurcellContinuous-v0"])
def test_purejaxrl_ppo_learns_the_square_gait(float32, name):
    from tests.env.purejaxrl_ppo import episode_returns, make_train

    env, params = jswim.gymnax.make(name)
    total = 150_000 if name == "Purcell-v0" else 100_000
    out = jax.jit(make_train({"TOTAL_TIMESTEPS": total}, env, params))(jax.random.PRNGKey(0))
    done = np.asarray(out["metrics"]["returned_episode"]).sum((1, 2)) > 0
    returns = np.asarray(episode_returns(out["metrics"]))[done]
    # first episodes near a random policy's return; the last within 1% of the square gait's
    assert returns[0] < 0.5 * SQUARE_RETURN, returns
    assert returns[-3:].mean() > 0.99 * SQUARE_RETURN, returns
    assert returns.max() <= SQUARE_RETURN + 1e-3, returns


@pytest.mark.slow
def test_params_batch_over_directions(float32):
    from jswim.gymnax import Params

    env, params = jswim.gymnax.make("NG-v0")
    batched = Params(params.world.replace(direction=jnp.array([1.0, -1.0])), 200)
    axes = Params(params.world.replace(zeta=None, direction=0, init=None), None)
    _obs, state = jax.vmap(env.reset, in_axes=(None, axes))(jax.random.PRNGKey(0), batched)
    _obs, state, reward, *_ = jax.vmap(env.step, in_axes=(None, 0, None, axes))(
        jax.random.PRNGKey(1), state, 0, batched
    )
    assert float(reward[0]) != 0.0 and float(reward[1]) == -float(reward[0])
