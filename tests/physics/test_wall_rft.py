"""Purcell's swimmer above a wall: the wall-corrected drag against independent numbers.

- The closed-form link averages of Blake's image against a quadrature of Blake's tensor written
  here from Blake (1971) (itself checked against :mod:`jswim.swimmers.mobility`'s Blake blocks).
- Their far limits: de Mestre & Russel's 3 l / (16 h), 3 l / (8 h) (Brennen & Winet 1977).
- Their near limit: both logarithms become ln(h / b) + O(1) with k_N - k_T -> 1, which with
  slender-body theory's bulk constants (L - 1/2 along, L + 1/2 across) is Katz, Blake &
  Paveri-Fontana's equal logarithms ln(2 h / b) (ratio 2) at the wall.
- The square stroke's displacement per cycle against h by an RK4 integration written here, from
  the coefficients' ratio: the bulk 0.19124724 at ratio 2, monotone in h, and the far approach
  equal to the bulk model's sensitivity to the ratio times the ratio's excess 3 / (8 L h).
"""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jswim.errors import ConfigError
from jswim.swimmers import mobility, nlink, wall_rft
import itertools

BULK_CYCLE = 0.19124724  # DESIGN.md: Purcell's square gait at d_max = pi/3
HEIGHTS = (1.5, 2.0, 3.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 1000.0)


def blake_image(rho: np.ndarray, h: float) -> np.ndarray:
    """8 pi mu x (Blake's tensor minus the free Stokeslet) for a force at (0, 0, h) and points
    (rho_x, rho_y, h), ``rho`` (..., 2) -> (..., 3, 3) (rows: velocity, columns: force); Blake
    (1971) as written in :mod:`jswim.swimmers.mobility`'s docstring, differentiated by hand here."""
    rho = np.asarray(rho, np.float64)
    big = np.concatenate([rho, np.full(rho.shape[:-1] + (1,), 2.0 * h)], -1)
    r = np.linalg.norm(big, axis=-1)[..., None, None]
    eye = np.eye(3)
    rr = big[..., :, None] * big[..., None, :]  # R_i R_k
    out = -(eye / r + rr / r**3)
    m = np.array([1.0, 1.0, -1.0])
    r3 = big[..., 2][..., None, None]
    e3 = eye[2]
    # d/dR_k [h R_i / R^3 - delta_i3 / R - R_i R_3 / R^3], index [i, k]
    d = (
        h * (eye / r**3 - 3 * rr / r**5)
        + e3[:, None] * big[..., None, :] / r**3
        - (eye * r3 + big[..., :, None] * e3[None, :]) / r**3
        + 3 * rr * r3 / r**5
    )
    return out + 2 * h * m * d


def test_the_tests_blake_tensor_is_jswims():
    # jswim's Blake blocks (8 pi mu G in the x-z plane): same heights, offset along x
    with jax.enable_x64(True):
        for rx, h in ((0.7, 1.3), (3.0, 0.4), (0.2, 2.0)):
            xx, xz, zx, zz = (
                float(v)
                for v in mobility.blake_entries(*(jnp.asarray(v, jnp.float64) for v in (rx, h, h)))
            )
            sxx, _, szz = (
                float(v)
                for v in mobility.stokeslet(
                    jnp.asarray(rx, jnp.float64), jnp.asarray(0.0, jnp.float64)
                )
            )
            img = blake_image(np.array([rx, 0.0]), h)
            assert xx == pytest.approx(sxx + img[0, 0], rel=1e-12)
            assert zz == pytest.approx(szz + img[2, 2], rel=1e-12)
            assert xz == pytest.approx(img[0, 2], rel=1e-12) and zx == pytest.approx(
                img[2, 0], rel=1e-12
            )
    # the sphere's 9/16: a point force's own image at its place, -3 / (4 h) along the wall
    np.testing.assert_allclose(
        np.diag(blake_image(np.zeros(2), 2.0))[:2], -3 / (4 * 2.0), rtol=1e-14
    )


@pytest.mark.parametrize("h", [0.25, 0.6, 1.5, 4.0, 20.0])
def test_link_averaged_image_closed_form_against_quadrature(h):
    # (1/l) double integral over the link of the image's in-plane blocks, Gauss-Legendre (l = 1)
    s, w = np.polynomial.legendre.leggauss(160)
    s, w = 0.5 * s, 0.5 * w
    dx = s[:, None] - s[None, :]
    g = blake_image(np.stack([dx, np.zeros_like(dx)], -1), h)
    ww = w[:, None] * w[None, :]
    tt, nn = np.sum(ww * g[..., 0, 0]), np.sum(ww * g[..., 1, 1])
    # k_T = -(2 pi mu / f) u_image along, k_N = -(4 pi mu / f) u_image across (u = f G / 8 pi mu)
    k_t, k_n = wall_rft.log_corrections(h)
    assert k_t == pytest.approx(-tt / 4, rel=1e-9)
    assert k_n == pytest.approx(-nn / 2, rel=1e-9)


def test_far_limit_is_de_mestre_russel():
    for h in (50.0, 500.0, 5000.0):
        k_t, k_n = wall_rft.log_corrections(h)
        # next order (l/h)^3: the link's extent in the image's 1/R
        assert k_t * 16 * h / 3 == pytest.approx(1.0, abs=0.5 / h**2)
        assert k_n * 8 * h / 3 == pytest.approx(1.0, abs=0.5 / h**2)
    xi_t, xi_n = wall_rft.drag_coefficients(1e7)
    assert (xi_t, xi_n) == (
        pytest.approx(1.0, abs=1e-7),
        pytest.approx(2.0, abs=1e-7),
    )  # jswim's bulk


