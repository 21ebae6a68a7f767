"""What an LLM run reads of its world: the world a run spec names ([`world`][jswim.agents.world_view.world], by
[`jswim.make`][jswim.env.registry.make], unless the driver is handed another builder, a test's toy world included),
and the prompt's view of it ([`view`][jswim.agents.world_view.view]: from ``env.n_swimmers``, the world's ``wall``
attribute and the swimmers' starts; docs/design.md, agents row). DOF ranges and the run's
defaults are the named swimmer's (`jswim.agents.defaults`), over the world's joint DOFs; a
registered world's come from the world ([`model`][jswim.agents.world_view.model]: its DOFs per swimmer and their range).
"""

from __future__ import annotations

import dataclasses
import json
import math
from typing import Any
from collections.abc import Sequence

import numpy as np

from jswim.agents.fidelity import scene_deviation
from jswim.agents.variants import LLMRunSpec
from jswim.env.base import Environment
from jswim.env.registry import make, registered_worlds
from jswim.env.flows import FLOW_LENGTH, Shear, flow_from_dict
from jswim.env.targets import target_from_dict
from jswim.prompt import NavView, PromptTemplate, SceneView, SwimmerText, scene_template
from jswim.scenes.scene import Scene
from jswim.swimmers.models import SwimmerModel, make_model


def world(spec: LLMRunSpec) -> tuple[Environment, Any]:
    """The world and params of ``spec``: its swimmer in its scene (``spec.scene``, canonical JSON;
    ``""``: the paper's world), noise level, direction, start and ROC lattice."""
    if spec.target:  # a navigation task (docs/navigation.md): the swimmer's world and the target
        return make(
            spec.swimmer,
            zeta=spec.zeta,
            init=spec.init,
            roc_levels=spec.roc_levels,
            target=target_from_dict(json.loads(spec.target)),
            flow=flow_from_dict(json.loads(spec.flow)) if spec.flow else None,
            **dict(spec.swimmer_options),
        )
    if not spec.scene:
        return make(
            spec.swimmer,
            zeta=spec.zeta,
            direction=spec.direction,
            init=spec.init,
            roc_levels=spec.roc_levels,
            **dict(spec.swimmer_options),
        )
    corners = isinstance(spec.init, (tuple, list)) and all(
        v in (0, 1) for v in spec.init
    )  # else the scene's own
    return make(
        spec.swimmer,
        json.loads(spec.scene),
        zeta=spec.zeta,
        direction=spec.direction,
        init=tuple(int(v) for v in spec.init) if corners else None,
        roc_levels=spec.roc_levels,
    )


