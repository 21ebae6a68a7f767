"""The navigation study (``jswim study navigate``; docs/navigation.md): Purcell's swimmer sent to
targets at several distances and bearings, along a path and after a moving target, by the LLM,
Q-learning, PPO, the steering controller and the random policy.

Its cells are targets ([`cells`][jswim.studies.kinds.navigate.cells]); every run of a cell has the
target's step budget ([`jswim.env.targets.default_budget`][jswim.env.targets.default_budget]:
measured for the steering controller, with a safety factor). Every run, whatever its agent,
becomes one row through [`nav_row`][jswim.studies.kinds.navigate.nav_row] (success = the target
reached, steps to it, path length over the straight distance, energy and energy per distance);
[`nav_summary`][jswim.studies.kinds.navigate.nav_summary] is the study's table.
"""

from __future__ import annotations

import dataclasses
import functools
import json
import math
from typing import Any
from collections.abc import Sequence

import jax
import jax.numpy as jnp
import numpy as np

from jswim import env as jenv
from jswim.env.flows import FLOWS, SWIM_SPEED, Flow, Uniform, flow_from_dict, flow_json, study_flow
from jswim.env.navigation import NavSummary, energy_per_distance, summarise
from jswim.env.episodes import rollout
from jswim.env.registry import make
from jswim.env.targets import (
    BUDGET_SAFETY,
    FLOW_BUDGET_FACTOR,
    FixedTarget,
    MovingTarget,
    Target,
    Waypoints,
    default_budget,
    flow_budget,
    target_from_dict,
)
from jswim.env.work import lighthill_efficiency
from jswim.action_codes import encode_action
from jswim.judging import lattice
from jswim.agents.protocol import derived_seed
from jswim.agents.variants import init_label
from jswim.judging.stats import median_interval, wilson_interval
from jswim.results import as_run_rows, is_failed
from jswim.results.optimum import cell_key
from jswim.results.row import RunRow
from jswim.studies.options import (
    CONTINUOUS_AGENT,
    CONTROLLER_AGENT,
    MPC_AGENT,
    OPTIMAL_AGENT,
    ZERMELO_AGENT,
    StudyOptions,
)
from jswim.studies.plans import Cell, Plan
from jswim.studies.study import Study, listed
from jswim.studies.success import navigation_rule
from jswim.swimmers.models import make_model

__all__ = [
    "CONTROLLER_AGENT",
    "DEFAULT_BEARINGS",
    "DEFAULT_DISTANCES",
    "FLOW_BUDGET_FACTOR",
    "MAX_SEEDS",
    "MOVING",
    "NAV_AGENTS",
    "NAV_ROC_LEVELS",
    "NAV_TRAIN_EPISODES",
    "PATH",
    "START_SPREAD",
    "YARDSTICKS",
    "cells",
    "clear_seeds",
    "flow_columns",
    "flow_grid",
    "nav_overview",
    "nav_ppo_config",
    "nav_qconfig",
    "nav_row",
    "nav_summary",
    "optimal_path",
    "plan_cell",
    "plan_flow",
    "seed_optimum",
    "seeded_start",
    "start_label",
    "target_json",
    "target_kind",
    "target_order",
    "targets",
    "with_budgets",
    "zermelo_path",
    "zermelo_rows",
]


#: The agents of every navigation cell, in the rows' order.
NAV_AGENTS = (
    "llm",
    "qlearning",
    CONTINUOUS_AGENT,
    CONTROLLER_AGENT,
    MPC_AGENT,
    OPTIMAL_AGENT,
    "random",
)

#: The default grid: targets 3 a away (about 16 square-gait cycles; outside the quarter loop's
#: turning circle, radius 1.165 a, where the steering controller reaches every bearing), ahead,
#: to the left and behind (the study's small default; ``--distances`` and ``--bearings`` scale
#: it up).
DEFAULT_DISTANCES = (3.0,)
DEFAULT_BEARINGS = (0.0, 90.0, 180.0)

#: The path of every navigation study: 3 a ahead, then 3 a to the left of that (a turn of 90
#: degrees between the legs).
PATH = Waypoints(((3.0, 0.0), (3.0, 3.0)))

#: The moving target of every navigation study: 3 a ahead, moving sideways (to +y) at 0.005 a
#: per step, a tenth of the square gait's mean speed (0.0478 a per step).
MOVING = MovingTarget(3.0, 0.0, (0.0, 0.005))

#: K of the navigation worlds when ``--roc-levels`` leaves the paper's K = 1 (which cannot turn):
#: the least even K, on which the quarter loops turn.
NAV_ROC_LEVELS = 2


def target_json(spec: Target) -> str:
    """A target as canonical JSON (a plan's and a row's ``target``)."""
    return json.dumps(spec.to_dict(), sort_keys=True)


def targets(distances: Sequence[float], bearings: Sequence[float]) -> list[tuple[str, str, Target]]:
    """``(group, tag, spec)`` of every target of the grid: the fixed points (every distance
    crossed with every bearing), then `PATH` and `MOVING`."""
    out: list[tuple[str, str, Target]] = []
    for d in distances:
        for b in bearings:
            out.append((f"fixed d={d:g} b={b:g}", f"d{d:g}b{b:g}", FixedTarget(d, b)))
    out.append(("path", "path", PATH))
    out.append(("moving", "moving", MOVING))
    return out


