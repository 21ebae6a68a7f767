"""Worlds in a uniform background flow: Galilean invariance through `jswim.make` and
`jswim.rollout` (every stroke moves as in still fluid plus u t, with the same orientation), on the
paper's corner table, the K lattice, float ROC vectors, with noise, and in the navigation world;
in float64 to 1e-12 and in the default float32; and the one-line refusals of what does not step
yet."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jswim
from jswim.env.flows import Poiseuille, Shear, TaylorGreen, Uniform
from jswim.env.targets import FixedTarget
from jswim.errors import ConfigError
from jswim.scenes import Scene

U = (0.02, -0.011)


def _positions(env, params, actions, key=0):
    traj = jswim.rollout(env, params, jax.random.PRNGKey(key), jnp.asarray(actions))
    obs = traj.obs
    return np.asarray(obs.position[..., 0, :]), np.asarray(obs.orientation[..., 0])


CASES = {
    "corner table, noise": (dict(zeta=0.5), [1, 3, 0, 2, 4, 1, 5, 3]),
    "K = 2 lattice": (dict(roc_levels=2), [1, 6, 3, 8, 0, 9, 2, 7]),
    "float ROC vectors": (dict(), [[0.4, 0.0], [0.0, -0.7], [-1.0, 0.0], [0.0, 0.3]]),
    "navigation": (dict(roc_levels=2, target=FixedTarget(3.0, 90.0)), [1, 6, 3, 8, 0, 9]),
}


@pytest.mark.parametrize("case", CASES, ids=list(CASES))
def test_a_uniform_flow_adds_exactly_u_t_to_any_stroke(case):
    options, actions = CASES[case]
    still = _positions(*jswim.make("purcell", **options), actions)
    moved = _positions(*jswim.make("purcell", flow=Uniform(U), **options), actions)
    t = np.arange(1, len(actions) + 1)[:, None]  # one tau per step
    np.testing.assert_allclose(moved[0], still[0] + t * np.asarray(U), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(moved[1], still[1])  # the flow turns nothing


def test_the_same_holds_in_the_default_float32(float32):
    options, actions = CASES["K = 2 lattice"]
    still = _positions(*jswim.make("purcell", **options), actions)
    moved = _positions(*jswim.make("purcell", flow=Uniform(U), **options), actions)
    assert moved[0].dtype == np.float32
    t = np.arange(1, len(actions) + 1)[:, None]
    np.testing.assert_allclose(moved[0], still[0] + t * np.asarray(U), rtol=0, atol=2e-7)


def test_a_batch_of_swimmers_drifts_together():
    env, params = jswim.make("purcell", roc_levels=2, flow=Uniform(U))
    actions = jnp.asarray(np.random.default_rng(0).integers(0, env.n_actions, (64, 12)))
    still_env, still_params = jswim.make("purcell", roc_levels=2)
    moved = jswim.rollout(env, params, jax.random.PRNGKey(3), actions).obs.position
    still = jswim.rollout(still_env, still_params, jax.random.PRNGKey(3), actions)
    drift = np.asarray(moved - still.obs.position)[:, -1, 0, :]
    np.testing.assert_allclose(drift, np.broadcast_to(12 * np.asarray(U), (64, 2)), atol=1e-12)


@pytest.mark.parametrize(
    "call, says",
    [
        (lambda: jswim.make("purcell", diagonal=True, flow=Shear(0.1)), "diagonal strokes"),
        (lambda: jswim.make("ng", flow=Uniform(U)), "moves on a line"),
        (lambda: jswim.make("purcell", flow=(0.02, 0.0)), "jswim.env.flows flow"),
        (
            lambda: jswim.make("purcell", Scene(medium="wall", height=2.0), flow=Uniform(U)),
            "bulk only",
        ),
        (lambda: jswim.make("ng", Scene(medium="free", swimmers=2), flow=Uniform(U)), "bulk only"),
    ],
)
def test_what_does_not_step_in_a_flow_is_refused_in_one_line(call, says):
    with pytest.raises(ConfigError, match=says) as err:
        call()
    assert "\n" not in str(err.value)


def test_still_fluid_is_the_default_and_the_params_say_so():
    _, params = jswim.make("purcell")
    assert params.flow is None
    _, params = jswim.make("purcell", flow=Uniform(U))
    assert params.flow == Uniform(U) and hash(params.flow) == hash(Uniform(U))


def _hold_straight_in(flow, steps=6):
    """Purcell's swimmer taken to the K = 2 lattice's centre (straight: both hinges at 0), then
    held (ROC 0) for ``steps`` steps in ``flow``: its orientations and centroids after each."""
    env, params = jswim.make("purcell", roc_levels=2, flow=flow)
    hold = 2  # DOF 1, k = 0
    actions = [1, 6] + [hold] * steps  # D1 then D2 by -1/2 of the range: the straight shape
    place, angle = _positions(env, params, actions)
    return place[2:], angle[2:], place[1], angle[1]


@pytest.mark.slow  # compiles the flow-integrated step (16 RK4 pieces, unrolled)
def test_a_straight_swimmer_held_in_shear_tumbles_on_jeffery_s_orbit():
    gamma = 0.05
    place, angle, place0, angle0 = _hold_straight_in(Shear(gamma))
    # d phi / dt = -gamma sin^2 phi: cot(phi) grows by gamma each step (one tau)
    cot = 1.0 / np.tan(np.concatenate([[angle0], angle]))
    np.testing.assert_allclose(np.diff(cot), gamma, rtol=0, atol=1e-10)
    # the centroid (the middle link's centre: the rod is symmetric) is carried at gamma y
    y0 = place0[1]
    np.testing.assert_allclose(place[:, 1], y0, atol=1e-12)
    np.testing.assert_allclose(
        np.diff(np.concatenate([[place0[0]], place[:, 0]])), gamma * y0, atol=1e-12
    )


@pytest.mark.slow  # compiles the flow-integrated step (16 RK4 pieces, unrolled)
def test_a_still_flow_integrated_step_by_step_is_the_exact_table():
    options, actions = CASES["K = 2 lattice"]
    still = _positions(*jswim.make("purcell", **options), actions)
    zero = _positions(*jswim.make("purcell", flow=Shear(0.0), **options), actions)  # integrated
    np.testing.assert_allclose(zero[0], still[0], rtol=0, atol=1e-6)
    np.testing.assert_allclose(zero[1], still[1], rtol=0, atol=1e-6)


def test_the_flow_step_has_converged():
    from jswim.env.stepping import FLOW_SUBSTEPS, flow_step
    from jswim.swimmers.models import make_model

    model = make_model("purcell")
    s0, s1, pose = jnp.asarray([1.0, 1.0]), jnp.asarray([0.0, 1.0]), jnp.asarray([0.3, 0.7, 0.2])
    for flow in (Shear(0.05), Poiseuille(0.03, 4.0), TaylorGreen(0.04, 10.0)):
        coarse = flow_step(model, flow, s0, s1, pose)
        fine = flow_step(model, flow, s0, s1, pose, substeps=4 * FLOW_SUBSTEPS)
        np.testing.assert_allclose(np.asarray(coarse), np.asarray(fine), rtol=0, atol=1e-7)


@pytest.mark.slow  # compiles the flow-integrated step (16 RK4 pieces, unrolled)
def test_navigation_steps_in_every_flow_in_float32(float32):
    for flow in (Shear(0.005), Poiseuille(0.024, 10.0), TaylorGreen(0.024, 20.0)):
        env, params = jswim.make("purcell", roc_levels=2, target=FixedTarget(3.0, 90.0), flow=flow)
        place, angle = _positions(env, params, [1, 6, 3, 8, 0, 9])
        assert (
            place.dtype == np.float32 and np.all(np.isfinite(place)) and np.all(np.isfinite(angle))
        )
