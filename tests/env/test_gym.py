"""The Gymnasium door (jswim.gym): every id through Gymnasium's own checkers, its conventions
(max_episode_steps, render modes, keywords, the vector entry point and its autoreset, forked
workers), the Box actions and the observation options (jswim.env.door)."""

import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")
import jswim.gym  # noqa: E402  (registers the ids)
from jswim.errors import ConfigError  # noqa: E402

SQUARE_CODES = [3, 0, 5, 2]  # Purcell from (+, +): D2 -, D1 -, D2 +, D1 +
#: Purcell's square gait, net x per 4-step cycle (docs/design.md's reference, d_max = pi/3).
PURCELL_CYCLE = 0.19124724
FAST_IDS = ["jswim/Purcell-v0", "jswim/NG-v0"]
SLOW_IDS = sorted(set(jswim.gym.ENVIRONMENTS) - set(FAST_IDS))


def test_every_world_is_registered_as_gymnasium_expects():
    names = {k.removeprefix("jswim/") for k in jswim.gym.ENVIRONMENTS}
    assert {"Purcell-v0", "NG-v0", "FourLink-v0", "FourSphere-v0", "PurcellContinuous-v0"} <= names
    assert {"PurcellWall-v0", "NGWall-v0", "NGPair-v0", "NGSchool-v0"} <= names
    for env_id in jswim.gym.ENVIRONMENTS:
        spec = gym.spec(env_id)
        # a navigation id ends its own episodes (its target's budget)
        navigates = "target" in jswim.gym.ENVIRONMENTS[env_id]
        assert spec.max_episode_steps == (None if navigates else 200)
        assert spec.vector_entry_point == "jswim.gym:JswimVectorEnv"
    meta = jswim.gym.JswimEnv.metadata
    assert set(meta["render_modes"]) == {"rgb_array", "human"} and meta["render_fps"] > 0


def test_unknown_keyword_is_one_line_naming_the_valid_ones():
    for bad in ("height", "foo"):
        with pytest.raises(ConfigError) as err:
            gym.make("jswim/Purcell-v0", **{bad: 3})
        text = str(err.value)
        assert "\n" not in text and repr(bad) in text
        assert "zeta" in text and "history" in text and "direction" in text
    with pytest.raises(ConfigError, match="render_mode"), warnings.catch_warnings():
        warnings.simplefilter("ignore")  # Gymnasium's own warning comes first
        gym.make("jswim/Purcell-v0", render_mode="ascii")


def _check(env_id, render=False):
    from gymnasium.utils.env_checker import check_env

    env = gym.make(env_id, render_mode="rgb_array" if render else None)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the checker's advice counts as a failure
        check_env(env.unwrapped, skip_render_check=not render)
        # the passive checker (gym.make's wrapper) on reset and step
        obs, _ = env.reset(seed=0)
        assert env.observation_space.contains(obs)
        env.step(env.action_space.sample())
    if "target" in jswim.gym.ENVIRONMENTS[env_id]:  # a target, not a direction: -x is refused
        with pytest.raises(ConfigError, match="direction does not apply"):
            gym.make(env_id, direction="-x")
        return env
    # The reward is progress toward the target direction: -x mirrors +x, step by step.
    rewards = {}
    for direction in ("+x", "-x"):
        e = gym.make(env_id, direction=direction)
        e.reset(seed=0)
        e.action_space.seed(2)
        rewards[direction] = [e.step(e.action_space.sample())[1] for _ in range(8)]
    assert np.any(np.asarray(rewards["+x"]) != 0)
    np.testing.assert_array_equal(rewards["-x"], -np.asarray(rewards["+x"]))
    return env


@pytest.mark.parametrize("env_id", FAST_IDS)
def test_paper_worlds_pass_the_checkers(env_id):
    env = _check(env_id)
    assert env.action_space.n == 6 and env.observation_space.shape == (2,)


@pytest.mark.slow
@pytest.mark.parametrize("env_id", SLOW_IDS)
def test_every_other_world_passes_the_checkers(env_id):
    env = _check(env_id, render=True)
    low, high = env.observation_space.low, env.observation_space.high
    assert np.all(np.isfinite(low)) and np.all(np.isfinite(high))


def test_max_episode_steps_is_gymnasiums_and_overrides_work():
    env = gym.make("jswim/Purcell-v0", max_episode_steps=5)
    env.reset(seed=0)
    flags = [env.step(SQUARE_CODES[i % 4])[3] for i in range(5)]
    assert flags == [False] * 4 + [True]
    env = gym.make("jswim/Purcell-v0", max_episode_steps=300)
    env.reset(seed=0)
    n = next(t for t in range(1, 400) if env.step(SQUARE_CODES[t % 4])[3])
    assert n == 300