def flow_grid(o: Any) -> list[tuple[str, str, float | None, str]]:
    """``(group suffix, tag, fraction, flow JSON)`` of each flow speed of options ``o``: one
    still-fluid entry without ``--flow``; else each of ``--flows`` (fractions of the swimming
    speed, [`jswim.env.flows.study_flow`][jswim.env.flows.study_flow]; a fraction of 0 is still
    fluid, written as a uniform stream of speed 0 so its rows carry the flow's columns)."""
    if not o.flow:
        return [("", "", None, "")]
    out = []
    for f in o.flows:
        flow = study_flow(o.flow, f) if f > 0 else Uniform((0.0, 0.0))
        out.append((f", {o.flow} {f:g}v", f"{o.flow}{f:g}", float(f), flow_json(flow)))
    return out


#: Seeded starts (``--starts``) turn the swimmer by up to this many degrees either way from the
#: lab's +x: a target ahead stays ahead (within 45 degrees), one at 90 degrees to the side.
START_SPREAD = 45.0


def seeded_start(seed: int, index: int) -> tuple[float, str]:
    """Start ``index`` of a study seeded ``seed``: ``(start heading, shape)``, the heading in
    degrees from the lab's +x (uniform within `START_SPREAD` either way, to 0.01 degree) and the
    shape a corner of the shape square as signs (``"+-"``: DOF 1 at ``hi``, DOF 2 at ``lo``;
    each corner equally likely). Start 0 is the study's own: ``(0.0, "++")``. The same for every
    agent, cell and flow of the study (`cells`)."""
    if index == 0:
        return 0.0, "++"
    rng = np.random.default_rng(derived_seed("navigation-start", int(seed), int(index)))
    heading = round(float(rng.uniform(-START_SPREAD, START_SPREAD)), 2)
    return heading, "".join("+" if b else "-" for b in rng.integers(0, 2, 2))


def cells(o: Any, swimmer: str = "purcell") -> list[Cell]:
    """The navigation study's cells for options ``o``: one per target (and, with ``--flow``,
    per flow speed: `flow_grid`; with ``--starts N``, per seeded start, `seeded_start`: the
    same group, so that its rows pool the starts), on the K lattice of ``--roc-levels`` (2
    where it is 1). Their runs' steps are the target's budget (`--steps` overrides it), which
    the world measures: planning leaves them to `with_budgets`. In a flow Zermelo's steerer
    joins the agents of the first start (a point has no heading or shape to start from)."""
    k = o.roc_levels if o.roc_levels > 1 else NAV_ROC_LEVELS
    out = []
    for index in range(o.starts):
        heading, shape = seeded_start(o.seed, index)
        for suffix, ftag, fraction, flow in flow_grid(o):
            for group, tag, spec in targets(o.distances, o.bearings):
                yardstick = (ZERMELO_AGENT,) if flow and index == 0 else ()
                out.append(
                    Cell(
                        group + suffix,
                        NAV_AGENTS + yardstick,
                        n_ht=o.n_ht,
                        init=shape if index else None,  # None: the study's (hi, hi)
                        roc_levels=k,
                        tag="-".join(t for t in (tag, ftag, f"s{index}" if index else "") if t),
                        target=target_json(dataclasses.replace(spec, start_heading=heading)),
                        flow=flow,
                        flow_fraction=fraction,
                    )
                )
    return out


def plan_flow(plan: Any) -> Flow | None:
    """A plan's (or row's) background flow (``None``: still fluid)."""
    return flow_from_dict(json.loads(plan.flow)) if plan.flow else None


def zermelo_path(target: str, flow: str) -> Any:
    """Zermelo's optimal path ([`jswim.agents.zermelo.zermelo`][jswim.agents.zermelo.zermelo]) to
    ``target`` through ``flow`` (both canonical JSON; ``""``: still fluid) at the swimming
    speed, computed once per process per target and flow (the target's budget aside)."""
    spec = target_from_dict(json.loads(target))  # a point: no budget, no start heading
    return _zermelo(target_json(dataclasses.replace(spec, budget=None, start_heading=0.0)), flow)


def optimal_path(plan: Any) -> Any:
    """The swimmer's own optimum ([`jswim.agents.optimal.solve`][jswim.agents.optimal.solve])
    for a plan's world (its target with the study's budget, flow, K lattice and start), its
    beam seeded with every run of the cell that reached the target (`seed_optimum`): never
    longer than any of them. Computed once per process per world and seeds."""
    cell = plan_cell(plan)
    init = plan.init if isinstance(plan.init, (tuple, list)) else None
    return _optimal(
        plan.target,
        plan.flow,
        plan.roc_levels,
        tuple(int(v) for v in init) if init is not None else None,
        _SEEDS.get(cell, ()),
    )


@functools.lru_cache(maxsize=256)
def _optimal(
    target: str,
    flow: str,
    roc_levels: int,
    init: tuple[int, ...] | None,
    seeds: tuple[tuple[int, ...], ...] = (),
) -> Any:
    from jswim.agents import optimal  # lazy: start-up (the search's JAX)

    env, params = make(
        "purcell",
        init=init,
        roc_levels=roc_levels,
        target=target_from_dict(json.loads(target)),
        flow=flow_from_dict(json.loads(flow)) if flow else None,
    )
    return optimal.solve(env, params, key=0, incumbents=[np.asarray(q, np.int64) for q in seeds])


