"""Navigation targets: hashable specs of where a swimmer is sent, and the arrays a world reads.

Three kinds, each with a success radius and a step budget (``a``: the swimmer's length unit,
link lengths for Purcell's swimmer; angles in degrees, counterclockwise positive, from the
lab's +x, which is the default start heading: the paper's swimmer starts with its middle link
along +x and its square gait swims that way):

* [`FixedTarget`][jswim.env.targets.FixedTarget]: a point ``distance`` away at ``bearing``
  (180: straight behind);
* [`Waypoints`][jswim.env.targets.Waypoints]: points visited in order; the task is over at the
  last one;
* [`MovingTarget`][jswim.env.targets.MovingTarget]: a point starting ``distance`` away at
  ``bearing`` and moving at a constant ``velocity`` (``a`` per step, lab frame).

Every kind compiles to the same arrays ([`TargetParams`][jswim.env.targets.TargetParams]):
waypoints ``(P, 2)`` and a velocity; the target at step ``t`` of an episode, while waypoint
``i`` is current, is ``points[i] + velocity t``. A budget left ``None`` is set from the
steering controller's measured physics ([`default_budget`][jswim.env.targets.default_budget]).

Every kind also carries the swimmer's ``start_heading`` (degrees from the lab's +x, default 0):
the navigation world turns the swimmer about its centroid by it at every start (a seeded start
of `jswim study navigate --starts`); the target stays where the spec puts it, so a target at
bearing 90 is 90 - ``start_heading`` degrees off the swimmer's nose.
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from typing import Any, NamedTuple

import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.env.flows import SWIM_SPEED
from jswim.errors import MAX_COUNT, ConfigError
from jswim.swimmers.turning import square_gait

__all__ = [
    "BUDGET_SAFETY",
    "DEFAULT_RADIUS",
    "FLOW_BUDGET_FACTOR",
    "FixedTarget",
    "MovingTarget",
    "Target",
    "TargetParams",
    "Waypoints",
    "budget_source",
    "course_time",
    "default_budget",
    "flow_budget",
    "target_from_dict",
    "target_params",
]

#: Success radius (``a``) unless a spec gives its own: a quarter link length, about the
#: centroid's sway within one square-gait cycle.
DEFAULT_RADIUS = 0.25

#: Safety factor of the default budgets over the controller's estimated steps
#: ([`jswim.env.loops.steering_budget`][jswim.env.loops.steering_budget]); docs/navigation.md
#: ("Budgets") gives the measured steps it covers.
BUDGET_SAFETY = 1.5

#: In a moving flow a target's budget is at least this many times a least time of a point
#: swimmer (the steering controller's still-fluid budget does not see the flow): `flow_budget`.
FLOW_BUDGET_FACTOR = 4

#: Points of the midpoint rule along each straight leg of `course_time`.
COURSE_POINTS = 64

#: Largest budget (steps): the worlds count steps in int32.
MAX_BUDGET = MAX_COUNT

#: Largest distance of a target or waypoint from the start, radius and speed (``a``, ``a`` per
#: step): float32 positions there resolve about 1e-3 a (eps 1.2e-7 times 1e4), ten times finer
#: than one step's displacement (~0.01 a); farther out a float32 world would blur its steps.
MAX_DISTANCE = 1.0e4

#: Bearings are degrees within one turn either way.
MAX_BEARING = 360.0


def _number(value: Any, what: str, positive: bool = False, limit: float | None = None) -> float:
    """``value`` as a float: a real number (not a string, not a bool), finite, ``> 0`` where
    ``positive``, ``|v| <= limit`` where given."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real):
        raise ConfigError(f"{what} must be a number, got {value!r}")
    v = float(value)
    if not math.isfinite(v) or (positive and v <= 0):
        raise ConfigError(
            f"{what} must be a finite number{' > 0' if positive else ''}, got {value!r}"
        )
    if limit is not None and abs(v) > limit:
        raise ConfigError(f"{what} must be within -{limit:g}..{limit:g}, got {value!r}")
    return v


