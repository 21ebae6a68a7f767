"""Loops in shape space measured exactly: each cycle's rigid motion and work from the K-lattice
tables.

A cycle of lattice steps is a product of table rows: the centroid displacement of each step
(body frame at the step's start) rotated by the orientation reached so far, and the rotations
added (`jswim.env.step_tables.lattice_table`); its work is the sum
of the steps' rows of [`jswim.env.work.lattice_work_table`][jswim.env.work.lattice_work_table].
The loops themselves and the steering controller are kinematics:
[`jswim.swimmers.turning`][jswim.swimmers.turning].
"""

from __future__ import annotations

import functools
import math
from typing import NamedTuple

from jax import Array

import jax
import jax.numpy as jnp
import numpy as np

from jswim.env.params import EnvParams
from jswim.env.state import reset
from jswim.env.stepping import advance
from jswim.env.step_tables import lattice_table
from jswim.env.work import lattice_step_work, lattice_work_table
from jswim.swimmers.models import SwimmerModel
from jswim.swimmers.turning import (
    Loop,
    SteeringPlan,
    controller_start,
    controller_step,
    lower_quarter_loop,
    quarter_loop,
    rectangle_loops,
    square_gait,
    turning_radius,
)


class LoopMotion(NamedTuple):
    """One cycle of a loop: rigid motion of the centroid and work, exact (float64 tables)."""

    loop: Loop
    dx: float  # centroid displacement, body frame at the cycle's start (a)
    dy: float
    rotation: float  # change of orientation (rad)
    work: float  # xi_par a^3 / tau (links) or 6 pi mu a^3 / tau (spheres)
    steps: int

    @property
    def displacement(self) -> float:
        """Length of the centroid's displacement per cycle."""
        return math.hypot(self.dx, self.dy)

    @property
    def radius(self) -> float:
        """Radius of the circle the centroid follows when the cycle is repeated."""
        return turning_radius(self.displacement, self.rotation)


def _check(model: SwimmerModel) -> None:
    if model.n_dof != 2:
        raise ValueError(f"loops in shape space are for two-DOF swimmers, not {model.label}")


def loop_motion(model: SwimmerModel, roc_levels: int, loop: Loop) -> LoopMotion:
    """Rigid motion and work of one cycle of ``loop`` on the K = ``roc_levels`` lattice.

    Raises
    ------
    ValueError
        For a swimmer that does not have two DOFs, or a loop off the lattice.
    """
    _check(model)
    k = roc_levels
    rows = lattice_table(model, k)
    work_rows = lattice_work_table(model, k)
    n = model.n_dof
    x = y = theta = work = 0.0
    levels = list(loop.start)
    for dof, q in loop.moves():
        end = levels[dof] + q
        if not (min(levels) >= 0 and max(levels) <= k and 0 <= end <= k):
            raise ValueError(f"loop {loop.vertices} leaves the K = {k} lattice")
        shape = levels[0] + (k + 1) * levels[1]
        row = (shape * n + dof) * (k + 1) + end
        c, s = math.cos(theta), math.sin(theta)
        x += c * rows[row, 0] - s * rows[row, 1]
        y += s * rows[row, 0] + c * rows[row, 1]
        theta += rows[row, 2]
        work += work_rows[row]
        levels[dof] = end
    return LoopMotion(loop, float(x), float(y), float(theta), float(work), len(loop.moves()))


def lattice_loops(model: SwimmerModel, roc_levels: int) -> list[LoopMotion]:
    """Every rectangle loop of the K lattice ([`rectangle_loops`][jswim.swimmers.turning.rectangle_loops],
    one orientation each; the reverse turns and moves the other way at the same work), measured."""
    return [loop_motion(model, roc_levels, lp) for lp in rectangle_loops(roc_levels)]


