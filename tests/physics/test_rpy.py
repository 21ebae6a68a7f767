"""Finite-size spheres (``mobility="rpy"``): Rotne-Prager-Yamakawa and -Blake, checked against
the Faxen operators applied numerically (autodiff Laplacians) to the Oseen tensor and to Blake's
image system written here in 3-D, and a lone swimmer's cycle against an independent quadrature."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import quad

from jswim.errors import ConfigError
from jswim.env import scene_rollout
from jswim.scenes import Scene
from jswim.swimmers.mobility import mobility_matrix, rpb_entries, rpy_entries, wall_self_factors

SQUARE = [(1, -1), (2, -1), (1, 1), (2, 1)]


def _stokeslet3(r):
    n = jnp.sqrt(r @ r)
    return jnp.eye(3) / n + jnp.outer(r, r) / n**3


def _blake3(x, y):
    """8 pi mu times Blake's tensor, 3-D, field x, source y (Blake 1971): Stokeslet, minus its
    mirror image, plus 2 h m_k d/dR_k [h R_i / R^3 - delta_i3 / R - R_i R_3 / R^3] (h held)."""
    h = y[2]
    ystar = y * jnp.array([1.0, 1.0, -1.0])
    R = x - ystar

    def f(R, h):
        n = jnp.sqrt(R @ R)
        return h * R / n**3 - jnp.array([0.0, 0.0, 1.0]) / n - R * R[2] / n**3

    m = jnp.array([1.0, 1.0, -1.0])
    return _stokeslet3(x - y) - _stokeslet3(R) + 2.0 * h * jax.jacfwd(f)(R, h) * m[None, :]


def _faxen(g, x, y, ai, aj):
    """(3/4) (1 + ai^2/6 lap_x)(1 + aj^2/6 lap_y) g(x, y), by autodiff."""
    lap_x = lambda fun: (
        lambda x, y: jnp.trace(jax.jacfwd(jax.jacfwd(fun, 0), 0)(x, y), axis1=-2, axis2=-1)
    )
    lap_y = lambda fun: (
        lambda x, y: jnp.trace(jax.jacfwd(jax.jacfwd(fun, 1), 1)(x, y), axis1=-2, axis2=-1)
    )
    return 0.75 * (
        g(x, y)
        + ai**2 / 6 * lap_x(g)(x, y)
        + aj**2 / 6 * lap_y(g)(x, y)
        + ai**2 * aj**2 / 36 * lap_x(lap_y(g))(x, y)
    )


def _plane(m3):
    return np.asarray(m3)[np.ix_([0, 2], [0, 2])]


@pytest.mark.slow  # ~10-20 s: fourth derivatives by autodiff
def test_rpy_is_the_faxen_operators_on_the_oseen_tensor():
    rng = np.random.default_rng(1)
    with jax.enable_x64(True):
        for _ in range(6):
            ai, aj = rng.uniform(0.3, 2.0, 2)
            r = rng.normal(size=2)
            r = r / np.linalg.norm(r) * rng.uniform(ai + aj, 6 * (ai + aj))
            x, y = jnp.array([r[0], 0.0, r[1]]), jnp.zeros(3)
            want = _plane(_faxen(lambda x, y: _stokeslet3(x - y), x, y, ai, aj))
            mxx, mxz, mzz = rpy_entries(jnp.float64(r[0]), jnp.float64(r[1]), ai, aj)
            np.testing.assert_allclose([[mxx, mxz], [mxz, mzz]], want, rtol=1e-11, atol=1e-14)


@pytest.mark.slow  # ~10-20 s: fourth derivatives by autodiff
def test_rpb_is_the_faxen_operators_on_blakes_image_system():
    rng = np.random.default_rng(2)
    with jax.enable_x64(True):
        for _ in range(8):
            zi, zj = rng.uniform(1.2, 12.0, 2)
            rx = rng.uniform(-15, 15)
            if np.hypot(rx, zi - zj) < 2.1:
                rx += 3.0
            x, y = jnp.array([rx, 0.0, zi]), jnp.array([0.0, 0.0, zj])
            want = _plane(_faxen(_blake3, x, y, 1.0, 1.0))
            got = np.reshape(rpb_entries(jnp.float64(rx), jnp.float64(zi), jnp.float64(zj)), (2, 2))
            np.testing.assert_allclose(got, want, rtol=1e-10, atol=1e-13)


@pytest.mark.slow  # fourth derivatives by autodiff: 8 s CPU compiled once (35 s op by op)
def test_the_wall_self_factors_are_the_rotne_prager_blake_self_terms():
    # The self term: 1 plus the Faxen operators applied to Blake's image part alone at y = x.
    def image_part(x, y):
        h = y[2]
        Rv = x - y * jnp.array([1.0, 1.0, -1.0])

        def f(Rv, h):
            n = jnp.sqrt(Rv @ Rv)
            return h * Rv / n**3 - jnp.array([0.0, 0.0, 1.0]) / n - Rv * Rv[2] / n**3

        return (
            -_stokeslet3(Rv) + 2.0 * h * jax.jacfwd(f)(Rv, h) * jnp.array([1.0, 1.0, -1.0])[None, :]
        )

    with jax.enable_x64(True):
        self_term = jax.jit(
            lambda x: _faxen(image_part, x, x, 1.0, 1.0)
        )  # one compile, three heights
        for h in (1.5, 3.0, 10.0):
            m = np.asarray(self_term(jnp.array([0.0, 0.0, h])))
            par, nor = wall_self_factors(1.0 / h)
            np.testing.assert_allclose([1.0 + m[0, 0], 1.0 + m[2, 2]], [par, nor], rtol=1e-12)


def test_mobility_matrix_rpy_blocks_and_symmetry():
    rng = np.random.default_rng(3)
    with jax.enable_x64(True):
        pos = jnp.asarray(
            np.stack([np.arange(4) * 3.1 + rng.uniform(0, 0.5, 4), rng.uniform(2.0, 6.0, 4)], -1)
        )
        for wall in (False, True):
            m = np.asarray(mobility_matrix(pos, jnp.ones(4), wall, "rpy"))
            np.testing.assert_allclose(m, m.T, atol=1e-14)
            assert np.all(np.linalg.eigvalsh(m) > 0)
            p = np.asarray(mobility_matrix(pos, jnp.ones(4), wall))
            np.testing.assert_allclose(np.diag(m), np.diag(p), rtol=1e-15)  # self terms as before
            assert np.max(np.abs(m - p)) > 1e-3  # the pair blocks changed


def _collinear_rpy_velocity(d1, d2, d1dot, d2dot):
    """Middle sphere's velocity of a force-free collinear three-sphere swimmer with RPY blocks
    along the axis (3/(2r) - 1/r^3), self 1; solved from scratch."""
    x = np.array([-d1, 0.0, d2])
    m = np.eye(3)
    for i in range(3):
        for j in range(3):
            if i != j:
                r = abs(x[i] - x[j])
                m[i, j] = 1.5 / r - 1.0 / r**3
    # unknowns F1, F2, F3, U: M F - U 1 = (-d1dot, 0, d2dot), sum F = 0
    a = np.zeros((4, 4))
    a[:3, :3] = m
    a[:3, 3] = -1.0
    a[3, :3] = 1.0
    return np.linalg.solve(a, np.array([-d1dot, 0.0, d2dot, 0.0]))[3]


def test_rpy_lone_square_stroke_matches_a_quadrature():
    legs = [
        quad(
            lambda d: _collinear_rpy_velocity(d, 10.0, 1.0, 0.0),
            10.0,
            6.0,
            epsabs=1e-13,
            epsrel=1e-12,
        )[0],
        quad(
            lambda d: _collinear_rpy_velocity(6.0, d, 0.0, 1.0),
            10.0,
            6.0,
            epsabs=1e-13,
            epsrel=1e-12,
        )[0],
        quad(
            lambda d: _collinear_rpy_velocity(d, 6.0, 1.0, 0.0),
            6.0,
            10.0,
            epsabs=1e-13,
            epsrel=1e-12,
        )[0],
        quad(
            lambda d: _collinear_rpy_velocity(10.0, d, 0.0, 1.0),
            6.0,
            10.0,
            epsabs=1e-13,
            epsrel=1e-12,
        )[0],
    ]
    want = sum(legs)
    r = scene_rollout("ng", SQUARE, Scene(medium="free", mobility="rpy"))
    assert abs(r.x[-1, 0] - want) < 1e-8
    assert (
        abs(r.z[-1, 0] - 10.0) < 1e-12 and abs(r.tilt[-1, 0]) < 1e-12
    )  # collinear: no lift, no turn
    point = scene_rollout("ng", SQUARE, Scene(medium="free"))
    assert abs(point.x[-1, 0] - 0.17209143957) < 1e-10  # the point-force default unchanged
    assert abs(r.x[-1, 0] - point.x[-1, 0]) > 1e-4


def test_rpy_scene_fields():
    assert "mobility" not in Scene(medium="free").to_dict()  # earlier scenes' JSON unchanged
    s = Scene(medium="wall", mobility="rpy")
    assert Scene.from_dict(s.to_dict()) == s
    for bad in (
        dict(medium="free", mobility="stokes"),
        dict(medium="bulk", mobility="rpy"),
        dict(medium="wall", mobility="rpy", obstacles=((0.0, 5.0, 2.0),)),
    ):
        with pytest.raises(ConfigError):
            Scene(**bad).validate()
