"""Turning: closed loops in a two-DOF swimmer's shape space, and a steering controller.

A stroke that is a closed loop in shape space returns the swimmer to its shape moved by a rigid
motion: a displacement and a rotation. The body's angular velocity is linear in the shape rates
and does not depend on position or orientation, ``d theta / dt = A(d) . d_dot``, so the rotation
over a loop is the line integral of ``A`` around it, the integral of its curl over the enclosed
area (Stokes' theorem; the geometric view of Shapere & Wilczek, J. Fluid Mech. 198, 557, 1989;
for Purcell's swimmer, Becker, Koehler & Stone, J. Fluid Mech. 490, 15, 2003). For Purcell's
swimmer the curl changes sign across the centre of shape space: a loop symmetric about the
centre (the square gait) does not rotate, and a loop off the centre along the diagonal ``d1 =
d2`` does, with the sign of its orientation (the quarters on the other diagonal do not). So the swimmer steers with two kinds of cycle: the square gait to swim straight
(forward, or backward when reversed), and the quarter loops to turn. The quarter loop around
``(hi, hi)`` and its mirror image around ``(lo, lo)`` each turn one way while moving forward,
and the other way when run backward; both touch the square gait's path.

Everything here is kinematics on the K lattice of the environment (DOF ``k`` at ``lo + (j_k /
K)(hi - lo)``, ``j_k`` in ``0..K``): loops as vertex lists, their moves as integer lattice steps
``(dof, q)`` (ROC ``q / K``), and a controller that is a pure function of the bearing. The rigid
motion of each loop is measured by the environment from its exact tables
([`jswim.env.loops`][jswim.env.loops]).
"""

from __future__ import annotations

import itertools
import math
from typing import NamedTuple

import jax.numpy as jnp
from jax import Array


class Loop(NamedTuple):
    """A closed lattice loop of a two-DOF swimmer: its vertices in order, the first repeated at
    the end implicitly; consecutive vertices differ in one DOF only."""

    vertices: tuple[tuple[int, int], ...]

    @property
    def start(self) -> tuple[int, int]:
        """The vertex each cycle starts and ends on."""
        return self.vertices[0]

    def moves(self) -> tuple[tuple[int, int], ...]:
        """The loop's lattice steps ``(dof, q)``: DOF ``dof`` (0-based) moves by ``q`` lattice
        units (ROC ``q / K``), one step per side."""
        out = []
        verts = self.vertices + self.vertices[:1]
        for a, b in itertools.pairwise(verts):
            diff = [b[0] - a[0], b[1] - a[1]]
            if (diff[0] != 0) == (diff[1] != 0):
                raise ValueError(f"loop sides move one DOF at a time, got {a} -> {b}")
            dof = 0 if diff[0] != 0 else 1
            out.append((dof, diff[dof]))
        return tuple(out)

    def reversed(self) -> Loop:
        """The same loop run the other way, from the same start (the time-reversed stroke)."""
        return Loop((self.vertices[0], *self.vertices[:0:-1]))


def rectangle(corner_a: tuple[int, int], corner_b: tuple[int, int], start: tuple[int, int]) -> Loop:
    """The rectangle with opposite corners ``corner_a`` and ``corner_b`` (lattice points), run
    from ``start`` (one of its corners) moving DOF 2 first.

    Raises
    ------
    ValueError
        If ``start`` is not a corner or the rectangle is degenerate.
    """
    (i0, j0), (i1, j1) = corner_a, corner_b
    if i0 == i1 or j0 == j1:
        raise ValueError("a rectangle loop needs distinct values in both DOFs")
    if start[0] not in (i0, i1) or start[1] not in (j0, j1):
        raise ValueError(f"{start} is not a corner of the rectangle {corner_a}-{corner_b}")
    other_i = i1 if start[0] == i0 else i0
    other_j = j1 if start[1] == j0 else j0
    return Loop((start, (start[0], other_j), (other_i, other_j), (other_i, start[1])))


def rectangle_loops(roc_levels: int) -> list[Loop]:
    """Every axis-aligned rectangle on the K lattice, once, each from its corner with the largest
    ``(j_1, j_2)`` and moving DOF 2 first (its reverse is the other orientation)."""
    k = roc_levels
    out = []
    for i0 in range(k + 1):
        for i1 in range(i0 + 1, k + 1):
            for j0 in range(k + 1):
                for j1 in range(j0 + 1, k + 1):
                    out.append(rectangle((i0, j0), (i1, j1), (i1, j1)))
    return out


def square_gait(roc_levels: int) -> Loop:
    """The paper's square gait on the K lattice, from ``(hi, hi)``: DOF 2 down, DOF 1 down, DOF 2
    up, DOF 1 up (for Purcell's swimmer from the authors' start this swims toward +x)."""
    k = roc_levels
    return rectangle((0, 0), (k, k), (k, k))