def _check_common(radius: Any, budget: Any) -> tuple[float, int | None]:
    r = _number(radius, "radius", positive=True, limit=MAX_DISTANCE)
    if budget is not None and (
        isinstance(budget, (bool, np.bool_))
        or not isinstance(budget, (int, np.integer))
        or not 1 <= budget <= MAX_BUDGET
    ):
        raise ConfigError(
            f"budget must be a whole number of steps in 1..{MAX_BUDGET:,} (int32) or None, "
            f"got {budget!r}"
        )
    return r, None if budget is None else int(budget)


def _check_heading(spec: Any) -> None:
    object.__setattr__(
        spec, "start_heading", _number(spec.start_heading, "start_heading", limit=MAX_BEARING)
    )


def _without_default_heading(data: dict[str, Any]) -> dict[str, Any]:
    # the default start leaves no key: every spec's JSON (a row's target, a run's identity) is
    # as it was before start headings existed
    if data.get("start_heading") == 0.0:
        data.pop("start_heading")
    return data


def _polar(distance: float, bearing: float) -> tuple[float, float]:
    b = math.radians(bearing)
    return distance * math.cos(b), distance * math.sin(b)


@dataclasses.dataclass(frozen=True)
class FixedTarget:
    """A fixed point ``distance`` (``a``) away at ``bearing`` (degrees from the start heading,
    counterclockwise; 180 is straight behind).

    Parameters
    ----------
    distance : float
        From the start's centroid (``a``), above ``radius`` and at most `MAX_DISTANCE`.
    bearing : float
        Degrees from the start heading, counterclockwise, within one turn (`MAX_BEARING`).
    radius : float
        Success radius (``a``, default `DEFAULT_RADIUS`): the target is reached when the
        centroid comes within it.
    budget : int, optional
        Steps per episode (at most `MAX_BUDGET`); default: measured for the steering controller
        ([`default_budget`][jswim.env.targets.default_budget]).
    start_heading : float
        The swimmer's heading at the start (degrees from the lab's +x, counterclockwise, within
        one turn; default 0, the paper's start): the world turns it about its centroid.

    Raises
    ------
    ConfigError
        A distance not above the radius, a bad radius or budget.
    """

    distance: float
    bearing: float = 0.0
    radius: float = DEFAULT_RADIUS
    budget: int | None = None
    start_heading: float = 0.0

    kind = "fixed"

    def __post_init__(self) -> None:
        r, b = _check_common(self.radius, self.budget)
        _check_heading(self)
        d = _number(self.distance, "distance", positive=True, limit=MAX_DISTANCE)
        if d <= r:
            raise ConfigError(f"distance {d} must exceed the success radius {r}")
        object.__setattr__(self, "distance", d)
        object.__setattr__(self, "bearing", _number(self.bearing, "bearing", limit=MAX_BEARING))
        object.__setattr__(self, "radius", r)
        object.__setattr__(self, "budget", b)

    def points(self) -> tuple[tuple[float, float], ...]:
        """The waypoints, lab frame (``a``)."""
        return (_polar(self.distance, self.bearing),)

    @property
    def velocity(self) -> tuple[float, float]:
        return (0.0, 0.0)

    def to_dict(self) -> dict[str, Any]:
        """The spec as plain JSON values (``kind`` first); [`target_from_dict`][jswim.env.targets.target_from_dict] reads it."""
        return _without_default_heading({"kind": self.kind, **dataclasses.asdict(self)})


