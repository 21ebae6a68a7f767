"""The ecosystem's doors: Gymnasium environments (jswim.gym, each through Gymnasium's own
checker) and the gymnax interface (jswim.env.gymnax_env) in a PureJaxRL-style loop and through
gymnax's own wrappers."""

import warnings

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jswim
from jswim.env.gymnax_env import GymnaxEnv

SQUARE_CODES = [3, 0, 5, 2]


def _check(env_id):
    gym = pytest.importorskip("gymnasium")
    from gymnasium.utils.env_checker import check_env

    import jswim.gym  # noqa: F401  (registers the ids)

    env = gym.make(env_id)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the checker's advice on unbounded heights
        check_env(env.unwrapped, skip_render_check=True)
    # The reward is progress toward the target direction: -x mirrors +x, step by step.
    rewards = {}
    for direction in ("+x", "-x"):
        e = gym.make(env_id, direction=direction, max_steps=8)
        obs, _ = e.reset(seed=0)
        assert e.observation_space.contains(obs)
        rewards[direction] = [e.step(c)[1] for c in SQUARE_CODES * 2]
    assert np.any(np.asarray(rewards["+x"]) != 0)
    np.testing.assert_array_equal(rewards["-x"], -np.asarray(rewards["+x"]))
    return env


@pytest.mark.parametrize("env_id", ["jswim/Purcell-v0", "jswim/NG-v0"])
def test_gymnasium_paper_worlds_pass_the_checker(env_id):
    env = _check(env_id)
    assert env.action_space.n == 6 and env.observation_space.shape == (2,)


@pytest.mark.slow
@pytest.mark.parametrize("env_id", ["jswim/NGWall-v0", "jswim/NGPair-v0"])
def test_gymnasium_scene_worlds_pass_the_checker(env_id):
    env = _check(env_id)
    assert env.observation_space.shape == (4,)  # 2 arms + height + tilt; or 4 arms


def test_gymnasium_episode_truncates_and_continuous_actions():
    gym = pytest.importorskip("gymnasium")
    import jswim.gym  # noqa: F401

    env = gym.make("jswim/Purcell-v0", max_steps=3, continuous=True)
    env.reset(seed=1)
    flags = [env.step(np.array([0.0, -0.5], np.float32))[3] for _ in range(3)]
    assert flags == [False, False, True]


def _purejaxrl_loop(env, params, n_envs, n_steps, key):
    """A PureJaxRL-style loop: envs vmapped, time scanned, auto-reset by the env's step; a
    linear softmax policy trained by REINFORCE on each batch of transitions."""
    n_obs, n_act = env.observation_space(params).shape[0], env.action_space(params).n
    reset_keys = jax.random.split(key, n_envs)
    obs, state = jax.vmap(env.reset, in_axes=(0, None))(reset_keys, params)
    weights = jnp.zeros((n_obs, n_act))

    def env_step(carry, k):
        obs, state, weights = carry
        k_act, k_env = jax.random.split(k)
        logits = obs @ weights
        action = jax.random.categorical(k_act, logits)
        step_keys = jax.random.split(k_env, n_envs)
        new_obs, state, reward, _terminated, truncated, info = jax.vmap(
            env.step, in_axes=(0, 0, 0, None)
        )(step_keys, state, action, params)
        return (new_obs, state, weights), (obs, action, reward, truncated, state, info)

    def update(carry, k):
        (obs, state, weights), traj = jax.lax.scan(env_step, carry, jax.random.split(k, n_steps))
        o, a, r, *_ = traj

        def loss(w):
            logp = jax.nn.log_softmax(o @ w)
            return -jnp.mean(
                jnp.take_along_axis(logp, a[..., None], -1)[..., 0] * (r - jnp.mean(r))
            )

        weights = weights - 50.0 * jax.grad(loss)(weights)
        return (obs, state, weights), traj

    (_, _, weights), traj = jax.lax.scan(update, (obs, state, weights), jax.random.split(key, 3))
    return weights, traj


@pytest.mark.slow
def test_gymnax_interface_in_a_purejaxrl_loop(float32):
    world, params = jswim.make("purcell")
    env = GymnaxEnv(world, max_steps=5)
    weights, (obs, _action, reward, truncated, state, info) = jax.jit(
        _purejaxrl_loop, static_argnums=(0, 2, 3)
    )(env, params, 4, 10, jax.random.PRNGKey(0))
    assert (
        weights.shape == (2, 6)
        and bool(jnp.all(jnp.isfinite(weights)))
        and bool(jnp.any(weights != 0))
    )
    assert reward.dtype == jnp.float32 and obs.dtype == jnp.float32
    # Every 5th step ends an episode and the env starts afresh: time back to 0, shape at the start.
    t = np.asarray(state.time).reshape(-1, 4)
    np.testing.assert_array_equal(t[:, 0], np.tile([1, 2, 3, 4, 0], 6))
    np.testing.assert_array_equal(
        np.asarray(truncated).reshape(-1, 4)[:, 0], np.tile([0, 0, 0, 0, 1], 6).astype(bool)
    )
    done = np.asarray(truncated).reshape(-1, 4)
    reset_obs = np.asarray(env.reset(jax.random.PRNGKey(0), params)[0])
    # (the observation after a reset is the start shape, +/+: both DOFs at their upper limit)
    np.testing.assert_array_equal(reset_obs, [1.0, 1.0])
    # Within an episode the rewards sum to the swimmer's x (no noise): the reward is the progress.
    r = np.asarray(reward).reshape(-1, 4)
    x = np.asarray(info["x"]).reshape(-1, 4)
    np.testing.assert_allclose(np.cumsum(r[:4, 0]), x[:4, 0], atol=1e-6)
    assert done.shape == (30, 4)


@pytest.mark.slow
def test_gymnax_wrappers_take_the_world(float32):
    pytest.importorskip("gymnax")
    from gymnax.wrappers.purerl import LogWrapper

    world, params = jswim.make("ng", zeta=0.5)
    env = LogWrapper(GymnaxEnv(world, max_steps=4))
    _obs, state = jax.vmap(env.reset, in_axes=(0, None))(
        jax.random.split(jax.random.PRNGKey(0), 3), params
    )

    def body(state, k):
        keys = jax.random.split(k, 3)
        action = jnp.full((3,), SQUARE_CODES[0], jnp.int32)
        _obs, state, reward, _terminated, _truncated, info = jax.vmap(
            env.step, in_axes=(0, 0, 0, None)
        )(keys, state, action, params)
        return state, (reward, info["returned_episode"], info["returned_episode_returns"])

    _, (reward, ended, returns) = jax.lax.scan(
        body, state, jax.random.split(jax.random.PRNGKey(1), 8)
    )
    np.testing.assert_array_equal(np.asarray(ended)[:, 0], [0, 0, 0, 1, 0, 0, 0, 1])
    # gymnax's logger sums the world's rewards over each episode.
    np.testing.assert_allclose(np.asarray(returns)[3], np.asarray(reward)[:4].sum(0), rtol=1e-6)
