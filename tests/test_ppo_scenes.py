"""PPO on scenes (issue 19): jswim.agents.ppo.train_scene_batch and its world adapter."""

from __future__ import annotations

import jax
import numpy as np
import pytest

from jswim.agents import ppo
from jswim.errors import ConfigError
from jswim.scenes import Scene, scene_advance, scene_params, scene_reset

STEPS = 8


def _replay_x(params, actions):
    """Mean centroid x after each step, the actions replayed by hand through scene_advance
    (noiseless): swimmer dof // 2, arm dof % 2, ROC the non-zero entry."""
    state = scene_reset(params)

    def centroid(s):
        return float(np.mean(np.asarray(s.centre[:, 0]) + (np.asarray(s.arms[:, 1]) - np.asarray(s.arms[:, 0]))
                             * np.cos(np.asarray(s.tilt)) / 3.0))

    x0, out = centroid(state), []
    for a in actions:
        j = int(np.argmax(np.abs(a)))
        state, _ = scene_advance(params, state, (j // 2, j % 2, float(a[j])), np.zeros(params.n_swimmers))
        out.append(centroid(state) - x0)
    return np.array(out)


@pytest.mark.slow  # one compilation (~40 s of CPU)
def test_wall_scene_run_records_the_scene_progress():
    with jax.enable_x64(False):
        params = scene_params("ng", Scene(medium="wall", height=10.0))
        keys = jax.random.split(jax.random.PRNGKey(0), 3)
        config = ppo.PPOConfig(steps=STEPS)
        run = ppo.train_scene_batch(keys, params, config, direction=np.array([1, -1, 1]))
        assert run.x.shape == (3, STEPS) and run.dofs.shape == (3, STEPS, 2) and run.actions.shape == (3, STEPS, 2)
        for field in (run.x, run.progress, run.dofs, run.y, run.orientation):
            assert np.all(np.isfinite(np.asarray(field)))
        # One arm per step, within [d_min, d_max]; the swimmer's height changes near a wall.
        assert np.all(np.count_nonzero(np.asarray(run.actions), axis=-1) <= 1)
        assert np.all((np.asarray(run.dofs) >= 6.0 - 1e-5) & (np.asarray(run.dofs) <= 10.0 + 1e-5))
        # Progress is the scene's: direction times the step of the mean centroid x, and x is what
        # the actions give when replayed through the scene by hand.
        x = np.asarray(run.x, np.float64)
        dx = np.diff(np.concatenate([np.zeros((3, 1)), x], axis=1), axis=1)
        np.testing.assert_allclose(np.asarray(run.progress), dx * np.array([1, -1, 1])[:, None], atol=1e-5)
        for i in range(3):
            np.testing.assert_allclose(x[i], _replay_x(params, np.asarray(run.actions[i])), atol=2e-4)
        report = ppo.evaluate_scene(run, params, direction=np.array([1, -1, 1]))
        assert np.asarray(report.success).shape == (3,)


def test_evaluate_scene_refuses_a_pair():
    pair = scene_params("ng", Scene(medium="free", swimmers=2, separation=30.0))
    with pytest.raises(ConfigError):
        ppo.evaluate_scene(None, pair)