@dataclasses.dataclass(frozen=True)
class Waypoints:
    """Points ``((x, y), ...)`` (``a``, lab frame: x along the start heading) visited in order;
    each is reached within ``radius``, and the task is over at the last one.

    Parameters
    ----------
    points_xy : tuple of (float, float)
        The waypoints (``a``, lab frame), in the order they are visited.
    radius : float
        Success radius (``a``, default `DEFAULT_RADIUS`): the target is reached when the
        centroid comes within it.
    budget : int, optional
        Steps per episode (at most `MAX_BUDGET`); default: measured for the steering controller
        ([`default_budget`][jswim.env.targets.default_budget]).
    start_heading : float
        The swimmer's heading at the start (degrees from the lab's +x, counterclockwise, within
        one turn; default 0, the paper's start): the world turns it about its centroid.

    Raises
    ------
    ConfigError
        No points, a point that is not two finite numbers, the first point within the radius of
        the start, a bad radius or budget.
    """

    points_xy: tuple[tuple[float, float], ...]
    radius: float = DEFAULT_RADIUS
    budget: int | None = None
    start_heading: float = 0.0

    kind = "waypoints"

    def __post_init__(self) -> None:
        r, b = _check_common(self.radius, self.budget)
        _check_heading(self)
        try:
            pts = tuple(
                (
                    _number(p[0], "a waypoint's x", limit=MAX_DISTANCE),
                    _number(p[1], "a waypoint's y", limit=MAX_DISTANCE),
                )
                for p in self.points_xy
            )
            ok = all(len(p) == 2 for p in self.points_xy)
        except (TypeError, IndexError):
            ok = False
        if not ok or not pts:
            raise ConfigError(
                f"waypoints must be a non-empty list of (x, y), got {self.points_xy!r}"
            )
        if math.hypot(*pts[0]) <= r:
            raise ConfigError(
                f"the first waypoint {pts[0]} lies within the radius {r} of the start"
            )
        object.__setattr__(self, "points_xy", pts)
        object.__setattr__(self, "radius", r)
        object.__setattr__(self, "budget", b)

    def points(self) -> tuple[tuple[float, float], ...]:
        return self.points_xy

    @property
    def velocity(self) -> tuple[float, float]:
        return (0.0, 0.0)

    def to_dict(self) -> dict[str, Any]:
        return _without_default_heading(
            {
                "kind": self.kind,
                "points": [list(p) for p in self.points_xy],
                "radius": self.radius,
                "budget": self.budget,
                "start_heading": self.start_heading,
            }
        )


@dataclasses.dataclass(frozen=True)
class MovingTarget:
    """A point starting ``distance`` (``a``) away at ``bearing`` (degrees) and moving at the
    constant ``velocity`` ``(vx, vy)`` (``a`` per step, lab frame).

    Parameters
    ----------
    distance, bearing : float
        Where it starts, as for `FixedTarget`.
    velocity : (float, float)
        ``(vx, vy)``, ``a`` per step, lab frame; slower than the square gait's mean speed when
        the budget is left to `default_budget`.
    radius : float
        Success radius (``a``, default `DEFAULT_RADIUS`): the target is reached when the
        centroid comes within it.
    budget : int, optional
        Steps per episode (at most `MAX_BUDGET`); default: measured for the steering controller
        ([`default_budget`][jswim.env.targets.default_budget]).
    start_heading : float
        The swimmer's heading at the start (degrees from the lab's +x, counterclockwise, within
        one turn; default 0, the paper's start): the world turns it about its centroid.

    Raises
    ------
    ConfigError
        A distance not above the radius, a velocity that is not two finite numbers, a bad
        radius or budget.
    """

    distance: float
    bearing: float = 0.0
    velocity: tuple[float, float] = (0.0, 0.0)
    radius: float = DEFAULT_RADIUS
    budget: int | None = None
    start_heading: float = 0.0

    kind = "moving"

    def __post_init__(self) -> None:
        r, b = _check_common(self.radius, self.budget)
        _check_heading(self)
        d = _number(self.distance, "distance", positive=True, limit=MAX_DISTANCE)
        if d <= r:
            raise ConfigError(f"distance {d} must exceed the success radius {r}")
        try:
            v = (
                _number(self.velocity[0], "velocity x", limit=MAX_DISTANCE),
                _number(self.velocity[1], "velocity y", limit=MAX_DISTANCE),
            )
            ok = len(self.velocity) == 2
        except (TypeError, IndexError):
            ok = False
        if not ok:
            raise ConfigError(f"velocity must be (vx, vy) in a per step, got {self.velocity!r}")
        object.__setattr__(self, "distance", d)
        object.__setattr__(self, "bearing", _number(self.bearing, "bearing", limit=MAX_BEARING))
        object.__setattr__(self, "velocity", v)
        object.__setattr__(self, "radius", r)
        object.__setattr__(self, "budget", b)

    def points(self) -> tuple[tuple[float, float], ...]:
        return (_polar(self.distance, self.bearing),)

    def to_dict(self) -> dict[str, Any]:
        out = {"kind": self.kind, **dataclasses.asdict(self)}
        out["velocity"] = list(self.velocity)
        return _without_default_heading(out)