#: Each cell's runs that reached its target, as action codes (`seed_optimum`), by `plan_cell`.
_SEEDS: dict[tuple[str, str, int, str], tuple[tuple[int, ...], ...]] = {}

#: Most runs a cell's optimum is seeded with (the shortest first): each holds a row of its beam.
MAX_SEEDS = 64

#: The agents whose rows are measured against the optimum but do not seed it: the optimum
#: itself, the model-predictive agent (its own seed already) and Zermelo's point (no strokes).
YARDSTICKS = (OPTIMAL_AGENT, MPC_AGENT, ZERMELO_AGENT)


def start_label(plan: Any) -> str:
    """A navigation plan's start shape as its rows show it: signs (``"+-"``); the study's own
    start ``(hi, hi)`` where the plan names none: ``"++"``."""
    return init_label(plan.init) if isinstance(plan.init, (tuple, list)) else "++"


def plan_cell(plan: Any) -> tuple[str, str, int, str]:
    """A navigation plan's cell: its world (target, flow, K, start shape's label)."""
    return (plan.target or "", plan.flow or "", int(plan.roc_levels), start_label(plan))


def _row_codes(row: Any) -> tuple[int, ...] | None:
    """The action codes of a row's run up to the step it reached the target (None: a move
    off the K lattice, which no code names)."""
    k = int(row.roc_levels)
    out = []
    for dof, roc in row.actions[: row.steps_to_target]:
        step = round(float(roc))
        if float(roc) != step or abs(step) > k:
            return None
        out.append(int(lattice.encode(int(dof), step, k)))
    return tuple(out)


def seed_optimum(rows: Sequence[Any]) -> None:
    """Add the runs of ``rows`` that reached their target (the yardsticks' aside, `YARDSTICKS`)
    to their cells' seeds: the optimum of each cell is then searched from them as well, and
    never longer than any (the search alone missed the least time in strong flows: in shear
    at 0.9 v, 148 steps where PPO reached the 90-degree target in 99; docs/navigation.md)."""
    for row in rows:
        if row.agent in YARDSTICKS or not row.reached or not row.steps_to_target:
            continue
        q = _row_codes(row)
        if q:
            cell = cell_key(row)
            _SEEDS[cell] = tuple(sorted({*_SEEDS.get(cell, ()), q}, key=lambda c: (len(c), c)))[
                :MAX_SEEDS
            ]


def clear_seeds() -> None:
    """Forget every cell's seeds: a study session starts from its own folder's runs only, so an
    earlier study in the same process (a notebook's) never seeds this one's optimum."""
    _SEEDS.clear()


@functools.lru_cache(maxsize=256)
def _zermelo(target: str, flow: str) -> Any:
    from jswim.agents.zermelo import zermelo  # lazy: start-up (the shooting method's JAX)

    spec = target_from_dict(json.loads(target))
    return zermelo(flow_from_dict(json.loads(flow)) if flow else None, spec, SWIM_SPEED)


def with_budgets(plans: Sequence[Plan]) -> list[Plan]:
    """``plans`` with every navigation run's steps filled in: ``episodes`` of its target's budget,
    as the world of the run measures it when it is made ([`default_budget`][jswim.env.targets.default_budget],
    the steering controller's physics, measured once per swimmer and K); in a flow the worlds'
    rule ([`jswim.env.targets.flow_budget`][jswim.env.targets.flow_budget]: at least
    `FLOW_BUDGET_FACTOR` times a least time) with Zermelo's least time (a target Zermelo cannot
    reach, and a flow of speed 0, keep the still-fluid budget: the former's rows say
    unreachable). A world made in Python passes the straight crab course's time instead, never
    below Zermelo's. Plans with their steps set are returned as they are.

    Raises
    ------
    ConfigError
        As `default_budget` (a target that needs more steps than a world counts).
    """
    budgets: dict[tuple[str, str, int, str], int] = {}

    def budget(p: Plan) -> int:
        key = (p.swimmer, p.target, p.roc_levels, p.flow)
        if key not in budgets:
            spec = target_from_dict(json.loads(p.target))
            if spec.budget is not None:  # set by the spec (or filled in below): the world's
                budgets[key] = spec.budget
                return spec.budget
            still = default_budget(spec, make_model(p.swimmer), p.roc_levels)
            moving = p.flow and flow_from_dict(json.loads(p.flow)).speed > 0
            best = zermelo_path(p.target, p.flow).steps if moving else None
            budgets[key] = flow_budget(still, best)  # the worlds' rule, with Zermelo's time
        return budgets[key]

    def filled(p: Plan) -> Plan:
        if p.flow and target_from_dict(json.loads(p.target)).budget is None:
            # the world counts its own budget: in a flow the spec carries it (the row's target)
            spec = dataclasses.replace(target_from_dict(json.loads(p.target)), budget=budget(p))
            p = dataclasses.replace(p, target=target_json(spec))
        return p if p.steps is not None else dataclasses.replace(p, steps=budget(p) * p.episodes)

    return [filled(p) for p in plans]


