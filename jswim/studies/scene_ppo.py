"""The continuous RL baseline (PPO, :mod:`jswim.agents.ppo`) as rows of the scene studies
(``jswim study wall`` and ``jswim study pair``; issue 19, an extension).

The learner is the continuous study's (same network, :class:`~jswim.agents.ppo.PPOConfig` and
temperature) in the world of :class:`jswim.agents.ppo_envs.SceneEnv`, and its task is the other
scene agents': the reward of a step is the progress of the swimmers' mean centroid x in the target
direction, the budget is the study's ``--steps`` (one learner per run, learning online, no
episodes), ``--q-runs`` learners per cell and direction, ``--noise`` the scene's. It moves one arm
of one swimmer per step by a real ROC in [-1, 1]; for a pair it steers both (joint DOFs D1..D4).

Success is the study's criterion in its real-valued form (:func:`jswim.agents.ppo.evaluate_scene`):
on each swimmer's own moves, with the bulk swimmer's noiseless displacements, the shape judge of
the continuous study (:func:`jswim.judging.shape_judge.judge_shapes`) where the lattice agents get
:func:`jswim.judging.gait.judge`; a pair succeeds when both swimmers' own move sequences do. Whether it
found a joint stroke faster than two square strokes is read, as for the other agents, from the
row's ``speed`` (progress per step over the second half) against the strokes' rows. Wall runs get
their fate (:func:`jswim.studies.scenes.fate`) from the heights and contacts the training run
recorded. Rows are :func:`jswim.studies.scenes.scene_row`'s, with the moves as ``[dof, real ROC]``.
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from jswim.judging.gait import Criterion
from jswim.studies import scenes
from jswim.studies.grids import Plan


def run_all(plans: Sequence[Plan], horizon: int) -> list[dict[str, Any]]:
    """:func:`run` for each start among ``plans`` (:func:`jswim.studies.scenes.by_start`)."""
    return scenes.by_start(plans, horizon, run)


def run(plans: Sequence[Plan], horizon: int) -> list[dict[str, Any]]:
    """Train and judge the PPO runs of one (scene, zeta) group in one batch; their rows.

    ``plans`` share the scene, the start and the noise level (the study groups them so); their
    directions may differ.
    """
    import jax.numpy as jnp

    from jswim.agents import ppo, scene_env

    p0 = plans[0]
    scene, params = scenes._params(p0)
    direction = np.array([p.direction for p in plans], np.int32)
    trained = ppo.train_scene_batch(scenes._keys(plans), params, ppo.PPOConfig(steps=p0.steps),
                                    jnp.asarray(direction))
    rep = ppo.evaluate_scene(trained, params, direction, criterion=Criterion(horizon=horizon))
    rec = trained.scene
    xs, z, tilt = (np.asarray(v, np.float64) for v in (rec.xs, rec.z, rec.tilt))
    stuck, contact = np.asarray(rec.stuck, bool), np.asarray(rec.contact, bool)
    x = np.asarray(trained.x, np.float64)
    dof = np.asarray(trained.dof, np.int64)
    rocs = np.asarray(trained.actions, np.float64)
    _, obs0 = scene_env.start(params, 1)
    o0 = scene_env.as_numpy(obs0)
    rows = []
    for i, p in enumerate(plans):
        moves = [[int(d), float(rocs[i, t, d - 1])] for t, d in enumerate(dof[i])]
        judged = {"success": bool(rep.success[i]), "learned": bool(rep.learned[i]),
                  "steps_to_learn": int(rep.steps_to_learn[i]) if rep.learned[i] else None,
                  # a pair's period is 0, as the lattice judge of the pair rows gives it
                  "period": int(rep.period[i]) if scene.swimmers == 1 else 0}
        extra = {"xs": xs[i].tolist(), "heights": z[i].tolist(), "tilts": tilt[i].tolist(),
                 "contact": contact[i].tolist(), "stuck": stuck[i].tolist()}
        rows.append(scenes.scene_row(p, [], x[i].tolist(), extra, horizon, z0=o0["z"][0], tilt0=o0["tilt"][0],
                                     judged=judged, moves=moves))
    return rows
