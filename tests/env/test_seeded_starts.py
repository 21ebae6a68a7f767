"""A navigation world's start heading and shape (the seeded starts of ``jswim study navigate
--starts``): the swimmer turned about its centroid, the budget measured from its heading, and
still fluid's rotation symmetry: a start heading ``h`` with a target at bearing ``b`` is the
default start with the target at ``b - h``, step for step."""

import dataclasses
import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jswim
from jswim.agents import steering
from jswim.env.navigation import summarise
from jswim.env.state import turned
from jswim.env.targets import FixedTarget, MovingTarget, Waypoints, target_from_dict
from jswim.errors import ConfigError

K = 2


def _world(spec, init=None):
    return jswim.make("purcell", roc_levels=K, init=init, target=spec)


def _controller_steps(spec, init=None):
    env, params = _world(spec, init)
    episode = summarise(env, params, steering.run(env, params, 0))[0]
    return episode.reached, episode.steps, int(params.target.budget)


def test_the_start_is_turned_about_its_centroid_in_the_default_dtype(float32):
    env, params = _world(FixedTarget(3.0, 90.0, start_heading=30.0))
    state = env.reset(jax.random.PRNGKey(0), params)
    obs = env.observe(state, params)
    assert obs.orientation.dtype == jnp.float32  # the users' default
    assert float(obs.orientation[0]) == pytest.approx(math.radians(30.0), abs=1e-7)
    np.testing.assert_array_equal(np.asarray(obs.position), 0.0)  # the centroid stays put
    # the target stays where the spec puts it: 60 degrees off the nose
    assert math.degrees(float(env.target_view(state, params).bearing)) == pytest.approx(
        60.0, abs=1e-4
    )
    # cos and sin carried with the heading agree with it (the step reads them, not theta)
    s = state.swimmer
    assert float(s.cos) == pytest.approx(math.cos(math.radians(30.0)), abs=1e-7)
    assert float(s.sin) == pytest.approx(math.sin(math.radians(30.0)), abs=1e-7)


@pytest.mark.parametrize("x64", [False, True])
def test_a_zero_turn_leaves_the_state_bit_for_bit(x64):
    with jax.enable_x64(x64):
        _zero_turn()


def _zero_turn():
    env, params = _world(FixedTarget(3.0, 90.0))
    state = env.inner.reset(jax.random.PRNGKey(0), params.swimmer)
    same = turned(state, jnp.float32(0.0))
    for a, b in zip(jax.tree.leaves(state), jax.tree.leaves(same), strict=True):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


@pytest.mark.parametrize(
    "heading, bearing", [(30.0, 90.0), (-40.0, 0.0), (45.0, 180.0), (-12.5, -100.0)]
)
def test_still_fluid_is_rotation_symmetric(heading, bearing, float32):
    # the same task seen from a turned start: identical budget and controller steps
    turned_start = _controller_steps(FixedTarget(3.0, bearing, start_heading=heading))
    plain = _controller_steps(FixedTarget(3.0, bearing - heading))
    assert turned_start == plain
    assert turned_start[0]


def test_budget_turns_are_measured_from_the_start_heading():
    model = jswim.make("purcell")[0].model
    from jswim.env.targets import default_budget

    # a target 90 degrees to the left needs no turn from a start headed at it
    assert default_budget(FixedTarget(3.0, 90.0, start_heading=90.0), model) == default_budget(
        FixedTarget(3.0, 0.0), model
    )
    path = Waypoints(((3.0, 0.0), (3.0, 3.0)))
    rotated = Waypoints(((0.0, 3.0), (-3.0, 3.0)), start_heading=90.0)
    assert default_budget(path, model) == default_budget(rotated, model)
    moving = MovingTarget(3.0, 0.0, (0.0, 0.005))
    moving_turned = MovingTarget(3.0, 90.0, (-0.005, 0.0), start_heading=90.0)
    assert default_budget(moving, model) == default_budget(moving_turned, model)


@pytest.mark.parametrize("init", [(1, 1), (0, 0), (1, 0), (0, 1)])
def test_the_controller_starts_from_every_corner_of_the_shape_square(init):
    reached, steps, budget = _controller_steps(FixedTarget(3.0, 90.0), init)
    assert reached and steps <= budget


def test_the_default_start_leaves_no_key_in_the_json():
    for spec in (
        FixedTarget(3.0, 90.0),
        Waypoints(((3.0, 0.0), (3.0, 3.0))),
        MovingTarget(3.0, 0.0, (0.0, 0.005)),
    ):
        assert "start_heading" not in spec.to_dict()  # rows and identities as before
        turned_spec = dataclasses.replace(spec, start_heading=-31.25)
        data = turned_spec.to_dict()
        assert data["start_heading"] == -31.25
        assert target_from_dict(data) == turned_spec


@pytest.mark.parametrize("bad", ["30", float("nan"), float("inf"), 400.0, True, None])
def test_a_bad_start_heading_is_refused_in_one_line(bad):
    with pytest.raises(ConfigError, match="start_heading") as err:
        FixedTarget(3.0, 0.0, start_heading=bad)
    assert "\n" not in str(err.value)