def nav_row(
    plan: Plan,
    x: Sequence[float],
    y: Sequence[float],
    orientation: Sequence[float],
    actions: list[list[float]],
    episode: NavSummary,
    init: str | None = None,
    **columns: Any,
) -> RunRow:
    """The row of one navigation run of ``plan``, whatever its agent.

    The row's success is ``reached``; ``steps_to_target`` the steps when reached;
    ``path_length`` the centroid's path; ``path_ratio`` that over the task's straight distance
    (None when not reached); ``energy`` the summed work, ``energy_per_distance`` it over the
    distance closed on the target (None when none was closed); ``efficiency`` Lighthill's over
    the net displacement ([`jswim.env.work.lighthill_efficiency`][jswim.env.work.lighthill_efficiency]).

    Parameters
    ----------
    x, y, orientation : sequence of float
        The centroid (``a``, lab frame; the start is ``(0, 0)``) and heading (rad) after each
        step of the episode (up to the step it ended: the target reached or the budget spent).
    actions : list of list
        Each step's ``[dof, roc]``.
    episode : NavSummary
        The episode ([`jswim.env.navigation.summarise`][jswim.env.navigation.summarise]).
    init : str, optional
        The start's shape as the row shows it (signs, ``"+-"``); default the plan's (the
        study's own start ``(hi, hi)``: ``"++"``).
    **columns
        Further columns (an LLM run's own, through `jswim.studies.rows.with_llm`).

    """
    from jswim.studies.rows import build_row  # lazy: start-up (rows load the LLM driver)

    steps, reached = int(episode.steps), bool(episode.reached)  # plain numbers: the record's
    if init is None:
        init = start_label(plan)

    verdict = {
        "success": reached,
        "learned": reached,
        "steps_to_learn": steps if reached else None,
        "period": 0,
    }
    row = build_row(
        plan,
        x,
        actions,
        verdict,
        init=init,
        y=[float(v) for v in y],
        orientation=[float(v) for v in orientation],
        **columns,
    )
    net = float(np.hypot(x[-1], y[-1])) if len(x) else 0.0
    finite = math.isfinite(episode.energy)
    per = episode.energy_per_distance
    bodies = make_model(plan.swimmer).n_dof + 1
    return dataclasses.replace(
        row,
        **flow_columns(plan, steps if reached else None),
        energy=float(episode.energy) if finite else None,
        energy_per_distance=float(per) if finite and math.isfinite(per) else None,
        efficiency=float(lighthill_efficiency(net, episode.energy, steps, bodies))
        if finite and episode.energy > 0
        else None,
        target=plan.target,
        reached=reached,
        steps_to_target=steps if reached else None,
        path_length=float(episode.path),
        path_ratio=float(episode.path_ratio) if reached else None,
    )


def flow_columns(plan: Plan, steps_to_target: float | None) -> dict[str, Any]:
    """A navigation row's yardstick columns (`jswim.results.row.FLOW`): on the ``optimal``
    agent's row the swimmer's own least time to the target (`optimal_path`) and the run's time
    over it (every other row of the cell reads them from that row when the folder is read,
    [`jswim.results.optimum.with_cell_optimum`][jswim.results.optimum.with_cell_optimum]: the
    optimum is searched after them, seeded with them); in a flow also the flow, its speed
    fraction, whether Zermelo's point reaches the target, his least time and the run's time
    over his."""

    def ratio(best: float | None) -> float | None:
        if best is None or steps_to_target is None or best <= 0:
            return None
        return round(float(steps_to_target) / float(best), 6)

    own = optimal_path(plan).steps if plan.agent == OPTIMAL_AGENT else None
    out: dict[str, Any] = {"optimal_steps": own, "time_ratio": ratio(own)}
    if not plan.flow:
        return out
    best = zermelo_path(plan.target, plan.flow).steps
    return {
        "flow": plan.flow,
        "flow_fraction": plan.flow_fraction,
        "reachable": best is not None,
        "zermelo_steps": None if best is None else round(float(best), 6),
        "zermelo_ratio": ratio(best),
        **out,
    }


def zermelo_rows(plans: Sequence[Plan]) -> list[RunRow]:
    """The rows of Zermelo's point steerer ([`jswim.agents.zermelo`][jswim.agents.zermelo]):
    the optimal path sampled each step, reached where the target is reachable, its steps the
    least time rounded up; no strokes (``actions`` empty), no energy (a point does no modelled
    work). The yardstick is never cut: ``--steps`` shortens the agents' runs, not his (a
    budget is at least four of his times in a flow)."""
    from jswim.studies.rows import build_row  # lazy: start-up (rows load the LLM driver)

    out = []
    for plan in plans:
        best = zermelo_path(plan.target, plan.flow)
        xy = np.asarray(best.xy, np.float64).reshape(-1, 2)[1:]
        steps = len(xy)
        reached = best.steps is not None
        verdict = {
            "success": reached,
            "learned": reached,
            "steps_to_learn": steps if reached else None,
            "period": 0,
        }
        heading = np.asarray(best.heading, np.float64).reshape(-1)[1:]
        row = build_row(
            plan,
            [float(v) for v in xy[:, 0]],
            [],
            verdict,
            init="",
            y=[float(v) for v in xy[:, 1]],
            orientation=[float(v) for v in heading],
        )
        path = float(np.hypot(*np.diff(np.vstack([[0.0, 0.0], xy]), axis=0).T).sum())
        straight = _straight(target_from_dict(json.loads(plan.target)), steps)
        cols = flow_columns(plan, best.steps if reached else None)
        out.append(
            dataclasses.replace(
                row,
                **cols,
                target=plan.target,
                reached=reached,
                steps_to_target=steps if reached else None,
                path_length=path,
                path_ratio=path / straight if reached and straight > 0 else None,
            )
        )
    return out