#: Any target spec.
Target = FixedTarget | Waypoints | MovingTarget

_KINDS = {"fixed": FixedTarget, "waypoints": Waypoints, "moving": MovingTarget}


def target_from_dict(data: dict[str, Any]) -> Target:
    """A spec from its ``to_dict`` (as a study row stores it).

    Parameters
    ----------
    data : dict
        ``{"kind": "fixed" | "waypoints" | "moving", ...fields}``; a waypoints spec's points
        under ``points`` or ``points_xy``.

    Returns
    -------
    FixedTarget, Waypoints or MovingTarget
        The spec, checked as its constructor checks it.

    Raises
    ------
    ConfigError
        An unknown kind or a bad field.
    """
    data = dict(data)
    kind = data.pop("kind", None)
    if kind not in _KINDS:
        raise ConfigError(f"target kind must be one of {', '.join(_KINDS)}, got {kind!r}")
    if kind == "waypoints":
        data["points_xy"] = tuple(tuple(p) for p in data.pop("points", data.pop("points_xy", ())))
    if kind == "moving" and "velocity" in data:
        data["velocity"] = tuple(data["velocity"])
    try:
        return _KINDS[kind](**data)
    except TypeError as exc:
        raise ConfigError(f"bad {kind} target fields: {exc}") from None


class TargetParams(NamedTuple):
    """A target as a world reads it (leaves may carry a leading batch axis).

    Attributes
    ----------
    points : Array (P, 2)
        Waypoints, lab frame (``a``); one for a fixed or moving target.
    velocity : Array (2,)
        The target's velocity (``a`` per step).
    radius : Array ()
        Success radius (``a``).
    budget : Array () int32
        Steps per episode.
    heading : Array ()
        The swimmer's start heading (rad, from the lab's +x; ``start_heading`` of the spec).
    """

    points: Array
    velocity: Array
    radius: Array
    budget: Array
    heading: Array


def flow_budget(still: int, least_time: float | None) -> int:
    """The budget rule in a moving flow, one for the worlds and the studies: the still-fluid
    budget ``still`` (steps), raised to `FLOW_BUDGET_FACTOR` times ``least_time`` (steps, a
    point swimmer's time to the target through the flow) where that is larger; ``least_time``
    ``None`` (no time known: the target unreachable for a point) keeps ``still``.

    The navigation study ([`with_budgets`][jswim.studies.kinds.navigate.with_budgets]) passes
    Zermelo's least time; a world made in Python passes `course_time`, which is never below it
    (Zermelo lives above the worlds). At most `MAX_BUDGET`.

    Raises
    ------
    ConfigError
        A budget past `MAX_BUDGET`.
    """
    n = still if least_time is None else max(still, math.ceil(FLOW_BUDGET_FACTOR * least_time))
    if n > MAX_BUDGET:
        raise ConfigError(
            f"the target needs {n:,} steps in this flow, more than a world counts (int32, "
            f"{MAX_BUDGET:,}); bring it closer or give it a budget"
        )
    return n


def _leg_time(
    start: np.ndarray, end: np.ndarray, radius: float, flow: Any, speed: float
) -> float | None:
    """Steps along the straight segment from ``start`` toward ``end``, up to ``radius`` short of
    it, at the crab heading (None where the flow somewhere on it is too fast across or against
    it for ``speed`` to hold the line)."""
    span = end - start
    full = float(np.hypot(*span))
    if full <= radius:
        return 0.0
    d = span / full
    length = full - radius
    frac = (np.arange(COURSE_POINTS) + 0.5) / COURSE_POINTS
    u = np.asarray(flow.velocity(start + (frac * length)[:, None] * d), np.float64)
    along = u @ d
    cross = d[0] * u[:, 1] - d[1] * u[:, 0]
    disc = speed**2 - cross**2
    ground = along + np.sqrt(np.maximum(disc, 0.0))
    if np.any(disc <= 0) or np.any(ground <= 0):
        return None
    return float(np.mean(1.0 / ground) * length)


