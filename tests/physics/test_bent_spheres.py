"""The bent three-sphere swimmer: force and torque balance, the collinear limit against an
independent force-free solve, mirror symmetry, and circle swimming (rotation per cycle)."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jswim.swimmers import bent_spheres
from tests.physics.test_dissipation import spheres_reference

solve = jax.jit(bent_spheres.solve, static_argnums=2)
body_velocity = jax.jit(bent_spheres.body_velocity, static_argnums=2)
power = jax.jit(bent_spheres.power, static_argnums=2)


def test_forces_and_torques_balance_and_spheres_move_as_prescribed():
    rng = np.random.default_rng(5)
    for _ in range(5):
        d = jnp.asarray([*rng.uniform(6, 10, 2), rng.uniform(-1.2, 1.2)])
        d_dot = jnp.asarray(rng.normal(size=3))
        m = solve(d, d_dot, "point")
        x = np.asarray(jax.jit(bent_spheres.positions)(d))
        f = np.asarray(m.forces)
        np.testing.assert_allclose(f.sum(0), 0.0, atol=1e-12)
        np.testing.assert_allclose(np.sum(x[:, 0] * f[:, 1] - x[:, 1] * f[:, 0]), 0.0, atol=1e-11)
        # arm lengths change at the prescribed rates: relative velocities along the arms
        v = (
            np.asarray(m.velocity)
            + float(m.omega) * np.stack([-x[:, 1], x[:, 0]], -1)
            + np.asarray(jax.jit(bent_spheres.shape_velocities)(d, d_dot))
        )
        e1 = (x[1] - x[0]) / np.linalg.norm(x[1] - x[0])
        e2 = (x[2] - x[1]) / np.linalg.norm(x[2] - x[1])
        np.testing.assert_allclose((v[1] - v[0]) @ e1, float(d_dot[0]), atol=1e-12)
        np.testing.assert_allclose((v[2] - v[1]) @ e2, float(d_dot[1]), atol=1e-12)
        assert float(power(d, d_dot, "point")) > 0


def test_straight_swimmer_is_the_collinear_force_free_swimmer():
    rng = np.random.default_rng(6)
    for _ in range(4):
        arms, rates = rng.uniform(6, 10, 2), rng.normal(size=2)
        u_mean, p_ref = spheres_reference(arms, rates)
        w = np.array([0.0, rates[0], rates[0] + rates[1]])  # velocities relative to sphere 0
        middle = u_mean - w.mean() + w[1]
        d, d_dot = jnp.asarray([*arms, 0.0]), jnp.asarray([*rates, 0.0])
        u, v, om = np.asarray(body_velocity(d, d_dot, "point"))
        np.testing.assert_allclose([u, v, om], [middle, 0.0, 0.0], atol=1e-12)
        np.testing.assert_allclose(float(power(d, d_dot, "point")), p_ref, rtol=1e-12)


def test_mirror_image_turns_the_other_way():
    d, d_dot = jnp.array([7.0, 9.0, 0.5]), jnp.array([0.3, -1.0, 0.2])
    u, v, om = np.asarray(body_velocity(d, d_dot, "point"))
    um, vm, omm = np.asarray(
        body_velocity(d * jnp.array([1, 1, -1]), d_dot * jnp.array([1, 1, -1]), "point")
    )
    np.testing.assert_allclose([um, vm, omm], [u, -v, -om], atol=1e-14)


def _cycle_rotation(beta, reverse=False, nodes=16):
    """Rotation per square cycle of the arms in [6, 10] at a fixed bend: the line integral of
    omega (the rotation does not depend on the pose), Gauss-Legendre on each side."""
    verts = [(6.0, 6.0), (10.0, 6.0), (10.0, 10.0), (6.0, 10.0)]
    if reverse:
        verts = verts[::-1]
    x, w = np.polynomial.legendre.leggauss(nodes)
    total = 0.0
    for a, b in zip(verts, verts[1:] + verts[:1]):
        a3, b3 = np.array([*a, beta]), np.array([*b, beta])
        for xk, wk in zip(x, w):
            d = jnp.asarray(a3 + (b3 - a3) * (xk + 1) / 2)
            total += wk / 2 * float(body_velocity(d, jnp.asarray(b3 - a3), "point")[2])
    return total


@pytest.mark.parametrize("beta", [0.3, 0.6])
def test_bent_swimmer_swims_on_a_circle(beta):
    turn = _cycle_rotation(beta)
    assert abs(_cycle_rotation(0.0)) < 1e-15  # straight: no turn
    assert abs(turn) > 1e-3  # bent: ~3e-3 (0.3 rad) and ~6e-3 (0.6 rad) per cycle
    np.testing.assert_allclose(_cycle_rotation(-beta), -turn, rtol=1e-12)
    np.testing.assert_allclose(_cycle_rotation(beta, reverse=True), -turn, rtol=1e-12)
