"""Background flows in the plane: what the fluid does where the swimmer is not.

Each flow is a static, hashable dataclass (a world can hold it as a static field and JAX can take
it as a static argument) whose ``velocity(x)``, ``gradient(x)`` and ``hessian(x)`` are plain JAX
functions of the position, so they jit and vmap with the step that calls them. Positions are in
link lengths ``a`` (the paper's unit), velocities in ``a / tau`` (``tau``: a hinge sweeping its
range at |ROC| = 1); for scale, the paper's square stroke moves Purcell's swimmer 0.191 a per
cycle of four steps, 0.048 a per step (docs/physics.md gives flow speeds as multiples of it).

The flows are steady solutions of the Stokes equations in the plane (the Taylor-Green cells with a
body force that keeps them steady); the swimmer is taken not to disturb them beyond its own drag
(resistive force theory: each link element feels the flow at its own position,
`jswim.swimmers.flow_response`).
"""

from __future__ import annotations

import dataclasses
import json
import math
from typing import Any

import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.errors import ConfigError
from jswim.reals import is_real

__all__ = [
    "FLOWS",
    "FLOW_LENGTH",
    "MAX_FLOW_LENGTH",
    "MAX_FLOW_RATE",
    "MAX_FLOW_SPEED",
    "MIN_FLOW_LENGTH",
    "SWIM_SPEED",
    "Flow",
    "Poiseuille",
    "Shear",
    "TaylorGreen",
    "Uniform",
    "flow_from_dict",
    "flow_json",
    "study_flow",
]

#: The swimming speed ``v`` flows are measured against (``a / tau``): the paper's square stroke
#: moves Purcell's swimmer 0.19124724 a per cycle of four steps (the exact tables;
#: tests/physics check it), whichever way it is played.
SWIM_SPEED = 0.19124724 / 4

#: The length (``a``) a study's flows vary over: the default target distance. A shear reaches
#: ``fraction * SWIM_SPEED`` this far across, a Poiseuille channel is twice it wide each side,
#: a Taylor-Green cell twice it square (`study_flow`).
FLOW_LENGTH = 3.0


# The ranges a flow's numbers are taken in: each flow refuses a number outside them with a
# `ConfigError` naming the range (docs/physics.md, "Background flows", "Ranges"). They keep every
# step's arithmetic finite, in float64 and in the default float32, through the tables and the
# RK4 reference, far beyond the study's flows (at most 2 v, gradients up to 0.05 a step).

#: Largest flow speed (``a / tau``): ``|u|`` of `Uniform`, ``|u_max|``, ``|u0|``; 1000 times the
#: swimming speed, 47.8 a a step. The swimmer's own step is then a thousandth of its drift, about
#: what a float32 position resolves within the targets' range (`jswim.env.targets.MAX_DISTANCE`,
#: 1e4 a: ~1e-3 a); faster, it is a tracer whose stroke the numbers no longer see.
#: ``Uniform((1e300, 0))`` was inf in float32, then NaN.
MAX_FLOW_SPEED = 1000.0 * SWIM_SPEED

#: Largest velocity gradient (``1 / tau``): ``|rate|`` of `Shear` and `Flow.max_gradient` of every
#: flow, a radian of turn a step at most. Ten times the tables' range
#: (`jswim.env.params.MAX_TABLE_GRADIENT`, which warns): a table step's turn is still a rotation
#: (`jswim.env.flow_steps.small_sincos` is exact to 1e-16 below a radian; a few radians turn into
#: growth, then NaN: a shear of 10 a step was NaN within 400 steps); the RK4 reference turns
#: 1/16 rad a piece, and Zermelo's steerer takes at most 20 RK4 steps a step
#: (`jswim.agents.zermelo.STEP_RATE`).
MAX_FLOW_RATE = 1.0

#: Smallest ``half_width`` and ``cell`` (``a``): a link. Narrower, a channel cannot hold the
#: three-link body, and a Taylor-Green cell outruns the wave tables' harmonics (``J_n(K L)``,
#: ``K = sqrt(2) pi / cell``, at the body's reach ``L ~ 1.5 a`` falls below their cutoff by
#: ``n ~ 17`` of the 31 kept at a cell of 1 a, by ``n ~ 27`` at 0.5 a). At 1e-300 a, ``h^2``
#: was 0: a division by zero.
MIN_FLOW_LENGTH = 1.0

