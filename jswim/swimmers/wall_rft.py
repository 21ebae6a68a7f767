"""Resistive force theory of Purcell's swimmer above a plane wall, its plane parallel to the wall.

Every link (length ``l = 1``, the unit of length; radius ``b``) lies in the plane z = h above a
no-slip wall at z = 0. Its drag per unit length is ``xi_T`` along it and ``xi_N`` across it, in
the plane. Only these two matter: by the mirror symmetries of a straight link parallel to the
wall (x -> -x through its middle, y -> -y through its axis), motion in the plane gives no force
normal to the wall, so the swimmer stays at height h and moves in its plane as in the bulk.

**Only the ratio changes the stroke.** The swimmer is force- and torque-free and its shape is
prescribed, so its velocities solve a linear system homogeneous in ``(xi_T, xi_N)``: scaling both
by one factor changes nothing (the tests check it, to rounding). A wall that raised both alike
would not change the stroke's displacement at all; it changes only through
``xi_N / xi_T``, which grows above 2 near the wall here, so the stroke goes further there.

Coefficients (leading order in ``1 / ln(l / b)``, the order of the bulk model's ratio 2)::

    xi_T = 2 pi mu / (L - k_T(h)),   xi_N = 4 pi mu / (L - k_N(h)),   L = ln(l / b),

returned in units of the bulk ``xi_T = 2 pi mu / L``: ``(L / (L - k_T), 2 L / (L - k_N))``, which
is ``(1, 2)``, jswim's bulk Purcell coefficients (:mod:`jswim.swimmers.nlink`, ``xi_ratio = 2``),
as h -> infinity. ``k_T``, ``k_N`` are the wall's image (Blake 1971) of a uniform force density on
the link, averaged over the link: slender-body theory's local approximation, as in Gray & Hancock's
and Lighthill's coefficients. With ``c = 2 h`` and ``S = sqrt(l^2 + c^2)`` the averages are in
closed form (written out here from Blake's tensor at equal heights)::

    k_T = asinh(l / c) - 2 l / (S + c) + l (2 S + c) / (4 S (S + c))
    k_N = asinh(l / c) - l / (2 (S + c))

Limits (the tests check both against the literature's forms):

* far from the wall (h >> l): ``k_T = 3 l / (16 h)``, ``k_N = 3 l / (8 h)``. The link's own
  image slows it as a point force's image slows a sphere (the 9/16 of Lorentz and Faxen); this is
  de Mestre & Russel's far-wall correction (J. Eng. Math. 9, 81, 1975), as Brennen & Winet give it
  (Annu. Rev. Fluid Mech. 9, 339, 1977). The ratio then exceeds 2 by ``3 / (8 L) (l / h)``.
* near the wall (b << h << l): ``L - k_T -> ln(h / b) + 3/2`` and ``L - k_N -> ln(h / b) + 1/2``:
  both coefficients are set by the distance to the wall rather than the link's length, the
  ``ln(2 h / b)`` of Katz, Blake & Paveri-Fontana (J. Fluid Mech. 72, 529, 1975). Their
  ``xi_N / xi_T = 2`` there holds once the bulk's own O(1) constants are kept (the local terms of
  slender-body theory, Gray & Hancock's ``L - 1/2`` along and ``L + 1/2`` across: ``k_N - k_T -> 1``
  cancels their difference; tested);
  jswim's bulk ratio 2 drops those constants, so here the near-wall ratio is
  ``2 (ln(h/b) + 3/2) / (ln(h/b) + 1/2)``, above 2.

Range of validity: b << h (lubrication between link and wall is not modelled; heights below
:data:`MIN_GAP` radii are refused) and ``L`` large. Like the bulk model, the theory is local: it
leaves out the other links' flows, so it also leaves out their images. For h >> l the images of a
force-free swimmer's links cancel at first order, so there the ``l / h`` correction is a property
of the local model (a full Stokes solve of a force-free body decays faster, as the NG swimmer's
``h^-3`` in :mod:`jswim.scenes` does); at h <~ l the wall screens the links from one another
(the image cancels each link's far field beyond ~2 h), which is where local drag does best.
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


def drag_coefficients(height: Any, link_radius: float = LINK_RADIUS, xp: Any = np) -> tuple[Any, Any]:
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

    A :class:`~jswim.swimmers.models.SwimmerModel` of kind ``"purcell"`` (prompt, defaults and
    tables as the paper's swimmer), its velocities from the general resistive-force solve
    (:func:`jswim.swimmers.nlink.velocity`) with both coefficients as given; ``xi_ratio`` is their
    ratio. ``height`` and ``link_radius`` (link lengths) record where they came from
    (:func:`wall_model`; ``inf``: not from a wall).
    """

    xi_par: float = 1.0
    xi_perp: float = 2.0
    height: float = math.inf
    link_radius: float = LINK_RADIUS

    def body_velocity(self, d: Array, d_dot: Array) -> Array:
        return nlink.velocity(d, d_dot, 0.0, self.xi_perp, xi_par=self.xi_par)


def wall_model(height: float, link_radius: float = LINK_RADIUS, *, d_max: float | None = None,
               scale: tuple[float, float] | None = None) -> WallPurcellModel:
    """Purcell's swimmer with its plane ``height`` link lengths above a wall.

    Parameters
    ----------
    height : float
        Height of the swimmer's plane above the wall, in link lengths; more than
        :data:`MIN_GAP` link radii.
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
        raise ConfigError(f"link_radius must lie in (0, 0.1] link lengths (a slender link), got {link_radius!r}")
    h = _number("height", height)
    if not h > MIN_GAP * b:
        raise ConfigError(f"the swimmer's height above the wall must exceed {MIN_GAP:g} link radii "
                          f"({MIN_GAP * b:g} link lengths), got {height!r}")
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
