"""A new world in a few dozen lines: a toy two-DOF swimmer implementing the protocol
(jswim.env.base) runs through the protocol's rollouts and the agents that take any world (the
random policy, PPO) without jswim.make or any change to jswim. docs/design.md (*Adding a world*)
points here.

The toy's physics is the area rule: a step moves the swimmer by ``(f1 df2 - f2 df1) / 2`` at the
step's mid-shape (``f`` the DOFs' places in [0, 1]), so a closed stroke nets minus the signed
area it encloses: the square gait (DOF 2 down, DOF 1 down, DOF 2 up, DOF 1 up) from (1, 1) goes
clockwise around the unit square, -1 per cycle, exactly.
"""

import dataclasses
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jswim.agents import ppo, random_policy
from jswim.env.base import Environment, Observation, StepInfo, first_move, scaled
from jswim.env.episodes import rollout


class ToyState(NamedTuple):
    frac: jax.Array  # (2,) each DOF's place in [0, 1]
    x: jax.Array


class ToyParams(NamedTuple):
    zeta: Any = 0.0
    direction: Any = 1.0


@dataclasses.dataclass(frozen=True)
class ToyWorld(Environment):
    n_dof = 2  # a class attribute is enough for a size

    @property
    def default_params(self) -> ToyParams:
        return ToyParams()

    def reset(self, key, params):
        return ToyState(jnp.ones(2, jnp.result_type(float)), jnp.zeros((), jnp.result_type(float)))

    def advance(self, state, action, noise, params):
        action = jnp.asarray(action)
        if jnp.issubdtype(action.dtype, jnp.integer):  # the protocol's codes, K = 1
            dof, roc = action // 3, (action % 3 - 1).astype(state.x.dtype)
        else:
            dof, roc = first_move(action)
        f1 = jnp.clip(state.frac + roc * (jnp.arange(2) == dof), 0.0, 1.0)
        mid, d = (state.frac + f1) / 2, f1 - state.frac
        dx = 0.5 * (mid[0] * d[1] - mid[1] * d[0]) * (1.0 + params.zeta * noise[0])
        moved = jnp.any(d != 0)
        info = StepInfo(
            jnp.stack([dx, 0.0 * dx])[None],
            params.direction * dx,
            (roc != 0) & ~moved,
            moved,
            jnp.zeros((), bool),
            jnp.asarray(jnp.inf, dx.dtype),
        )
        return ToyState(f1, state.x + dx), info

    def observe(self, state, params):
        position = jnp.stack([state.x, 0.0 * state.x])[None]
        return Observation(state.frac, position, jnp.zeros(1, state.x.dtype), position[:, 1])

    def features(self, state, params):
        return scaled(state.frac, 0.0, 1.0)


SQUARE = jnp.array([3, 0, 5, 2], jnp.int32)  # (2, -1), (1, -1), (2, +1), (1, +1)


def test_toy_world_rollouts_follow_the_area_rule(float32):
    env, params = ToyWorld(), ToyParams()
    assert env.n_actions == 6 and env.n_swimmers == 1
    tr = rollout(env, params, 0, jnp.tile(SQUARE, 3))
    assert float(tr.obs.position[-1, 0, 0]) == pytest.approx(-3.0, abs=1e-6)
    assert tr.info.progress.dtype == jnp.float32
    back = rollout(env, ToyParams(direction=-1.0), 0, jnp.tile(SQUARE, 3))
    np.testing.assert_array_equal(back.info.progress, -tr.info.progress)
    # A batch, with noise: one scan over members, each as its own rollout.
    noisy = ToyParams(zeta=0.5)
    batch = rollout(env, noisy, 1, jnp.stack([SQUARE, SQUARE[::-1]]))
    keys = jax.random.split(jax.random.PRNGKey(1), 2)
    np.testing.assert_array_equal(
        batch.info.progress[1], rollout(env, noisy, keys[1], SQUARE[::-1]).info.progress
    )
    # The reversed gait goes counter-clockwise: +1 per cycle, with noise on each step.
    assert float(jnp.sum(batch.info.progress[1])) > 0 > float(jnp.sum(batch.info.progress[0]))


@pytest.mark.slow
def test_agents_take_the_toy_world(float32):
    env, params = ToyWorld(), ToyParams()
    run = random_policy.run(env, params, jax.random.split(jax.random.PRNGKey(0), 8), 40, trace=True)
    assert run.actions.shape == (8, 40) and set(np.unique(run.actions).tolist()) <= set(range(6))
    # Each step's reward is the position's change (the toy has no noise here).
    np.testing.assert_allclose(
        np.cumsum(run.trace.info.progress, 1), run.trace.obs.position[..., 0, 0], atol=1e-5
    )
    trained = ppo.train(
        env, params, jax.random.split(jax.random.PRNGKey(1), 2), ppo.PPOConfig(steps=64)
    )
    assert trained.x.shape == (2, 64) and trained.dofs.shape == (2, 64, 2)
    np.testing.assert_allclose(np.cumsum(trained.progress, 1), trained.x, atol=1e-5)