def model(spec: LLMRunSpec, env: Environment) -> SwimmerModel:
    """The swimmer description a run's prompt, memory and defaults read (`jswim.agents.defaults`):
    the named paper swimmer's model ([`jswim.swimmers.models.make_model`][jswim.swimmers.models.make_model], its options); for a
    world of [`jswim.register_world`][jswim.env.registry.register_world], one swimmer of the world itself: its DOFs per swimmer
    over [`dof_range`][jswim.env.base.Environment.dof_range], ``kind`` the world's name (no paper
    swimmer's defaults: n_ht 3, the two-DOF clearing rule for two DOFs). Only its size, range
    and kind are read; it carries no physics."""
    if spec.swimmer not in registered_worlds():
        return make_model(spec.swimmer, **dict(spec.swimmer_options))
    lo, hi = (float(v) for v in env.dof_range)
    return SwimmerModel(spec.swimmer, int(env.n_dof) // int(env.n_swimmers), lo, hi)


def view(env: Environment, x0: Sequence[float], y0: Sequence[float]) -> SceneView | None:
    """What the prompt shows of ``env`` whose swimmers start at ``(x0, y0)`` (each ``(S,)``,
    `jswim.env.base.Observation.position`); ``None``: nothing beyond the paper's prompt
    (one swimmer, no wall)."""
    n, wall = int(env.n_swimmers), bool(getattr(env, "wall", False))
    if n == 1 and not wall:
        return None
    starts = tuple(
        (round(float(x0[k] - x0[0]), 9), round(float(y0[k] - y0[0]), 9)) for k in range(n)
    )
    return SceneView(n, wall, starts[1][0] if n > 1 else 0.0, starts=starts if n > 2 else ())


def nav_view(spec: LLMRunSpec) -> NavView | None:
    """What the prompt shows of the navigation task ``spec.target`` names (its kind, success
    radius, waypoints and velocity; the target's position each step comes from the world's
    observation); ``None`` for the paper's task."""
    if not spec.target:
        return None
    t = json.loads(spec.target)
    return NavView(
        kind=t["kind"],
        radius=float(t["radius"]),
        waypoints=len(t.get("points") or [()]),
        velocity=tuple(float(v) for v in t.get("velocity", (0.0, 0.0))),
        flow=bool(spec.flow),
    )


#: Link lengths kept between the farthest place a navigation task's target can be and ``X_min``.
NAV_MARGIN = 2.0


def nav_x_min(spec: LLMRunSpec, x_min: float) -> float:
    """``X_min`` of a navigation run: ``x_min``, lowered to a whole number of link lengths below
    every place the target can be within ``spec.n_steps`` (minus `NAV_MARGIN`), so that X and
    Y stay positive while the swimmer heads for it (the paper picks ``X_min`` for the same
    reason; a target behind or to the right would otherwise be sent as negative numbers). In a
    flow, also below where the flow could carry the swimmer in ``spec.n_steps`` (its speed on
    the study's scale, `jswim.env.flows.FLOW_LENGTH`, every step)."""
    t = json.loads(spec.target)
    points = t.get("points") or [
        (
            t["distance"] * math.cos(math.radians(t["bearing"])),
            t["distance"] * math.sin(math.radians(t["bearing"])),
        )
    ]
    drift = math.hypot(*t.get("velocity", (0.0, 0.0))) * spec.n_steps
    if spec.flow:
        flow = flow_from_dict(json.loads(spec.flow))
        scale = FLOW_LENGTH if isinstance(flow, Shear) else 1.0
        drift += flow.speed * scale * spec.n_steps
    low = min(min(p) for p in points) - drift - NAV_MARGIN
    return min(float(x_min), float(math.floor(min(low, 0.0 - NAV_MARGIN))))


def text(
    base: SwimmerText, template: PromptTemplate, n_dof: int, scene: SceneView | None, own: int = 0
) -> tuple[SwimmerText, PromptTemplate]:
    """The swimmer text over the world's ``n_dof`` joint DOFs (``base``: one swimmer's,
    [`jswim.agents.protocol.setup`][jswim.agents.protocol.setup]) with its view and the template the view needs
    ([`jswim.prompt.scene_template`][jswim.prompt.scene_template]); ``own`` >= 1: swimmer ``own``'s text alone (its own DOFs)."""
    if scene is None:
        return dataclasses.replace(base, n_dof=n_dof), template
    if own:
        scene = dataclasses.replace(scene, own=own)
        n_dof //= scene.swimmers
    lo, hi = (
        tuple(np.resize(v, n_dof).tolist()) if isinstance(v, tuple) else v
        for v in (base.lo, base.hi)
    )
    return dataclasses.replace(base, n_dof=n_dof, lo=lo, hi=hi, scene=scene), scene_template(
        scene, template
    )


def notes(spec: LLMRunSpec) -> tuple[dict[str, Any], str | None]:
    """What a run's transcript records of the scene its spec names (``{"scene": ...}``) and its
    fidelity line (`jswim.agents.fidelity.scene_deviation`); nothing for the paper's world."""
    if not spec.scene:
        return {}, None
    scene = json.loads(spec.scene)
    return {"scene": scene}, scene_deviation(Scene.from_dict(scene), spec.pair_prompt)
