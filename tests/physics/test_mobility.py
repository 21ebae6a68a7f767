"""Point-force mobilities (jswim.swimmers.mobility) and the force-free solve: independent checks."""

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jswim.swimmers import bodyframe, forcefree, mobility

# Under jit, as scene steps call them: one compile per shape (op by op, the matrix and the solve
# compiled dozens of small programs per shape, about twice the CPU; the block solves below stay op by
# op: jitted, the wall's solve compiled longer than it ran)
_matrix = jax.jit(mobility.mobility_matrix, static_argnums=2)
_solve = jax.jit(forcefree.solve, static_argnums=5)


def random_config(rng, n, wall, min_gap=0.0, box=12.0):
    """Centres of ``n`` unit spheres in the x-z plane, surfaces at least ``min_gap`` apart (and
    from the wall)."""
    pts = []
    while len(pts) < n:
        p = np.array([rng.uniform(-box, box), rng.uniform(1.0 + min_gap, 1.0 + min_gap + box)])
        if all(np.hypot(*(p - q)) >= 2.0 + min_gap for q in pts):
            pts.append(p)
    return np.array(pts)


def test_blake_velocity_vanishes_on_the_wall():
    rng = np.random.default_rng(0)
    rx = jnp.asarray(rng.uniform(-20, 20, 50))
    h = jnp.asarray(rng.uniform(0.5, 30, 50))
    g = mobility.blake(rx, jnp.zeros(50), h)
    scale = np.abs(np.asarray(mobility.oseen(rx, -h))).max()
    assert np.abs(np.asarray(g)).max() < 1e-14 * scale


def test_blake_tends_to_oseen_far_from_the_wall():
    # relative image contribution ~ r / (2h): check that it shrinks like 1/h
    rx, rz = jnp.asarray(3.0), jnp.asarray(-2.0)
    errs = []
    for h in (1e2, 1e3, 1e4):
        g = np.asarray(mobility.blake(rx, jnp.asarray(h + rz), jnp.asarray(h)))
        o = np.asarray(mobility.oseen(rx, rz))
        errs.append(np.abs(g - o).max() / np.abs(o).max())
    assert errs[0] < 0.05 and errs[1] / errs[0] < 0.11 and errs[2] / errs[1] < 0.11


def test_self_image_is_the_first_order_wall_correction():
    # the image of a point force at its own position: -9/16 a/h along the wall, -9/8 a/h normal
    # (Lorentz 1907; Faxen); the self-mobility's first-order terms
    h, eps = 7.0, 1e-7
    g = np.asarray(mobility.blake(jnp.asarray(eps), jnp.asarray(h), jnp.asarray(h)))
    s = np.asarray(mobility.oseen(jnp.asarray(eps), jnp.asarray(0.0)))
    image = mobility.OSEEN_PREFACTOR * (g - s) * h
    np.testing.assert_allclose(np.diag(image), [-9 / 16, -9 / 8], atol=1e-6)
    par, nor = mobility.wall_self_factors(jnp.asarray(1 / h))
    assert (
        abs(float(par) - (1 - 9 / 16 / h)) < 2 / h**3
        and abs(float(nor) - (1 - 9 / 8 / h)) < 1 / h**3
    )


@pytest.mark.parametrize("wall", [False, True])
def test_mobility_symmetric_positive_definite(wall):
    rng = np.random.default_rng(1 + wall)
    for n in (2, 3, 6, 12):
        for _ in range(10):
            pos = random_config(rng, n, wall)
            m = np.asarray(_matrix(jnp.asarray(pos), jnp.ones(n), wall))
            assert np.abs(m - m.T).max() < 1e-14
            assert np.linalg.eigvalsh(m).min() > 0


def test_blake_symmetry_between_points():
    rng = np.random.default_rng(3)
    for _ in range(20):
        xi, xj = rng.uniform(-5, 5, 2)
        zi, zj = rng.uniform(0.5, 9, 2)
        g = np.asarray(mobility.blake(jnp.asarray(xi - xj), jnp.asarray(zi), jnp.asarray(zj)))
        gt = np.asarray(mobility.blake(jnp.asarray(xj - xi), jnp.asarray(zj), jnp.asarray(zi)))
        np.testing.assert_allclose(g, gt.T, rtol=1e-13, atol=1e-15)


