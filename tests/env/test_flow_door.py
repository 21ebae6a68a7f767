"""The flow navigation door (``NavigatePurcellFlow-v0``, jswim.env.door): its flow and budget,
Gymnasium's checkers, the flow entries of the observation inside their bounds, the stream's
drift in the stepped positions, the vector entry point, the gymnax name, and `build`'s
refusals of the flows `jswim.make` refuses."""

from __future__ import annotations

import math
import warnings

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jswim.env.door import EXTRA_BOUND, IDS, NAVIGATE_FLOW, NAVIGATE_FLOW_TARGET, build
from jswim.env.flows import SWIM_SPEED, Shear, TaylorGreen, Uniform, study_flow
from jswim.env.targets import FixedTarget
from jswim.errors import ConfigError

gym = pytest.importorskip("gymnasium")
import jswim.gym  # noqa: E402  (registers the ids)

ID = "jswim/NavigatePurcellFlow-v0"
#: The stream across the start heading, in swimming speeds (the id's flow).
FRACTION = 0.5
#: Purcell's square gait from (+, +) on K = 2 (tests/env/test_navigation.py's SQUARE).
SQUARE = [5, 0, 9, 4]


def test_the_id_is_purcell_k2_in_half_the_swimming_speed_across_its_heading():
    kw = IDS["NavigatePurcellFlow-v0"]
    assert kw["swimmer"] == "purcell" and kw["roc_levels"] == 2
    assert kw["flow"] == NAVIGATE_FLOW == study_flow("uniform", FRACTION)
    assert NAVIGATE_FLOW.u == pytest.approx((0.0, FRACTION * SWIM_SPEED))
    # cross-stream: straight ahead, where the stream alone never carries the swimmer
    assert (kw["target"].distance, kw["target"].bearing) == (3.0, 0.0)
    spec = gym.spec(ID)
    assert spec.max_episode_steps is None  # a navigation id ends its own episodes
    assert spec.vector_entry_point == "jswim.gym:JswimVectorEnv"


def test_the_budget_is_the_navigation_studys_rule_in_this_flow():
    from jswim.env.flows import flow_json
    from jswim.env.targets import default_budget
    from jswim.studies.kinds.navigate import FLOW_BUDGET_FACTOR, target_json, zermelo_path
    from jswim.swimmers.models import make_model

    still = FixedTarget(3.0, 0.0)
    best = zermelo_path(target_json(still), flow_json(NAVIGATE_FLOW)).steps
    assert best is not None  # Zermelo reaches it: the crab ~30 degrees into the stream
    rule = max(
        default_budget(still, make_model("purcell"), 2), math.ceil(FLOW_BUDGET_FACTOR * best)
    )
    assert NAVIGATE_FLOW_TARGET.budget == rule == 263


def test_it_passes_gymnasiums_checkers_and_its_flow_entries_keep_their_bounds():
    from gymnasium.utils.env_checker import check_env

    env = gym.make(ID)
    assert env.observation_space.shape == (7,) and env.action_space.n == 10
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the checker's advice counts as a failure
        check_env(env.unwrapped, skip_render_check=True)
        obs, _ = env.reset(seed=0)
        # 2 hinges at (+, +), the target straight ahead 3 a away (/ 4 a), then the stream in the
        # body frame over the swimming speed: across the middle link, half of it
        np.testing.assert_allclose(obs, [1, 1, 1, 0, 0.75, 0, FRACTION], atol=1e-6)
        assert env.observation_space.contains(obs)
        env.action_space.seed(0)
        for _ in range(40):  # the passive checker (gym.make's wrapper) on every step
            obs, reward, terminated, truncated, _ = env.step(env.action_space.sample())
            assert env.observation_space.contains(obs) and np.isfinite(reward)
            # a uniform stream turns with the body, its size unchanged
            assert np.hypot(*obs[5:]) == pytest.approx(FRACTION, abs=1e-5)
            assert not terminated and not truncated
    low, high = env.observation_space.low, env.observation_space.high
    np.testing.assert_array_equal(high[5:], [EXTRA_BOUND] * 2)
    np.testing.assert_array_equal(low, -high)
    with pytest.raises(ConfigError, match="direction does not apply"):
        gym.make(ID, direction="-x")


def test_the_stream_carries_the_swimmer_by_u_each_step():
    # A uniform stream adds u to every step's displacement: the same strokes in still fluid
    # (the same target, flow=None) end t u apart after t steps.
    flowing = gym.make(ID)
    still = gym.make(ID, flow=None)
    assert still.observation_space.shape == (5,)
    flowing.reset(seed=0)
    still.reset(seed=0)
    for t, code in enumerate(SQUARE * 3, start=1):
        *_, f_info = flowing.step(code)
        *_, s_info = still.step(code)
        np.testing.assert_allclose(
            f_info["position"] - s_info["position"], [0.0, t * FRACTION * SWIM_SPEED], atol=1e-9
        )


