"""The examples of docs/rl.md learn Purcell's square gait (return 9.562 over a 200-step
episode, the optimum): the CleanRL-structured PPO over ``gym.make_vec``, and Stable-Baselines3's
PPO and DQN where SB3 (and torch) are installed; elsewhere those skip, saying so."""

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

#: Purcell's square gait over a 200-step episode: 50 cycles of 0.19124724 (docs/design.md).
SQUARE_RETURN = 50 * 0.19124724


@pytest.mark.slow
def test_cleanrl_style_ppo_learns_the_square_gait(float32):
    from tests.env.cleanrl_ppo import train

    returns = np.asarray([r for _, r in train(total_timesteps=100_000)])
    assert returns[:16].mean() < 0.5 * SQUARE_RETURN, returns[:16]
    assert returns[-16:].mean() > 0.98 * SQUARE_RETURN, returns[-16:]
    assert returns.max() <= SQUARE_RETURN + 1e-4


def _sb3():
    try:
        import stable_baselines3
    except ImportError:
        pytest.skip("stable-baselines3 and torch are not installed (pip install stable-baselines3)")
    return stable_baselines3


def _greedy_return(model, env_id):
    env = gym.make(env_id)
    obs, _ = env.reset(seed=0)
    total, done = 0.0, False
    while not done:
        action, _ = model.predict(obs, deterministic=True)
        obs, r, term, trunc, _ = env.step(action)
        total, done = total + r, term or trunc
    return total


@pytest.mark.slow
@pytest.mark.parametrize("algo", ["PPO", "DQN"])
def test_sb3_learns_the_square_gait(algo):
    sb3 = _sb3()
    import jswim.gym  # noqa: F401

    kwargs = {"n_steps": 256, "batch_size": 64} if algo == "PPO" else {"learning_starts": 500}
    model = getattr(sb3, algo)("MlpPolicy", gym.make("jswim/Purcell-v0"), seed=0, **kwargs)
    model.learn(8_000 if algo == "PPO" else 10_000)
    assert _greedy_return(model, "jswim/Purcell-v0") == pytest.approx(SQUARE_RETURN, rel=1e-3)
