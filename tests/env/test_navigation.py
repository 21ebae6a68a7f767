"""The navigation world: targets, the view in the body frame, the reward, the end of an episode,
the learners' restart, and what it refuses."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jswim
from jswim.env.loops import loop_motion
from jswim.env.navigation import NavCells
from jswim.env.targets import (
    FixedTarget,
    MovingTarget,
    Waypoints,
    default_budget,
    target_from_dict,
)
from jswim.errors import ConfigError
from jswim.swimmers.turning import square_gait

K = 2
#: Square gait on the K = 2 lattice as integer codes (DOF 0-based d: code d (2K + 1) + q + K).
SQUARE = [d * (2 * K + 1) + q + K for d, q in [(1, -2), (0, -2), (1, 2), (0, 2)]]


def _gait_dx():
    return loop_motion(jswim.make("purcell")[0].model, K, square_gait(K)).dx


def test_view_is_the_target_in_the_body_frame(float32):
    for bearing in (0.0, 45.0, 90.0, -135.0, 180.0):
        env, params = jswim.make("purcell", roc_levels=K, target=FixedTarget(3.0, bearing))
        state = env.reset(jax.random.key(0), params)
        view = env.target_view(state, params)
        b = math.radians(bearing)
        np.testing.assert_allclose(view.position, [3 * math.cos(b), 3 * math.sin(b)], atol=1e-6)
        np.testing.assert_allclose(view.distance, 3.0, rtol=1e-6)
        # the start heading is the lab's +x: the bearing is the spec's (180 wraps to +pi)
        np.testing.assert_allclose(
            abs(math.remainder(float(view.bearing) - b, 2 * math.pi)), 0, atol=1e-6
        )
        assert env.observe(state, params).target.distance == view.distance
        assert env.features(state, params).shape == (env.n_features,)


def test_reward_is_the_distance_decrease_and_sums_to_it(float32):
    env, params = jswim.make("purcell", roc_levels=K, target=FixedTarget(30.0, 0.0))
    traj = jswim.rollout(env, params, 0, jnp.asarray(SQUARE * 10))
    d = np.asarray(traj.obs.target.distance, np.float64)
    p = np.asarray(traj.info.progress, np.float64)
    np.testing.assert_allclose(p[1:], d[:-1] - d[1:], atol=1e-5)
    # straight ahead the distance falls by the gait's displacement per cycle (closed tables)
    np.testing.assert_allclose(p.sum(), 10 * _gait_dx(), rtol=1e-5)
    assert np.all(np.isfinite(np.asarray(traj.info.work)))


def test_success_ends_the_episode_and_later_steps_earn_nothing(float32):
    dx = _gait_dx()
    # reached after 3 cycles: the centroid sits within the radius of the target
    env, params = jswim.make("purcell", roc_levels=K, target=FixedTarget(3 * dx, 0.0, radius=0.05))
    traj = jswim.rollout(env, params, 0, jnp.asarray(SQUARE * 5))
    reached = np.asarray(traj.state.reached)
    first = int(np.argmax(reached))
    assert first == 11 and reached[first:].all()  # the 12th step closes the third cycle
    assert np.all(np.asarray(traj.info.progress)[first + 1 :] == 0)
    assert np.asarray(traj.state.t)[-1] == 12
    term, trunc = env.termination(jax.tree.map(lambda v: v[-1], traj.state), params)
    assert bool(term) and not bool(trunc)


def test_budget_truncates(float32):
    env, params = jswim.make("purcell", roc_levels=K, target=FixedTarget(5.0, 90.0, budget=8))
    traj = jswim.rollout(env, params, 0, jnp.asarray(SQUARE * 3))
    last = jax.tree.map(lambda v: v[-1], traj.state)
    assert tuple(map(bool, env.termination(last, params))) == (False, True)
    assert np.asarray(traj.state.done).tolist() == [False] * 7 + [True] * 5


def test_waypoints_in_order_and_the_learners_restart(float32):
    dx = _gait_dx()
    pts = ((dx, 0.0), (2 * dx, 0.0))
    env, params = jswim.make("purcell", roc_levels=K, target=Waypoints(pts, radius=0.05))
    assert env.n_points == 2
    traj = jswim.rollout(env, params, 0, jnp.asarray(SQUARE * 3))
    index = np.asarray(traj.state.index)
    assert index[3] == 1 and index[7] == 2 and np.asarray(traj.state.reached)[7]
    # the learners' step restarts the episode at once, and counts it
    state = env.reset(jax.random.key(0), params)
    noise = jnp.zeros((1,))
    for t in range(8):
        state, _ = env.learner_advance(state, jnp.int32(SQUARE[t % 4]), noise, params)
    assert (int(state.episodes), int(state.successes), int(state.last_steps)) == (1, 1, 8)
    assert int(state.t) == 0 and float(jnp.abs(state.swimmer.x)) == 0.0


def test_moving_target_moves_with_the_episode_clock(float32):
    env, params = jswim.make(
        "purcell", roc_levels=K, target=MovingTarget(3.0, 90.0, velocity=(0.01, 0.0))
    )
    traj = jswim.rollout(env, params, 0, jnp.zeros(5, jnp.int32) + SQUARE[0])
    np.testing.assert_allclose(traj.obs.target.position[:, 0], 0.01 * np.arange(1, 6), atol=1e-6)


def test_cells_cross_the_shape_with_the_bearing():
    env, params = jswim.make("purcell", roc_levels=K, target=FixedTarget(3.0, 90.0))
    cells = env.cells()
    assert isinstance(cells, NavCells) and cells.n_cells == 9 * 8
    state = env.reset(jax.random.key(0), params)
    j = cells.positions(state, params)
    assert j.tolist() == [2, 2]
    # lattice point (2, 2) is row 8; 90 degrees is bin 2 of 8
    assert int(cells.cell(state, j, params)) == 8 * 8 + 2


def test_lattice_option_rounds_float_rocs():
    env, params = jswim.make("purcell", roc_levels=K, target=FixedTarget(3.0), lattice=True)
    state = env.reset(jax.random.key(0), params)
    state, _ = env.advance(state, jnp.asarray([0.0, -0.4]), jnp.zeros(1), params)
    assert np.asarray(state.swimmer.frac).tolist() == [1.0, 0.5]


def test_refusals_are_one_line():
    for kwargs, match in [
        ({"swimmer": "purcell"}, "corner world"),
        ({"swimmer": "ng", "roc_levels": 2}, "move on a line"),
        (
            {"swimmer": "ng", "scene": {"medium": "free", "obstacles": [[10.0, 0.0, 2.0]]}},
            "scene's NG",
        ),
        ({"swimmer": "purcell", "roc_levels": 2, "bearing_bins": 0}, "bearing_bins"),
    ]:
        with pytest.raises(ConfigError, match=match) as err:
            jswim.make(target=FixedTarget(3.0), **kwargs)
        assert "\n" not in str(err.value)
    with pytest.raises(ConfigError, match="target must be"):
        jswim.make("purcell", roc_levels=2, target=(3.0, 90.0))
    with pytest.raises(ConfigError, match="exceed"):
        FixedTarget(0.1)
    with pytest.raises(ConfigError, match="budget"):
        default_budget(FixedTarget(3.0), jswim.make("nlink")[0].model)


def test_wall_plane_hosts_navigation():
    env, params = jswim.make(
        "purcell", {"medium": "wall", "height": 2.0}, roc_levels=K, target=FixedTarget(3.0, 90.0)
    )
    assert env.scenery().plane_height == 2.0
    assert int(params.target.budget) > 0


def test_specs_round_trip_and_hash():
    specs = [
        FixedTarget(3.0, 135.0),
        Waypoints(((1.0, 1.0), (2.0, 0.0)), radius=0.3, budget=500),
        MovingTarget(4.0, -45.0, velocity=(0.0, 0.005)),
    ]
    for spec in specs:
        assert target_from_dict(spec.to_dict()) == spec
        assert hash(spec) == hash(target_from_dict(spec.to_dict()))


def test_default_budgets_follow_the_measured_physics():
    model = jswim.make("purcell")[0].model
    fixed = default_budget(FixedTarget(3.0, 90.0), model)
    ahead = default_budget(FixedTarget(3.0, 0.0), model)
    behind = default_budget(FixedTarget(3.0, 180.0), model)
    assert ahead == behind < fixed  # behind: swims backward, no turn
    moving = default_budget(MovingTarget(3.0, 90.0, velocity=(0.0, 0.01)), model)
    assert moving > fixed


def test_gymnasium_id_passes_check_env_and_ends_at_the_target():
    gymnasium = pytest.importorskip("gymnasium")
    from gymnasium.utils.env_checker import check_env

    import jswim.gym  # noqa: F401

    env = gymnasium.make("jswim/NavigatePurcell-v0")
    check_env(env.unwrapped, skip_render_check=True)
    obs, _ = env.reset(seed=0)
    assert obs.shape == (5,) and env.action_space.n == 10
    # a target one square-gait cycle ahead: terminated after 4 steps of the gait
    env = gymnasium.make("jswim/NavigatePurcell-v0", target=FixedTarget(0.2, 0.0, radius=0.05))
    env.reset(seed=0)
    flags = [env.step(int(a))[2] for a in SQUARE]
    assert flags == [False, False, False, True]


def test_gymnax_navigation_ends_its_episodes():
    pytest.importorskip("gymnax")
    import jswim.gymnax

    env, params = jswim.gymnax.make("NavigatePurcell-v0")
    assert params.max_steps_in_episode == int(params.world.target.budget)
    obs, state = env.reset(jax.random.key(0), params)
    obs, state, _, done, _ = env.step_env(jax.random.key(1), state, SQUARE[0], params)
    assert obs.shape == (5,) and not bool(done)


# -- budgets in a flow: the worlds' rule is the study's (issue 60) ---------------------------


def test_a_world_in_a_flow_gets_the_flow_budget_and_says_so(float32):
    """Poiseuille at 0.5 v, target 3 a upstream: the still-fluid 96 steps are short of
    Zermelo's 115; the world's budget is 4 x its straight crab course (115.0 steps, where the
    head flow is half the swimming speed), the study's 461 (4 x Zermelo's 115.2)."""
    from jswim.env.flows import SWIM_SPEED, Uniform, study_flow
    from jswim.env.targets import FLOW_BUDGET_FACTOR, course_time, flow_budget

    spec = FixedTarget(3.0, 180.0)
    flow = study_flow("poiseuille", 0.5)
    env, params = jswim.make("purcell", roc_levels=K, target=spec)
    assert int(params.target.budget) == 96  # still fluid: unchanged
    env, params = jswim.make("purcell", roc_levels=K, target=spec, flow=flow)
    t = course_time(spec, flow)
    assert t == pytest.approx(2.75 / (0.5 * SWIM_SPEED), rel=1e-6)  # on the centre line
    assert int(params.target.budget) == int(env.default_params.target.budget) == 461
    assert int(params.target.budget) == flow_budget(96, t) == math.ceil(FLOW_BUDGET_FACTOR * t)
    assert "budget=461 steps (4 x 115.0 steps of the straight course" in repr(env)
    # a budget given is kept; a flow of speed 0 and a target within the still budget keep it
    given = jswim.make(
        "purcell", roc_levels=K, target=FixedTarget(3.0, 180.0, budget=50), flow=flow
    )
    assert int(given[1].target.budget) == 50 and "the target's own" in repr(given[0])
    calm = jswim.make("purcell", roc_levels=K, target=spec, flow=Uniform((0.0, 0.0)))
    assert int(calm[1].target.budget) == 96
    # in still fluid the course is the straight line: (distance - radius) / speed
    assert course_time(spec, Uniform((0.0, 0.0))) == pytest.approx(2.75 / SWIM_SPEED)
    # a head flow faster than the swimmer: no course; the still budget, and the repr says why
    fast = Uniform((1.5 * SWIM_SPEED, 0.0))
    assert course_time(spec, fast) is None
    env, params = jswim.make("purcell", roc_levels=K, target=spec, flow=fast)
    assert int(params.target.budget) == 96 and "too fast" in repr(env)


def test_the_world_s_course_is_never_shorter_than_zermelo_s_least_time():
    from jswim.env.flows import flow_json, study_flow
    from jswim.env.targets import course_time
    from jswim.studies.kinds.navigate import MOVING, target_json, zermelo_path

    for kind, spec in (
        ("poiseuille", FixedTarget(3.0, 180.0)),
        ("shear", FixedTarget(3.0, 90.0)),
        ("uniform", FixedTarget(3.0, 0.0)),
        ("taylor-green", MOVING),
    ):
        flow = study_flow(kind, 0.5)
        best = zermelo_path(target_json(spec), flow_json(flow)).steps
        t = course_time(spec, flow)
        assert best - 1e-6 <= t <= 1.15 * best, (kind, best, t)
