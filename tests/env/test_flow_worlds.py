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
        (lambda: jswim.make("purcell", flow=Shear(0.1)), "Uniform flows only"),
        (lambda: jswim.make("purcell", flow=Poiseuille(0.1, 2.0)), "Uniform flows only"),
        (lambda: jswim.make("purcell", flow=TaylorGreen(0.1, 5.0)), "Uniform flows only"),
        (lambda: jswim.make("ng", flow=Uniform(U)), "moves on a line"),
        (lambda: jswim.make("purcell", flow=(0.02, 0.0)), "jswim.env.flows flow"),
        (
            lambda: jswim.make("purcell", Scene(medium="wall", height=2.0), flow=Uniform(U)),
            "bulk only",
        ),
        (lambda: jswim.make("ng", Scene(medium="free", swimmers=2), flow=Uniform(U)), "bulk only"),
    ],
)
def test_what_does_not_step_in_a_flow_yet_is_refused_in_one_line(call, says):
    with pytest.raises(ConfigError, match=says) as err:
        call()
    assert "\n" not in str(err.value)


def test_still_fluid_is_the_default_and_the_params_say_so():
    _, params = jswim.make("purcell")
    assert params.flow is None
    _, params = jswim.make("purcell", flow=Uniform(U))
    assert params.flow == Uniform(U) and hash(params.flow) == hash(Uniform(U))