def test_make_vec_steps_the_batch_as_single_envs_step():
    envs = gym.make_vec(ID, num_envs=3)
    assert isinstance(envs.unwrapped, jswim.gym.JswimVectorEnv)
    assert envs.single_observation_space.shape == (7,)
    obs, _ = envs.reset(seed=0)
    single = gym.make(ID)
    s_obs, _ = single.reset(seed=0)
    np.testing.assert_array_equal(obs[0], s_obs)
    for code in SQUARE * 2:
        obs, reward, terminated, truncated, _ = envs.step(np.full(3, code))
        s_obs, s_reward, *_ = single.step(code)
        np.testing.assert_allclose(obs[1], s_obs, atol=1e-6)
        np.testing.assert_allclose(reward, s_reward, rtol=1e-6)
        assert envs.observation_space.contains(obs)
        assert not terminated.any() and not truncated.any()


def test_the_gymnax_name_gives_the_same_world_bounds_and_budget():
    pytest.importorskip("gymnax")
    from gymnax.environments import spaces
    from gymnax.wrappers.purerl import FlattenObservationWrapper, LogWrapper

    import jswim.gymnax

    assert "NavigatePurcellFlow-v0" in jswim.gymnax.registered()
    env, params = jswim.gymnax.make("NavigatePurcellFlow-v0")
    assert params.max_steps_in_episode == NAVIGATE_FLOW_TARGET.budget == 263
    assert isinstance(env.action_space(params), spaces.Discrete)
    box = env.observation_space(params)
    ref = gym.make(ID).observation_space
    np.testing.assert_array_equal(np.asarray(box.low), ref.low)
    np.testing.assert_array_equal(np.asarray(box.high), ref.high)
    # gymnax's wrappers, vmapped and scanned as PureJaxRL runs them
    wrapped = LogWrapper(FlattenObservationWrapper(env))
    n = 2
    _, state = jax.vmap(wrapped.reset, in_axes=(0, None))(
        jax.random.split(jax.random.PRNGKey(0), n), params
    )

    def body(state, inp):
        k, code = inp
        obs, state, reward, _t, done, _i = jax.vmap(wrapped.step, in_axes=(0, 0, 0, None))(
            jax.random.split(k, n), state, jnp.full((n,), code), params
        )
        return state, (obs, reward, done)

    codes = jnp.asarray(SQUARE * 2)
    _, (obs, reward, done) = jax.lax.scan(
        body, state, (jax.random.split(jax.random.PRNGKey(1), len(codes)), codes)
    )
    assert obs.shape == (len(codes), n, 7) and obs.dtype == jnp.float32
    assert bool(jnp.all((obs >= box.low) & (obs <= box.high)))
    np.testing.assert_allclose(np.hypot(obs[..., 5], obs[..., 6]), FRACTION, atol=1e-5)
    assert reward.dtype == jnp.float32 and not bool(jnp.any(done))


@pytest.mark.parametrize(
    "options, says",
    [
        ({"swimmer": "ng"}, "moves on a line"),
        ({"scene": {"medium": "wall", "height": 2.0}, "flow": Shear(0.01)}, "keeps no-slip"),
        ({"flow": (0.0, 0.02)}, "flow must be a jswim.env.flows flow"),
        ({"flow": {"kind": "uniform", "u": [0.0, 0.02]}}, "flow must be a jswim.env.flows flow"),
    ],
)
def test_build_refuses_the_flows_make_refuses_in_one_line(options, says):
    kw = {"swimmer": "purcell", "roc_levels": 2, "target": FixedTarget(3.0, 0.0)}
    kw["flow"] = Uniform((0.0, 0.02))
    with pytest.raises(ConfigError) as err:
        build(**{**kw, **options})
    assert says in str(err.value) and "\n" not in str(err.value)


def test_box_actions_in_a_flow_and_flow_among_the_valid_options():
    # every joint at once is the diagonal stroke, stepped exactly in a uniform stream only
    door, _ = build("purcell", flow=Uniform((0.0, 0.02)), continuous=True)
    assert door.world.diagonal and door.n_obs == 2  # no target: the flow adds no entries
    with pytest.raises(ConfigError, match="continuous=True moves every joint at once") as err:
        build("purcell", flow=Shear(0.01), continuous=True)
    assert "\n" not in str(err.value) and "diagonal" not in str(err.value)
    # with a target one DOF moves a step: any flow
    door, _ = build(
        "purcell",
        roc_levels=2,
        target=FixedTarget(3.0, 0.0),
        flow=TaylorGreen(0.03, 6.0),
        continuous=True,
    )
    assert door.n_obs == 7
    with pytest.raises(ConfigError, match="valid: .*flow"):
        build("purcell", flows=0.5)


def _steps_to_end(env, code: int) -> tuple[int, bool]:
    env.reset(seed=0)
    for t in range(1, 1000):
        _, _, terminated, truncated, _ = env.step(code)
        if terminated or truncated:
            return t, terminated
    raise AssertionError("no end within 1000 steps")


def test_drift_alone_reaches_a_downstream_target_but_not_the_ids():
    # why the id's target is straight ahead (docs/rl.md): code 2 moves no joint, so only the
    # stream moves the swimmer; it reaches the target at 90 degrees (downstream), not this one
    downstream = gym.make("jswim/NavigatePurcell-v0", flow=NAVIGATE_FLOW)
    t, reached = _steps_to_end(downstream, 2)
    assert reached and t < int(downstream.unwrapped.params.target.budget) == 256
    t, reached = _steps_to_end(gym.make(ID), 2)
    assert not reached and t == NAVIGATE_FLOW_TARGET.budget
