"""One pipeline for every study's runs other than the LLM's, and one row builder for the LLM's.

Every plan goes the same way, whatever its world: [`make`][jswim.env.registry.make] builds the world
from the plan's swimmer, scene, noise, start and ROC lattice (the paper's world, a scene world,
Purcell's swimmer above a wall, or a world of [`register_world`][jswim.env.registry.register_world]);
the learner's one entry point runs the group's plans on it (the stroke player
[`play`][jswim.agents.strokes.play], [`random_policy.run`][jswim.agents.random_policy.run],
[`qlearning.train`][jswim.agents.qlearning.train], [`ppo.train`][jswim.agents.ppo.train]: one
vectorised call, a target direction per run); each run becomes one row through
[`build_row`][jswim.studies.rows.build_row], with a scene's columns read from the run's
[`Trajectory`][jswim.env.episodes.Trajectory] when the plan has a scene; the caller stores it.
"""

from __future__ import annotations

import dataclasses
import json
from typing import Any
from collections.abc import Sequence

import jax
import numpy as np

from jswim import env
from jswim.agents import qlearning, random_policy, strokes
from jswim.agents.llm import RunResult
from jswim.agents.variants import init_label
from jswim.env.base import Environment, Observation
from jswim.env.episodes import rollout as jswim_rollout
from jswim.env.registry import make
from jswim.judging import lattice
from jswim.judging.gait import Criterion
from jswim.results.row import RunRow
from jswim.scenes import Scene
from jswim.studies import scene_studies
from jswim.studies.options import CONTINUOUS_AGENT, STROKE_AGENT
from jswim.studies.kinds import navigate
from jswim.studies.plans import Plan
from jswim.studies.rows import judged_rows, with_llm


def _keys(plans: Sequence[Plan]) -> jax.Array:
    return jax.vmap(jax.random.PRNGKey)(np.array([env.seed32(p.seed) for p in plans], np.uint32))


def scene_of(plan: Plan) -> Scene | None:
    """The [`Scene`][jswim.scenes.scene.Scene] of a plan (its canonical JSON), ``None`` without one."""
    return Scene.from_dict(json.loads(plan.scene)) if plan.scene else None


def world(plan: Plan) -> tuple[Environment, Any]:
    """A plan's world and its params ([`make`][jswim.env.registry.make]), toward +x (the runs set
    their own direction). A corner start is the plan's; a random one is drawn at reset in the
    paper's world; a scene's other starts are the scene's own."""
    init: Any = None
    if isinstance(plan.init, (tuple, list)) and all(v in (0, 1) for v in plan.init):
        init = tuple(int(v) for v in plan.init)
    elif plan.init == "random" and not plan.scene:
        init = "random"
    lattice = {"roc_levels": plan.roc_levels} if plan.roc_levels > 1 else {}
    return make(plan.swimmer, scene_of(plan), zeta=plan.zeta, init=init, **lattice)


def _lift(obs: Observation, scene: Scene, side_view: bool) -> tuple[np.ndarray, np.ndarray]:
    """Each swimmer's height and tilt ``(..., S)`` as a scene row records them: a world seen from
    the side ([`Scenery.side_view`][jswim.env.base.Scenery]) gives its own
    (`Observation.height`, its orientation); one seen from above (Purcell's swimmer in a plane
    parallel to the wall, a registered world) stays at the scene's start height (0 in the paper's
    bulk fluid), untilted."""
    if side_view:
        return np.asarray(obs.height, np.float64), np.asarray(obs.orientation, np.float64)
    shape = np.shape(obs.orientation)
    return np.full(shape, scene.height if scene.medium != "bulk" else 0.0), np.zeros(shape)


def start(world: Environment, params: Any, scene: Scene) -> tuple[np.ndarray, ...]:
    """Each swimmer's start x, height and tilt ``(S,)`` (`_lift`), and the DOFs' start
    corner (the world's discretiser's lattice positions, ``(n_dof,)``)."""
    state = world.reset(jax.random.PRNGKey(0), params)
    obs = world.observe(state, params)
    corner = np.asarray(world.cells().positions(state, params), np.int64)
    side_view = world.scenery().side_view
    return (np.asarray(obs.position[:, 0], np.float64), *_lift(obs, scene, side_view), corner)


def _per_run(params: Any, directions: Sequence[int]) -> Any:
    """``params`` with a target direction per run (the rest shared)."""
    d = np.asarray(directions, np.float64)
    if dataclasses.is_dataclass(params):
        return dataclasses.replace(params, direction=d)
    return params._replace(direction=d)


