"""What a navigation world in a background flow shows its agents: the local flow in the target
view (lab frame), in the features (body frame, over the swimming speed) and in the tabular
learners' cells; and the steering controller's crab angle. Still fluid keeps today's numbers."""

from __future__ import annotations

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jswim
from jswim.agents import steering
from jswim.agents.steering import crab_bearing
from jswim.env.flows import SWIM_SPEED, Shear, TaylorGreen, Uniform, study_flow
from jswim.env.navigation import FLOW_BINS, summarise
from jswim.env.targets import FixedTarget

V = SWIM_SPEED


def _world(flow, bearing=90.0, **kw):
    return jswim.make("purcell", roc_levels=2, target=FixedTarget(3.0, bearing, **kw), flow=flow)


def _turned(env, params, theta):
    """The start state with the swimmer's heading turned to ``theta`` (rad), in place."""
    state = env.reset(jax.random.PRNGKey(0), params)
    sw = state.swimmer
    dtype = sw.theta.dtype
    sw = sw._replace(
        theta=jnp.asarray(theta, dtype),
        cos=jnp.asarray(math.cos(theta), dtype),
        sin=jnp.asarray(math.sin(theta), dtype),
    )
    return state._replace(swimmer=sw)


def test_still_fluid_views_are_todays():
    env, params = _world(None)
    state = env.reset(jax.random.PRNGKey(0), params)
    assert env.flow is None and env.n_features == 5
    assert env.cells().n_cells == 9 * 8
    np.testing.assert_array_equal(env.observe(state, params).target.flow, [0.0, 0.0])
    assert env.features(state, params).shape == (5,)


@pytest.mark.parametrize("theta", [0.0, 0.7, -2.4])
def test_the_view_holds_the_lab_flow_and_the_features_the_body_flow(theta):
    u = (0.012, -0.03)
    env, params = _world(Uniform(u))
    state = _turned(env, params, theta)
    view = env.observe(state, params).target
    np.testing.assert_allclose(view.flow, u, rtol=1e-6)
    feats = np.asarray(env.features(state, params))
    assert env.n_features == 7 and feats.shape == (7,)
    # the body frame: the lab vector rotated by -theta, over the swimming speed
    c, s = math.cos(theta), math.sin(theta)
    body = (c * u[0] + s * u[1], -s * u[0] + c * u[1])
    np.testing.assert_allclose(feats[5:], np.asarray(body) / V, rtol=1e-5, atol=1e-6)


def test_a_shear_and_a_vortex_cell_give_their_local_velocity():
    env, params = _world(Shear(0.01))
    state = env.reset(jax.random.PRNGKey(0), params)
    y = float(env.observe(state, params).position[0, 1])
    np.testing.assert_allclose(env.observe(state, params).target.flow, [0.01 * y, 0.0], atol=1e-8)
    env, params = _world(TaylorGreen(0.02, 6.0))
    state = env.reset(jax.random.PRNGKey(0), params)
    x, y = (float(v) for v in env.observe(state, params).position[0])
    k = math.pi / 6.0
    want = 0.02 * np.array([math.sin(k * x) * math.cos(k * y), -math.cos(k * x) * math.sin(k * y)])
    np.testing.assert_allclose(env.observe(state, params).target.flow, want, atol=1e-7)


@pytest.mark.parametrize(
    "u, theta, want",
    [
        ((0.0, 0.0), 0.0, 0),  # calm
        ((0.001 * V, 0.0), 0.0, 0),  # slower than a tenth of v: calm
        ((V, 0.0), 0.0, 1),  # from ahead
        ((0.0, V), 0.0, 2),  # to the left
        ((-V, 0.0), 0.0, 3),  # from behind
        ((0.0, -V), 0.0, 4),  # to the right
        ((0.0, V), math.pi / 2, 1),  # the same stream, the swimmer turned to face it
    ],
)
def test_the_flow_bin_reads_the_body_frame(u, theta, want):
    env, params = _world(Uniform(u))
    cells = env.cells()
    assert cells.n_cells == 9 * 8 * FLOW_BINS
    state = _turned(env, params, theta)
    assert int(cells.flow_bin(state, params)) == want
    j = cells.positions(state, params)
    place = int(env.cells().cell(state, j, params)) // FLOW_BINS
    assert 0 <= place < 9 * 8


@pytest.mark.parametrize("bearing", [0.0, 0.9, -2.0, 3.1])
@pytest.mark.parametrize("u", [(0.3 * V, 0.2 * V), (-0.6 * V, 0.5 * V), (0.0, 0.95 * V)])
def test_the_crab_heading_makes_the_ground_track_point_at_the_target(bearing, u):
    h = float(crab_bearing(jnp.asarray(bearing), jnp.asarray(u), V))
    ground = V * np.array([math.cos(h), math.sin(h)]) + np.asarray(u)
    d = np.array([math.cos(bearing), math.sin(bearing)])
    cross = d[0] * u[1] - d[1] * u[0]
    if abs(cross) < V and (d @ u + math.sqrt(V**2 - cross**2)) > 0:
        assert abs(d[0] * ground[1] - d[1] * ground[0]) < 1e-9  # along d
        assert d @ ground > 0  # toward the target
    else:  # no heading holds the course: it aims upstream of the target
        aim = V * d - np.asarray(u)
        assert math.isclose(h, math.atan2(aim[1], aim[0]), abs_tol=1e-9)


def test_the_crab_heading_in_still_fluid_is_the_bearing():
    for b in (-3.0, -0.5, 0.0, 1.2, 3.1):
        assert math.isclose(float(crab_bearing(jnp.asarray(b), jnp.zeros(2), V)), b, abs_tol=1e-6)


def test_the_controller_crosses_a_stream_of_half_its_speed():
    # a target straight ahead across a stream of 0.5 v: steering the bearing alone drifts; the
    # crab angle holds the course (a generous budget: the point is that it gets there)
    env, params = _world(study_flow("uniform", 0.5), bearing=0.0, budget=400)
    episode = summarise(env, params, steering.run(env, params, jax.random.PRNGKey(0)))[0]
    assert episode.reached
    # at least the time of Zermelo's straight crab path: (3 - 0.25) / sqrt(v^2 - u^2)
    assert episode.steps >= (3.0 - 0.25) / math.sqrt(V**2 - (0.5 * V) ** 2)