#: Largest ``half_width`` and ``cell`` (``a``): 100 times the farthest target. A wider channel is
#: uniform to 1e-4 over any task, a wider cell's gradient below 1.5e-4 a step; ``1 / h^2`` stays
#: a normal float32 (``h^2`` overflowed at 1e300).
MAX_FLOW_LENGTH = 1.0e6


def _shown(value: Any) -> str:
    """``repr(value)``, shortened (an int of 400 digits is one line, not a screenful)."""
    text = repr(value)
    return text if len(text) <= 40 else f"{text[:24]}... ({len(text)} characters)"


def _finite(
    value: Any, name: str, low: float = -math.inf, high: float = math.inf, unit: str = ""
) -> float:
    """``value`` as a float: a real number (`jswim.reals.is_real`), finite, in ``low..high``
    (the message names the range, ``unit`` after it)."""
    if not is_real(value):
        raise ConfigError(f"flow {name} must be a number, got {_shown(value)}")
    try:
        v = float(value)
    except (OverflowError, ValueError):  # an int past float's range (10**400)
        v = math.nan
    if not (math.isfinite(v) and low <= v <= high):
        within = "" if math.isinf(low) and math.isinf(high) else f" within {low:.4g}..{high:.4g}"
        raise ConfigError(f"flow {name} must be a finite number{within}{unit}, got {_shown(value)}")
    return v


def _speed(value: Any, name: str) -> float:
    return _finite(
        value,
        name,
        -MAX_FLOW_SPEED,
        MAX_FLOW_SPEED,
        " a per step (1000 times the swimming speed: MAX_FLOW_SPEED)",
    )


def _rate(value: Any, name: str) -> float:
    unit = " per step (MAX_FLOW_RATE: a radian of turn a step)"
    return _finite(value, name, -MAX_FLOW_RATE, MAX_FLOW_RATE, unit)


def _length(value: Any, name: str) -> float:
    unit = " a (MIN_FLOW_LENGTH..MAX_FLOW_LENGTH: a link to a million)"
    return _finite(value, name, MIN_FLOW_LENGTH, MAX_FLOW_LENGTH, unit)


def _gradient(flow: Flow, formula: str) -> None:
    """Refuse a flow whose largest gradient passes `MAX_FLOW_RATE`."""
    if flow.max_gradient > MAX_FLOW_RATE:
        raise ConfigError(
            f"{flow!r} has a velocity gradient {formula} = {flow.max_gradient:.4g} per step; it "
            f"must be at most {MAX_FLOW_RATE:g} (MAX_FLOW_RATE: a radian of turn a step)"
        )


class Flow:
    """What every flow offers: ``velocity`` (..., 2), ``gradient`` (..., 2, 2;
    ``[..., i, j] = du_i / dx_j``, ``1 / tau``) and ``hessian`` (..., 2, 2, 2;
    ``[..., i, j, k] = d^2 u_i / dx_j dx_k``, ``1 / (a tau)``) at positions (..., 2), the largest
    speed it reaches (``speed``, ``a / tau``) and ``to_dict``."""

    kind = ""

    def velocity(self, x: Array) -> Array:  # pragma: no cover - each flow defines it
        raise NotImplementedError

    def gradient(self, x: Array) -> Array:  # pragma: no cover - each flow defines it
        raise NotImplementedError

    def hessian(self, x: Array) -> Array:  # pragma: no cover - each flow defines it
        raise NotImplementedError

    @property
    def speed(self) -> float:  # pragma: no cover - each flow defines it
        raise NotImplementedError

    @property
    def max_gradient(self) -> float:  # pragma: no cover - each flow defines it
        """The largest entry of the velocity gradient a swimmer meets (``1 / tau``): how fast the
        flow turns and strains a body (Poiseuille: at the channel's walls)."""
        raise NotImplementedError

    def to_dict(self) -> dict[str, Any]:
        """The flow as plain JSON values (``kind`` first); `flow_from_dict` reads it."""
        return {"kind": self.kind, **dataclasses.asdict(self)}