def steering_plan(
    model: SwimmerModel,
    roc_levels: int = 2,
    tolerance: float | None = None,
    reverse: bool = True,
) -> SteeringPlan:
    """The steering controller's plan for ``model``: the square gait to swim straight, the two
    quarter loops that touch it (around ``(hi, hi)`` and ``(lo, lo)``) to turn.

    Parameters
    ----------
    model : SwimmerModel
        A two-DOF planar swimmer.
    roc_levels : int
        K of the lattice the loops live on (even: the quarter loops need the centre).
    tolerance : float, optional
        |bearing| (rad) under which the swimmer swims straight; default twice the turning loops'
        rotation per cycle, so that one turning cycle cannot overshoot from one side of the
        dead band to the other.
    reverse : bool
        Reach targets behind by swimming backward (the reversed gait) instead of turning round.

    Raises
    ------
    ValueError
        For a swimmer that cannot turn in the plane, an odd K, or loops whose measured motion
        does not have the signs the controller relies on (each quarter loop turning one way
        while moving forward, the other way while moving backward).
    """
    _check(model)
    if not model.planar:
        raise ValueError(f"{model.label} moves on a line and cannot steer")
    k = roc_levels
    gait = square_gait(k)
    half = gait.moves()[:2], gait.moves()[2:]
    back = gait.reversed().moves()
    upper = loop_motion(model, k, quarter_loop(k))
    lower = loop_motion(model, k, lower_quarter_loop(k))
    # Orient each quarter loop so that it moves forward (+x of the body frame at its hub).
    upper_fwd = upper.loop if upper.dx > 0 else upper.loop.reversed()
    lower_fwd = lower.loop if lower.dx > 0 else lower.loop.reversed()
    turn_up = loop_motion(model, k, upper_fwd).rotation
    turn_low = loop_motion(model, k, lower_fwd).rotation
    if not (turn_up > 0 > turn_low and math.isclose(turn_up, -turn_low, rel_tol=1e-9)):
        raise ValueError(
            f"{model.label}: the quarter loops do not turn opposite ways while moving forward "
            f"({turn_up:+.3g}, {turn_low:+.3g} rad per cycle)"
        )
    cycles = [
        (half[0], 0, 1),  # FORWARD_HALF from hub 0
        (half[1], 1, 0),  # FORWARD_HALF from hub 1
        (back[:2], 0, 1),  # BACKWARD_HALF from hub 0
        (back[2:], 1, 0),  # BACKWARD_HALF from hub 1
        (upper_fwd.moves(), 0, 0),  # LEFT_FORWARD
        (upper_fwd.reversed().moves(), 0, 0),  # RIGHT_BACKWARD
        (lower_fwd.moves(), 1, 1),  # RIGHT_FORWARD
        (lower_fwd.reversed().moves(), 1, 1),  # LEFT_BACKWARD
    ]
    width = max(len(c[0]) for c in cycles)
    moves = np.zeros((len(cycles), width, 2), np.int32)
    for i, (mv, _, _) in enumerate(cycles):
        moves[i, : len(mv)] = mv
    straight_0 = loop_motion(model, k, gait)
    straight_1 = loop_motion(model, k, Loop(((0, 0), (0, k), (k, k), (k, 0))))
    tol = 2.0 * turn_up if tolerance is None else float(tolerance)
    return SteeringPlan(
        moves=moves,
        lengths=np.array([len(c[0]) for c in cycles], np.int32),
        hub=np.array([c[1] for c in cycles], np.int32),
        next_hub=np.array([c[2] for c in cycles], np.int32),
        heading=np.array(
            [math.atan2(straight_0.dy, straight_0.dx), math.atan2(straight_1.dy, straight_1.dx)]
        ),
        turn=turn_up,
        tolerance=tol,
        reverse=bool(reverse),
        radius=loop_motion(model, k, upper_fwd).radius,
    )