def quarter_loop(roc_levels: int) -> Loop:
    """The loop around the upper-right quarter of shape space, from ``(hi, hi)``, DOF 2 first:
    for Purcell's swimmer at ``d_max = pi / 3`` and K = 2, ``(pi/3, pi/3) -> (pi/3, 0) -> (0, 0)
    -> (0, pi/3)``. ``roc_levels`` must be even."""
    k = roc_levels
    if k % 2:
        raise ValueError(f"the quarter loop needs an even K (the centre on the lattice), got {k}")
    return rectangle((k // 2, k // 2), (k, k), (k, k))


def lower_quarter_loop(roc_levels: int) -> Loop:
    """The loop around the lower-left quarter of shape space, from ``(lo, lo)``, DOF 2 first:
    the mirror image of [`quarter_loop`][jswim.swimmers.turning.quarter_loop] under the
    swimmer's end-to-end symmetry. ``roc_levels`` must be even."""
    k = roc_levels
    if k % 2:
        raise ValueError(f"the quarter loop needs an even K (the centre on the lattice), got {k}")
    return rectangle((0, 0), (k // 2, k // 2), (0, 0))


#: The steering controller's cycles (rows of [`SteeringPlan.moves`][jswim.swimmers.turning.SteeringPlan]).
#: Two hubs: 0 is ``(hi, hi)`` (the paper's start), 1 is ``(lo, lo)``; the square gait passes
#: through both, half a gait each way.
FORWARD_HALF = (0, 1)  # the square gait's half from hub 0 to hub 1, and from hub 1 to hub 0
BACKWARD_HALF = (2, 3)  # the reversed gait's halves, same hubs
LEFT_FORWARD, RIGHT_BACKWARD = 4, 5  # the upper quarter loop at hub 0, and its reverse
RIGHT_FORWARD, LEFT_BACKWARD = 6, 7  # the lower quarter loop at hub 1, and its reverse


class SteeringPlan(NamedTuple):
    """What the controller needs from the physics, measured once per swimmer
    ([`jswim.env.loops.steering_plan`][jswim.env.loops.steering_plan]).

    Eight cycles between two hubs on the square gait's path, ``(hi, hi)`` (hub 0) and ``(lo,
    lo)`` (hub 1): the gait's halves forward and backward (hub to hub), and at each hub the
    quarter loop of shape space that touches it, in both orientations. Each quarter loop turns
    the body one way while moving it forward and the other way while moving it backward, so a
    turn either way can be made while moving along the heading: left at hub 0, right at hub 1
    (forward), and the reverse when swimming backward. Cycle indices: the module's constants.
    """

    moves: Array  # int32 (8, P, 2): (dof, q) of each cycle's steps (shorter cycles: q = 0 pads)
    lengths: Array  # int32 (8,): steps per cycle
    hub: Array  # int32 (8,): the hub each cycle starts on
    next_hub: Array  # int32 (8,): the hub each cycle ends on
    heading: (
        Array  # float (2,): direction of the gait's displacement per cycle, body frame, per hub
    )
    turn: float  # rotation per cycle of the turning loops (rad, > 0)
    tolerance: float  # |bearing| below which the swimmer swims straight (rad)
    reverse: bool  # whether a target behind is reached by swimming backward
    radius: float = 0.0  # radius of the turning loops' circle (a); 0: no inside rule


#: Steps ahead the controller predicts the flow's turn of its heading (the feed-forward of
#: `choose_cycle`): the half gait it runs when swimming straight.
FEED_STEPS = 2.0


def wrap(angle: Array) -> Array:
    """An angle in ``(-pi, pi]``."""
    return jnp.pi - jnp.mod(jnp.pi - angle, 2 * jnp.pi)


def choose_cycle(
    plan: SteeringPlan,
    hub: Array,
    bearing: Array,
    distance: Array | float = jnp.inf,
    reach: Array | float = 0.0,
    rotation: Array | float = 0.0,
) -> Array:
    """Which cycle to run next from ``hub``, given the target's bearing in the body frame
    (and its distance).

    ``bearing`` is the angle of the target direction from the body frame's x axis (the middle
    link). Measured from the forward heading at this hub it is ``b``; with ``plan.reverse`` a
    target more than 90 degrees off is measured from the backward heading instead. Within
    ``plan.tolerance`` the swimmer swims straight (half a gait, to the other hub). Otherwise it
    turns toward the target: a body rotation ``+turn`` lowers ``b`` by ``turn``, so ``b > 0``
    needs a left (positive) turn. It runs the loop that makes that turn while moving along the
    heading when that loop is at this hub, and otherwise swims half a gait to the other hub,
    where it is.

    A target ahead (``cos b > 0``) that swimming straight would pass within ``reach`` of
    (``distance |sin b| < reach``) is swum to straight. Otherwise a target inside the circle
    the turn would follow
    (radius ``plan.radius``: ``distance < 2 radius |sin b|``, ``b`` from the forward heading)
    cannot be reached by turning, which would circle round it: the swimmer swims forward, which
    moves the target back and out of the circle, and turns after. (Targets closer than about
    one turning diameter to the side can still trap it between the two rules:
    docs/navigation.md.)

    In a background flow that turns the body by ``rotation`` (rad per step, counterclockwise;
    ``0`` in still fluid, where every choice is as without it) the bearing is predicted
    `FEED_STEPS` steps ahead, ``b - FEED_STEPS rotation`` (a feed-forward: the flow's turn is
    cancelled before it shows), and a turn the flow beats (``turn + 4 rotation <= 0`` for a left
    turn, ``turn - 4 rotation <= 0`` for a right one) is made the other way round, with the
    flow. docs/navigation.md gives where the flow's rotation beats the turning loops.

    Returns
    -------
    int32 Array, shape ()
    """
    hub = jnp.asarray(hub, jnp.int32)
    omega = jnp.asarray(rotation)
    # feed-forward: the flow turns the body by omega per step, so the bearing a cycle from now
    # is lower by omega times its steps (exactly b in still fluid, omega = 0)
    b = wrap(jnp.asarray(bearing) - jnp.asarray(plan.heading)[hub] - FEED_STEPS * omega)
    backward = jnp.asarray(plan.reverse) & (jnp.abs(b) > jnp.pi / 2)
    b = jnp.where(backward, wrap(b - jnp.pi), b)
    half = jnp.where(backward, jnp.asarray(BACKWARD_HALF)[hub], jnp.asarray(FORWARD_HALF)[hub])
    # the turning loops' rotation per cycle with the flow's added: left plan.turn + 4 omega,
    # right plan.turn - 4 omega (magnitudes); a turn the flow beats (<= 0) cannot be made, and
    # the swimmer turns the other way, with the flow
    cycle = 4.0  # steps of a turning loop
    left = jnp.where(b > 0, plan.turn + cycle * omega > 0, plan.turn - cycle * omega <= 0)
    loop = jnp.where(
        backward,
        jnp.where(left, LEFT_BACKWARD, RIGHT_BACKWARD),
        jnp.where(left, LEFT_FORWARD, RIGHT_FORWARD),
    )
    turn = jnp.where(jnp.asarray(plan.hub)[loop] == hub, loop, half)
    distance = jnp.asarray(distance)
    # passing within reach counts only for a target ahead: one straight behind (sin b = 0) is
    # passed by swimming away from it
    passes = (distance * jnp.abs(jnp.sin(b)) < reach) & (jnp.cos(b) > 0)
    aligned = (jnp.abs(b) <= plan.tolerance) | passes
    b_forward = wrap(jnp.asarray(bearing) - jnp.asarray(plan.heading)[hub] - FEED_STEPS * omega)
    inside = ~aligned & (distance < 2.0 * plan.radius * jnp.abs(jnp.sin(b_forward)))
    out = jnp.where(aligned, half, jnp.where(inside, jnp.asarray(FORWARD_HALF)[hub], turn))
    return out.astype(jnp.int32)


class ControllerState(NamedTuple):
    """The controller's memory: the hub it left from, the cycle it is running and the next
    step's place in it."""

    hub: Array  # int32 ()
    cycle: Array  # int32 ()
    phase: Array  # int32 ()


def controller_start() -> ControllerState:
    """A controller on hub 0, ``(hi, hi)``, about to choose its first cycle."""
    zero = jnp.zeros((), jnp.int32)
    return ControllerState(zero, zero, zero)


def controller_step(
    plan: SteeringPlan,
    memory: ControllerState,
    bearing: Array,
    distance: Array | float = jnp.inf,
    reach: Array | float = 0.0,
    rotation: Array | float = 0.0,
) -> tuple[Array, ControllerState]:
    """The steering controller: the next lattice step ``(dof, q)`` and the updated memory.

    At the start of a cycle (``phase == 0``; the swimmer is on ``memory.hub``) it picks a cycle
    with [`choose_cycle`][jswim.swimmers.turning.choose_cycle]; within a cycle it plays the
    cycle's steps, and at its end moves to the cycle's end hub. A pure function of its
    arguments (``jit``, ``vmap``, ``scan``).

    Returns
    -------
    move : int32 Array, shape (2,)
        ``(dof, q)``: DOF (0-based) and ROC in lattice units (ROC ``q / K``).
    memory : ControllerState
    """
    start = memory.phase == 0
    cycle = jnp.where(
        start, choose_cycle(plan, memory.hub, bearing, distance, reach, rotation), memory.cycle
    )
    move = jnp.asarray(plan.moves)[cycle, memory.phase]
    phase = (memory.phase + 1) % jnp.asarray(plan.lengths)[cycle]
    hub = jnp.where(phase == 0, jnp.asarray(plan.next_hub)[cycle], memory.hub)
    return move.astype(jnp.int32), ControllerState(
        hub.astype(jnp.int32), cycle.astype(jnp.int32), phase.astype(jnp.int32)
    )


def turning_radius(displacement: float, rotation: float) -> float:
    """Radius of the circle a swimmer repeating one cycle travels on: the chord ``displacement``
    subtends the angle ``rotation`` (``inf`` for a cycle that does not rotate)."""
    if rotation == 0:
        return math.inf
    return displacement / (2.0 * abs(math.sin(rotation / 2.0)))
