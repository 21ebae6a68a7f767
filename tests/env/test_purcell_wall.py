"""Purcell's swimmer above a wall through the worlds: make, scene_rollout, dtypes, null check.

Independent numbers: the square stroke's displacement per cycle from the test-side RK4 of
tests/physics/test_wall_rft.py (at the ratio of the wall's coefficients), and the bulk world's
trajectories for the null check (both coefficients scaled alike must change nothing).
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jswim
from jswim import env
from jswim.env.swimmer_world import SwimmerWorld
from jswim.errors import ConfigError
from jswim.env import scene_rollout
from jswim.scenes import Scene
from jswim.swimmers import wall_rft
from jswim.swimmers.models import make_model
from tests.physics.test_wall_rft import cycles

SQUARE = [(2, -1), (1, -1), (2, 1), (1, 1)]  # from (+, +), toward +x
CODES = [3, 0, 5, 2]  # the same as integer codes (dof - 1) * 3 + roc + 1
H = 3.0
WALL = Scene(medium="wall", height=H)


@pytest.fixture(scope="module")
def expected():
    xi_t, xi_n = wall_rft.drag_coefficients(H)
    return float(cycles([xi_n / xi_t])[0, 0])


@pytest.mark.slow  # compile-heavy: tables and programs of new models
def test_scene_rollout_per_cycle_is_the_independent_rk4(expected):
    r = scene_rollout("purcell", SQUARE * 3, WALL)
    np.testing.assert_allclose(r.x[3::4, 0], expected * np.arange(1, 4), rtol=1e-9)
    assert r.x.dtype == np.float64 and r.z.shape == (12, 1)
    np.testing.assert_array_equal(r.z, H)  # the plane stays at its height
    np.testing.assert_array_equal(r.tilt, 0.0)
    np.testing.assert_allclose(r.orientation[3::4, 0], 0.0, atol=1e-12)
    np.testing.assert_allclose(r.gap, H - wall_rft.LINK_RADIUS)
    assert not r.contact.any() and not r.stuck.any()
    np.testing.assert_allclose(np.cumsum(r.dx[:, 0]), r.x[:, 0], atol=1e-14)
    # jswim.env.rollout_moves(..., scene=) is the same record
    r2 = jswim.env.rollout_moves("purcell", SQUARE * 3, scene=WALL)
    np.testing.assert_array_equal(r2.x, r.x)
    assert expected > 0.19124724 + 1e-3  # the wall's ratio above 2 makes the stroke go further


def test_make_gives_the_paper_world_over_the_wall_model():
    world, params = jswim.make("purcell", scene=WALL, direction="-x")
    assert isinstance(world, SwimmerWorld) and world.model == params.model
    xi_t, xi_n = wall_rft.drag_coefficients(H)
    m = params.model
    assert (m.kind, m.height, m.xi_par, m.xi_perp) == ("purcell", H, xi_t, xi_n) and float(
        params.direction
    ) == -1.0
    assert (world.n_dof, world.n_actions, world.n_swimmers) == (2, 6, 1)
    assert world.dof_range == pytest.approx(
        (-np.pi / 3, np.pi / 3)
    )  # the hinges' +-60 degrees (the paper's)
    # the plain bulk scene is still the paper's own swimmer
    assert jswim.make("purcell", scene=Scene())[1].model == make_model("purcell")


@pytest.mark.slow  # compile-heavy: the wall model's tables and programs in both dtypes
def test_make_float32_default_and_float64(float32, expected):
    world, params = jswim.make("purcell", scene=WALL)
    assert world.n_dof == 2 and world.n_swimmers == 1 and params.model.height == H
    t = jswim.rollout(world, params, 0, jnp.asarray(CODES * 3))
    assert t.obs.position.dtype == jnp.float32  # the default dtype users get
    x = np.asarray(t.obs.position[:, 0, 0], np.float64)
    np.testing.assert_allclose(x[3::4], expected * np.arange(1, 4), rtol=2e-7)
    assert float(t.info.progress.sum()) == pytest.approx(3 * expected, rel=2e-7)
    with jax.enable_x64(True):
        world64, params64 = jswim.make("purcell", scene=WALL)
        t64 = jswim.rollout(world64, params64, 0, jnp.asarray(CODES * 3))
        assert t64.obs.position.dtype == jnp.float64
        np.testing.assert_allclose(
            np.asarray(t64.obs.position[3::4, 0, 0]), expected * np.arange(1, 4), rtol=1e-9
        )


@pytest.mark.slow  # compile-heavy: tables and programs of new models
def test_batch_with_noise_is_one_vectorised_call(float32):
    world, params = jswim.make("purcell", scene=WALL, zeta=0.5)
    t = jswim.rollout(world, params, 1, jnp.tile(jnp.asarray(CODES * 2), (4, 1)))
    x = np.asarray(t.obs.position[:, -1, 0, 0])
    assert (
        x.shape == (4,) and np.all(np.isfinite(x)) and len(set(x.tolist())) == 4
    )  # noise differs per member


@pytest.mark.slow  # compile-heavy: tables and programs of new models
def test_coefficients_scaled_alike_give_the_bulk_trajectories(float32):
    # The wall's tangential factor at h = 1.5 applied to both coefficients: a wall that raised
    # both alike. The trajectories must be the bulk ones (the paper's closed form) to rounding.
    c = float(wall_rft.drag_coefficients(1.5)[0])
    base = make_model("purcell")
    model = wall_rft.WallPurcellModel("purcell", 2, base.lo, base.hi, 2.0, c, 2.0 * c)
    rng = np.random.default_rng(0)
    moves = [(int(d), int(r)) for d, r in zip(rng.integers(1, 3, 40), rng.integers(-1, 2, 40))]
    bulk = env.rollout_moves("purcell", moves)
    alike = env.rollout_moves(model, moves)
    for f in ("x", "y", "orientation"):
        np.testing.assert_allclose(getattr(alike, f), getattr(bulk, f), rtol=0, atol=1e-12)
    assert np.abs(bulk.x).max() > 0.05  # the moves do move it
    # and in the float32 world users get: equal to float32 rounding
    w_b, p_b = jswim.make("purcell")
    w_a, p_a = jswim.make(model)
    codes = jnp.asarray([(d - 1) * 3 + r + 1 for d, r in moves])
    tb, ta = jswim.rollout(w_b, p_b, 0, codes), jswim.rollout(w_a, p_a, 0, codes)
    np.testing.assert_allclose(
        np.asarray(ta.obs.position), np.asarray(tb.obs.position), rtol=0, atol=1e-7
    )


@pytest.mark.parametrize(
    "scene, words",
    [
        (Scene(medium="free"), "medium"),
        (Scene(medium="wall", swimmers=2), "swimmers"),
        (Scene(medium="wall", tilt=0.2), "tilt"),
        (Scene(medium="wall", obstacles=((0.0, 20.0, 1.0),)), "obstacles"),
        (Scene(medium="wall", mobility="rpy"), "mobility"),
    ],
)
def test_what_is_not_built_is_refused_in_one_line(scene, words):
    for call in (
        lambda: jswim.make("purcell", scene=scene),
        lambda: scene_rollout("purcell", SQUARE, scene),
    ):
        with pytest.raises(ConfigError) as e:
            call()
        assert words in str(e.value) and "\n" not in str(e.value)
    for kw in ({"link_radius": 0.5}, {"xi_ratio": 3.0}, {"nodes": 4}):
        with pytest.raises(ConfigError):
            jswim.make("purcell", scene=WALL, **kw)
    with pytest.raises(ConfigError):
        scene_rollout("purcell", SQUARE, WALL, sweeps=3)
