"""The navigation study (``jswim study navigate``; docs/navigation.md): Purcell's swimmer sent to
targets at several distances and bearings, along a path and after a moving target, by the LLM,
Q-learning, PPO, the steering controller and the random policy.

Its cells are targets ([`cells`][jswim.studies.navigate.cells]); every run of a cell has the
target's step budget ([`jswim.env.targets.default_budget`][jswim.env.targets.default_budget]:
measured for the steering controller, with a safety factor). Every run, whatever its agent,
becomes one row through [`nav_row`][jswim.studies.navigate.nav_row] (success = the target
reached, steps to it, path length over the straight distance, energy and energy per distance);
[`nav_summary`][jswim.studies.navigate.nav_summary] is the study's table.
"""

from __future__ import annotations

import dataclasses
import json
import math
from typing import Any
from collections.abc import Sequence

import numpy as np

from jswim.env.targets import (
    FixedTarget,
    MovingTarget,
    Target,
    Waypoints,
    default_budget,
    target_from_dict,
)
from jswim.results.row import RunRow
from jswim.studies.options import CONTINUOUS_AGENT, CONTROLLER_AGENT
from jswim.studies.plans import Cell, Plan
from jswim.swimmers.models import make_model

__all__ = [
    "CONTROLLER_AGENT",
    "DEFAULT_BEARINGS",
    "DEFAULT_DISTANCES",
    "MOVING",
    "NAV_AGENTS",
    "NAV_ROC_LEVELS",
    "PATH",
    "cells",
    "nav_row",
    "nav_summary",
    "target_json",
    "targets",
]


#: The agents of every navigation cell, in the rows' order.
NAV_AGENTS = ("llm", "qlearning", CONTINUOUS_AGENT, CONTROLLER_AGENT, "random")

#: The default grid: targets 2 a away, ahead, to the left and behind (the study's small default;
#: ``--distances`` and ``--bearings`` scale it up).
DEFAULT_DISTANCES = (2.0,)
DEFAULT_BEARINGS = (0.0, 90.0, 180.0)

#: The path of every navigation study: 2 a ahead, then 1.5 a to the left of that (a turn of 90
#: degrees between the legs).
PATH = Waypoints(((2.0, 0.0), (2.0, 1.5)))

#: The moving target of every navigation study: 2 a ahead, moving sideways (to +y) at 0.005 a
#: per step, a tenth of the square gait's mean speed (0.0478 a per step).
MOVING = MovingTarget(2.0, 0.0, (0.0, 0.005))

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


def cells(o: Any) -> list[Cell]:
    """The navigation study's cells for options ``o``: one per target, with its budget as the
    runs' steps (`--steps` overrides it) on the K lattice of ``--roc-levels`` (2 where it is 1)."""
    k = o.roc_levels if o.roc_levels > 1 else NAV_ROC_LEVELS
    model = make_model("purcell")
    return [
        Cell(
            group,
            NAV_AGENTS,
            n_ht=o.n_ht,
            roc_levels=k,
            tag=tag,
            target=target_json(spec),
            steps=default_budget(spec, model, k),
        )
        for group, tag, spec in targets(o.distances, o.bearings)
    ]


def _straight(spec: Target, end_target: Sequence[float]) -> float:
    """The task's straight distance: from the start through the waypoints, the last one where
    the target was at the end (a moving target's place when caught)."""
    pts = [tuple(p) for p in spec.points()[:-1]] + [tuple(end_target)]
    total, here = 0.0, (0.0, 0.0)
    for p in pts:
        total += math.dist(here, p)
        here = p
    return total


def _end_target(spec: Target, steps: int) -> tuple[float, float]:
    """Where the last waypoint is after ``steps`` steps (a moving target has moved)."""
    p = spec.points()[-1]
    v = spec.velocity
    return (p[0] + v[0] * steps, p[1] + v[1] * steps)