@pytest.mark.parametrize("wall", [False, True])
def test_force_and_torque_free(wall):
    rng = np.random.default_rng(4)
    for _ in range(5):
        centre = jnp.asarray([[0.0, 9.0], [31.0, 8.0]])
        tilt = jnp.asarray(rng.uniform(-0.3, 0.3, 2))
        arms = jnp.asarray(rng.uniform(6, 10, (2, 2)))
        rates = jnp.asarray([[1.0, 0.0], [0.0, -1.0]])
        obstacles = jnp.asarray([[15.0, 20.0, 2.5]])
        r = _solve(centre, tilt, arms, rates, obstacles, wall)
        f = np.asarray(r.forces)
        pos = np.asarray(forcefree.sphere_centres(centre, tilt, arms))
        for s in range(2):
            fs, rel = f[3 * s : 3 * s + 3], pos[s] - np.asarray(centre[s])
            assert np.abs(fs.sum(0)).max() < 1e-12
            assert abs(np.sum(rel[:, 0] * fs[:, 1] - rel[:, 1] * fs[:, 0])) < 1e-12
        assert np.abs(f[6]).max() > 1e-6  # the obstacle is held: it carries a force
        # sphere velocities from the forces (M F) are rigid + prescribed; the obstacle's is zero
        radii = np.ones(7)
        radii[6] = 2.5
        allpos = np.concatenate([pos.reshape(6, 2), np.asarray(obstacles)[:, :2]])
        v = (
            np.asarray(_matrix(jnp.asarray(allpos), jnp.asarray(radii), wall)) @ f.reshape(-1)
        ).reshape(7, 2)
        assert np.abs(v[6]).max() < 1e-12
        e = np.stack([np.cos(tilt), np.sin(tilt)], -1)
        q = np.asarray(forcefree.axial_offsets(arms))
        qd = np.asarray(forcefree.axial_offsets(rates))
        for s in range(2):
            rel = pos[s] - np.asarray(centre[s])
            want = (
                np.asarray(r.velocity[s])
                + float(r.omega[s]) * np.stack([-rel[:, 1], rel[:, 0]], -1)
                + qd[s][:, None] * e[s]
            )
            np.testing.assert_allclose(v[3 * s : 3 * s + 3], want, atol=1e-12)
        assert np.allclose(np.hypot(*(pos[0, 1:] - pos[0, :-1]).T), q[0, 1:] - q[0, :-1])


# Two cases cover a wall, a pair and obstacles in the fast tier; the other two (each ~3 s of
# compiling a new unrolled size) run in the slow tier.
@pytest.mark.parametrize(
    "S, O, wall",
    [
        (1, 0, True),
        pytest.param(2, 0, True, marks=pytest.mark.slow),
        pytest.param(1, 3, False, marks=pytest.mark.slow),
        (2, 1, False),
    ],
)
def test_unrolled_solve_matches_lapack(S, O, wall):
    rng = np.random.default_rng(5)
    c = jnp.asarray([[0.0, 9.0], [31.0, 8.0]][:S])
    t = jnp.asarray(rng.uniform(-0.3, 0.3, S))
    a = jnp.asarray(rng.uniform(6, 10, (S, 2)))
    r = jnp.asarray(rng.uniform(-1, 1, (S, 2)))
    ob = jnp.asarray([[15.0, 20.0, 2.5], [-20, 15, 1.0], [0, 30, 3]][:O]).reshape(O, 3)
    want = forcefree.solve(c, t, a, r, ob, wall)
    got = forcefree.solve_unrolled(c, t, a, r, ob, wall)
    for x, y in zip(want, got):
        np.testing.assert_allclose(np.asarray(y), np.asarray(x), atol=1e-14)


