"""Local resistive force theory of Purcell's swimmer above a plane wall (``wall_model="local-rft"``).

Every link (length ``l = 1``, the unit of length; radius ``b``) lies in the plane z = h above a
no-slip wall at z = 0, with drag per unit length ``xi_T`` along it and ``xi_N`` across it. The
model is jswim's own construction, not one from the literature: the bulk coefficients (ratio 2)
with each link's logarithm lowered by the wall's image (Blake 1971) of a uniform force density
along that link alone, averaged over the link (written out here from Blake's tensor at equal
heights). With ``c = 2 h``, ``S = sqrt(l^2 + c^2)``::

    xi_T = 2 pi mu / (L - k_T(h)),   xi_N = 4 pi mu / (L - k_N(h)),   L = ln(l / b),
    k_T = asinh(l / c) - 2 l / (S + c) + l (2 S + c) / (4 S (S + c))
    k_N = asinh(l / c) - l / (2 (S + c))

Returned in units of the bulk ``xi_T = 2 pi mu / L``: ``(1, 2)`` as h -> infinity
([`jswim.swimmers.nlink`][jswim.swimmers.nlink], ``xi_ratio = 2``). Far away ``k_T -> 3 l / (16 h)`` and
``k_N -> 3 l / (8 h)``: a link's own image slowing it, as a point force's image slows a sphere
by ``(9/16) a / h`` (Lorentz 1907). Near the wall (b << h << l) ``L - k_T -> ln(h / b) + 3/2`` and
``L - k_N -> ln(h / b) + 1/2``, constants that come from the averaging. Only ``xi_N / xi_T``
changes the stroke.

Range, plainly: the corrections are O(1 / ln(l / b)), the order of the terms local RFT drops (the
other links' flows and their images), so the model is a guide for b << h below ~l, not a
prediction; above ~l the links left out matter as much as the effect computed, and its far-field
approach ``X - X_bulk ~ 0.0141 l^2 / h`` is an artefact of the locality: a force-free swimmer's
link images cancel at O(l / h) and the true effect decays faster (the non-local
[`jswim.swimmers.purcell_beads`][jswim.swimmers.purcell_beads], ``wall_model="beads"``). It keeps the swimmer's height and
plane by construction; the non-local model pitches. docs/scenes.md, "Purcell's swimmer near a
wall", gives both models' tables.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from jax import Array

from jswim.errors import ConfigError
from jswim.swimmers import nlink
from jswim.swimmers.models import SwimmerModel, make_model

#: Default link radius b in link lengths (a slender link: l / b = 100, ln(l / b) = 4.61).
LINK_RADIUS = 0.01

#: Heights must exceed this many link radii (b << h is the theory's range).
MIN_GAP = 2.0


def log_corrections(height: Any, length: float = 1.0, xp: Any = np) -> tuple[Any, Any]:
    """The wall's corrections ``(k_T, k_N)`` to the logarithms of the drag coefficients.

    Parameters
    ----------
    height : float or array
        Height h of the link's axis above the wall, in the units of ``length`` (> 0).
    length : float
        Link length l.
    xp : module
        ``numpy`` (default, float64) or ``jax.numpy``.

    Returns
    -------
    (k_T, k_N)
        Dimensionless, positive, decreasing in h; ``3 l / (16 h)`` and ``3 l / (8 h)`` far away.
    """
    c = 2.0 * xp.asarray(height)
    s = xp.sqrt(length * length + c * c)
    a = xp.arcsinh(length / c)
    k_t = a - 2.0 * length / (s + c) + length * (2.0 * s + c) / (4.0 * s * (s + c))
    k_n = a - length / (2.0 * (s + c))
    return k_t, k_n


def drag_coefficients(
    height: Any, link_radius: float = LINK_RADIUS, xp: Any = np
) -> tuple[Any, Any]:
    """``(xi_T, xi_N)`` of a link of unit length at ``height``, in units of the bulk ``xi_T``.

    ``(1, 2)`` (jswim's bulk) as ``height -> inf``; see the module docstring for the formulas,
    their sources and range. ``height`` and ``link_radius`` in link lengths.
    """
    big_l = math.log(1.0 / link_radius)
    k_t, k_n = log_corrections(height, 1.0, xp)
    return big_l / (big_l - k_t), 2.0 * big_l / (big_l - k_n)


@dataclasses.dataclass(frozen=True)
class WallPurcellModel(SwimmerModel):
    """Purcell's swimmer whose links have drag ``xi_par`` along and ``xi_perp`` across them.

    A [`SwimmerModel`][jswim.swimmers.models.SwimmerModel] of kind ``"purcell"`` (prompt, defaults and
    tables as the paper's swimmer), its velocities from the general resistive-force solve
    ([`jswim.swimmers.nlink.velocity`][jswim.swimmers.nlink.velocity]) with both coefficients as given; ``xi_ratio`` is their
    ratio. ``height`` and ``link_radius`` (link lengths) record where they came from
    ([`wall_model`][jswim.swimmers.wall_rft.wall_model]; ``inf``: not from a wall).
    """

    xi_par: float = 1.0
    xi_perp: float = 2.0
    height: float = math.inf
    link_radius: float = LINK_RADIUS

    def body_velocity(self, d: Array, d_dot: Array) -> Array:
        return nlink.velocity(d, d_dot, 0.0, self.xi_perp, xi_par=self.xi_par)


def wall_model(
    height: float,
    link_radius: float = LINK_RADIUS,
    *,
    d_max: float | None = None,
    scale: tuple[float, float] | None = None,
) -> WallPurcellModel:
    """Purcell's swimmer with its plane ``height`` link lengths above a wall.

    Parameters
    ----------
    height : float
        Height of the swimmer's plane above the wall, in link lengths; more than
        `MIN_GAP` link radii.
    link_radius : float
        b, in link lengths, in (0, 0.1] (slender links).
    d_max : float, optional
        Hinge limit (default pi/3, the paper's).
    scale : (float, float), optional
        Multiply ``(xi_T, xi_N)`` by these after the wall's correction (``(s, s)``: the null check
        that a common factor changes nothing).

    Raises
    ------
    ConfigError
        A height or radius out of range (one line).
    """
    b = _number("link_radius", link_radius)
    if not 0.0 < b <= 0.1:
        raise ConfigError(
            f"link_radius must lie in (0, 0.1] link lengths (a slender link), got {link_radius!r}"
        )
    h = _number("height", height)
    if not h > MIN_GAP * b:
        raise ConfigError(
            f"the swimmer's height above the wall must exceed {MIN_GAP:g} link radii "
            f"({MIN_GAP * b:g} link lengths), got {height!r}"
        )
    base = make_model("purcell", d_max=d_max)
    xi_t, xi_n = (float(v) for v in drag_coefficients(h, b))
    if scale is not None:
        xi_t, xi_n = xi_t * float(scale[0]), xi_n * float(scale[1])
    return WallPurcellModel("purcell", base.n_dof, base.lo, base.hi, xi_n / xi_t, xi_t, xi_n, h, b)


def _number(name: str, value: Any) -> float:
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise ConfigError(f"{name} must be a number, got {value!r}") from None
    if not math.isfinite(out):
        raise ConfigError(f"{name} must be finite, got {value!r}")
    return out