def nav_row(
    plan: Plan,
    x: Sequence[float],
    y: Sequence[float],
    orientation: Sequence[float],
    actions: list[list[float]],
    reached: bool,
    work: Sequence[float] | None,
    init: str = "++",
    **columns: Any,
) -> RunRow:
    """The row of one navigation run of ``plan``, whatever its agent.

    Parameters
    ----------
    x, y, orientation : sequence of float
        The centroid (``a``, lab frame; the start is ``(0, 0)``) and heading (rad) after each
        step, up to the step the task ended (reached or the budget spent).
    actions : list of list
        Each step's ``[dof, roc]``.
    reached : bool
        The target was reached (at the last step).
    work : sequence of float, optional
        Each step's work (``xi_par a^3 / tau``).
    init : str
        The start as the row shows it (signs; the controller's hub ``(hi, hi)``: ``"++"``).
    **columns
        Further columns (an LLM run's own, through `jswim.studies.rows.with_llm`).

    The row's success is ``reached``; ``steps_to_target`` the steps when reached;
    ``path_length`` the sum of the steps' displacements; ``path_ratio`` that over the task's
    straight distance (`_straight`); ``energy`` the summed work, ``energy_per_distance`` it over
    the net displacement in the plane, ``efficiency`` Lighthill's with that displacement
    (`jswim.studies.rows.energy_columns`).
    """
    from jswim.studies.rows import build_row, energy_columns  # the one row builder

    spec = target_from_dict(json.loads(plan.target))
    xy = np.column_stack([np.asarray(x, np.float64), np.asarray(y, np.float64)])
    path = np.vstack([np.zeros((1, 2)), xy]) if len(xy) else np.zeros((1, 2))
    length = float(np.sum(np.hypot(*np.diff(path, axis=0).T))) if len(xy) else 0.0
    steps = len(xy)
    net = float(np.hypot(*path[-1]))
    straight = _straight(spec, _end_target(spec, steps))
    verdict = {
        "success": bool(reached),
        "learned": bool(reached),
        "steps_to_learn": steps if reached else None,
        "period": 0,
    }
    row = build_row(
        plan,
        x,
        actions,
        verdict,
        init=init,
        work=None,
        y=[float(v) for v in y],
        orientation=[float(v) for v in orientation],
        **columns,
    )
    energy = energy_columns(plan.swimmer, net, work)
    return dataclasses.replace(
        row,
        **energy,
        target=plan.target,
        reached=bool(reached),
        steps_to_target=steps if reached else None,
        path_length=length,
        path_ratio=length / straight if reached and straight > 0 else None,
    )


def cut(done: np.ndarray) -> int:
    """Steps up to and including the first at which the task ended (all of them if it never did)."""
    hit = np.flatnonzero(np.asarray(done, bool))
    return int(hit[0]) + 1 if hit.size else len(done)


def nav_summary(rows: Sequence[Any]) -> list[dict[str, Any]]:
    """The study's table: per (agent, target group), runs, successes, the mean steps to the
    target over the runs that reached it, the mean path ratio, energy and energy per distance."""
    from jswim.results import as_run_rows, is_failed

    out: dict[tuple[str, str], list[RunRow]] = {}
    for r in as_run_rows(rows):
        if r.target is None or is_failed(r):
            continue
        out.setdefault((r.agent, r.group), []).append(r)

    def mean(vals: list[Any]) -> float | None:
        vals = [float(v) for v in vals if v is not None]
        return float(np.mean(vals)) if vals else None

    table = []
    for (agent, group), g in sorted(out.items(), key=lambda kv: (kv[0][1], kv[0][0])):
        table.append(
            {
                "group": group,
                "agent": agent,
                "n": len(g),
                "reached": sum(bool(r.reached) for r in g),
                "success_rate": sum(bool(r.reached) for r in g) / len(g),
                "steps_to_target": mean([r.steps_to_target for r in g]),
                "path_ratio": mean([r.path_ratio for r in g]),
                "energy": mean([r.energy for r in g]),
                "energy_per_distance": mean([r.energy_per_distance for r in g]),
            }
        )
    return table