def nav_summary(rows: Sequence[Any]) -> list[dict[str, Any]]:
    """The study's table: per (agent, target group), runs, successes (with their Wilson 95 %
    interval), the mean steps to the target over the runs that reached it, the mean path ratio,
    energy and energy per distance, the swimmer's own least time (``optimal_steps``) and the
    median time ratio to it over the runs that reached the target (with a bootstrap 95 %
    interval); in a flow, Zermelo's time and the mean ratio to it."""
    out: dict[tuple[str, str], list[RunRow]] = {}
    for r in as_run_rows(rows):
        if r.target is None or is_failed(r):
            continue
        out.setdefault((r.agent, r.group), []).append(r)

    def mean(vals: list[Any]) -> float | None:
        vals = [float(v) for v in vals if v is not None]
        return float(np.mean(vals)) if vals else None

    table = []

    def order(kv: tuple[tuple[str, str], list[RunRow]]) -> tuple:
        # by flow speed (the grid's order, not the group's text), then target, then agent
        (agent, group), g = kv
        fraction = g[0].flow_fraction if g[0].flow_fraction is not None else -1.0
        return (fraction, target_order(group), agent)

    for (agent, group), g in sorted(out.items(), key=order):
        reached = sum(bool(r.reached) for r in g)
        lo, hi = wilson_interval(reached, len(g))
        ratio, ratio_lo, ratio_hi = median_interval([r.time_ratio for r in g if r.reached])
        table.append(
            {
                "group": group,
                "agent": agent,
                "n": len(g),
                "reached": reached,
                "success_rate": reached / len(g),
                "success_ci": (lo, hi),
                "steps_to_target": mean([r.steps_to_target for r in g]),
                "path_ratio": mean([r.path_ratio for r in g]),
                "energy": mean([r.energy for r in g]),
                "energy_per_distance": mean([r.energy_per_distance for r in g]),
                "optimal_steps": _median([r.optimal_steps for r in g]),
                "time_ratio": None if math.isnan(ratio) else ratio,
                "time_ratio_ci": None if math.isnan(ratio) else (ratio_lo, ratio_hi),
                **(
                    {
                        "flow_fraction": g[0].flow_fraction,
                        "reachable": bool(g[0].reachable),
                        "zermelo_steps": g[0].zermelo_steps,
                        "zermelo_ratio": mean([r.zermelo_ratio for r in g]),
                    }
                    if g[0].flow
                    else {}
                ),
            }
        )
    return table


def target_order(group: str) -> tuple:
    """A sort key of navigation groups in the study's order: the fixed targets by distance, then
    bearing (numbers, not text: 90 before 180), then the path, then the moving target."""
    kind = target_kind(group)
    if kind.startswith("fixed"):
        try:
            d, b = (float(part.split("=")[1]) for part in kind.split()[1:3])
            return (0, d, b, kind)
        except (IndexError, ValueError):  # a group written otherwise: after the grid's
            return (0, math.inf, math.inf, kind)
    return ({"path": 1, "moving": 2}.get(kind, 3), 0.0, 0.0, kind)


def _median(vals: list[Any]) -> float | None:
    # a cell's optimum: one value per start (the median of the starts' with --starts)
    vals = [float(v) for v in vals if v is not None]
    return float(np.median(vals)) if vals else None


def target_kind(group: str) -> str:
    """A navigation group's target kind: ``fixed d=3 b=90``, ``path`` or ``moving`` (the group
    without its flow)."""
    return group.split(",")[0].strip()


def nav_overview(rows: Sequence[Any]) -> list[dict[str, Any]]:
    """The study's first table: per (agent, flow, flow speed, target kind), runs, successes
    with their Wilson 95 % interval, the median time ratio to the swimmer's own optimum over the
    runs that reached the target with its bootstrap 95 % interval, and the median energy per
    distance closed. Zermelo's point is left out (a yardstick, not an agent).

    Returns
    -------
    list of dict
        Keys ``agent``, ``flow`` (kind, ``""`` in still fluid), ``flow_fraction`` (None in still
        fluid), ``target``, ``n``, ``reached``, ``success_ci``, ``time_ratio``,
        ``time_ratio_ci`` (None where no run reached), ``n_ratio`` (the runs behind it),
        ``n_below`` (of those, the runs shorter than the optimum: the search's answer is an upper
        bound, and a run below it shows where it is not the least time) and
        ``energy_per_distance``; ordered by flow, speed, target, then agent (the study's order).
    """
    out: dict[tuple[str, str, float, str], list[RunRow]] = {}
    for r in as_run_rows(rows):
        if r.target is None or is_failed(r) or r.agent == ZERMELO_AGENT:
            continue
        kind = json.loads(r.flow).get("kind", "") if r.flow else ""
        fraction = -1.0 if r.flow_fraction is None else float(r.flow_fraction)
        out.setdefault((kind, fraction, target_kind(r.group), r.agent), []).append(r)
    order = {a: i for i, a in enumerate(NAV_AGENTS)}
    table = []
    for (kind, fraction, target, agent), g in sorted(
        out.items(),
        key=lambda kv: (
            *kv[0][:2],
            target_order(kv[0][2]),
            order.get(kv[0][3], len(order)),
            kv[0][3],
        ),
    ):
        reached = sum(bool(r.reached) for r in g)
        ratios = [r.time_ratio for r in g if r.reached and r.time_ratio is not None]
        ratio, lo, hi = median_interval(ratios)
        per = [r.energy_per_distance for r in g if r.energy_per_distance is not None]
        table.append(
            {
                "agent": agent,
                "flow": kind,
                "flow_fraction": None if fraction < 0 else fraction,
                "target": target,
                "n": len(g),
                "reached": reached,
                "success_ci": wilson_interval(reached, len(g)),
                "time_ratio": None if math.isnan(ratio) else ratio,
                "time_ratio_ci": None if math.isnan(ratio) else (lo, hi),
                "n_ratio": len(ratios),
                "n_below": sum(r < 1.0 for r in ratios),  # runs shorter than the search's optimum
                "energy_per_distance": float(np.median(per)) if per else None,
            }
        )
    return table