def test_near_limit_is_katz_blake_paveri_fontana():
    b = 1e-4
    for h in (1e-2, 1e-3):
        k_t, k_n = wall_rft.log_corrections(h)
        big_l = math.log(1 / b)
        # both logarithms set by the wall distance: ln(h/b) + 3/2 along, + 1/2 across (next: -7h/2, -h)
        assert big_l - k_t - math.log(h / b) == pytest.approx(1.5 - 3.5 * h, abs=h * h * 10)
        assert big_l - k_n - math.log(h / b) == pytest.approx(0.5 - h, abs=h * h * 10)
        # with slender-body theory's bulk constants (L - 1/2 along, L + 1/2 across) the two become
        # equal: KBP's ratio 2 at the wall
        assert (big_l - 0.5 - k_t) - (big_l + 0.5 - k_n) == pytest.approx(0.0, abs=3 * h)


def test_ratio_grows_toward_the_wall():
    r = [float(n / t) for t, n in (wall_rft.drag_coefficients(h) for h in (0.05, *HEIGHTS))]
    assert all(a > b for a, b in itertools.pairwise(r)) and r[-1] > 2.0
    # the far excess 2 (k_N - k_T) / L = 3 / (8 L h)
    assert r[-1] - 2.0 == pytest.approx(3 / (8 * math.log(100.0) * 1000.0), rel=1e-3)


def test_bad_heights_and_radii_are_one_line_errors():
    for kw in (
        {"height": 0.01},
        {"height": float("nan")},
        {"height": 2.0, "link_radius": 0.5},
        {"height": 2.0, "link_radius": 0.0},
        {"height": "x"},
    ):
        with pytest.raises(ConfigError) as e:
            wall_rft.wall_model(**kw)
        assert "\n" not in str(e.value)


def test_common_factor_leaves_the_velocities():
    rng = np.random.default_rng(3)
    d, rate = rng.uniform(-1, 1, (20, 2)), rng.normal(size=(20, 2))
    c = rng.uniform(0.3, 3.0, 20)
    with jax.enable_x64(True):
        vel = jax.jit(jax.vmap(lambda d, r, c: nlink.velocity(d, r, 0.0, 2.0 * c, xi_par=c)))
        ref = np.asarray(vel(d, rate, np.ones(20)))
        np.testing.assert_allclose(np.asarray(vel(d, rate, c)), ref, rtol=0, atol=1e-13)
        assert np.abs(ref).max() > 0.1


# -- the square stroke by a test-side RK4 ---------------------------------------------------------


def _cycle_rk4(ratio: jax.Array, n: int = 256) -> jax.Array:
    """Centroid (= middle link, the cycle closes with no rotation) x per square cycle from (+, +)."""
    dm = math.pi / 3
    dt = 2 * dm / n

    def rate(p, d, r):
        u = nlink.velocity(d, r, 0.0, ratio)
        c, s = jnp.cos(p[2]), jnp.sin(p[2])
        return jnp.array([c * u[0] - s * u[1], s * u[0] + c * u[1], u[2]])

    rates = jnp.array(
        [[0.0, -1.0], [-1.0, 0.0], [0.0, 1.0], [1.0, 0.0]]
    )  # D2 down, D1 down, D2 up, D1 up

    def body(j, p):
        r = rates[j // n]
        d0 = jnp.array([dm, dm]) + 2 * dm * jnp.sum(
            jnp.where(jnp.arange(4)[:, None] < j // n, rates, 0.0), 0
        )
        t = (j % n) * dt
        k1 = rate(p, d0 + r * t, r)
        k2 = rate(p + 0.5 * dt * k1, d0 + r * (t + 0.5 * dt), r)
        k3 = rate(p + 0.5 * dt * k2, d0 + r * (t + 0.5 * dt), r)
        k4 = rate(p + dt * k3, d0 + r * (t + dt), r)
        return p + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    return jax.lax.fori_loop(0, 4 * n, body, jnp.zeros(3, jnp.float64))


def cycles(ratios):
    with jax.enable_x64(True):
        return np.asarray(jax.jit(jax.vmap(_cycle_rk4))(jnp.asarray(ratios, jnp.float64)))


def test_square_stroke_per_cycle_against_height():
    xi = [wall_rft.drag_coefficients(h) for h in HEIGHTS]
    ratios = [float(n / t) for t, n in xi]
    eps = 1e-4
    out = cycles([2.0, 2.0 - eps, 2.0 + eps, *ratios])
    bulk, lo, hi, per = out[0, 0], out[1, 0], out[2, 0], out[3:, 0]
    assert bulk == pytest.approx(BULK_CYCLE, abs=5e-9)
    np.testing.assert_allclose(out[:, 2], 0.0, atol=1e-12)  # no net rotation per cycle
    assert np.all(np.diff(per) < 0) and np.all(per > bulk)  # monotone approach from above
    slope = (hi - lo) / (2 * eps)  # the bulk model's dX/d(ratio) at 2
    big_l = math.log(100.0)
    for h, x in zip(HEIGHTS, per):
        if h >= 100:  # far: X - bulk = slope * 3 / (8 L h) to O(1/h^2)
            assert x - bulk == pytest.approx(slope * 3 / (8 * big_l * h), rel=5 / h)
    assert per[-1] - bulk < 2e-5  # h = 1000 l: within 2e-5 l of the bulk
