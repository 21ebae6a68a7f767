"""A model-predictive agent: the swimmer's optimum re-planned from where it is.

Every ``replan`` steps (8) the agent searches, from its own state, the least-time sequence over a
receding horizon with the world's own step at zeta 0 (the beam of
[`jswim.agents.optimal`][jswim.agents.optimal], ranked by its estimated time to go beyond the
horizon), warm-started with what is left of its previous plan (kept in the beam, so a new plan
is never worse than the old one by the model's reckoning), and plays the plan's first steps in
the world, noise included. In a noiseless world it follows the optimum's kind of path; under
noise (zeta > 0) it is the strongest agent that reacts to what happens.

Example::

    env, params = jswim.make("purcell", roc_levels=2, target=FixedTarget(3.0, 90.0))
    actions = mpc.run(env, params, 0)          # (budget,) codes, replayable
    traj = jswim.rollout(env, params, 0, actions)
"""

from __future__ import annotations

from typing import Any

import numpy as np
from jax import Array

from jswim.agents import optimal
from jswim.env.navigation import NavigationWorld

__all__ = ["HORIZON", "REPLAN", "run"]

#: Steps looked ahead, steps played between plans and states kept per layer (measured beside
#: ``HORIZON`` in `jswim.agents.optimal`).
HORIZON, REPLAN, BEAM = optimal.HORIZON, optimal.REPLAN, optimal.BEAM


def run(
    env: NavigationWorld,
    params: Any,
    key: Array | int,
    steps: int | None = None,
    *,
    horizon: int = HORIZON,
    replan: int = REPLAN,
    beam: int = BEAM,
) -> np.ndarray:
    """The agent's actions in one run of navigation world ``env`` (module docs).

    Parameters
    ----------
    env : NavigationWorld
        On a K >= 2 lattice (integer codes); any zeta.
    params : NavParams
        Its params (one target).
    key : PRNG key or int
        The run's key: the start (``env.reset``) and each step's noise (``split(key, steps)``,
        as [`jswim.rollout`][jswim.env.episodes.rollout] draws them).
    steps : int, optional
        Steps of the run; default the target's budget.
    horizon, replan, beam : int
        Steps planned ahead, steps played between plans, states kept per layer.

    Returns
    -------
    ndarray (steps,) int32
        The codes played; after the episode ended, the plan's no-op (DOF 1, ROC 0). Replayed with
        ``jswim.rollout(env, params, key, actions)`` they give the run.

    Raises
    ------
    ConfigError
        As [`optimal.solve`][jswim.agents.optimal.solve] (zeta aside); a size below 1.
    """
    horizon = optimal.check_whole(horizon, "horizon")
    replan = optimal.check_whole(replan, "replan")
    beam = optimal.check_whole(beam, "beam")
    optimal.check_world(env, params._replace(swimmer=params.swimmer.replace(zeta=0.0)))
    if steps is not None:
        steps = optimal.check_whole(steps, "steps")
    return optimal.receding(env, params, key, steps, horizon=horizon, replan=replan, beam=beam)