@pytest.mark.parametrize("wall", [False, True])
def test_block_solve_by_swimmer_converges_to_the_coupled_solve(wall):
    # block Gauss-Seidel by swimmer (what scene steps of pairs use) against the LAPACK solve of the
    # whole coupled system: each sweep is force- and torque-free per swimmer exactly, and the
    # coupling converges by the swimmers' far field (~2e-3 per sweep at D = 30 a)
    rng = np.random.default_rng(7)
    c = jnp.asarray([[0.0, 9.0], [30.0, 8.0]])
    t = jnp.asarray(rng.uniform(-0.2, 0.2, 2))
    a = jnp.asarray(rng.uniform(6, 10, (2, 2)))
    r = jnp.asarray(rng.uniform(-1, 1, (2, 2)))
    # compiled whole, not a compile per eager operation (both cases: 10.5 s -> 8.4 s, fast tier)
    want = jax.jit(forcefree.solve, static_argnums=5)(c, t, a, r, jnp.zeros((0, 3)), wall)
    sweep = jax.jit(forcefree.solve_by_swimmer, static_argnums=4)
    centres = np.asarray(forcefree.sphere_centres(c, t, a))
    forces = jnp.zeros((6, 2))
    errors = []
    for _ in range(6):
        got = sweep(c, t, a, r, wall, forces)
        forces = got.forces
        f = np.asarray(forces).reshape(2, 3, 2)
        rel = centres - np.asarray(c)[:, None, :]
        np.testing.assert_allclose(f.sum(1), 0.0, atol=1e-13)  # force-free, each swimmer
        np.testing.assert_allclose(
            (rel[..., 0] * f[..., 1] - rel[..., 1] * f[..., 0]).sum(1), 0.0, atol=1e-12
        )
        errors.append(float(np.abs(np.asarray(got.velocity) - np.asarray(want.velocity)).max()))
    scale = float(np.abs(np.asarray(want.velocity)).max())
    assert errors[0] > 1e-5 * scale  # the first sweep ignores the other swimmer's forces
    assert errors[2] < 1e-6 * scale and errors[-1] < 1e-13 * scale
    np.testing.assert_allclose(np.asarray(got.omega), np.asarray(want.omega), atol=1e-13 * scale)


def test_free_fluid_response_solves_each_swimmer_exactly():
    # the unbounded fluid's scene path (jswim.swimmers.bodyframe): each swimmer through (P, Q), a
    # function of its arms alone, at any pose. One swimmer: one sweep is the LAPACK solve. Two:
    # the Gauss-Seidel sweeps converge to the coupled 12 x 12 LAPACK solve, every sweep force- and
    # torque-free per swimmer (K'^T P = 0)
    rng = np.random.default_rng(11)
    for S in (1, 2):
        c = jnp.asarray([[0.0, 9.0], [26.0, 3.0]][:S])
        t = jnp.asarray(rng.uniform(-0.4, 0.4, S))
        a = jnp.asarray(rng.uniform(6, 10, (S, 2)))
        r = jnp.asarray(rng.uniform(-1, 1, (S, 2)))
        want = forcefree.solve(c, t, a, r, jnp.zeros((0, 3)), False)
        e = np.stack([np.cos(t), np.sin(t)], -1)
        nrm = np.stack([-e[:, 1], e[:, 0]], -1)
        want_body = np.stack(
            [
                (np.asarray(want.velocity) * e).sum(-1),
                (np.asarray(want.velocity) * nrm).sum(-1),
                np.asarray(want.omega),
            ],
            -1,
        )
        resp = bodyframe.response(a)
        np.testing.assert_allclose(
            np.asarray(resp.p), np.asarray(resp.p).transpose(0, 2, 1), atol=1e-14
        )
        forces = jnp.zeros((S, 3, 2))
        errors = []
        for _ in range(7):
            forces, xi = bodyframe.sweep(c, t, a, r, resp, forces)
            f = np.asarray(forces)
            q = np.asarray(forcefree.axial_offsets(a))
            np.testing.assert_allclose(f.sum(1), 0.0, atol=1e-13)  # force-free (body frame)
            np.testing.assert_allclose((q * f[..., 1]).sum(1), 0.0, atol=1e-12)  # torque-free
            errors.append(float(np.abs(np.asarray(xi) - want_body).max()))
        scale = float(np.abs(want_body).max())
        if S == 1:
            assert errors[0] < 1e-14 * scale
        else:
            assert (
                errors[0] > 1e-5 * scale and errors[2] < 1e-6 * scale and errors[-1] < 1e-13 * scale
            )
        lab = f[..., :1] * e[:, None, :] + f[..., 1:] * nrm[:, None, :]
        np.testing.assert_allclose(
            lab.reshape(-1, 2), np.asarray(want.forces), atol=1e-12 * np.abs(lab).max()
        )
