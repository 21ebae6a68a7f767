"""The random-policy baseline (jswim.agents.random_policy)."""

from __future__ import annotations

import jax
import numpy as np

from jswim.env.swimmer_world import SwimmerWorld
from jswim import env

from jswim.judging import gait
from jswim.agents import random_policy


def test_random_baseline_honours_the_action_set():
    params = env.make_params("purcell", init=(1, 1))
    keys = jax.random.split(jax.random.PRNGKey(0), 64)
    model = params.model
    for action_set in ("shape-changing", "all"):
        run = random_policy.run(SwimmerWorld(model), params, keys, 40, action_set)
        acts = np.asarray(run.actions)
        rp = gait.replay(acts.T, model, np.asarray(run.levels0))
        rocs = np.vectorize(lambda a: env.decode_action(int(a))[1])(acts)
        if action_set == "shape-changing":
            assert rp.moved.all() and (rocs != 0).all()  # only moves that change the shape
        else:
            assert not rp.moved.all() and (rocs == 0).any()  # the full set includes no-ops
        # Uniform over what is offered: both DOFs are moved often.
        dofs = np.vectorize(lambda a: env.decode_action(int(a))[0])(acts)
        assert 0.35 < (dofs == 1).mean() < 0.65
