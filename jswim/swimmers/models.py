"""Swimmer models: one hashable description per swimmer, shared by the env, prompt and plots.

A model gives the body-frame velocity of its reference point, ``(u, v, omega)`` at orientation 0,
for a shape ``d`` and shape rate ``d_dot``, and the offset of the geometric centroid from that
reference point. Everything else (stepping, tables, noise) is generic.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import jax.numpy as jnp
from jax import Array

from jswim.errors import ConfigError
from jswim.swimmers import ng, nlink, nsphere, purcell

#: Names accepted by [`make_model`][jswim.swimmers.models.make_model].
SWIMMERS = ("purcell", "ng", "nlink", "nsphere")


@dataclass(frozen=True)
class SwimmerModel:
    """Static description of a swimmer (hashable, so it can key caches and jit).

    Attributes
    ----------
    kind : str
        ``"purcell"`` (closed form), ``"nlink"`` (general RFT solve), ``"ng"`` (paper's formula)
        or ``"nsphere"`` (first-order Oseen model).
    n_dof : int
        Number of degrees of freedom (hinges or arms).
    lo, hi : float
        The two levels each DOF takes; one step sweeps ``[lo, hi]`` in ``hi - lo`` time units.
    xi_ratio : float
        ``xi_perp / xi_par`` of the link swimmers (ignored by the sphere swimmers).
    """

    kind: str
    n_dof: int
    lo: float
    hi: float
    xi_ratio: float = 2.0

    @property
    def planar(self) -> bool:
        """Whether the swimmer moves in the plane and rotates (link swimmers)."""
        return self.kind in ("purcell", "nlink")

    @property
    def duration(self) -> float:
        """Dimensionless duration of one step at ``|ROC| = 1``."""
        return self.hi - self.lo

    @property
    def label(self) -> str:
        """Human-readable name for tables and plots."""
        names = {
            "purcell": "Purcell three-link",
            "ng": "NG three-sphere",
            "nlink": f"{self.n_dof + 1}-link",
            "nsphere": f"{self.n_dof + 1}-sphere",
        }
        return names[self.kind]

    def body_velocity(self, d: Array, d_dot: Array) -> Array:
        """Reference-point velocity ``(u, v, omega)`` in the body frame."""
        if self.kind == "purcell":
            return purcell.velocity(d, d_dot, 0.0)
        if self.kind == "nlink":
            return nlink.velocity(d, d_dot, 0.0, self.xi_ratio)
        u = ng.velocity(d, d_dot) if self.kind == "ng" else nsphere.velocity(d, d_dot)
        zero = jnp.zeros_like(u)
        return jnp.stack([u, zero, zero])

    def centroid_offset(self, d: Array) -> Array:
        """Geometric centroid minus reference point, in the body frame."""
        if self.planar:
            return nlink.centroid_offset(d)
        return jnp.zeros((2,), jnp.result_type(d))


def make_model(
    swimmer: str,
    *,
    d_max: float | None = None,
    d_min: float | None = None,
    n_links: int | None = None,
    n_spheres: int | None = None,
    xi_ratio: float = 2.0,
) -> SwimmerModel:
    """Build and validate a swimmer model with the paper's defaults.

    Parameters
    ----------
    swimmer : str
        ``"purcell"``, ``"ng"``, ``"nlink"`` or ``"nsphere"``.
    d_max : float, optional
        Purcell/N-link: hinge limit, DOFs in ``[-d_max, d_max]`` (default pi/3; 2*pi/9 for
        N-link swimmers with N > 3), in ``(0, pi)``. NG/N-sphere: longest arm (default 10).
    d_min : float, optional
        NG/N-sphere only: shortest arm (default 6); must satisfy ``2 < d_min < d_max`` so spheres
        of unit radius do not overlap.
    n_links, n_spheres : int, optional
        Number of links (``"nlink"``, default 4) or spheres (``"nsphere"``, default 4), >= 2.
    xi_ratio : float
        ``xi_perp / xi_par`` of the link swimmers (default 2, the slender limit). The Purcell
        closed form only holds for 2, so another value switches to the general solve.
    """
    if not isinstance(swimmer, str) or swimmer.lower() not in SWIMMERS:
        raise ConfigError(f"unknown swimmer {swimmer!r}; choose one of {', '.join(SWIMMERS)}")
    kind = swimmer.lower()
    if kind in ("purcell", "nlink"):
        if d_min is not None:
            raise ConfigError("d_min applies to the sphere swimmers only; link swimmers use d_max")
        n = 3 if kind == "purcell" else (4 if n_links is None else n_links)
        if n_spheres is not None or (kind == "purcell" and n_links not in (None, 3)):
            raise ConfigError("purcell has 3 links; use swimmer='nlink' with n_links=N")
        _check_count("n_links", n)
        default = math.pi / 3 if n == 3 else 2 * math.pi / 9
        dm = default if d_max is None else _number("d_max", d_max)
        if not 0.0 < dm < math.pi:
            raise ConfigError(f"d_max must lie in (0, pi) for link swimmers, got {dm}")
        if not xi_ratio > 0:
            raise ConfigError(f"xi_ratio must be positive, got {xi_ratio}")
        if kind == "purcell" and xi_ratio != 2.0:
            kind = "nlink"  # the closed form is for xi_perp/xi_par = 2 only
        return SwimmerModel(kind, n - 1, -dm, dm, float(xi_ratio))
    n = 3 if kind == "ng" else (4 if n_spheres is None else n_spheres)
    if n_links is not None or (kind == "ng" and n_spheres not in (None, 3)):
        raise ConfigError("ng has 3 spheres; use swimmer='nsphere' with n_spheres=N")
    _check_count("n_spheres", n)
    lo = 6.0 if d_min is None else _number("d_min", d_min)
    hi = 10.0 if d_max is None else _number("d_max", d_max)
    if not lo < hi:
        raise ConfigError(f"d_min must be smaller than d_max, got d_min={lo}, d_max={hi}")
    if not lo > 2.0:
        raise ConfigError(
            f"d_min must exceed 2 (two sphere radii) so spheres do not overlap, got {lo}"
        )
    return SwimmerModel(kind, n - 1, lo, hi, float(xi_ratio))


def _number(name: str, value: object) -> float:
    try:
        out = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(out):
        raise ConfigError(f"{name} must be finite, got {value!r}")
    return out


def _check_count(name: str, n: object) -> None:
    if not isinstance(n, int) or isinstance(n, bool) or n < 2 or n > 12:
        raise ConfigError(f"{name} must be an integer between 2 and 12, got {n!r}")
