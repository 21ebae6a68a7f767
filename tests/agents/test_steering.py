"""The steering controller on the navigation world: fixed targets at every bearing, waypoints and
a moving target, each within the budget measured from the loops' physics."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jswim
from jswim.agents import steering
from jswim.env.loops import loop_motion
from jswim.env.navigation import NavParams, summarise
from jswim.env.targets import FixedTarget, MovingTarget, TargetParams, Waypoints
from jswim.errors import ConfigError
from jswim.swimmers.turning import square_gait

BEARINGS = (0.0, 45.0, -45.0, 90.0, -90.0, 135.0, -135.0, 180.0)
DISTANCE = 3.0


def _batched(specs, roc_levels=2):
    """One world and params holding one target per run (the specs share their waypoint count)."""
    made = [jswim.make("purcell", roc_levels=roc_levels, target=s) for s in specs]
    env, params = made[0]
    stack = TargetParams(*(jnp.stack(v) for v in zip(*(p.target for _, p in made), strict=True)))
    return env, NavParams(params.swimmer, stack)


def test_controller_reaches_fixed_targets_at_every_bearing_within_budget(float32):
    env, params = _batched([FixedTarget(DISTANCE, b) for b in BEARINGS])
    budgets = np.asarray(params.target.budget)
    traj = steering.run(env, params, jax.random.split(jax.random.key(0), len(BEARINGS)))
    runs = [
        summarise(
            env,
            NavParams(params.swimmer, TargetParams(*(v[i] for v in params.target))),
            jax.tree.map(lambda v, i=i: v[i], traj),
        )[0]
        for i in range(len(BEARINGS))
    ]
    steps = np.array([r.steps for r in runs])
    assert all(r.reached for r in runs), steps
    assert np.all(steps <= budgets), (steps, budgets)
    # straight ahead and straight behind (the reversed gait) take the gait's cycles only
    gait = loop_motion(env.model, 2, square_gait(2))
    cycles = math.ceil((DISTANCE - 0.25) / gait.displacement)
    assert steps[0] == steps[-1] <= 4 * cycles
    # a 90 degree turn costs about 27 quarter loops more than straight ahead
    assert 4 * 20 <= steps[3] - steps[0] <= 4 * 40
    # energy per distance closed: the square gait's own when straight (work / dX per cycle)
    np.testing.assert_allclose(
        runs[0].energy_per_distance, gait.work / gait.displacement, rtol=0.05
    )
    assert all(r.energy_per_distance >= runs[0].energy_per_distance * 0.9 for r in runs)


def test_controller_follows_waypoints_and_catches_a_moving_target(float32):
    for spec in (
        Waypoints(((2.0, 1.0), (4.0, -1.0), (6.0, 1.0))),
        Waypoints(((2.0, 0.0), (2.0, 2.0), (0.0, 2.0))),
        MovingTarget(3.0, 90.0, velocity=(0.01, 0.0)),
        MovingTarget(3.0, 180.0, velocity=(0.0, -0.02)),
    ):
        env, params = jswim.make("purcell", roc_levels=2, target=spec)
        run = summarise(env, params, steering.run(env, params, 0))[0]
        assert run.reached and run.steps <= int(params.target.budget), (spec, run)


@pytest.mark.slow  # real ROCs go through the integrator's tables: a few seconds to compile
def test_controller_on_real_rocs_matches_the_lattice():
    spec = FixedTarget(DISTANCE, 90.0)
    lattice = jswim.make("purcell", roc_levels=2, target=spec)
    real = jswim.make("purcell", roc_levels=3, target=spec)  # odd K: float ROC vectors of q / 2
    a = summarise(*lattice, steering.run(*lattice, 0))[0]
    b = summarise(*real, steering.run(*real, 0))[0]
    assert a.reached and b.reached and a.steps == b.steps
    np.testing.assert_allclose(b.path, a.path, rtol=1e-6)


def test_controller_refusals():
    # every corner of the shape square is a start now (tests/env/test_seeded_starts.py); a
    # world without a target is still refused
    with pytest.raises(ConfigError, match="navigation world"):
        steering.controller(jswim.make("purcell", roc_levels=2)[0])


# -- in a flow: the feed-forward of the flow's turn (issue 60) ------------------------------


def test_flow_rotation_is_jeffery_s_turn_and_zero_where_the_flow_does_not_turn(float32):
    from jswim.env.flows import Shear, Uniform

    rate = 0.01
    g = Shear(rate).gradient(jnp.zeros(2))
    for phi in (0.0, 0.4, math.pi / 2, 2.0):
        # Jeffery: -(rate / 2)(1 - B cos 2 phi); half the vorticity alone with shape 0
        want = -(rate / 2) * (1 - steering.JEFFERY * math.cos(2 * phi))
        assert float(steering.flow_rotation(g, phi)) == pytest.approx(want, rel=1e-5)
        assert float(steering.flow_rotation(g, phi, 0.0)) == pytest.approx(-rate / 2, rel=1e-6)
    assert float(steering.flow_rotation(Uniform((0.3, -0.2)).gradient(jnp.zeros(2)), 1.0)) == 0.0


def test_the_feed_forward_is_exactly_nothing_in_still_fluid_and_turns_with_a_strong_flow():
    from jswim.swimmers.turning import LEFT_FORWARD, RIGHT_FORWARD, choose_cycle

    env, _ = jswim.make("purcell", roc_levels=2, target=FixedTarget(3.0, 90.0))
    ctrl = steering.controller(env)
    plan = ctrl.plan
    bearings = jnp.linspace(-jnp.pi, jnp.pi, 721)
    for hub in (0, 1):
        for dist in (0.5, 3.0):
            base = jax.vmap(lambda b, h=hub, d=dist: choose_cycle(plan, h, b, d, 0.125))(bearings)
            fed = jax.vmap(lambda b, h=hub, d=dist: choose_cycle(plan, h, b, d, 0.125, 0.0))(
                bearings
            )
            np.testing.assert_array_equal(base, fed)
    assert float(ctrl.speed(jnp.float32(0.0))) == np.float32(steering.SWIM_SPEED)
    # a target to the left; a clockwise flow turn slower than the loops: still a left turn
    weak = -0.5 * plan.turn / 4
    assert int(choose_cycle(plan, 0, 0.5, 3.0, 0.0, weak)) == LEFT_FORWARD
    # faster than the loops turn (per step): the left turn cannot be made, it turns right
    strong = -1.5 * plan.turn / 4
    assert int(choose_cycle(plan, 1, 0.5, 3.0, 0.0, strong)) == RIGHT_FORWARD
    # the feed-forward: a bearing just inside the dead band leaves it when the flow turns away
    edge = 0.9 * plan.tolerance
    assert int(choose_cycle(plan, 0, edge, 3.0, 0.0)) != LEFT_FORWARD
    assert int(choose_cycle(plan, 0, edge, 3.0, 0.0, weak)) == LEFT_FORWARD
    # holding a heading against the flow's turn slows it: the loops' share of the steps
    assert float(ctrl.speed(weak)) < steering.SWIM_SPEED


@pytest.mark.slow  # two flow worlds' scans compile (~20 s each on a loaded CI core)
@pytest.mark.parametrize("fraction", [0.25, 0.5])
def test_controller_reaches_the_90_degree_target_in_shear(float32, fraction):
    from jswim.env.flows import study_flow

    # the study's budget there (4 x Zermelo's least time is below the still-fluid 256)
    env, params = jswim.make(
        "purcell",
        roc_levels=2,
        target=FixedTarget(3.0, 90.0, budget=256),
        flow=study_flow("shear", fraction),
    )
    run = summarise(env, params, steering.run(env, params, 0))[0]
    assert run.reached, run.steps
    assert run.steps <= 160  # 141 and 125 steps measured (float32)