def test_square_gait_reward_and_rgb_frames():
    env = gym.make("jswim/Purcell-v0", render_mode="rgb_array")
    env.reset(seed=0)
    first = env.render()
    rewards = [env.step(c)[1] for c in SQUARE_CODES * 2]
    # two cycles of the square gait: the reference displacement, twice
    assert sum(rewards) == pytest.approx(2 * PURCELL_CYCLE, abs=1e-6)
    frame = env.render()
    assert frame.shape == (360, 480, 3) and frame.dtype == np.uint8
    # a body is drawn (dark pixels on the pale fluid) and the shape changed between the frames
    assert (frame.sum(-1) < 300).sum() > 100
    assert np.any(frame != first)


def test_history_holds_the_records_positions_relative_to_now():
    env = gym.make("jswim/Purcell-v0", history=3)
    assert env.observation_space.shape == (2 + 6,)
    obs, _ = env.reset(seed=0)
    np.testing.assert_array_equal(obs[2:], 0.0)  # no records yet: the start position
    positions = [np.zeros(2)]
    for c in SQUARE_CODES:
        obs, _, _, _, info = env.step(c)
        positions.append(info["position"])
    # the three positions before the current one, oldest first, minus the current one
    expected = np.concatenate([p - positions[-1] for p in positions[-4:-1]])
    np.testing.assert_allclose(obs[2:], expected, atol=1e-6)
    assert env.observation_space.contains(obs)
    with pytest.raises(ConfigError, match="history"):
        gym.make("jswim/Purcell-v0", history=-1)


@pytest.mark.slow
def test_pair_and_school_see_their_separation():
    pair = gym.make("jswim/NGPair-v0")
    obs, _ = pair.reset(seed=0)
    # 4 arms scaled to [-1, 1], then swimmer 2 - swimmer 1 in units of D = 30 a: (1, 0) at the start
    assert obs.shape == (6,)
    np.testing.assert_allclose(obs[4:], [1.0, 0.0], atol=1e-6)
    obs, *_ = pair.step(0)
    info_obs = obs[4]
    assert info_obs != 1.0  # swimmer 1 moved, swimmer 2 did not: the separation changed
    school = gym.make("jswim/NGSchool-v0", separation=False)
    assert school.observation_space.shape == (6,)
    school = gym.make("jswim/NGSchool-v0")
    obs, _ = school.reset(seed=0)
    np.testing.assert_allclose(obs[6:], [1.0, 0.0, 1.0, 0.0], atol=1e-6)


def _moved_fraction(env_id, n=200, **options):
    env = gym.make(env_id, max_episode_steps=n, **options)
    env.reset(seed=0)
    inner = env.unwrapped
    rng = np.random.default_rng(0)

    def dofs():
        return np.asarray(inner.door.world.observe(inner._state.env_state, inner.params).dofs)

    moved, before = np.zeros(inner.door.world.n_dof), dofs()
    for _ in range(n):
        env.step(np.clip(rng.normal(0.0, 1.0, env.action_space.shape), -1, 1).astype(np.float32))
        after = dofs()
        moved += after != before
        before = after
    return moved / n


@pytest.mark.slow
def test_gaussian_box_actions_move_every_joint():
    # The paper's worlds: every DOF at its ROC, so each joint moves unless it sits at a limit
    # and is pushed further.
    frac = _moved_fraction("jswim/PurcellContinuous-v0")
    assert np.all(frac > 0.5), frac
    frac = _moved_fraction("jswim/FourLink-v0", n=100, continuous=True)
    assert np.all(frac > 0.5), frac
    # Scenes move the arm of largest |a_i|: one arm a step at most, each of a pair's four arms
    # chosen in about a quarter of the steps (half of which push it past a limit it sits at).
    frac = _moved_fraction(
        "jswim/NGPair-v0", n=100, continuous=True, scene={"medium": "bulk", "swimmers": 2}
    )
    assert np.all(frac > 0.03) and 0.3 < frac.sum() <= 1.0, frac


def test_box_reading_of_scenes_is_the_largest_entry():
    from jswim.env.door import build

    door, _ = build("ng", {"medium": "free", "swimmers": 2, "separation": 30.0}, continuous=True)
    a = np.asarray(door.world_action(np.array([0.2, -0.9, 0.5, 0.0], np.float32)))
    np.testing.assert_allclose(a, [0.0, -0.9, 0.0, 0.0], atol=1e-7)
    door, _ = build("purcell", continuous=True)
    a = np.asarray(door.world_action(np.array([0.2, -1.7], np.float32)))
    np.testing.assert_allclose(a, [0.2, -1.0], atol=1e-7)  # every DOF, clipped to [-1, 1]


