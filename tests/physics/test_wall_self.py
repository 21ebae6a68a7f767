"""Sphere-wall self-mobility (``wall_self_factors``) against numbers derived here independently:
Brenner's series summed term by term in plain float64 (no overflow guard, no shared code),
Brenner's tabulated drag factors, the far-field expansions and the near-contact asymptotes."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jswim.swimmers import mobility


@pytest.fixture(autouse=True)
def _x64():
    with jax.enable_x64(True):
        yield


def brenner_lambda(h: float, terms: int = 120) -> float:
    """Brenner (1961): drag factor normal to the wall at centre height h (radius 1), summed
    directly with math.sinh (alpha <= 1.8 here, so no term overflows)."""
    al = math.acosh(h)
    total = 0.0
    for n in range(1, terms + 1):
        num = 2 * math.sinh((2 * n + 1) * al) + (2 * n + 1) * math.sinh(2 * al)
        den = 4 * math.sinh((n + 0.5) * al) ** 2 - (2 * n + 1) ** 2 * math.sinh(al) ** 2
        total += n * (n + 1) / ((2 * n - 1) * (2 * n + 3)) * (num / den - 1)
    return 4 / 3 * math.sinh(al) * total


@pytest.mark.parametrize("h", [1.1, 1.5, 3.0])
def test_exact_normal_factor_is_brenners_series(h):
    _, nor = mobility.wall_self_factors(np.float64(1 / h), "exact")
    assert abs(float(nor) * brenner_lambda(h) - 1) < 1e-4


def test_brenners_tabulated_drag_factors():
    # Brenner (1961), his table: lambda = 3.0361 at alpha = 1 (h = cosh 1 = 1.5431 a) and
    # 9.2518 at alpha = 0.5 (h = 1.1276 a); 1.1 a is 11.46, not ~3.04 (that is h = 1.54 a).
    for alpha, lam in ((1.0, 3.0361), (0.5, 9.2518)):
        _, nor = mobility.wall_self_factors(np.float64(1 / math.cosh(alpha)), "exact")
        assert abs(1 / float(nor) - lam) < 1e-4 * lam


def test_rpb_departs_from_brenner_as_the_issue_measured():
    # RPB normal over Brenner: +0.9 % at 3 a, 1.22 at 1.5 a, 3.16 at 1.1 a
    for h, ratio in ((3.0, 1.009), (1.5, 1.223), (1.1, 3.155)):
        rpb = float(mobility.wall_self_factors(np.float64(1 / h), "rpb")[1])
        assert abs(rpb * brenner_lambda(h) - ratio) < 2e-3


def test_normal_factor_lubrication_and_far_field():
    # near contact: 1 / (1/g + (1/5) ln(1/g) + 0.971264), Cox & Brenner (1967); the series and the
    # asymptote agree where they are joined
    g = 1e-3
    lub = 1 / (1 / g + 0.2 * math.log(1 / g) + 0.971264)
    series = 1 / float(mobility.brenner_drag(np.float64(g)))
    assert abs(series / lub - 1) < 1e-5
    for g in (1e-4, 1e-5):
        nor = float(mobility.wall_self_factors(np.float64(1 / (1 + g)), "exact")[1])
        assert abs(nor / g - 1) < 20 * g * math.log(1 / g) + 1e-3  # ~ gap/a
    # far away: 1 - 9/8 e + 1/2 e^3 (Lorentz; the O(e^4) term is -57/100 e^4 or smaller)
    for h in (20.0, 200.0, 5e3):
        e = 1 / h
        nor = float(mobility.wall_self_factors(np.float64(e), "exact")[1])
        assert abs(nor - (1 - 9 / 8 * e + e**3 / 2)) < 0.6 * e**4 + 1e-13


def test_parallel_factor_faxen_and_contact():
    for h in (1.2, 2.0, 5.0):
        e = 1 / h
        par = float(mobility.wall_self_factors(np.float64(e), "exact")[0])
        assert abs(par - (1 - 9 / 16 * e + e**3 / 8 - 45 / 256 * e**4 - e**5 / 16)) < 1e-14
    # near contact ~ 1 / ((1/2) ln(a/gap)): the torque-free limit of Goldman, Cox & Brenner's
    # F^t - F^r T^t / T^r = (8/15 - (4/3)(1/10)^2 / (2/5)) ln gap = (1/2) ln gap
    for g in (1e-5, 1e-6):
        par = float(mobility.wall_self_factors(np.float64(1 / (1 + g)), "exact")[0])
        assert abs(par * 0.5 * math.log(1 / g) - 1) < 0.2
    # continuous at the join, and monotone through it
    gj = mobility.PARALLEL_JOIN_GAP
    lo, hi = (
        float(mobility.wall_self_factors(np.float64(1 / (1 + gj * f)), "exact")[0])
        for f in (1 - 1e-9, 1 + 1e-9)
    )
    assert abs(lo - hi) < 1e-8
    hs = 1 + np.geomspace(1e-4, 10, 200)
    par = np.asarray(mobility.wall_self_factors(1 / hs, "exact")[0])
    assert np.all(np.diff(par) > 0)


@pytest.mark.slow  # float32 and float64 series compiled op by op: ~8 s under load
def test_float32_and_limits():
    with jax.enable_x64(False):
        _float32_and_limits()


def _float32_and_limits():
    hs = np.array(
        [1.01, 1.1, 1.5, 3.0, 30.0, 3e4], np.float32
    )  # float32 near contact: see the docstring
    p32, n32 = mobility.wall_self_factors(jnp.asarray(1 / hs), "exact")
    assert p32.dtype == jnp.float32 and np.all(np.isfinite(n32)) and np.all(np.isfinite(p32))
    with jax.enable_x64(True):
        p64, n64 = mobility.wall_self_factors(1 / hs.astype(np.float64), "exact")
    np.testing.assert_allclose(np.asarray(n32), np.asarray(n64), rtol=2e-4)
    np.testing.assert_allclose(np.asarray(p32), np.asarray(p64), rtol=2e-5)
    p0, n0 = mobility.wall_self_factors(np.float64(0.0), "exact")
    assert float(p0) == 1.0 and float(n0) == 1.0
    with pytest.raises(ValueError, match="rpb, exact"):
        mobility.wall_self_factors(0.5, "faxen")


@pytest.mark.slow  # three mobility matrices op by op: ~8 s under load
def test_solves_keep_the_grand_mobility_positive_definite_near_contact():
    # a lying three-sphere swimmer pushed to a 1e-3 a gap (a refused step's trial pose): the
    # exact normal factor there (~1e-3) is below the far-field pair blocks, so the solves floor
    # the gap at SOLVE_MIN_GAP; above the floor the matrix is positive definite as it is
    pos = jnp.asarray([[-6.0, 1.001], [0.0, 1.001], [6.0, 1.001]])
    for mob in ("point", "rpy"):
        m = np.asarray(mobility.mobility_matrix(pos, jnp.ones(3), True, mob, "exact"))
        assert np.linalg.eigvalsh(m).min() > 0
    g = mobility.SOLVE_MIN_GAP
    pos = pos.at[:, 1].set(1.0 + g)
    m = np.asarray(mobility.mobility_matrix(pos, jnp.ones(3), True, "point", "exact"))
    nor = float(mobility.wall_self_factors(np.float64(1 / (1 + g)), "exact")[1])
    assert abs(m[1, 1] - nor) < 1e-12 and np.linalg.eigvalsh(m).min() > 0