def baseline_rows(plans: Sequence[Plan], horizon: int) -> list[RunRow]:
    """The rows of one (agent, swimmer, scene, zeta, action set, ROC lattice, variant) group of
    plans, run in sub-batches by start, in the order of ``plans``."""
    by_init: dict[Any, list[Plan]] = {}
    for p in plans:
        by_init.setdefault(p.init, []).append(p)
    done = {r.run_id: r for g in by_init.values() for r in _run_group(g, horizon)}
    return [done[p.run_id] for p in plans]


def _learn(plans: Sequence[Plan], world: Environment, task: Any, corner: np.ndarray) -> Any:
    """The group's learner through its one entry point (every run traced)."""
    p0, keys = plans[0], _keys(plans)
    if p0.agent == STROKE_AGENT:
        n_sw = world.n_swimmers
        codes = np.stack(
            [
                scene_studies.stroke_codes(
                    p.variant, p.direction, p.steps, n_sw, corner, world.n_actions // n_sw
                )
                for p in plans
            ]
        )
        return codes, strokes.play(world, task, keys, codes)
    if p0.agent == "random":
        return random_policy.run(world, task, keys, p0.steps, p0.action_set, trace=True)
    if p0.agent == CONTINUOUS_AGENT:
        from jswim.agents import ppo  # lazy: start-up (optax's PPO, for PPO runs only)

        return ppo.train(world, task, keys, ppo.PPOConfig(steps=p0.steps), trace=True)
    config = qlearning.QConfig(steps=p0.steps, action_set=p0.action_set)
    return qlearning.train(world, task, keys, config, pose=True, trace=True)


def _moves(run: Any) -> list[list[list[float]]]:
    """Each PPO run's ``[dof, real ROC]`` per step."""
    dof, rocs = np.asarray(run.dof, np.int64), np.asarray(run.actions, np.float64)
    return [
        [[int(d), float(rocs[i, t, d - 1])] for t, d in enumerate(dof[i])] for i in range(len(dof))
    ]


def _run_group(plans: Sequence[Plan], horizon: int) -> list[RunRow]:
    p0 = plans[0]
    if p0.target:  # a navigation task: its own episodes and columns (jswim.studies.kinds.navigate)
        return navigate.baseline_rows(plans)
    world_, params = world(p0)
    task = _per_run(params, [p.direction for p in plans])
    if p0.scene:
        return _scene_rows(plans, world_, params, task, horizon)
    run = _learn(plans, world_, task, np.zeros(world_.n_dof, np.int64))
    pose = (np.asarray(run.y), np.asarray(run.orientation))
    work = np.asarray(run.trace.info.work, np.float64).reshape(len(plans), -1)
    if p0.agent == CONTINUOUS_AGENT:
        from jswim.agents import ppo  # lazy: start-up (optax's PPO, for PPO runs only)

        batched = world_.batch_params(task, len(plans))[0]
        rep = ppo.evaluate(run, batched, criterion=Criterion(horizon=horizon))
        dof = np.asarray(run.dof, np.int64)
        lo, span = params.model.lo, params.model.hi - params.model.lo
        corners = np.rint((np.asarray(run.dofs0, np.float64) - lo) / span).astype(np.int64)
        return judged_rows(
            plans,
            np.zeros(dof.shape, np.int64),
            np.asarray(run.x),
            corners,
            horizon,
            pose=pose,
            report=rep,
            moves=_moves(run),
            work=work,
        )
    return judged_rows(
        plans,
        np.asarray(run.actions),
        np.asarray(run.x),
        np.asarray(run.levels0),
        horizon,
        pose=pose,
        work=work,
    )


