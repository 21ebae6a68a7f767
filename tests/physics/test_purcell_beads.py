"""The bead model of Purcell's swimmer (``jswim.swimmers.purcell_beads``) against independent
numbers: the 3-D wall blocks against jswim's tested x-z RPB blocks and RPB self terms, symmetry
of the grand mobility, a straight rod's drag against slender-body theory, symmetry of the
in-plane motion, and the scene option against the module's own cycle."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jswim.errors import ConfigError
from jswim.swimmers import mobility, purcell_beads


@pytest.fixture(autouse=True)
def _x64():
    with jax.enable_x64(True):
        yield


def test_wall_blocks_in_the_xz_plane_are_rpb_entries():
    # beads of radius 1 at heights zi, zj, offset along x: the (x, z) entries are rpb_entries'
    # wall part (rpb_entries minus the unbounded RPY)
    for rx, zi, zj in ((2.5, 1.5, 3.0), (-4.0, 2.0, 1.2), (0.3, 5.0, 2.5)):
        w = np.asarray(purcell_beads.rpb_wall_blocks(jnp.array([rx, 0.0]), zi, zj, 1.0))
        full = [float(v) for v in mobility.rpb_entries(*(jnp.asarray(v) for v in (rx, zi, zj)))]
        free = [float(v) for v in mobility.rpy_entries(jnp.asarray(rx), jnp.asarray(zi - zj))]
        np.testing.assert_allclose(
            [w[0, 0], w[0, 2], w[2, 0], w[2, 2]],
            [full[0] - free[0], full[1] - free[1], full[2] - free[1], full[3] - free[2]],
            atol=1e-13,
        )
        assert abs(w[1, 0]) < 1e-15 and abs(w[0, 1]) < 1e-15  # y decouples for an x offset


def test_wall_blocks_rotate_about_the_normal_and_scale_with_radius():
    rng = np.random.default_rng(3)
    for _ in range(5):
        rho = rng.normal(size=2) * 3
        zi, zj, b = 1.0 + rng.random() * 3, 1.0 + rng.random() * 3, 0.3 + rng.random()
        ang = rng.random() * 2 * math.pi
        c, s = math.cos(ang), math.sin(ang)
        rot = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
        w = np.asarray(purcell_beads.rpb_wall_blocks(jnp.asarray(rho), zi, zj, b))
        w_rot = np.asarray(purcell_beads.rpb_wall_blocks(jnp.asarray(rot[:2, :2] @ rho), zi, zj, b))
        np.testing.assert_allclose(w_rot, rot @ w @ rot.T, atol=1e-13)
        w1 = np.asarray(purcell_beads.rpb_wall_blocks(jnp.asarray(rho / b), zi / b, zj / b, 1.0))
        np.testing.assert_allclose(w, w1 / b, atol=1e-12)
    # the self limit: Blake's self terms (RPB) at equal points, 1 + wall part = the RPB factors
    h = 2.7
    w = np.asarray(purcell_beads.rpb_wall_blocks(jnp.array([0.0, 0.0]), h, h, 1.0))
    par, nor = mobility.wall_self_factors(1 / h, "rpb")
    np.testing.assert_allclose([1 + w[0, 0], 1 + w[1, 1], 1 + w[2, 2]], [par, par, nor], atol=1e-14)


@pytest.mark.slow  # three mobilities compiled: ~5 s
def test_grand_mobility_symmetric_positive_definite():
    pos, _ = purcell_beads.bead_frame(jnp.array([0.7, -0.4]), jnp.zeros(2), 12)
    for wall, h in ((False, 1.0), (True, 0.05), (True, 0.5)):
        m = np.asarray(purcell_beads.grand_mobility(pos, jnp.asarray(h), 0.02, wall))
        assert np.abs(m - m.T).max() < 1e-10 * np.abs(m).max()
        assert np.linalg.eigvalsh(m).min() > 0


@pytest.mark.slow  # a 1800-row mobility built and inverted: ~8 s
def test_straight_rod_drag_ratio_is_slender_body_theory():
    # a straight chain (hinges at 0) dragged rigidly: resistance along and across against
    # slender-body theory's 2 pi mu l / (ln(l/b) - 1/2) and 4 pi mu l / (ln(l/b) + 1/2) to the
    # order its constants hold (Batchelor 1970; here in units of 6 pi mu): the ratio within 5 %
    b, m = 0.01, 200
    pos, _ = purcell_beads.bead_frame(jnp.zeros(2), jnp.zeros(2), m)
    mob = np.asarray(purcell_beads.grand_mobility(pos, jnp.asarray(1.0), b, False))
    res = np.linalg.inv(mob)
    n = pos.shape[0]
    ex = np.tile([1.0, 0, 0], n)
    ey = np.tile([0, 1.0, 0], n)
    along, across = ex @ res @ ex, ey @ res @ ey
    big = math.log(3.0 / b)  # the rod is 3 links long here
    sbt = 2 * (big - 0.5) / (big + 0.5)
    assert abs(across / along / sbt - 1) < 0.05


@pytest.mark.slow  # three bead solves compiled: ~11 s under load
def test_in_plane_motion_has_no_out_of_plane_part_in_the_bulk_and_is_linear_in_rates():
    d = jnp.array([0.6, -0.3])
    q = np.asarray(purcell_beads.body_rates(d, jnp.array([1.0, 0.0]), 1.0, 8, 0.02, False))
    assert np.abs(q[3:]).max() < 1e-12  # no heave, roll or pitch without the wall
    q2 = np.asarray(purcell_beads.body_rates(d, jnp.array([2.0, 0.0]), 1.0, 8, 0.02, False))
    np.testing.assert_allclose(q2, 2 * q, atol=1e-12)
    qw = np.asarray(purcell_beads.body_rates(d, jnp.array([1.0, 0.0]), 0.3, 8, 0.02, True))
    assert np.abs(qw[3:]).max() > 1e-6  # the wall gives them


def test_bad_options_are_one_line_errors():
    for kw in (dict(height=0.03), dict(height=1.0, link_radius=0.5), dict(height=1.0, beads=2)):
        with pytest.raises(ConfigError):
            purcell_beads.wall_model(**kw)


@pytest.mark.slow  # the motion table's 1681 bead solves and the cycle's compile: ~1 min
def test_scene_option_beads_matches_the_modules_cycle():
    from jswim.env import scene_rollout
    from jswim.scenes import Scene

    r = scene_rollout(
        "purcell",
        [(2, -1), (1, -1), (2, 1), (1, 1)],
        Scene(medium="wall", height=1.5),
        wall_model="beads",
        beads=8,
        link_radius=0.02,
    )
    x = float(purcell_beads.square_cycle(jnp.asarray(1.5), m=8, b=0.02, steps=64)[0])
    assert abs(float(r.x[-1, 0]) - x) < 1e-7 and float(r.z[-1, 0]) == 1.5


@pytest.mark.slow  # three cycles of a small chain compiled twice: ~1 min under load
def test_far_wall_effect_falls_faster_than_one_over_h():
    # force-free: the links' Stokeslet images cancel at O(l/h) and the in-plane dipole term by
    # symmetry, so X(h) - X_bulk falls as h^-3 (local RFT's as h^-1)
    cyc = lambda h, wall: float(
        purcell_beads.square_cycle(jnp.asarray(h), m=8, b=0.02, wall=wall, steps=8)[0]
    )
    bulk = cyc(1.0, False)
    d20, d40 = cyc(20.0, True) - bulk, cyc(40.0, True) - bulk
    p = math.log(d20 / d40) / math.log(2.0)
    assert d20 > 0 and d40 > 0 and abs(p - 3.0) < 0.05