@dataclasses.dataclass(frozen=True)
class Uniform(Flow):
    """A uniform stream ``u = (ux, uy)`` (``a / tau``).

    Raises
    ------
    ConfigError
        ``u`` not two finite numbers, or faster than `MAX_FLOW_SPEED`.
    """

    u: tuple[float, float] = (0.0, 0.0)
    kind = "uniform"

    def __post_init__(self) -> None:
        u = self.u
        if getattr(u, "shape", None) == (2,):  # a NumPy or JAX vector
            u = list(np.asarray(u))
        if not isinstance(u, (tuple, list)) or len(u) != 2:
            raise ConfigError(f"Uniform flow u must be (ux, uy), got {_shown(self.u)}")
        u = tuple(_speed(c, "u") for c in u)
        if math.hypot(*u) > MAX_FLOW_SPEED:
            raise ConfigError(
                f"flow u must have a speed |u| of at most {MAX_FLOW_SPEED:.4g} a per step (1000 "
                f"times the swimming speed: MAX_FLOW_SPEED), got {_shown(self.u)}"
            )
        object.__setattr__(self, "u", u)

    def velocity(self, x: Array) -> Array:
        x = jnp.asarray(x)
        return jnp.broadcast_to(jnp.asarray(self.u, x.dtype), x.shape)

    def gradient(self, x: Array) -> Array:
        x = jnp.asarray(x)
        return jnp.zeros(x.shape + (2,), x.dtype)

    def hessian(self, x: Array) -> Array:
        x = jnp.asarray(x)
        return jnp.zeros(x.shape + (2, 2), x.dtype)

    @property
    def speed(self) -> float:
        return math.hypot(*self.u)

    @property
    def max_gradient(self) -> float:
        return 0.0


@dataclasses.dataclass(frozen=True)
class Shear(Flow):
    """Simple shear ``u = (rate y, 0)``: vorticity ``-rate``, strain rate ``rate / 2``.

    ``speed`` is that at ``|y| = 1`` (the flow has no largest speed).

    Raises
    ------
    ConfigError
        ``rate`` not a finite number within ``+-MAX_FLOW_RATE``.
    """

    rate: float = 0.0
    kind = "shear"

    def __post_init__(self) -> None:
        object.__setattr__(self, "rate", _rate(self.rate, "rate"))

    def velocity(self, x: Array) -> Array:
        x = jnp.asarray(x)
        return jnp.stack([self.rate * x[..., 1], jnp.zeros_like(x[..., 0])], axis=-1)

    def gradient(self, x: Array) -> Array:
        x = jnp.asarray(x)
        g = jnp.asarray([[0.0, self.rate], [0.0, 0.0]], x.dtype)
        return jnp.broadcast_to(g, x.shape + (2,))

    def hessian(self, x: Array) -> Array:
        x = jnp.asarray(x)
        return jnp.zeros(x.shape + (2, 2), x.dtype)  # linear in position

    @property
    def speed(self) -> float:
        return abs(self.rate)

    @property
    def max_gradient(self) -> float:
        return abs(self.rate)


