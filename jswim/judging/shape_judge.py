"""The success criterion for real-valued strokes: cycles read from the shape, within a tolerance.

[`jswim.judging.gait.judge`][jswim.judging.gait.judge] reads cycles from action indices (on the K lattice, from lattice codes):
a cycle is a repeated block of actions that returns to the same corner. An agent with real ROCs
([`jswim.agents.ppo`][jswim.agents.ppo]) never repeats an action exactly, but it can repeat a *shape*: a push
past a limit stops at the limit, so a policy whose ROCs saturate returns to the same corner
exactly, and any other return is close. Here a run has learned from step ``s`` when, from ``s``
to the end of the run,

- the shape sequence is periodic with period ``p``: every shape is within ``tol`` (a fraction
  of the range ``hi - lo``, per DOF, default `SHAPE_TOL`) of the shape ``p`` steps later;
- every step changes the shape by more than ``tol``;
- the segment holds at least ``n_cycles`` periods, and every complete period moves the swimmer,
  exactly and without noise, by at least ``min_fraction`` of the best displacement per step of
  a closed stroke with the same constraints (one DOF at a time, ``|ROC| <= 1``), times ``p``.

The best stroke's speed is [`jswim.judging.gait.best_per_step`][jswim.judging.gait.best_per_step], the full square of corner moves:
for one DOF at a time and ``|ROC| <= 1`` a step sweeps at most the whole range, and a closed
stroke's displacement is the curvature integrated over the area it encloses, which the full
square maximises per step among the lattice strokes measured ([`jswim.judging.lattice.best_per_step`][jswim.judging.lattice.best_per_step]
finds the full square at every K). ``steps_to_learn``, ``success`` and the horizon are as in
[`jswim.judging.gait.judge`][jswim.judging.gait.judge] ([`jswim.judging.gait.Criterion`][jswim.judging.gait.Criterion], counted from 1). On corner-to-corner
runs (ROC in {-1, 1}) this judge and [`jswim.judging.gait.judge`][jswim.judging.gait.judge] agree, which the tests check.

Cycles are considered up to ``max_period`` steps (default ``2 * 2**n_dof``: a corner cycle, or a
stroke with sides of half the range).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from jswim.errors import ConfigError
from jswim.judging.gait import (
    REL_TOL,
    PAPER,
    Criterion,
    GaitReport,
    best_per_step,
    stroke_report,
    trailing_strokes,
)

#: Shape tolerance of a cycle, as a fraction of each DOF's range (a return within 0.1 % counts).
SHAPE_TOL = 1e-3


def default_max_period(n_dof: int) -> int:
    """Longest stroke considered for real-valued runs: ``2 * 2**n_dof`` steps."""
    return 2 * 2**n_dof


def judge_shapes(
    dofs: Any,
    x: Any,
    params: Any,
    *,
    dofs0: Any,
    criterion: Criterion = PAPER,
    tol: float = SHAPE_TOL,
    max_period: int | None = None,
) -> GaitReport:
    """Find, per run, the final stroke in its shape sequence and whether it qualifies.

    Parameters
    ----------
    dofs : float array-like (B, T, n_dof)
        DOF values after each step.
    x : float array-like (B, T)
        Exact (noiseless) centroid x after each step, starting from 0.
    params : EnvParams
        The runs' environment (``direction`` scalar or (B,)).
    dofs0 : float array-like (B, n_dof) or (n_dof,)
        DOF values before the first step.
    criterion : Criterion
        Horizon, cycle count and speed threshold (default: the paper's).
    tol : float
        Shape tolerance, a fraction of the DOF range (default `SHAPE_TOL`).
    max_period : int, optional
        Longest period considered (default [`default_max_period`][jswim.judging.shape_judge.default_max_period]).

    Returns
    -------
    GaitReport
        As [`jswim.judging.gait.judge`][jswim.judging.gait.judge]; ``cycle`` holds the stroke's DOFs moved (1-based), padded
        with -1, since real-valued actions have no index.

    Raises
    ------
    ConfigError
        For arrays of mismatched shapes or a tolerance outside (0, 1).
    """
    model = params.model
    n = model.n_dof
    d = np.asarray(dofs, np.float64)
    if d.ndim == 2:
        d = d[None]
    xs = np.asarray(x, np.float64).reshape(d.shape[:2])
    if d.ndim != 3 or d.shape[2] != n:
        raise ConfigError(f"dofs must have shape (runs, steps, {n})")
    if not 0.0 < tol < 1.0:
        raise ConfigError(f"tol must lie in (0, 1), got {tol!r}")
    b, steps, _ = d.shape
    c = criterion
    max_period = default_max_period(n) if max_period is None else int(max_period)
    d0 = np.broadcast_to(np.asarray(dofs0, np.float64), (b, n))
    shapes = np.concatenate([d0[:, None], d], axis=1).transpose(1, 0, 2)  # (T + 1, B, n)
    pos = np.concatenate([np.zeros((b, 1)), xs], axis=1).T  # (T + 1, B)
    tol_abs = tol * (model.hi - model.lo)
    direction = np.broadcast_to(np.sign(np.asarray(params.direction, np.float64)), (b,))
    best = np.where(direction > 0, best_per_step(model, 1), best_per_step(model, -1))
    threshold = c.min_fraction * best - REL_TOL * np.abs(best)

    moved = np.max(np.abs(shapes[1:] - shapes[:-1]), axis=-1) > tol_abs  # (T, B)

    def differs(p: int) -> np.ndarray:  # shape t and shape t + p differ; (T + 1 - p, B)
        return np.max(np.abs(shapes[p:] - shapes[:-p]), axis=-1) > tol_abs

    # Shapes periodic up to the final one already close the loop: no separate closure test.
    out_s, out_p, out_disp = trailing_strokes(
        differs,
        lambda sc, p: np.ones(b, bool),
        moved,
        pos,
        direction,
        threshold,
        min(max_period, steps // c.n_cycles),
        c.n_cycles,
    )

    moved_dof = np.argmax(np.abs(shapes[1:] - shapes[:-1]), axis=-1).T + 1  # (B, T), 1-based
    return stroke_report(out_s, out_p, out_disp, best, c, moved_dof, max_period)
