"""Time integration of one step: Gauss-Legendre collocation solved by Picard sweeps.

During a step the shape follows a known straight path (one arm at unit rate), and the poses
``y = (x, z, tilt)`` of all swimmers obey ``dy/dt = f(t, y)`` with ``f`` the force-free solve
([`jswim.swimmers.forcefree.solve`][jswim.swimmers.forcefree.solve]). We represent ``dy/dt`` on the step ``[0, T]`` by its
interpolant through ``n`` Gauss-Legendre nodes and require ``y(t_i) = y_0 + int_0^{t_i} f``
at every node: the collocation (implicit Runge-Kutta) method of order ``2n`` (Gauss-Legendre
IRK; Hairer, Norsett & Wanner, Solving ODEs I, sec. II.7). Its fixed point is found by Picard
sweeps started from ``y = y_0``: each sweep costs ``n`` solves, and since ``f`` depends on the
pose only through the wall and the other bodies (weakly: a few per cent at h = 3 a) each sweep
gains more than an order of magnitude. When ``f`` does not depend on the pose at all (a lone
swimmer in the unbounded fluid) one sweep is exact and the method is Gauss quadrature. By
default the number of sweeps is adaptive ([`jswim.scenes.scene_stepping.picard_tolerance`][jswim.scenes.scene_stepping.picard_tolerance]): the
iteration stops once its error estimate is below the working dtype's rounding.
"""

from __future__ import annotations

import functools

import numpy as np


@functools.lru_cache(maxsize=16)
def gauss_rule(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes on [0, 1], the running-integral matrix and the weights (float64).

    Returns ``(t, A, w)`` with ``A[i, j] = int_0^{t_i} L_j`` and ``w[j] = int_0^1 L_j``, ``L_j``
    the Lagrange polynomials of the nodes (``A`` is the Butcher matrix of the Gauss IRK).
    """
    x, w = np.polynomial.legendre.leggauss(n)
    t = (x + 1.0) / 2.0
    leg = np.polynomial.legendre
    # Lagrange basis through the nodes in the Legendre basis: V c = I, V[i, k] = P_k(x_i).
    coef = np.linalg.inv(leg.legvander(x, n - 1))  # column j: coefficients of L_j
    a = np.empty((n, n))
    for j in range(n):
        anti = leg.legint(coef[:, j], lbnd=-1)
        a[:, j] = leg.legval(x, anti) / 2.0
    return t, a, w / 2.0
