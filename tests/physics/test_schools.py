"""Schools of N >= 3 NG swimmers: an independent collinear solve, symmetries, the
far-spacing limit, pairwise superposition and the force-free sums (float64).

Every stroke here is the square stroke done by every swimmer at once and in phase
(``scene_step_joint``: each swimmer moves the same arm at the same rate).
"""

import jax
import jax.numpy as jnp
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from jswim.scenes import (
    Scene,
    batch_starts,
    scene_params,
    scene_positions,
    scene_reset,
    scene_step_joint,
)
from jswim.swimmers import bodyframe, forcefree

pytestmark = pytest.mark.slow  # compiles several school scenes (~1-2 min on 2 loaded cores)

SQUARE = [
    (0, -1),
    (1, -1),
    (0, 1),
    (1, 1),
]  # 0-based arm, ROC: from (10, 10), d1 short, d2 short, d1 long, d2 long
LONE = 0.17209143957  # a lone swimmer's cycle (tests/env/test_scenes.py: an independent collinear solve)


def collinear_school_cycle(n, spacing, lo=6.0, hi=10.0):
    """The middle spheres' displacement over one in-phase square cycle of ``n`` coaxial swimmers
    ``spacing`` apart: every sphere on the x axis, point forces (unit self mobility, Oseen 3/(2 r)
    along the line), each swimmer force-free; the middles' ODE integrated by SciPy (DOP853)."""

    def velocities(x_mid, arms, rates):
        q = np.array([-arms[0], 0.0, arms[1]])
        qdot = np.array([-rates[0], 0.0, rates[1]])
        xs = (x_mid[:, None] + q[None, :]).reshape(-1)
        r = np.abs(xs[:, None] - xs[None, :])
        m = np.eye(3 * n) + np.where(r > 0, 1.5 / np.where(r > 0, r, 1.0), 0.0)
        owner = np.repeat(np.arange(n), 3)
        k = (owner[:, None] == np.arange(n)[None, :]).astype(
            float
        )  # sphere i moves with its swimmer
        a = np.block([[m, -k], [k.T, np.zeros((n, n))]])
        sol = np.linalg.solve(a, np.concatenate([np.tile(qdot, n), np.zeros(n)]))
        return sol[3 * n :]

    x = np.arange(n) * float(spacing)
    arms = [hi, hi]
    for dof, sign in SQUARE:
        start = list(arms)

        def rhs(t, y, dof=dof, sign=sign, start=start):
            a = list(start)
            a[dof] += sign * t
            rr = [0.0, 0.0]
            rr[dof] = float(sign)
            return velocities(y, a, rr)

        x = solve_ivp(rhs, (0.0, hi - lo), x, method="DOP853", rtol=1e-13, atol=1e-14).y[:, -1]
        arms[dof] += sign * (hi - lo)
    return x - np.arange(n) * float(spacing)


def joint_cycles(scene, spacings, cycles=1):
    """Per-cycle displacement ``(B, S, 2)`` and tilt change ``(B, S)`` over the last of ``cycles``
    in-phase square cycles, one start per spacing (float64)."""
    n = scene.swimmers
    with jax.enable_x64(True):
        params = batch_starts(
            scene_params("ng", scene, dtype=jnp.float64), separation=np.asarray(spacings, float)
        )
        dofs = jnp.asarray([[d] * n for d, _ in SQUARE] * cycles, jnp.int32)
        rocs = jnp.asarray([[float(k)] * n for _, k in SQUARE] * cycles, jnp.float64)

        def one(centre0, tilt0):
            p = params.replace(centre0=centre0, tilt0=tilt0)
            body = lambda st, a: (
                (scene_step_joint(p, st, a[0], a[1], jax.random.PRNGKey(0))[0],) * 2
            )
            return jax.lax.scan(body, scene_reset(p), (dofs, rocs))[1]

        traj = jax.jit(jax.vmap(one))(params.centre0, params.tilt0)
        pos = scene_positions(traj)  # (B, T, S, 2), arms back at (10, 10) after each cycle
        start = pos[:, -5] if cycles > 1 else np.asarray(params.centre0)
        tilt = np.asarray(traj.tilt)
        t0 = tilt[:, -5] if cycles > 1 else np.asarray(params.tilt0)
        return pos[:, -1] - start, tilt[:, -1] - t0


@pytest.fixture(scope="module")
def line():
    """Lines of 2 and 3 at D = 30..480 a (the pair also at 2D, 3D, 4D for superposition)."""
    ds = np.array([30.0, 60.0, 120.0, 240.0, 360.0, 480.0, 720.0, 960.0])
    pair = joint_cycles(Scene(medium="free", swimmers=2), ds)
    three = joint_cycles(Scene(medium="free", swimmers=3), ds[:4])
    return ds, pair, three


