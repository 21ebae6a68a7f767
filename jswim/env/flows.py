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


def _finite(value: Any, name: str, positive: bool = False) -> float:
    if not is_real(value):
        raise ConfigError(f"flow {name} must be a number, got {value!r}")
    v = float(value)
    if not math.isfinite(v) or (positive and not v > 0):
        raise ConfigError(
            f"flow {name} must be a finite{' positive' if positive else ''} number, got {value!r}"
        )
    return v


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
        ``u`` not two finite numbers.
    """

    u: tuple[float, float] = (0.0, 0.0)
    kind = "uniform"

    def __post_init__(self) -> None:
        u = self.u
        if getattr(u, "shape", None) == (2,):  # a NumPy or JAX vector
            u = list(np.asarray(u))
        if not isinstance(u, (tuple, list)) or len(u) != 2:
            raise ConfigError(f"Uniform flow u must be (ux, uy), got {self.u!r}")
        object.__setattr__(self, "u", tuple(_finite(c, "u") for c in u))

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
        ``rate`` not a finite number.
    """

    rate: float = 0.0
    kind = "shear"

    def __post_init__(self) -> None:
        object.__setattr__(self, "rate", _finite(self.rate, "rate"))

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
        ``u_max`` not a finite number, ``half_width`` not a finite positive one.
    """

    u_max: float = 0.0
    half_width: float = 1.0
    kind = "poiseuille"

    def __post_init__(self) -> None:
        object.__setattr__(self, "u_max", _finite(self.u_max, "u_max"))
        object.__setattr__(self, "half_width", _finite(self.half_width, "half_width", True))

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
        ``u0`` not a finite number, ``cell`` not a finite positive one.
    """

    u0: float = 0.0
    cell: float = 10.0
    kind = "taylor-green"

    def __post_init__(self) -> None:
        object.__setattr__(self, "u0", _finite(self.u0, "u0"))
        object.__setattr__(self, "cell", _finite(self.cell, "cell", True))

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
        An unknown kind, or a fraction or length that is not a finite number (length > 0).
    """
    f = _finite(fraction, "fraction")
    length = _finite(length, "length", positive=True)
    if f < 0:
        raise ConfigError(f"flow fraction must be >= 0, got {fraction!r}")
    speed = f * SWIM_SPEED
    if kind == "uniform":
        return Uniform((0.0, speed))
    if kind == "shear":
        return Shear(speed / length)
    if kind == "poiseuille":
        return Poiseuille(speed, 2 * length)
    if kind == "taylor-green":
        return TaylorGreen(speed, 2 * length)
    raise ConfigError(f"flow kind must be one of {', '.join(FLOWS)}, got {kind!r}")


def flow_json(flow: Flow | None) -> str:
    """A flow as canonical JSON (a plan's and a row's ``flow``); ``""`` for still fluid."""
    return "" if flow is None else json.dumps(flow.to_dict(), sort_keys=True)


def flow_from_dict(data: dict[str, Any]) -> Flow:
    """A flow from its ``to_dict``.

    Raises
    ------
    ConfigError
        An unknown kind or a bad field.
    """
    data = dict(data)
    kind = data.pop("kind", None)
    if kind not in FLOWS:
        raise ConfigError(f"flow kind must be one of {', '.join(FLOWS)}, got {kind!r}")
    try:
        if kind == "uniform" and "u" in data:
            data["u"] = tuple(data["u"])
        return FLOWS[kind](**data)
    except TypeError as exc:
        raise ConfigError(f"bad {kind} flow fields: {exc}") from None
