"""Worlds in a background flow. A uniform flow is exact (Galilean invariance through `jswim.make`
and `jswim.rollout`: every stroke moves as in still fluid plus u t, with the same orientation, on
the paper's corner table, the K lattice, float ROC vectors, with noise, and in the navigation
world; float64 to 1e-12 and the default float32). The other flows step from the flow tables
(`jswim.env.flow_tables`, `jswim.env.flow_steps`), checked against the RK4 reference
(`jswim.env.stepping.flow_step`, or a world in an `Integrated` flow): single steps on every table
row, 200-step trajectories of the square gait and of the navigation world in the study flows at
0.5 and 0.9 of the swimming speed, the order of the corrector, Jeffery's orbit, the tables' own
identities (Galilean columns, a rigidly rotating fluid, converged quadratures, the wave form
against the Taylor form), float32 and batches. Tolerances are about 3 x the errors measured
(docs/physics.md, "Background flows"). And the one-line refusals of what does not step yet."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jswim
from jswim.env.flow_steps import Integrated, flow_increment, sincos, small_sincos, tabulated
from jswim.env.flow_tables import _moves, flow_table, step_flow_map, step_wave_map
from jswim.env.flows import (
    Flow,
    Poiseuille,
    Shear,
    TaylorGreen,
    Uniform,
    flow_from_dict,
    study_flow,
)
from jswim.env.step_tables import lattice_table, step_rows
from jswim.env.stepping import FLOW_SUBSTEPS, flow_step
from jswim.env.targets import FixedTarget
from jswim.errors import ConfigError
from jswim.integrate import integrate_stroke
from jswim.scenes import Scene
from jswim.swimmers.models import make_model

U = (0.02, -0.011)


def _positions(env, params, actions, key=0):
    traj = jswim.rollout(env, params, jax.random.PRNGKey(key), jnp.asarray(actions))
    obs = traj.obs
    return np.asarray(obs.position[..., 0, :]), np.asarray(obs.orientation[..., 0])


CASES = {
    "corner table, noise": (dict(zeta=0.5), [1, 3, 0, 2, 4, 1, 5, 3]),
    "K = 2 lattice": (dict(roc_levels=2), [1, 6, 3, 8, 0, 9, 2, 7]),
    "float ROC vectors": (dict(), [[0.4, 0.0], [0.0, -0.7], [-1.0, 0.0], [0.0, 0.3]]),
    "navigation": (dict(roc_levels=2, target=FixedTarget(3.0, 90.0)), [1, 6, 3, 8, 0, 9]),
}


@pytest.mark.parametrize("case", CASES, ids=list(CASES))
def test_a_uniform_flow_adds_exactly_u_t_to_any_stroke(case):
    options, actions = CASES[case]
    still = _positions(*jswim.make("purcell", **options), actions)
    moved = _positions(*jswim.make("purcell", flow=Uniform(U), **options), actions)
    t = np.arange(1, len(actions) + 1)[:, None]  # one tau per step
    np.testing.assert_allclose(moved[0], still[0] + t * np.asarray(U), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(moved[1], still[1])  # the flow turns nothing


def test_the_same_holds_in_the_default_float32(float32):
    options, actions = CASES["K = 2 lattice"]
    still = _positions(*jswim.make("purcell", **options), actions)
    moved = _positions(*jswim.make("purcell", flow=Uniform(U), **options), actions)
    assert moved[0].dtype == np.float32
    t = np.arange(1, len(actions) + 1)[:, None]
    np.testing.assert_allclose(moved[0], still[0] + t * np.asarray(U), rtol=0, atol=2e-7)


def test_a_batch_of_swimmers_drifts_together():
    env, params = jswim.make("purcell", roc_levels=2, flow=Uniform(U))
    actions = jnp.asarray(np.random.default_rng(0).integers(0, env.n_actions, (64, 12)))
    still_env, still_params = jswim.make("purcell", roc_levels=2)
    moved = jswim.rollout(env, params, jax.random.PRNGKey(3), actions).obs.position
    still = jswim.rollout(still_env, still_params, jax.random.PRNGKey(3), actions)
    drift = np.asarray(moved - still.obs.position)[:, -1, 0, :]
    np.testing.assert_allclose(drift, np.broadcast_to(12 * np.asarray(U), (64, 2)), atol=1e-12)


@pytest.mark.parametrize(
    "wall_model",
    ["local-rft", pytest.param("beads", marks=pytest.mark.slow)],  # beads: a minute of tables
)
def test_the_wall_s_shear_in_purcell_s_plane_adds_exactly_u_t(wall_model):
    # u = (rate z, 0) keeps no-slip; in the plane at height h it is the stream (rate h, 0), and
    # every element's drag is against its velocity relative to it: the body moves at it.
    rate, h = 0.004, 2.0
    scene = Scene(medium="wall", height=h)
    options, actions = CASES["corner table, noise"]
    moved = _positions(
        *jswim.make(
            "purcell", scene, flow=Uniform((rate * h, 0.0)), wall_model=wall_model, **options
        ),
        actions,
    )
    still = _positions(*jswim.make("purcell", scene, wall_model=wall_model, **options), actions)
    t = np.arange(1, len(actions) + 1)
    want = np.stack([rate * h * t, np.zeros(len(t))], -1)
    np.testing.assert_allclose(moved[0] - still[0], want, rtol=0, atol=1e-12)
    np.testing.assert_array_equal(moved[1], still[1])


def _line_drift(swimmer: str, ux: float = -0.013) -> tuple[np.ndarray, np.ndarray]:
    """A line swimmer's 12 noisy steps in a stream ``(ux, 0)`` less the same in still fluid, and
    ``u t``."""
    env, params = jswim.make(swimmer, flow=Uniform((ux, 0.0)), zeta=0.5)
    still_env, still_params = jswim.make(swimmer, zeta=0.5)
    actions = jnp.asarray(np.random.default_rng(2).integers(0, 4, 12))
    moved = _positions(env, params, actions)[0]
    still = _positions(still_env, still_params, actions)[0]
    assert moved.dtype == still.dtype == jnp.zeros(()).dtype
    drift = moved.astype(np.float64) - still
    return drift, np.stack([ux * np.arange(1, 13), np.zeros(12)], -1)


@pytest.mark.parametrize("swimmer", ["ng", "nsphere"])
def test_a_stream_along_a_line_swimmer_adds_exactly_u_t(swimmer):
    # A stream along the line carries every sphere at u: the force-free body too, whatever the
    # mobility. The paper's noise stays on the stroke's own displacement.
    drift, want = _line_drift(swimmer)
    np.testing.assert_allclose(drift, want, rtol=0, atol=1e-12)


def test_a_stream_along_a_line_swimmer_in_the_default_float32(float32):
    drift, want = _line_drift("ng")
    np.testing.assert_allclose(drift, want, rtol=0, atol=2e-6)


@pytest.mark.parametrize(
    "call, says",
    [
        (lambda: jswim.make("purcell", diagonal=True, flow=Shear(0.1)), "diagonal strokes"),
        (
            lambda: jswim.make("purcell", diagonal=True, flow=Integrated(Shear(0.1))),
            "uniform flow only, not in Integrated",
        ),
        (
            lambda: jswim.make("purcell", Scene(medium="bulk", swimmers=2), flow=Uniform(U)),
            "swims alone",
        ),
        (lambda: flow_from_dict({"kind": "uniform", "u": 3}), "Uniform flow u must be"),
        (lambda: jswim.make("ng", flow=Uniform(U)), "moves on a line"),
        (lambda: jswim.make("nsphere", flow=Shear(0.01)), "takes a Uniform"),
        (lambda: jswim.make("purcell", flow=(0.02, 0.0)), "jswim.env.flows flow"),
        (
            lambda: jswim.make("purcell", Scene(medium="wall", height=2.0), flow=Shear(0.01)),
            "keeps no-slip",
        ),
        (
            lambda: jswim.make("ng", Scene(medium="free", swimmers=2), flow=Uniform(U)),
            "sphere scene",
        ),
        (
            lambda: jswim.make("ng", Scene(medium="wall", height=5.0), flow=Uniform((0.01, 0.0))),
            "sphere scene",
        ),
    ],
)
def test_what_does_not_step_in_a_flow_is_refused_in_one_line(call, says):
    with pytest.raises(ConfigError, match=says) as err:
        call()
    assert "\n" not in str(err.value)


def test_still_fluid_is_the_default_and_the_params_say_so():
    _, params = jswim.make("purcell")
    assert params.flow is None
    _, params = jswim.make("purcell", flow=Uniform(U))
    assert params.flow == Uniform(U) and hash(params.flow) == hash(Uniform(U))


def _hold_straight_in(flow, steps=6):
    """Purcell's swimmer taken to the K = 2 lattice's centre (straight: both hinges at 0), then
    held (ROC 0) for ``steps`` steps in ``flow``: its orientations and centroids after each."""
    env, params = jswim.make("purcell", roc_levels=2, flow=flow)
    hold = 2  # DOF 1, k = 0
    actions = [1, 6] + [hold] * steps  # D1 then D2 by -1/2 of the range: the straight shape
    place, angle = _positions(env, params, actions)
    return place[2:], angle[2:], place[1], angle[1]


@pytest.mark.slow  # compiles the flow-integrated step (16 RK4 pieces, unrolled)
@pytest.mark.parametrize("integrated, tol", [(True, 1e-10), (False, 5e-7)], ids=["rk4", "tables"])
def test_a_straight_swimmer_held_in_shear_tumbles_on_jeffery_s_orbit(integrated, tol):
    gamma = 0.05
    flow = Integrated(Shear(gamma)) if integrated else Shear(gamma)
    place, angle, place0, angle0 = _hold_straight_in(flow)
    # d phi / dt = -gamma sin^2 phi: cot(phi) grows by gamma each step (one tau). The tables are
    # second order in the flow (gamma tau = 0.05 is a strong shear: 3.4e-6 of it per step).
    cot = 1.0 / np.tan(np.concatenate([[angle0], angle]))
    np.testing.assert_allclose(np.diff(cot), gamma, rtol=0, atol=tol)
    # the centroid (the middle link's centre: the rod is symmetric) is carried at gamma y
    y0 = place0[1]
    np.testing.assert_allclose(place[:, 1], y0, atol=1e-12)
    np.testing.assert_allclose(
        np.diff(np.concatenate([[place0[0]], place[:, 0]])), gamma * y0, atol=1e-12
    )


# The fast tier keeps one zero flow; the others compile their own tables (the slow tier).
@pytest.mark.parametrize(
    "flow",
    [
        Shear(0.0),
        pytest.param(Poiseuille(0.0, 3.0), marks=pytest.mark.slow),
        pytest.param(TaylorGreen(0.0, 6.0), marks=pytest.mark.slow),
    ],
    ids=["shear", "poiseuille", "taylor-green"],
)
def test_a_still_flow_through_the_tables_is_the_exact_table(flow):
    # Bit for bit on the lattice, which steps in float64 pairs with or without a flow. The corner
    # world's still-fluid step works in the session's dtype and its flow step in float64 pairs,
    # so they may part by an ulp (1.7e-18 a after 8 steps here, depending on what ran before).
    for case, atol in (("corner table, noise", 1e-16), ("K = 2 lattice", 0.0)):
        options, actions = CASES[case]
        still = _positions(*jswim.make("purcell", **options), actions)
        zero = _positions(*jswim.make("purcell", flow=flow, **options), actions)
        np.testing.assert_allclose(zero[0], still[0], rtol=0, atol=atol)
        np.testing.assert_allclose(zero[1], still[1], rtol=0, atol=atol)


@pytest.mark.slow  # compiles the flow-integrated step (16 RK4 pieces, unrolled)
def test_a_still_flow_integrated_step_by_step_is_the_exact_table():
    options, actions = CASES["K = 2 lattice"]
    still = _positions(*jswim.make("purcell", **options), actions)
    zero = _positions(*jswim.make("purcell", flow=Integrated(Shear(0.0)), **options), actions)
    np.testing.assert_allclose(zero[0], still[0], rtol=0, atol=1e-6)
    np.testing.assert_allclose(zero[1], still[1], rtol=0, atol=1e-6)


# Taylor-Green, the flow whose gradient varies most along a link, stays in the fast tier.
@pytest.mark.parametrize(
    "flow",
    [
        pytest.param(Shear(0.05), marks=pytest.mark.slow),
        pytest.param(Poiseuille(0.03, 4.0), marks=pytest.mark.slow),
        TaylorGreen(0.04, 10.0),
    ],
    ids=["shear", "poiseuille", "taylor-green"],
)
def test_the_flow_step_has_converged(flow):
    s0, s1, pose = jnp.asarray([1.0, 1.0]), jnp.asarray([0.0, 1.0]), jnp.asarray([0.3, 0.7, 0.2])
    coarse = flow_step(MODEL, flow, s0, s1, pose)
    fine = flow_step(MODEL, flow, s0, s1, pose, substeps=4 * FLOW_SUBSTEPS)
    np.testing.assert_allclose(np.asarray(coarse), np.asarray(fine), rtol=0, atol=1e-7)


NAV = dict(roc_levels=2, target=FixedTarget(3.0, 90.0))


def test_navigation_steps_in_every_flow_in_float32_as_in_float64():
    actions = np.random.default_rng(2).integers(0, 10, 60)
    for flow in (
        study_flow("shear", 0.9),
        study_flow("poiseuille", 0.9),
        study_flow("taylor-green", 0.9),
    ):
        env, params = jswim.make("purcell", flow=flow, **NAV)
        wide = _positions(env, params, actions)
        with jax.enable_x64(False):
            env, params = jswim.make("purcell", flow=flow, **NAV)
            place, angle = _positions(env, params, actions)
        assert place.dtype == np.float32 and angle.dtype == np.float32
        # the same float64 step; the observation rounds the pose to float32 (~5e-7 at 8 a)
        np.testing.assert_allclose(place, wide[0], rtol=0, atol=2e-6)
        np.testing.assert_allclose(angle, wide[1], rtol=0, atol=2e-7)


def test_a_batch_in_a_flow_steps_as_each_swimmer_alone():
    flow = study_flow("taylor-green", 0.9)
    env, params = jswim.make("purcell", flow=flow, **NAV)
    actions = np.random.default_rng(4).integers(0, env.n_actions, (8, 20))
    batch = jswim.rollout(env, params, jax.random.PRNGKey(5), jnp.asarray(actions))
    keys = jax.random.split(jax.random.PRNGKey(5), 8)
    for i in (0, 5):
        one = jswim.rollout(env, params, keys[i], jnp.asarray(actions[i]))
        np.testing.assert_allclose(
            np.asarray(batch.obs.position[i]), np.asarray(one.obs.position), rtol=0, atol=1e-12
        )


# --- the flow tables against the RK4 reference ---------------------------------------------

MODEL = make_model("purcell")

#: The study flows (`study_flow`), each with a fraction of the swimming speed.
STUDY = {
    f"{name} {frac}": (study_flow(kind, frac, length), frac)
    for frac in (0.5, 0.9)
    for name, kind, length in (
        ("shear", "shear", 3.0),
        ("poiseuille", "poiseuille", 3.0),
        ("tg6", "taylor-green", 3.0),
        ("tg10", "taylor-green", 5.0),
    )
}

#: Single steps, every row of both tables at 4 random poses each in [-3, 3]^2: the largest error
#: of the centroid (a) and the orientation (rad) measured, times ~3.
STEP_TOL = {
    "shear 0.5": (5e-6, 5e-6),
    "poiseuille 0.5": (1e-6, 1e-6),
    "tg6 0.5": (1.2e-5, 1.8e-5),
    "tg10 0.5": (6e-6, 6e-6),
    "shear 0.9": (2e-5, 1.6e-5),
    "poiseuille 0.9": (4e-6, 4e-6),
    "tg6 0.9": (4e-5, 6e-5),
    "tg10 0.9": (2e-5, 2e-5),
}


def _still_entries(roc_levels):
    """The still-fluid table row of every flow row (`_moves` order)."""
    if roc_levels is not None:
        start, end, _ = _moves(MODEL, roc_levels)
        j0, j1 = np.rint(start * roc_levels), np.rint(end * roc_levels)
        n, width = MODEL.n_dof, roc_levels + 1
        dof = np.tile(
            np.repeat(np.arange(n), 2 * roc_levels + 1), len(start) // (n * (2 * roc_levels + 1))
        )
        shape = (j0 * width ** np.arange(n)).sum(axis=1)
        row = (shape * n + dof) * width + j1[np.arange(len(j1)), dof]
        return np.asarray(lattice_table(MODEL, roc_levels))[row.astype(int)]
    inc = np.asarray(step_rows(MODEL))[:-1].reshape(-1, MODEL.n_dof, 5)
    hold = np.array([[0.0, 0.0, 0.0, 1.0, 0.0]])
    return np.concatenate([np.concatenate([c, hold]) for c in inc])


def _step_errors(flow, roc_levels, reps=4, seed=0, reference=None):
    """Largest centroid and orientation errors of table steps against RK4 (lab frame)."""
    start, end, duration = _moves(MODEL, roc_levels)
    s0, s1, t = np.tile(start, (reps, 1)), np.tile(end, (reps, 1)), np.tile(duration, reps)
    entries = jnp.asarray(np.tile(_still_entries(roc_levels), (reps, 1)))
    rows = jnp.asarray(np.tile(flow_table(MODEL, flow, roc_levels), (reps, 1)))
    rng = np.random.default_rng(seed)
    n = len(s0)
    poses = np.stack(
        [rng.uniform(-3, 3, n), rng.uniform(-3, 3, n), rng.uniform(-np.pi, np.pi, n)], -1
    )
    ref = jax.jit(
        jax.vmap(lambda a, b, p, t: flow_step(MODEL, reference or flow, a, b, p, duration=t))
    )(s0, s1, poses, t)

    def table(row, entry, p):
        c, s = jnp.cos(p[2]), jnp.sin(p[2])
        fx, fy, turn, _, _ = flow_increment(flow, tuple(row), entry[:2], p[0], p[1], c, s)
        bx, by = entry[0] + fx, entry[1] + fy
        return jnp.stack([c * bx - s * by, s * bx + c * by, entry[2] + turn])

    err = np.asarray(jax.jit(jax.vmap(table))(rows, entries, poses)) - np.asarray(ref)
    return float(np.hypot(err[:, 0], err[:, 1]).max()), float(np.abs(err[:, 2]).max())


@pytest.mark.parametrize(
    "name, roc_levels",
    [
        pytest.param(k, r, marks=[] if (k, r) == ("tg6 0.9", 2) else pytest.mark.slow)
        for k in STUDY
        for r in (None, 2)
    ],
    ids=lambda v: {None: "corners", 2: "K=2"}.get(v, v) if not isinstance(v, str) else v,
)
def test_a_table_step_matches_the_rk4_reference_on_every_row(name, roc_levels):
    flow, _ = STUDY[name]
    pos, ang = _step_errors(flow, roc_levels)
    tol_pos, tol_ang = STEP_TOL[name]
    assert pos < tol_pos and ang < tol_ang, (pos, ang)


@pytest.mark.slow
def test_the_corrector_is_second_order_and_exact_to_it_for_a_held_shape():
    # Halving the flow divides a held shape's error by 8 (third order left), a moving one's by
    # about 4 (what the response's change within the stroke leaves of the second order).
    def errors(scale):
        flow = TaylorGreen(0.9 * scale * jswim.env.flows.SWIM_SPEED, 10.0)
        start, end, _ = _moves(MODEL, 2)
        hold = np.all(start == end, axis=1)
        out = {}
        for label, pick in (("hold", hold), ("move", ~hold)):
            out[label] = _masked_error(flow, pick)
        return out

    big, small = errors(1.0), errors(0.5)
    assert big["hold"] / small["hold"] > 6.5
    assert 3.0 < big["move"] / small["move"] < 6.0


def _masked_error(flow, pick):
    start, end, duration = _moves(MODEL, 2)
    rows = jnp.asarray(flow_table(MODEL, flow, 2)[pick])
    entries = jnp.asarray(_still_entries(2)[pick])
    s0, s1, t = start[pick], end[pick], duration[pick]
    rng = np.random.default_rng(7)
    n = len(s0)
    poses = np.stack(
        [rng.uniform(-5, 5, n), rng.uniform(-5, 5, n), rng.uniform(-np.pi, np.pi, n)], -1
    )
    ref = jax.vmap(lambda a, b, p, t: flow_step(MODEL, flow, a, b, p, 32, duration=t))(
        s0, s1, poses, t
    )

    def table(row, entry, p):
        c, s = jnp.cos(p[2]), jnp.sin(p[2])
        fx, fy, turn, _, _ = flow_increment(flow, tuple(row), entry[:2], p[0], p[1], c, s)
        return jnp.stack([c * fx - s * fy, s * fx + c * fy, turn])

    still = jax.vmap(
        lambda e, p: jnp.stack(
            [
                jnp.cos(p[2]) * e[0] - jnp.sin(p[2]) * e[1],
                jnp.sin(p[2]) * e[0] + jnp.cos(p[2]) * e[1],
                e[2],
            ]
        )
    )
    got = jax.vmap(table)(rows, entries, poses) + still(entries, poses)
    return float(np.abs(np.asarray(got) - np.asarray(ref)).max())


#: 200 steps, the table world against the same world in the `Integrated` flow (RK4): the largest
#: centroid (a) and orientation (rad) errors along the trajectory measured, times ~3.
TRAJECTORY_TOL = {
    ("square", "shear 0.5"): (3e-5, 2e-6),
    ("square", "poiseuille 0.5"): (1.3e-5, 1e-7),
    ("square", "tg6 0.5"): (1.6e-4, 2e-5),
    ("square", "tg10 0.5"): (1e-4, 6e-6),
    ("square", "shear 0.9"): (1e-4, 1.3e-5),
    ("square", "poiseuille 0.9"): (1.3e-5, 1e-7),
    ("square", "tg6 0.9"): (7e-4, 2.6e-4),
    ("square", "tg10 0.9"): (3e-4, 3e-5),
    ("navigation", "shear 0.5"): (2e-6, 4e-6),
    ("navigation", "poiseuille 0.5"): (4e-7, 2e-7),
    ("navigation", "tg6 0.5"): (8e-5, 2e-5),
    ("navigation", "tg10 0.5"): (1.1e-5, 1e-5),
    ("navigation", "shear 0.9"): (5e-6, 4e-5),
    ("navigation", "poiseuille 0.9"): (4e-7, 2e-7),
    ("navigation", "tg6 0.9"): (7e-4, 5e-5),
    ("navigation", "tg10 0.9"): (1.7e-4, 3e-5),
}

#: The paper's square gait from (hi, hi) on the corner table: DOF 2 down, 1 down, 2 up, 1 up.
SQUARE = [3, 0, 5, 2]


@pytest.mark.slow  # two worlds compiled per case, one of them the unrolled RK4 step
@pytest.mark.parametrize(
    "world, name", list(TRAJECTORY_TOL), ids=[f"{w} {n}" for w, n in TRAJECTORY_TOL]
)
def test_two_hundred_steps_through_the_tables_follow_the_rk4_reference(world, name):
    flow, _ = STUDY[name]
    if world == "square":
        options, actions = {}, SQUARE * 50
    else:
        options, actions = NAV, np.random.default_rng(1).integers(0, 10, 200)
    fast = _positions(*jswim.make("purcell", flow=flow, **options), actions)
    ref = _positions(*jswim.make("purcell", flow=Integrated(flow), **options), actions)
    tol_pos, tol_ang = TRAJECTORY_TOL[world, name]
    assert np.abs(fast[0] - ref[0]).max() < tol_pos
    assert np.abs(fast[1] - ref[1]).max() < tol_ang


# --- the tables' own identities ------------------------------------------------------------

MOVES = [((1.0, 1.0), (0.0, 1.0)), ((0.5, 0.0), (0.5, 1.0)), ((0.5, 0.5), (0.5, 0.5))]


@pytest.mark.parametrize("s0, s1", MOVES, ids=["corner move", "lattice move", "hold"])
def test_the_first_order_map_carries_uniform_and_rigidly_rotating_fluid_rigidly(s0, s1):
    s0, s1 = jnp.asarray(s0), jnp.asarray(s1)
    tmat, e, e_c, o1 = step_flow_map(MODEL, s0, s1)
    # Galilean invariance: a uniform flow moves the reference point by u and turns nothing
    np.testing.assert_allclose(np.asarray(tmat[:, :2]), [[1, 0], [0, 1], [0, 0]], atol=1e-14)
    # fluid turning rigidly at omega about e turns the body with it: the step ends turned by
    # omega, its end point p(1) (the still stroke's) carried round e
    omega = 0.01
    coef = jnp.zeros(14).at[3].set(-omega).at[4].set(omega)  # G = omega J
    span = MODEL.hi - MODEL.lo
    d0 = MODEL.lo + span * s0
    end = integrate_stroke(MODEL, d0, (s1 - s0) * span, 1.0, n_sub=32)
    p1 = end[:2]
    expected = [-omega * (p1[1] - e[1]), omega * (p1[0] - e[0]), omega]
    np.testing.assert_allclose(np.asarray(tmat @ coef), np.asarray(expected), rtol=0, atol=1e-15)
    # the expansion point from the start centroid, and the end centroid about the end point
    np.testing.assert_allclose(
        np.asarray(e - e_c), np.asarray(MODEL.centroid_offset(d0)), atol=1e-15
    )
    off1 = MODEL.centroid_offset(MODEL.lo + span * s1)
    c, s = jnp.cos(end[2]), jnp.sin(end[2])
    rotated = [c * off1[0] - s * off1[1], s * off1[0] + c * off1[1]]
    np.testing.assert_allclose(np.asarray(o1), np.asarray(rotated), rtol=0, atol=1e-14)


@pytest.mark.slow  # compiles the degree-48 quadrature of every row
def test_the_rows_quadratures_have_converged():
    s0, s1 = jnp.asarray([1.0, 0.5]), jnp.asarray([0.0, 0.5])
    coarse, fine = step_flow_map(MODEL, s0, s1), step_flow_map(MODEL, s0, s1, degree=48)
    for a, b in zip(coarse, fine):
        np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=0, atol=1e-14)
    k = np.sqrt(2) * np.pi / 6.0
    waves = step_wave_map(MODEL, s0, s1, k)[0]
    finer = step_wave_map(MODEL, s0, s1, k, angles=128, degree=48)[0]
    np.testing.assert_allclose(np.asarray(waves), np.asarray(finer[:32]), rtol=0, atol=1e-14)
    # the harmonics fall as J_n(K L): 1e-6 of the largest by n = 8 in a cell of 6 a
    size = np.abs(np.asarray(waves)).max(axis=1)
    assert size[9:].max() < 1e-6 * size.max()


class _TaylorModel(Flow):
    """A Taylor-Green cell seen by the tables through its velocity, gradient and hessian only."""

    def __init__(self, cell: TaylorGreen) -> None:
        self.cell = cell

    def velocity(self, x):
        return self.cell.velocity(x)

    def gradient(self, x):
        return self.cell.gradient(x)

    def hessian(self, x):
        return self.cell.hessian(x)

    def __hash__(self):
        return hash(("taylor", self.cell))

    def __eq__(self, other):
        return isinstance(other, _TaylorModel) and other.cell == self.cell


@pytest.mark.slow
def test_the_wave_form_agrees_with_the_taylor_form_where_that_holds_and_not_in_small_cells():
    wide = TaylorGreen(0.04, 200.0)  # L / cell = 0.015: the Taylor model's (L/cell)^2 is 2e-4
    assert tabulated(_TaylorModel(wide))
    waves = _step_errors(wide, 2, reps=1, seed=3)
    taylor = _step_errors(_TaylorModel(wide), 2, reps=1, seed=3, reference=wide)
    assert max(waves) < 2e-7 and max(taylor) < 2e-7
    # in a cell of 6 a the Taylor model is off by ~10 % of the flow's turn, the waves by 1e-3
    small = TaylorGreen(0.043, 6.0)
    assert max(_step_errors(_TaylorModel(small), 2, reps=1, seed=3, reference=small)) > 1e-3
    assert max(_step_errors(small, 2, reps=1, seed=3)) < 4e-5


def test_the_step_s_trigonometry_is_float64_accurate():
    x = jnp.asarray(np.concatenate([np.linspace(-1e4, 1e4, 100001), np.linspace(-7, 7, 1001)]))
    s, c = sincos(x)
    np.testing.assert_allclose(np.asarray(s), np.sin(np.asarray(x)), rtol=0, atol=3e-16)
    np.testing.assert_allclose(np.asarray(c), np.cos(np.asarray(x)), rtol=0, atol=3e-16)
    for top, tol in ((1.0, 1e-15), (4.0, 1e-10)):
        x = jnp.linspace(-top, top, 1001)
        s, c = small_sincos(x)
        np.testing.assert_allclose(np.asarray(s), np.sin(np.asarray(x)), rtol=0, atol=tol)
        np.testing.assert_allclose(np.asarray(c), np.cos(np.asarray(x)), rtol=0, atol=tol)


def test_integrated_flows_are_hashable_move_the_fluid_alike_and_refuse_bad_fields():
    flow = Integrated(Shear(0.1), substeps=8)
    assert flow == Integrated(Shear(0.1), 8) and hash(flow) == hash(Integrated(Shear(0.1), 8))
    assert flow != Integrated(Shear(0.1)) and not tabulated(flow) and tabulated(Shear(0.1))
    x = jnp.asarray([[0.3, 1.2]])
    np.testing.assert_array_equal(np.asarray(flow.velocity(x)), np.asarray(Shear(0.1).velocity(x)))
    assert flow.speed == 0.1 and flow.to_dict()["flow"] == Shear(0.1).to_dict()
    for bad in (
        lambda: Integrated((0.1, 0.0)),
        lambda: Integrated(flow),
        lambda: Integrated(Shear(0.1), 0),
    ):
        with pytest.raises(ConfigError):
            bad()


def test_a_flow_beyond_the_tables_range_warns_and_its_integrated_form_does_not():
    import warnings

    from jswim.scenes.ranges import ModelRangeWarning

    # TaylorGreen(0.5, 2): gradient u0 pi / cell = 0.79 per step (the study's fastest: 0.023)
    for flow in (Shear(1.0), Poiseuille(0.3, 3.0), TaylorGreen(0.5, 2.0)):
        with pytest.warns(ModelRangeWarning, match="Integrated"):
            jswim.make("purcell", flow=flow)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        jswim.make("purcell", flow=Integrated(Shear(1.0)))
        for kind in ("shear", "poiseuille", "taylor-green"):
            jswim.make("purcell", flow=study_flow(kind, 2.0))  # the largest --flows speed
