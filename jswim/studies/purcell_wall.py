"""Purcell's swimmer in ``jswim study wall --swimmer purcell`` (issue 34).

Its plane lies ``h`` link lengths above the wall and stays there
(:mod:`jswim.scenes.purcell_wall`), so every run is the paper's planar world with the wall's drag
coefficients: the square stroke, Q-learning and the random policy run as in the bulk studies, on
that model, and each row gets the scene's columns (:func:`jswim.studies.scenes.scene_row`: medium,
start height, ``per_cycle``, ``xs``, ``heights``; the fate is ``gliding`` at h by construction). The
reference group ``bulk`` is the same stroke without the wall. Not offered for Purcell: the LLM and
PPO rows (their scene drivers are the NG swimmer's), so its cells hold these three agents only.
The rows' ``y`` and ``orientation`` are the swimmer's in its plane.
"""

from __future__ import annotations

import dataclasses

import json
from typing import Any, Sequence

import jax
import numpy as np

from jswim import env
from jswim.agents import qlearning, random_policy
from jswim.env.episodes import rollout as world_rollout
from jswim.env.swimmer_world import SwimmerWorld
from jswim.scenes import purcell_wall
from jswim.scenes.scene import Scene
from jswim.studies.grids import STROKE_AGENT, Plan
from jswim.studies.scenes import scene_row
from jswim.swimmers.models import SwimmerModel, make_model

#: Purcell's square stroke from the paper's start (+, +) as codes ``(dof - 1) * 3 + roc + 1``:
#: toward +x D2 down, D1 down, D2 up, D1 up; toward -x its time reverse.
SQUARE = {1: (3, 0, 5, 2), -1: (0, 3, 2, 5)}


def model_of(plan: Plan) -> tuple[Scene, SwimmerModel]:
    """The plan's scene and model: above the wall the wall-corrected one, in ``"bulk"`` the paper's."""
    scene = Scene.from_dict(json.loads(plan.scene))
    return scene, (make_model("purcell") if scene.medium == "bulk" else purcell_wall.model(scene))


def run_baselines(plans: Sequence[Plan], horizon: int) -> list[dict[str, Any]]:
    """Rows of one (agent, scene, ...) group of Purcell runs (stroke, Q-learning or random)."""
    p0 = plans[0]
    scene, model = model_of(p0)
    base = env.make_params(model)
    init = np.array([list(p.init) for p in plans], np.int32)
    params = qlearning.batch_params(base, len(plans), zeta=np.array([p.zeta for p in plans]),
                                    direction=np.array([p.direction for p in plans], float), init=init)
    keys = jax.vmap(jax.random.PRNGKey)(np.array([env.seed32(p.seed) for p in plans], np.uint32))
    if p0.agent == STROKE_AGENT:
        codes = np.stack([[SQUARE[1 if p.direction > 0 else -1][t % 4] for t in range(p.steps)] for p in plans])
        axes = env.param_axes(params)
        t = jax.vmap(lambda k, a, pr: world_rollout(SwimmerWorld(model), pr, k, a), in_axes=(0, 0, axes))(
            keys, codes.astype(np.int32), params)
        pos = np.asarray(t.obs.position[:, :, 0], np.float64)
        x, y, th, acts = pos[..., 0], pos[..., 1], np.asarray(t.obs.orientation[..., 0], np.float64), codes
    else:
        if p0.agent == "qlearning":
            run = qlearning.train_batch(keys, params, qlearning.QConfig(steps=p0.steps, action_set=p0.action_set),
                                        pose=True)
        else:
            run = random_policy.run_batch(keys, params, p0.steps, p0.action_set)
        x, y, th, acts = (np.asarray(v, np.float64) for v in (run.x, run.y, run.orientation, run.actions))
    h = scene.height if scene.medium == "wall" else 0.0
    rows = []
    for i, p in enumerate(plans):
        n = len(x[i])
        extra = {"xs": [[float(v)] for v in x[i]], "heights": [[h]] * n, "tilts": [[0.0]] * n,
                 "contact": [False] * n}
        row = scene_row(p, [int(a) for a in acts[i]], [float(v) for v in x[i]], extra, horizon,
                        z0=np.array([h]), tilt0=np.zeros(1))
        rows.append(dataclasses.replace(row, y=[float(v) for v in y[i]], orientation=[float(v) for v in th[i]]))
    return rows
