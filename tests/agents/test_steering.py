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
    env, params = jswim.make("purcell", roc_levels=2, target=FixedTarget(3.0), init="+-")
    with pytest.raises(ConfigError, match="hi, hi"):
        steering.run(env, params, 0)
    with pytest.raises(ConfigError, match="navigation world"):
        steering.controller(jswim.make("purcell", roc_levels=2)[0])