def course_time(spec: Target, flow: Any, speed: float | None = None) -> float | None:
    """Steps a point swimmer of speed ``speed`` (``a / tau``, default the square gait's
    `jswim.env.flows.SWIM_SPEED`; one step lasts one ``tau``) takes to ``spec`` through ``flow``
    on straight lines at the crab heading (Zermelo's heading in a locally uniform flow) until it
    is within the success radius: from the start through the waypoints in order (each leg from
    the previous waypoint); for a moving target, to where it is met (iterated).

    For a fixed or moving target a path a point can follow, so never shorter than Zermelo's least
    time ([`jswim.agents.zermelo`][jswim.agents.zermelo]), which it equals in still fluid
    (``(distance - radius) / speed``). A cheap estimate the worlds can make (midpoint rule,
    `COURSE_POINTS` per leg, float64): `flow_budget`'s least time for a world made in Python.

    Returns
    -------
    float or None
        Steps; None where the flow on a leg is too fast for the line to be held (a cross or head
        flow faster than the swimmer), or a moving target that is not met.
    """
    v = SWIM_SPEED if speed is None else float(speed)
    pts = [np.asarray(p, np.float64) for p in spec.points()]
    start = np.zeros(2)
    if spec.kind == "moving":
        vel = np.asarray(spec.velocity, np.float64)
        t = 0.0
        for _ in range(50):  # fixed point of t = time(p + vel t): contracts for |vel| < v
            nxt = _leg_time(start, pts[0] + vel * t, spec.radius, flow, v)
            if nxt is None or nxt > MAX_BUDGET:
                return None
            if abs(nxt - t) < 1e-9 * max(1.0, nxt):
                return nxt
            t = nxt
        return t
    total = 0.0
    for p in pts:
        leg = _leg_time(start, p, spec.radius, flow, v)
        if leg is None:
            return None
        total, start = total + leg, p
    return total


def budget_source(spec: Target, model: Any, roc_levels: int = 2, flow: Any = None) -> str:
    """Which rule gave ``spec``'s budget in a world with ``flow``, in words (the repr of a
    navigation world says it): the spec's own, the steering controller's still-fluid estimate,
    or `flow_budget` with `course_time`."""
    if spec.budget is not None:
        return "the target's own"
    if flow is None or not flow.speed > 0:
        return "the steering controller's still-fluid estimate"
    t = course_time(spec, flow)
    if t is None:
        return (
            "the steering controller's still-fluid estimate: the flow is too fast for a straight "
            "course (give the target a budget)"
        )
    still = default_budget(spec, model, roc_levels)
    if flow_budget(still, t) == still:
        return (
            f"the steering controller's still-fluid estimate, above {FLOW_BUDGET_FACTOR} x "
            f"{t:.1f} steps of the straight course through the flow"
        )
    return f"{FLOW_BUDGET_FACTOR} x {t:.1f} steps of the straight course through the flow"


def default_budget(spec: Target, model: Any, roc_levels: int = 2, flow: Any = None) -> int:
    """Steps the steering controller is given for ``spec`` (``spec.budget`` when set).

    From the controller's measured physics ([`jswim.env.loops.steering_budget`][jswim.env.loops.steering_budget],
    safety `BUDGET_SAFETY`): cycles to turn through the
    bearing at the quarter loop's rotation per cycle plus cycles to cover the distance at the
    square gait's displacement per cycle. Waypoints add one such leg per waypoint (the turn
    measured from the previous leg's direction). A moving target's is the fixed one for the
    point where a swimmer going straight at the square gait's mean speed ``v_gait`` would meet
    it, stretched by ``1 / (1 - |v| / v_gait)`` for the corrections a moving bearing asks for.

    In a flow that moves (``flow.speed > 0``) the budget follows `flow_budget`: at least
    `FLOW_BUDGET_FACTOR` times `course_time`, the straight crab course's steps through it.

    Parameters
    ----------
    spec : FixedTarget, Waypoints or MovingTarget
        The task.
    model : SwimmerModel
        The swimmer.
    roc_levels : int
        K of its lattice (an odd K is measured on K = 2: the quarter loops need a centre).
    flow : Flow, optional
        The world's background flow ([`jswim.env.flows`][jswim.env.flows]); None: still fluid.

    Returns
    -------
    int
        Steps, whole cycles of four (at most `MAX_BUDGET`); in a flow, whole steps.

    Raises
    ------
    ConfigError
        No budget given for a swimmer without the controller (not a two-DOF planar swimmer),
        a moving target at least as fast as the square gait, or a budget past `MAX_BUDGET`.
    """
    if spec.budget is not None:
        return spec.budget
    n = _measured_budget(spec, model, roc_levels)
    if n > MAX_BUDGET:
        raise ConfigError(
            f"the target needs {n:,} steps, more than a world counts (int32, {MAX_BUDGET:,}); "
            "bring it closer"
        )
    if flow is not None and flow.speed > 0:
        return flow_budget(n, course_time(spec, flow))
    return n