def steering_budget(
    model: SwimmerModel,
    distance: float,
    bearing: float,
    roc_levels: int = 2,
    reverse: bool = True,
    safety: float = 1.5,
) -> int:
    """A step budget for the steering controller to reach a target ``distance`` away at
    ``bearing`` (rad, from the forward heading), from the physics of its two cycles.

    The estimate is the turning loop's cycles to turn through the bearing, ``|bearing| / turn``
    (measured from the backward heading when ``reverse`` and the target is behind), plus the
    square gait's cycles to cover the distance, ``distance / dX``, four steps each; ``safety``
    covers what the estimate leaves out (the turning loop's own drift along its circle, and the
    corrections the controller makes on the way). Returned as whole cycles.
    """
    turn, displacement = _steering_rates(model, roc_levels, reverse)
    b = abs(math.remainder(bearing, 2 * math.pi))
    if reverse and b > math.pi / 2:
        b = math.pi - b
    cycles = b / turn + distance / displacement
    return 4 * math.ceil(safety * cycles)


@functools.lru_cache(maxsize=32)
def _steering_rates(model: SwimmerModel, roc_levels: int, reverse: bool) -> tuple[float, float]:
    """The turning loop's rotation per cycle (rad) and the square gait's displacement per cycle
    (a): the two numbers a budget needs, measured once per swimmer and K (a study's cells and the
    worlds made for its runs ask for the same ones)."""
    plan = steering_plan(model, roc_levels, reverse=reverse)
    straight = loop_motion(model, roc_levels, square_gait(roc_levels))
    return plan.turn, straight.displacement


class SteeringRun(NamedTuple):
    """What the steering controller did for each target (leading axis B, then steps T)."""

    steps: Array  # int32 (B,): first step that ends within the radius; 0 if none within T
    distance: Array  # (B, T) distance from the centroid to the target after each step (a)
    work: Array  # (B, T) work of each step (xi_par a^3 / tau)


def steer(
    params: EnvParams, plan: SteeringPlan, targets: Array, budget: int, radius: float
) -> SteeringRun:
    """Drive the swimmer of ``params`` (integer codes on its K lattice, noise off) with the
    steering controller toward each target, for ``budget`` steps.

    Parameters
    ----------
    params : EnvParams
        A planar two-DOF swimmer with ``roc_levels`` the plan's K; the start is ``params.init``
        (it must be the plan's start vertex, ``(hi, hi)``, the default).
    plan : SteeringPlan
        From [`steering_plan`][jswim.env.loops.steering_plan].
    targets : Array, shape (B, 2)
        Target points in the lab frame (the swimmer starts with its centroid at the origin and
        its middle link along +x).
    budget : int
        Steps per target (static).
    radius : float
        Success radius around the target (a).
    """
    model, big_k = params.model, params.roc_levels
    width = 2 * big_k + 1
    if np.asarray(params.init).tolist() != [1] * model.n_dof:
        raise ValueError(f"the controller starts on (hi, hi), got init {params.init}")

    def one(target: Array) -> tuple[Array, Array, Array]:
        def body(carry, _):
            state, memory = carry
            x, y = state.x + state.x_lo, state.y + state.y_lo
            bearing = jnp.arctan2(target[1] - y, target[0] - x) - (state.theta + state.theta_lo)
            dist = jnp.hypot(target[0] - x, target[1] - y)
            move, memory = controller_step(plan, memory, bearing, dist, 0.5 * radius)
            levels = jnp.round((state.frac + state.frac_lo) * big_k).astype(jnp.int32)
            work = lattice_step_work(model, big_k, levels, move[0], move[1])
            code = move[0] * width + move[1] + big_k
            state, _ = advance(state, code, jnp.zeros((), state.x.dtype), params)
            dist = jnp.hypot(target[0] - state.x - state.x_lo, target[1] - state.y - state.y_lo)
            return (state, memory), (dist, work.astype(state.x.dtype))

        start = reset(jax.random.PRNGKey(0), params)
        _, (dist, work) = jax.lax.scan(body, (start, controller_start()), None, length=budget)
        inside = dist < radius
        steps = jnp.where(jnp.any(inside), jnp.argmax(inside) + 1, 0).astype(jnp.int32)
        return steps, dist, work

    steps, dist, work = jax.jit(jax.vmap(one))(jnp.asarray(targets))
    return SteeringRun(steps, dist, work)