#: Episodes of the target's budget the learners train for by default (``--train-episodes``):
#: Q-learning reaches a target 3 a away at 90 degrees in 3 of 4 seeds after 400 (102,400 steps,
#: 12 s for 4 learners on the shared CPU; none after 100); their row is their last episode that
#: ended within the training.
NAV_TRAIN_EPISODES = 400


def nav_ppo_config(steps: int) -> Any:
    """PPO's settings for navigation (docs/navigation.md, *Baselines*): a categorical policy
    over the K-level action codes, 16 swimmers pooled per learner, rollouts of 64, discount
    0.99, GAE lambda 0.95, advantages standardised, rewards not rescaled, entropy weight 0.08,
    ``steps`` steps."""
    from jswim.agents.ppo import PPOConfig  # lazy: start-up (the learners load optax)

    return PPOConfig(
        steps=steps,
        rollout=64,
        envs=16,
        discount=0.99,
        gae_lambda=0.95,
        normalize_advantages=True,
        reward_norm=False,
        entropy_coef=0.08,
        policy="categorical",
    )


def nav_qconfig(steps: int, action_set: str = "all") -> Any:
    """Q-learning's settings for navigation (docs/navigation.md, *Baselines*): one continuing
    run of ``steps`` steps through many episodes, exploration falling linearly from 0.5 to 0 at
    80 % of it (the last episodes are greedy), discount 0.95, learning rate 0.2, table at 0."""
    import optax  # lazy: start-up (optax loads with the learners only)

    from jswim.agents.qlearning import QConfig  # lazy: start-up (the learners load optax)

    return QConfig(
        steps=steps,
        action_set=action_set,
        epsilon=optax.linear_schedule(0.5, 0.0, int(0.8 * steps)),
        discount=0.95,
        learning_rate=0.2,
        q_init=0.0,
    )


def world(plan: Plan) -> tuple[Any, Any]:
    """A navigation plan's world and params ([`jswim.make`][jswim.env.registry.make] with its target)."""
    init = plan.init if isinstance(plan.init, (tuple, list)) else None
    return make(
        plan.swimmer,
        zeta=plan.zeta,
        init=tuple(int(v) for v in init) if init is not None else None,
        roc_levels=plan.roc_levels,
        target=target_from_dict(json.loads(plan.target)),
        flow=plan_flow(plan),
    )


def _take(tree: Any, i: int) -> Any:
    return jax.tree.map(lambda v: v[i], tree)


def _lattice_moves(dofs: np.ndarray, dofs0: np.ndarray, lo: float, hi: float, k: int) -> list:
    """``[dof, roc]`` of each step from the DOFs before and after it (ROC in the lattice's
    integer units ``q``: the DOF moved by ``q / K`` of its range)."""
    before = np.vstack([dofs0[None], dofs[:-1]])
    diff = (dofs - before) / (hi - lo) * k
    out = []
    for row in diff:
        j = int(np.argmax(np.abs(row)))
        out.append([j + 1, round(float(row[j]), 6)])
    return out