def _measured_budget(spec: Target, model: Any, roc_levels: int) -> int:
    """`default_budget` of a spec without its own budget (unbounded)."""
    from jswim.env.loops import loop_motion, steering_budget  # lazy: loads the lattice tables

    if not (model.planar and model.n_dof == 2):
        raise ConfigError(
            f"give the target a budget: the default is measured for the steering controller, "
            f"which steers two-DOF planar swimmers, not {model.label}"
        )
    k = 2 if roc_levels % 2 else roc_levels

    def leg(distance: float, bearing: float) -> int:
        return steering_budget(model, distance, bearing, k, safety=BUDGET_SAFETY)

    pts = spec.points()
    nose = math.radians(spec.start_heading)  # every turn is measured from the swimmer's heading
    if spec.kind == "waypoints":
        total, start, heading = 0, (0.0, 0.0), nose
        for p in pts:
            dx, dy = p[0] - start[0], p[1] - start[1]
            direction = math.atan2(dy, dx)
            total += leg(math.hypot(dx, dy), direction - heading)
            start, heading = p, direction
        return total
    speed = math.hypot(*spec.velocity)
    if speed == 0:
        return leg(math.hypot(*pts[0]), math.atan2(pts[0][1], pts[0][0]) - nose)
    gait = loop_motion(model, k, square_gait(k))
    v_gait = gait.displacement / gait.steps
    if speed >= v_gait:
        raise ConfigError(
            f"the target moves at {speed:.3g} a per step, not slower than the square gait's "
            f"{v_gait:.3g}: give it a budget"
        )
    # where a swimmer at the gait's speed on a straight line meets it: |p + v t| = v_gait t
    p, v = np.asarray(pts[0]), np.asarray(spec.velocity)
    a, b, c = v @ v - v_gait**2, 2 * p @ v, p @ p
    t = (-b - math.sqrt(b * b - 4 * a * c)) / (2 * a)
    meet = p + v * t
    return math.ceil(
        leg(math.hypot(*meet), math.atan2(meet[1], meet[0]) - nose) / (1 - speed / v_gait)
    )


def target_params(
    spec: Target, model: Any, roc_levels: int = 2, dtype: Any = None, flow: Any = None
) -> TargetParams:
    """The arrays of ``spec`` for ``model`` (budget: [`default_budget`][jswim.env.targets.default_budget]).

    Parameters
    ----------
    spec : FixedTarget, Waypoints or MovingTarget
        The task.
    model : SwimmerModel
        The swimmer the budget is measured for.
    roc_levels : int
        K of the lattice the world steps on (the controller's budget is measured there).
    dtype : dtype, optional
        Of the float leaves; default JAX's default float (float32 unless x64 is on).
    flow : Flow, optional
        The world's background flow (its budget: `default_budget`); None: still fluid.

    Returns
    -------
    TargetParams
        ``points`` (P, 2), ``velocity`` (2,), ``radius`` () and ``heading`` () in ``dtype``,
        ``budget`` () int32.

    Raises
    ------
    ConfigError
        As `default_budget`.
    """
    dtype = jnp.result_type(float) if dtype is None else dtype
    return TargetParams(
        points=jnp.asarray(spec.points(), dtype),
        velocity=jnp.asarray(spec.velocity, dtype),
        radius=jnp.asarray(spec.radius, dtype),
        budget=jnp.asarray(default_budget(spec, model, roc_levels, flow), jnp.int32),
        heading=jnp.asarray(math.radians(spec.start_heading), dtype),
    )
