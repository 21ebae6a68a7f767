"""Navigation targets: hashable specs of where a swimmer is sent, and the arrays a world reads.

Three kinds, each with a success radius and a step budget (``a``: the swimmer's length unit,
link lengths for Purcell's swimmer; angles in degrees, counterclockwise positive, from the
start heading, which is the lab's +x: the paper's swimmer starts with its middle link along
+x and its square gait swims that way):

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
"""

from __future__ import annotations

import dataclasses
import math
import numbers
from typing import Any, NamedTuple

import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.errors import MAX_COUNT, ConfigError
from jswim.swimmers.turning import square_gait

__all__ = [
    "BUDGET_SAFETY",
    "DEFAULT_RADIUS",
    "FixedTarget",
    "MovingTarget",
    "Target",
    "TargetParams",
    "Waypoints",
    "default_budget",
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

    Raises
    ------
    ConfigError
        A distance not above the radius, a bad radius or budget.
    """

    distance: float
    bearing: float = 0.0
    radius: float = DEFAULT_RADIUS
    budget: int | None = None

    kind = "fixed"

    def __post_init__(self) -> None:
        r, b = _check_common(self.radius, self.budget)
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
        return {"kind": self.kind, **dataclasses.asdict(self)}


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

    Raises
    ------
    ConfigError
        No points, a point that is not two finite numbers, the first point within the radius of
        the start, a bad radius or budget.
    """

    points_xy: tuple[tuple[float, float], ...]
    radius: float = DEFAULT_RADIUS
    budget: int | None = None

    kind = "waypoints"

    def __post_init__(self) -> None:
        r, b = _check_common(self.radius, self.budget)
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
        return {
            "kind": self.kind,
            "points": [list(p) for p in self.points_xy],
            "radius": self.radius,
            "budget": self.budget,
        }


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

    kind = "moving"

    def __post_init__(self) -> None:
        r, b = _check_common(self.radius, self.budget)
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
        return out


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
    """

    points: Array
    velocity: Array
    radius: Array
    budget: Array


def default_budget(spec: Target, model: Any, roc_levels: int = 2) -> int:
    """Steps the steering controller is given for ``spec`` (``spec.budget`` when set).

    From the controller's measured physics ([`jswim.env.loops.steering_budget`][jswim.env.loops.steering_budget],
    safety `BUDGET_SAFETY`): cycles to turn through the
    bearing at the quarter loop's rotation per cycle plus cycles to cover the distance at the
    square gait's displacement per cycle. Waypoints add one such leg per waypoint (the turn
    measured from the previous leg's direction). A moving target's is the fixed one for the
    point where a swimmer going straight at the square gait's mean speed ``v_gait`` would meet
    it, stretched by ``1 / (1 - |v| / v_gait)`` for the corrections a moving bearing asks for.

    Parameters
    ----------
    spec : FixedTarget, Waypoints or MovingTarget
        The task.
    model : SwimmerModel
        The swimmer.
    roc_levels : int
        K of its lattice (an odd K is measured on K = 2: the quarter loops need a centre).

    Returns
    -------
    int
        Steps, whole cycles of four (at most `MAX_BUDGET`).

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
    if spec.kind == "waypoints":
        total, start, heading = 0, (0.0, 0.0), 0.0
        for p in pts:
            dx, dy = p[0] - start[0], p[1] - start[1]
            direction = math.atan2(dy, dx)
            total += leg(math.hypot(dx, dy), direction - heading)
            start, heading = p, direction
        return total
    speed = math.hypot(*spec.velocity)
    if speed == 0:
        return leg(math.hypot(*pts[0]), math.atan2(pts[0][1], pts[0][0]))
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
    return math.ceil(leg(math.hypot(*meet), math.atan2(meet[1], meet[0])) / (1 - speed / v_gait))


def target_params(spec: Target, model: Any, roc_levels: int = 2, dtype: Any = None) -> TargetParams:
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

    Returns
    -------
    TargetParams
        ``points`` (P, 2), ``velocity`` (2,), ``radius`` () in ``dtype``, ``budget`` () int32.

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
        budget=jnp.asarray(default_budget(spec, model, roc_levels), jnp.int32),
    )