def test_line_of_three_matches_an_independent_collinear_solve(line):
    ds, _, (disp, tilt) = line
    for i, d in enumerate(ds[:2]):
        want = collinear_school_cycle(3, d)
        # jswim: Gauss-Legendre collocation (6 nodes) and block Gauss-Seidel sweeps; SciPy: DOP853
        np.testing.assert_allclose(disp[i, :, 0], want, atol=1e-10, rtol=0)
    assert abs(want[1] - want[0]) > 1e-4  # a real effect at 60 a: the middle swimmer is faster
    np.testing.assert_array_equal(disp[..., 1], 0.0)  # on the axis: no z motion, no tilt (symmetry)
    np.testing.assert_array_equal(tilt, 0.0)


def test_line_ends_move_alike_and_the_middle_gains(line):
    # Mirror x -> -x and reverse time: the square stroke maps to itself and the line of three to
    # itself with its ends exchanged, so the two end swimmers' displacements per cycle agree (the
    # pair's zero relative drift is the same argument). Unlike the pair's, the reversed image
    # starts from the cycle's end, whose spacings differ from the start's by the middle's gain, so
    # here they agree to second order in the interaction: 1.8e-5 a at D = 30 a against a gain of
    # 1e-2, 2e-8 against 9e-4 at 60 a. The middle swimmer is not constrained: it feels two
    # neighbours at D, each end one at D and one at 2D.
    ds, (pd, _), (disp, _) = line
    ends = disp[:, 0, 0] - disp[:, 2, 0]
    gain = disp[:, 1, 0] - disp[:, 0, 0]
    assert np.all(np.abs(ends) < 3e-3 * np.abs(gain)) and np.all(np.diff(np.abs(ends / gain)) < 0)
    # Far apart the interactions add pair by pair (the far field is linear in each swimmer's
    # force distribution): middle minus end = delta(D) - delta(2D), delta the pair's change of
    # speed from a lone swimmer's, and the school's mean change = (2/3)(2 delta(D) + delta(2D)).
    delta = dict(zip(ds, pd[:, 0, 0] - LONE))
    for i, d in enumerate(ds[:4]):
        if d < 120:
            continue
        np.testing.assert_allclose(gain[i], delta[d] - delta[2 * d], rtol=0.01)
        mean = disp[i, :, 0].mean() - LONE
        np.testing.assert_allclose(mean, 2.0 / 3.0 * (2 * delta[d] + delta[2 * d]), rtol=0.01)


def test_line_far_spacing_limit(line):
    # each swimmer tends to the lone cycle; the pair's and the school's corrections fall as D^-3
    # (Pooley, Alexander & Yeomans 2007: no D^-2 term in phase)
    ds, (pd, _), (disp, _) = line
    corr = disp[:, :, 0] - LONE  # (4, 3)
    assert np.all(np.abs(corr[-1]) < 2e-5) and np.all(corr > 0)
    slope = np.log(corr[-2] / corr[-1]) / np.log(ds[3] / ds[2])
    assert np.all(np.abs(slope - 3.0) < 0.15)
    pslope = np.log((pd[-2, 0, 0] - LONE) / (pd[-1, 0, 0] - LONE)) / np.log(ds[-1] / ds[-2])
    assert abs(pslope - 3.0) < 0.05


def test_side_by_side_mirror_symmetry():
    # Side by side in the unbounded fluid, the plane z = z_middle mirrors the school of three
    # onto itself with swimmers 1 and 3 exchanged (each swimmer is symmetric about its own axis):
    # their x displacements agree, their z displacements and tilts are opposite, and the middle
    # swimmer neither rises nor turns.
    (disp, tilt) = joint_cycles(
        Scene(medium="free", swimmers=3, formation="side"), [5.0, 10.0, 30.0]
    )
    np.testing.assert_allclose(disp[:, 0, 0], disp[:, 2, 0], atol=1e-13, rtol=0)
    np.testing.assert_allclose(disp[:, 0, 1], -disp[:, 2, 1], atol=1e-13, rtol=0)
    np.testing.assert_allclose(tilt[:, 0], -tilt[:, 2], atol=1e-13, rtol=0)
    assert np.all(np.abs(disp[:, 1, 1]) < 1e-13) and np.all(np.abs(tilt[:, 1]) < 1e-13)
    assert np.all(np.abs(disp[:2, 0, 1]) > 1e-6)  # the outer ones do move sideways at 5-10 a
    # far apart every swimmer swims its lone cycle
    assert np.all(np.abs(disp[-1, :, 0] - LONE) < 2e-3)