@dataclasses.dataclass(frozen=True)
class Poiseuille(Flow):
    """Plane Poiseuille flow in a channel along x with walls at ``y = +-half_width``:
    ``u = (u_max (1 - y^2 / half_width^2), 0)``. Outside the channel the formula goes on (the
    walls themselves are not modelled: a swimmer near them feels no wall).

    Raises
    ------
    ConfigError
        ``u_max`` not a finite number within ``+-MAX_FLOW_SPEED``, ``half_width`` not one in
        ``MIN_FLOW_LENGTH..MAX_FLOW_LENGTH``, or a wall shear ``2 |u_max| / half_width`` past
        `MAX_FLOW_RATE`.
    """

    u_max: float = 0.0
    half_width: float = 1.0
    kind = "poiseuille"

    def __post_init__(self) -> None:
        object.__setattr__(self, "u_max", _speed(self.u_max, "u_max"))
        object.__setattr__(self, "half_width", _length(self.half_width, "half_width"))
        _gradient(self, "2 |u_max| / half_width")

    def velocity(self, x: Array) -> Array:
        x = jnp.asarray(x)
        y = x[..., 1] / self.half_width
        return jnp.stack([self.u_max * (1.0 - y * y), jnp.zeros_like(y)], axis=-1)

    def gradient(self, x: Array) -> Array:
        x = jnp.asarray(x)
        dudy = -2.0 * self.u_max * x[..., 1] / self.half_width**2
        zero = jnp.zeros_like(dudy)
        return jnp.stack(
            [jnp.stack([zero, dudy], axis=-1), jnp.stack([zero, zero], axis=-1)], axis=-2
        )

    def hessian(self, x: Array) -> Array:
        x = jnp.asarray(x)
        # quadratic in y: the one entry d^2 u_x / dy^2 = -2 u_max / h^2, the same everywhere
        h = jnp.zeros((2, 2, 2), x.dtype).at[0, 1, 1].set(-2.0 * self.u_max / self.half_width**2)
        return jnp.broadcast_to(h, x.shape[:-1] + (2, 2, 2))

    @property
    def speed(self) -> float:
        return abs(self.u_max)

    @property
    def max_gradient(self) -> float:
        return 2.0 * abs(self.u_max) / self.half_width


@dataclasses.dataclass(frozen=True)
class TaylorGreen(Flow):
    """A periodic lattice of counter-rotating vortices, each ``cell`` (``a``) square:
    stream function ``psi = (u0 / k) sin(k x) sin(k y)``, ``k = pi / cell``, so
    ``u = u0 (sin kx cos ky, -cos kx sin ky)``; the largest speed is ``u0``, on the cells' edges.

    Raises
    ------
    ConfigError
        ``u0`` not a finite number within ``+-MAX_FLOW_SPEED``, ``cell`` not one in
        ``MIN_FLOW_LENGTH..MAX_FLOW_LENGTH``, or a gradient ``pi |u0| / cell`` past
        `MAX_FLOW_RATE`.
    """

    u0: float = 0.0
    cell: float = 10.0
    kind = "taylor-green"

    def __post_init__(self) -> None:
        object.__setattr__(self, "u0", _speed(self.u0, "u0"))
        object.__setattr__(self, "cell", _length(self.cell, "cell"))
        _gradient(self, "pi |u0| / cell")

    @property
    def k(self) -> float:
        return math.pi / self.cell

    def stream(self, x: Array) -> Array:
        """The stream function ``psi`` (``a^2 / tau``) at positions (..., 2)."""
        x = jnp.asarray(x)
        k = self.k
        return self.u0 / k * jnp.sin(k * x[..., 0]) * jnp.sin(k * x[..., 1])

    def velocity(self, x: Array) -> Array:
        x = jnp.asarray(x)
        k = self.k
        sx, cx = jnp.sin(k * x[..., 0]), jnp.cos(k * x[..., 0])
        sy, cy = jnp.sin(k * x[..., 1]), jnp.cos(k * x[..., 1])
        return self.u0 * jnp.stack([sx * cy, -cx * sy], axis=-1)

    def gradient(self, x: Array) -> Array:
        x = jnp.asarray(x)
        k = self.k
        sx, cx = jnp.sin(k * x[..., 0]), jnp.cos(k * x[..., 0])
        sy, cy = jnp.sin(k * x[..., 1]), jnp.cos(k * x[..., 1])
        a = self.u0 * k
        return a * jnp.stack(
            [jnp.stack([cx * cy, -sx * sy], axis=-1), jnp.stack([sx * sy, -cx * cy], axis=-1)],
            axis=-2,
        )

    def hessian(self, x: Array) -> Array:
        x = jnp.asarray(x)
        k = self.k
        sx, cx = jnp.sin(k * x[..., 0]), jnp.cos(k * x[..., 0])
        sy, cy = jnp.sin(k * x[..., 1]), jnp.cos(k * x[..., 1])
        a = self.u0 * k * k
        p, q = sx * cy, cx * sy  # u = u0 (p, -q); each second derivative is -k^2 of p or q

        def sym(diag: Array, off: Array) -> Array:
            return jnp.stack(
                [jnp.stack([diag, off], axis=-1), jnp.stack([off, diag], axis=-1)], axis=-2
            )

        return a * jnp.stack([-sym(p, q), sym(q, p)], axis=-3)

    @property
    def speed(self) -> float:
        return abs(self.u0)

    @property
    def max_gradient(self) -> float:
        return abs(self.u0) * math.pi / self.cell