def baseline_rows(plans: Sequence[Plan]) -> list[RunRow]:
    """The rows of one (agent, target) group of navigation plans, other than the LLM's.

    The steering controller ([`jswim.agents.steering.run`][jswim.agents.steering.run]) and the
    random policy run one episode of the target's budget; Q-learning and PPO train for
    ``plan.steps`` steps (`NAV_TRAIN_EPISODES` budgets by default), restarting each ended
    episode (the world's learner step), and their row is their last episode that ended (the
    one run on what they learned, still exploring as their schedules leave them). Each episode
    is cut and measured by [`jswim.env.navigation.summarise`][jswim.env.navigation.summarise].
    """
    from jswim.agents import (  # lazy: start-up (the learners load optax)
        qlearning,
        random_policy,
        steering,
    )

    p0 = plans[0]
    if p0.agent == ZERMELO_AGENT:
        return zermelo_rows(plans)
    world_, params = world(p0)
    keys = jax.vmap(jax.random.PRNGKey)(np.array([jenv.seed32(p.seed) for p in plans], np.uint32))
    budget = int(np.asarray(params.target.budget))
    k = world_.roc_levels
    lo, hi = world_.model.lo, world_.model.hi
    codes = None
    if p0.agent == CONTROLLER_AGENT:
        trace = steering.run(world_, params, keys, budget)
    elif p0.agent == "random":
        run = random_policy.run(world_, params, keys, budget, p0.action_set, trace=True)
        trace, codes = run.trace, np.asarray(run.actions)
    elif p0.agent == "qlearning":
        config = nav_qconfig(p0.steps, p0.action_set)
        run = qlearning.train(world_, params, keys, config, trace=True)
        trace, codes = run.trace, np.asarray(run.actions)
    elif p0.agent in (OPTIMAL_AGENT, MPC_AGENT):
        codes = np.stack(
            [_planned(world_, params, p, keys[i], budget) for i, p in enumerate(plans)]
        )
        trace = rollout(world_, params, keys, jnp.asarray(codes))
    elif p0.agent == CONTINUOUS_AGENT:
        from jswim.agents import ppo  # lazy: start-up (optax's PPO, for PPO runs only)

        run = ppo.train(world_, params, keys, nav_ppo_config(p0.steps), trace=True)
        trace, codes = run.trace, _ppo_codes(run, k)
    else:
        raise ValueError(f"no navigation baseline {p0.agent!r}")
    rows = []
    start = world_.observe(world_.reset(keys[0], params), params)
    dofs0 = np.asarray(start.dofs, np.float64)
    for i, plan in enumerate(plans):
        tr = _take(trace, i)
        episodes = summarise(world_, params, tr)
        learner = plan.agent in ("qlearning", CONTINUOUS_AGENT)
        ended = [j for j, e in enumerate(episodes) if e.reached or e.steps >= budget]
        j = (ended[-1] if ended else len(episodes) - 1) if learner else 0
        begin = sum(e.steps for e in episodes[:j])
        sl = slice(begin, begin + episodes[j].steps)
        disp = np.asarray(tr.info.displacement, np.float64).reshape(-1, 2)[sl]
        xy = np.cumsum(disp, axis=0)
        heading = np.asarray(tr.obs.orientation, np.float64).reshape(-1)[sl]
        if codes is not None:
            moves = [list(lattice.decode(int(c), k)) for c in codes[i][sl]]
        else:
            dofs = np.asarray(tr.obs.dofs, np.float64)
            prev = dofs0 if begin == 0 else dofs[begin - 1]
            moves = _lattice_moves(dofs[sl], prev, lo, hi, k)
        rows.append(nav_row(plan, xy[:, 0], xy[:, 1], heading, moves, episodes[j]))
    return rows


def _ppo_codes(run: Any, k: int) -> np.ndarray:
    """The action codes a categorical PPO ran, ``(learners, steps)``, from its record (the
    chosen DOF and that DOF's ROC): the moves it asked for. Read back from the DOFs' change
    instead, a push clipped at the shape's limit reads as a shorter move, which in a flow is
    another step (it moves fast, then holds): the row's actions would not replay its run."""
    dof = np.asarray(run.dof, np.int64)
    roc = np.take_along_axis(np.asarray(run.actions, np.float64), dof[..., None] - 1, -1)[..., 0]
    return np.asarray(encode_action(dof, np.rint(roc * k).astype(np.int64), k), np.int32)


def _planned(env: Any, params: Any, plan: Plan, key: Any, budget: int) -> np.ndarray:
    """The codes of an optimal or mpc run, ``(budget,)``: the optimum's sequence (then no moves:
    the episode has ended) or the model-predictive agent's, replayed like every agent's."""
    idle = env.roc_levels  # (DOF 1, ROC 0)
    if plan.agent == MPC_AGENT:
        from jswim.agents import mpc  # lazy: start-up (the search's JAX)

        return mpc.run(env, params, key, budget)
    best = optimal_path(plan).actions
    out = np.full(budget, idle, np.int32)
    out[: min(len(best), budget)] = best[:budget]
    return out


def _straight(spec: Target, steps: int) -> float:
    """The task's straight distance (`NavSummary.straight`): from the start through the
    waypoints; a moving target's point where it was after ``steps`` steps."""
    pts = np.asarray(spec.points(), np.float64).reshape(-1, 2)
    first = pts[0] + np.asarray(spec.velocity, np.float64) * steps
    legs = float(np.hypot(*np.diff(pts, axis=0).T).sum()) if len(pts) > 1 else 0.0
    return float(np.hypot(*first)) + legs


def llm_episode(plan: Plan, r: Any, work: np.ndarray | None) -> NavSummary:
    """An LLM run's episode ([`NavSummary`][jswim.env.navigation.NavSummary]) from its own
    record: the run ends where the task did (the driver stops at the world's end), ``work`` is
    each step's, replayed (the work depends on the shape's path only)."""
    spec = target_from_dict(json.loads(plan.target))
    xy = np.column_stack([np.asarray(r.x, np.float64), np.asarray(r.y, np.float64)])
    path = float(np.hypot(*np.diff(np.vstack([np.zeros((1, 2)), xy]), axis=0).T).sum())
    straight = _straight(spec, r.steps)
    w = np.asarray(work, np.float64).reshape(-1) if work is not None else np.full(r.steps, np.nan)
    return NavSummary(
        bool(r.reached),
        r.steps,
        straight,
        path,
        path / straight if straight > 0 else float("nan"),
        float(np.sum(r.progress)),
        float(np.sum(w)),
        energy_per_distance(w, r.progress),
    )