def test_red_black_sweeps_converge_to_the_coupled_solve_and_are_force_free():
    # The school's solve (red-black block Gauss-Seidel by swimmer) against one LAPACK solve of all
    # spheres, at a generic pose of five swimmers (free fluid and wall), and the force-free sums.
    rng = np.random.default_rng(3)
    with jax.enable_x64(True):
        s = 5
        centre = jnp.asarray(
            np.stack([np.arange(s) * 26.0 + rng.normal(0, 1, s), 12.0 + rng.normal(0, 2, s)], -1)
        )
        tilt = jnp.asarray(rng.normal(0, 0.1, s))
        arms = jnp.asarray(rng.uniform(6, 10, (s, 2)))
        rates = jnp.asarray(rng.normal(0, 1, (s, 2)))
        none = jnp.zeros((0, 3))
        for wall in (False, True):
            ref = forcefree.solve(centre, tilt, arms, rates, none, wall)
            f = jnp.zeros((3 * s, 2))
            if wall:
                for _ in range(30):
                    r = forcefree.solve_by_swimmer(centre, tilt, arms, rates, True, f)
                    f = r.forces
                vel, om, forces = r.velocity, r.omega, r.forces
            else:
                resp = bodyframe.response(arms)
                fb = jnp.zeros((s, 3, 2))
                for _ in range(30):
                    fb, xi = bodyframe.sweep(centre, tilt, arms, rates, resp, fb)
                c, sn = jnp.cos(tilt), jnp.sin(tilt)
                vel = jnp.stack([c * xi[:, 0] - sn * xi[:, 1], sn * xi[:, 0] + c * xi[:, 1]], -1)
                om = xi[:, 2]
                e = jnp.stack([c, sn], -1)[:, None]
                nrm = jnp.stack([-sn, c], -1)[:, None]
                forces = (fb[..., :1] * e + fb[..., 1:] * nrm).reshape(-1, 2)
            np.testing.assert_allclose(np.asarray(vel), np.asarray(ref.velocity), atol=1e-12)
            np.testing.assert_allclose(np.asarray(om), np.asarray(ref.omega), atol=1e-13)
            np.testing.assert_allclose(np.asarray(forces), np.asarray(ref.forces), atol=1e-11)
            # each swimmer force- and torque-free (about its middle sphere), so the school too
            fs = np.asarray(forces).reshape(s, 3, 2)
            rel = (
                np.asarray(forcefree.sphere_centres(centre, tilt, arms))
                - np.asarray(centre)[:, None]
            )
            assert np.abs(fs.sum(1)).max() < 1e-12
            assert (
                np.abs((rel[..., 0] * fs[..., 1] - rel[..., 1] * fs[..., 0]).sum(1)).max() < 1e-11
            )


def test_one_and_two_swimmers_keep_their_numbers():
    # The school code is the only code: one swimmer and a pair give the numbers they gave before
    # it (commit 05c762b, the pair's own Python-unrolled solves), to the last bit in the free
    # fluid (a pair alternating square cycles, 30 a apart, float64), to a few ulp: XLA's CPU code
    # (vector width, fused multiply-adds) differs between processors, and so do the last bits
    # (the lone swimmer's x is 0.1720914395640445, 1 ulp off, on an AMD EPYC)
    from jswim.env import scene_rollout

    lone = scene_rollout("ng", [(1, -1), (2, -1), (1, 1), (2, 1)], Scene(medium="free"))
    assert lone.x[-1, 0] == pytest.approx(0.17209143956404405, rel=1e-14, abs=0)
    moves = [(s, d, k) for d, k in [(1, -1), (2, -1), (1, 1), (2, 1)] for s in (1, 2)] * 2
    pair = scene_rollout("ng", moves, Scene(medium="free", swimmers=2, separation=30.0))
    np.testing.assert_allclose(
        pair.x[-1], [0.34236806285915594, 30.342368062859176], rtol=1e-14, atol=0
    )
    # the numbers were recorded with the Rotne-Prager-Blake self term, the default then (the
    # exact one, the default now, moves the pair's x by 7e-6 at h = 10: docs/scenes.md)
    wall = scene_rollout(
        "ng",
        moves,
        Scene(medium="wall", swimmers=2, separation=30.0, height=10.0, self_mobility="rpb"),
    )
    np.testing.assert_allclose(
        wall.x[-1], [0.3321212518703214, 30.332091498616528], atol=0, rtol=1e-14
    )
    np.testing.assert_allclose(
        wall.tilt[-1], [-0.002504793702242466, -0.002518806917165861], atol=0, rtol=1e-13
    )