#: Every flow by its ``kind``.
FLOWS = {f.kind: f for f in (Uniform, Shear, Poiseuille, TaylorGreen)}


def study_flow(kind: str, fraction: float, length: float = FLOW_LENGTH) -> Flow:
    """The flow of kind ``kind`` whose speed is ``fraction`` of `SWIM_SPEED` (a study's
    ``--flow KIND --flows F,...``), laid out on the scale ``length`` (``a``) of its targets.

    * ``uniform``: a stream across the swimmer's start heading, ``u = (0, f v)``;
    * ``shear``: ``u = (rate y, 0)`` with ``rate = f v / length`` (``f v`` at ``|y| = length``);
    * ``poiseuille``: ``u_max = f v`` on the centre line ``y = 0`` (the start), walls at
      ``y = +-2 length``;
    * ``taylor-green``: ``u0 = f v``, cells ``2 length`` square; the start ``(0, 0)`` is a
      stagnation point between four cells.

    Raises
    ------
    ConfigError
        An unknown kind, a fraction or length that is not a finite number (fraction >= 0,
        length > 0), or a flow outside the flows' ranges (`MAX_FLOW_SPEED`, `MAX_FLOW_RATE`,
        `MIN_FLOW_LENGTH`, `MAX_FLOW_LENGTH`).
    """
    if not isinstance(kind, str) or kind not in FLOWS:
        raise ConfigError(f"flow kind must be one of {', '.join(FLOWS)}, got {_shown(kind)}")
    f = _finite(fraction, "fraction")
    length = _finite(length, "length")
    if f < 0:
        raise ConfigError(f"flow fraction must be >= 0, got {_shown(fraction)}")
    if not length > 0:
        raise ConfigError(f"flow length must be > 0, got {_shown(length)}")
    speed = f * SWIM_SPEED
    try:
        if kind == "uniform":
            return Uniform((0.0, speed))
        if kind == "shear":
            return Shear(speed / length)
        if kind == "poiseuille":
            return Poiseuille(speed, 2 * length)
        return TaylorGreen(speed, 2 * length)
    except ConfigError as exc:  # say which of the caller's numbers made it
        raise ConfigError(f"{kind} flow at {f:g} v on {length:g} a: {exc}") from None


def flow_json(flow: Flow | None) -> str:
    """A flow as canonical JSON (a plan's and a row's ``flow``); ``""`` for still fluid."""
    return "" if flow is None else json.dumps(flow.to_dict(), sort_keys=True)


def flow_from_dict(data: dict[str, Any]) -> Flow:
    """A flow from its ``to_dict``: ``kind`` and every field of that kind, nothing else (a
    record that lacks one was not written by ``to_dict``, and a default would silently be still
    fluid), each checked as the flow's constructor checks it.

    Raises
    ------
    ConfigError
        Not a mapping, a missing, unknown or extra field, an unknown kind, or a field's value
        the flow refuses; one line naming the field.
    """
    if not isinstance(data, dict):
        raise ConfigError(f"a flow must be a mapping with its kind and fields, got {_shown(data)}")
    if "kind" not in data:
        raise ConfigError(f"flow field 'kind' is missing (one of {', '.join(FLOWS)})")
    kind = data["kind"]
    if not isinstance(kind, str) or kind not in FLOWS:
        raise ConfigError(f"flow kind must be one of {', '.join(FLOWS)}, got {_shown(kind)}")
    cls = FLOWS[kind]
    names = [f.name for f in dataclasses.fields(cls)]
    fields = ", ".join(names)
    extra = [k for k in data if k != "kind" and k not in names]
    if extra:
        raise ConfigError(f"{kind} flow has no field {_shown(extra[0])} (its fields: {fields})")
    missing = [n for n in names if n not in data]
    if missing:
        raise ConfigError(f"{kind} flow field {missing[0]!r} is missing (its fields: {fields})")
    return cls(**{n: data[n] for n in names})  # the constructor checks each value, by name