def short_steps_warning(o: StudyOptions) -> str | None:
    """A warning when ``--steps`` is below what the steering controller is estimated to need for
    the nearest target (its budget over `BUDGET_SAFETY`): few runs, if any, can reach a target
    then. ``None`` without ``--steps`` (each target's own budget) or when it is long enough."""
    if o.steps is None:
        return None
    k = max(o.roc_levels, NAV_ROC_LEVELS)
    model = make_model("purcell")
    need = min(
        math.ceil(default_budget(spec, model, k) / BUDGET_SAFETY)
        for _, _, spec in targets(o.distances, o.bearings)
    )
    if o.steps >= need:
        return None
    return (
        f"--steps {o.steps} is shorter than the ~{need} steps the steering controller needs for "
        "the nearest target: few runs, if any, will reach a target"
    )


#: Seeds of the navigation study's learners and random policy per cell (``--q-runs``): 16,
#: trained together (vmapped), so that a cell's success and time ratio carry an interval.
NAV_SEEDS = 16

#: The navigation study's figures in order of importance (the page and the folder list them so):
#: the time ratio to the swimmer's own optimum, success, energy, then the paths. A study in a
#: flow draws the ``navigate-flow-*`` ones (`jswim.figures.flow_plots`) beside the others.
FIGURE_ORDER = (
    "navigate-flow-ratio",
    "navigate-ratio",
    "navigate-flow-success",
    "navigate-bearing",
    "navigate-flow-energy",
    "navigate-energy",
    "navigate-flow-paths",
    "navigate-paths",
)

STUDY = Study(
    name="navigate",
    help="Purcell's swimmer steered to targets at several distances and bearings, along a path "
    "and after a moving target (K = 2 unless --roc-levels), in still fluid or a background flow "
    "(--flow): the LLM, Q-learning, PPO, the steering controller, the model-predictive agent "
    "(mpc) and random, measured against the swimmer's own optimum (optimal: its least-time "
    "strokes; and Zermelo's point steerer in a flow); success, steps to the target, time over the "
    "optimum's, path over straight distance, energy and energy per distance",
    cells=cells,
    runs=1,
    init="paper",
    swimmers=("purcell",),
    swimmers_why="Purcell's swimmer only (--swimmer {swimmer}: the steering controller, the "
    "targets' budgets and the turning loops are Purcell's)",
    q_runs=NAV_SEEDS,
    ignores=("zetas", "n_hts", "roc_levels_grid", "init", "directions"),
    steps_text=(
        "each target's step budget; it is the length of an LLM run and of each training episode "
        "of Q-learning and PPO, while the controller and the random policy keep the budget"
    ),
    judged=False,
    own_budgets=True,
    min_roc_levels=2,
    roc_levels_why="the corner world, K = 1, cannot turn",
    success=navigation_rule,
    short_steps=short_steps_warning,
    order=13,
    tables=("agents x flows", "navigation"),
    figures=("navigation", "flow"),
    figure_order=FIGURE_ORDER,
    option_help={
        "--swimmer": "purcell only (the default): navigation needs a swimmer that turns in its "
        "plane; sphere swimmers move on a line",
        "--roc-levels": "ROC on K levels, K >= 2 (an extension): a reply's ROC k in -K..K moves "
        f"the DOF by k/K of its range (default {NAV_ROC_LEVELS}; the paper's K = 1 corner world "
        "cannot turn, and is refused)",
        "--n-ht": "history records in the prompt (default 3, Purcell's)",
        "--x-min": "X_min of the position encoding (X - X_min) * 1000 (default -2.5, the paper's); "
        "each run lowers it to a whole number of link lengths below every place its target can "
        "be, so that no position is sent as a negative number",
    },
    setting_notes={
        "x_min": "{v}, lowered per target to a whole a below every place the target can be "
        "(docs/navigation.md)"
    },
    flags=(
        (
            "--distances",
            dict(
                type=listed(float),
                metavar="D1,D2,...",
                help="distances of the fixed targets, in link lengths (default 3)",
            ),
        ),
        (
            "--bearings",
            dict(
                type=listed(float),
                metavar="B1,B2,...",
                help="bearings of the fixed targets, degrees counterclockwise from the start "
                "heading (default 0,90,180)",
            ),
        ),
        (
            "--flow",
            dict(
                choices=tuple(FLOWS),
                metavar="KIND",
                help="a background flow (an extension): uniform (across the start heading), shear "
                "(u = rate y), poiseuille (a channel along x) or taylor-green (vortex cells); "
                "Zermelo's point steerer (no turning limit, the flow at its centre) joins the "
                "agents as a yardstick, and every row gets its time over his beside its time over "
                "the swimmer's own optimum",
            ),
        ),
        (
            "--flows",
            dict(
                type=listed(float),
                metavar="F1,F2,...",
                help="the flow's speeds, fractions of the swimming speed 0.0478 a per step, at "
                "most 2 (default 0,0.5,0.9; past 1 some targets are unreachable and the rows say "
                "so); a grid size: more speeds on an existing folder add their runs to it",
            ),
        ),
        (
            "--starts",
            dict(
                type=int,
                metavar="N",
                help="seeded starts of every agent, the same for each (start 0 the study's own, "
                "(hi, hi) headed along +x; the others a heading within 45 degrees of +x and a "
                "corner of the shape square, drawn from --seed); each multiplies every agent's "
                "runs, pooled into the cell's row (default 1); a grid size: more starts on an "
                "existing folder add their runs to it",
            ),
        ),
        (
            "--train-episodes",
            dict(
                type=int,
                metavar="N",
                help="episodes of each target's budget that Q-learning and PPO train for "
                "(default 400)",
            ),
        ),
    ),
)