def _scene_rows(
    plans: Sequence[Plan], world_: Environment, params: Any, task: Any, horizon: int
) -> list[RunRow]:
    """A scene group's rows: the plan's columns and the scene's, read from the runs' trace."""
    p0 = plans[0]
    scene = scene_of(p0)
    x0, z0, tilt0, corner = start(world_, params, scene)
    judged, moves = [None] * len(plans), [None] * len(plans)
    out = _learn(plans, world_, task, corner)
    if p0.agent == STROKE_AGENT:
        codes, tr = out
    elif p0.agent == CONTINUOUS_AGENT:
        codes, tr = np.zeros((len(plans), 0), np.int64), out.trace
        moves = _moves(out)
        judged = scene_studies.ppo_judged(out, plans, world_, task, horizon)
    else:
        codes, tr = np.asarray(out.actions), out.trace
    obs = tr.obs
    xs = np.asarray(obs.position[..., 0], np.float64) - x0
    scenery = world_.scenery()
    heights, tilts = _lift(obs, scene, scenery.side_view)
    stuck, contact = (
        np.asarray(v, bool).reshape(xs.shape[:2] + (-1,)).any(-1)
        for v in (tr.info.stuck, tr.info.contact)
    )
    rows = []
    for i, p in enumerate(plans):
        extra = {
            "xs": xs[i].tolist(),
            "heights": heights[i].tolist(),
            "tilts": tilts[i].tolist(),
            "contact": contact[i].tolist(),
            "stuck": stuck[i].tolist(),
        }
        row = scene_studies.scene_row(
            p,
            [int(c) for c in codes[i]],
            xs[i].mean(axis=-1).tolist(),
            extra,
            horizon,
            z0=z0,
            tilt0=tilt0,
            judged=judged[i],
            moves=moves[i],
            plane_height=scenery.plane_height,
        )
        if not scenery.side_view:  # seen from above: swimmer 1's y and orientation in its plane
            y, orientation = (
                np.asarray(v[i, :, 0], np.float64).tolist()
                for v in (obs.position[..., 1], obs.orientation)
            )
            row = dataclasses.replace(row, y=y, orientation=orientation)
        rows.append(row)
    return rows


def _replayed_work(plan: Plan, r: RunResult) -> np.ndarray | None:
    """Each step's work of an LLM run in the paper's world ``(1, steps)``, from replaying its
    actions from its start: the work depends on the shape's path only, not on the noise, so the
    replay's is the run's. None when the run has no actions or they do not match its x series."""
    if not r.actions or len(r.actions) != len(r.x) or not r.levels0:
        return None
    lattice = {"roc_levels": plan.roc_levels} if plan.roc_levels > 1 else {}
    world_, params = make(plan.swimmer, init=tuple(int(v) for v in r.levels0), **lattice)
    codes = np.asarray(r.actions, np.int32)
    tr = jswim_rollout(world_, params, jax.random.PRNGKey(0), codes)
    return np.asarray(tr.info.work, np.float64)[None]


def llm_row(plan: Plan, r: RunResult, horizon: int) -> RunRow:
    """The judged row of one finished LLM run, with the run's own fields
    ([`with_llm`][jswim.studies.rows.with_llm]); a scene's has the scene's columns."""
    if plan.target:  # a navigation run: its episode and columns (jswim.studies.kinds.navigate)
        episode = navigate.llm_episode(plan, r, _replayed_work(plan, r))
        moves = [list(lattice.decode(int(a), plan.roc_levels)) for a in r.actions]
        init = init_label(tuple(int(bool(v)) for v in r.levels0))  # the run's own start
        row = navigate.nav_row(plan, r.x, r.y, r.orientation, moves, episode, init=init)
        return with_llm(row, r)
    if not plan.scene:
        acts = np.array([r.actions], np.int64).reshape(1, len(r.actions))
        xs = np.array([r.x], float).reshape(1, len(r.x))
        # The judge reads the start as lattice positions: a corner level times K.
        levels = np.array([r.levels0], np.int64) * plan.roc_levels
        work = _replayed_work(plan, r)
        return with_llm(judged_rows([plan], acts, xs, levels, horizon, work=work)[0], r)
    scene = scene_of(plan)
    world_, params = world(plan)
    _, z0, tilt0, _ = start(world_, params, scene)
    # A track the driver did not record (a world of one swimmer keeps no ``xs``, one that cannot
    # touch anything no ``contact``) is absent from the row, not an empty list of the wrong length.
    tracks = {k: getattr(r, k) or None for k in ("xs", "heights", "tilts", "contact", "stuck")}
    if not tracks["heights"]:
        # a run whose prompt showed no scene (one swimmer seen from above: Purcell's plane above
        # a wall, a registered world): the start's throughout, _lift's rule (z0 is its start)
        tracks.update(heights=[z0.tolist()] * len(r.x), tilts=[tilt0.tolist()] * len(r.x))
    row = scene_studies.scene_row(
        plan,
        list(r.actions),
        list(r.x),
        tracks,
        horizon,
        z0=z0,
        tilt0=tilt0,
        plane_height=world_.scenery().plane_height,
    )
    return with_llm(row, r)