def test_vector_entry_point_steps_like_single_envs_and_autoresets_next_step():
    envs = gym.make_vec("jswim/Purcell-v0", num_envs=3, max_episode_steps=4)
    assert isinstance(envs.unwrapped, jswim.gym.JswimVectorEnv)
    assert envs.metadata["autoreset_mode"] == gym.vector.AutoresetMode.NEXT_STEP
    obs, _ = envs.reset(seed=0)
    assert obs.shape == (3, 2)
    single = gym.make("jswim/Purcell-v0", max_episode_steps=4)
    s_obs, _ = single.reset(seed=0)
    np.testing.assert_array_equal(obs[0], s_obs)
    for t, c in enumerate(SQUARE_CODES):
        obs, reward, terminated, truncated, _ = envs.step(np.full(3, c))
        s_obs, s_reward, _, _s_trunc, _ = single.step(c)
        np.testing.assert_array_equal(obs[1], s_obs)
        np.testing.assert_allclose(reward, s_reward, rtol=1e-6)
        assert list(truncated) == [t == 3] * 3 and not terminated.any()
    # the next step resets: the start shape, reward 0, neither flag, the action ignored
    obs, reward, terminated, truncated, _ = envs.step(np.full(3, 1))
    np.testing.assert_array_equal(obs, np.ones((3, 2)))
    assert not reward.any() and not truncated.any() and not terminated.any()
    obs, reward, *_ = envs.step(np.full(3, SQUARE_CODES[0]))
    assert np.all(reward != 0)


def _run(code: str, timeout: float) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True,
        text=True,
        timeout=timeout,
        check=False,
    )


@pytest.mark.slow
def test_async_vector_envs_refuse_fork_and_work_with_spawn():
    # The parent has used JAX; forked workers would hang. They are refused, and the parent fails
    # instead of waiting (the timeout is the hang's test).
    forked = _run(
        """
        import gymnasium as gym, jswim.gym
        gym.make("jswim/Purcell-v0").reset(seed=0)
        try:
            gym.make_vec("jswim/Purcell-v0", num_envs=2, vectorization_mode="async",
                         vector_kwargs={"context": "fork"})
        except Exception as e:
            print("PARENT", type(e).__name__)
        """,
        120,
    )
    assert "cannot run in a forked process" in forked.stderr
    assert "PARENT" in forked.stdout
    spawned = _run(
        """
        import gymnasium as gym, jswim.gym
        gym.make("jswim/Purcell-v0").reset(seed=0)
        envs = gym.make_vec("jswim/Purcell-v0", num_envs=2, vectorization_mode="async",
                            vector_kwargs={"context": "spawn"})
        envs.reset(seed=0)
        print("REWARD", envs.step([3, 3])[1].tolist())
        envs.close()
        """,
        300,
    )
    assert "REWARD" in spawned.stdout, spawned.stderr[-2000:]


@pytest.mark.slow
def test_jswims_ppo_learns_in_the_box_doors_world(float32):
    import jax

    from jswim.agents import ppo

    env = gym.make("jswim/PurcellContinuous-v0")
    door, params = env.unwrapped.door, env.unwrapped.params
    assert door.world.diagonal  # every DOF at once: the Box door's world
    n = 8
    keys = jax.random.split(jax.random.PRNGKey(0), n)
    run = ppo.train(door.world, params, keys, ppo.PPOConfig(steps=2000))
    report = ppo.evaluate(run, jax.tree.map(lambda v: v, params))
    learned = np.asarray(report.learned)
    # docs/baselines.md: at 2,000 steps the learner finds Purcell's stroke (16 of 16 seeds)
    assert learned.sum() >= n - 2, learned
    # and swims: the last 200 steps move it forward by most of the square gait's 9.56 a
    x = np.asarray(run.x)
    assert np.median(x[:, -1] - x[:, -201]) > 0.7 * 50 * PURCELL_CYCLE, x[:, -1] - x[:, -201]


def test_human_render_mode_draws_in_a_window(monkeypatch):
    import matplotlib

    matplotlib.use("Agg")  # a headless window: the frames are drawn, nothing is shown
    env = gym.make("jswim/Purcell-v0", render_mode="human")
    shown = []
    monkeypatch.setattr("matplotlib.pyplot.pause", lambda s: shown.append(s))
    env.reset(seed=0)
    assert env.step(3)[1] != 0 and env.render() is None
    assert len(shown) == 3 and shown[0] == pytest.approx(1 / jswim.gym.RENDER_FPS)
    import matplotlib.pyplot as plt

    plt.close("all")
