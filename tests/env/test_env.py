"""The discrete environment: exact table steps, noise, batching, validation."""

import math

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jswim import env
from jswim.errors import ConfigError
from jswim.integrate import centroid, integrate_stroke
from jswim.swimmers import ng

PURCELL_PLUS_X = [(2, -1), (1, -1), (2, 1), (1, 1)]  # from (+, +), (dof, roc) as in the prompt
NG_PLUS_X = [(1, 1), (2, 1), (1, -1), (2, -1)]  # from (-, -)


@pytest.mark.slow  # compiles the integrator over random walks (32 s under load 8)
def test_table_steps_match_the_integrator_over_random_walks():
    """Every step of a random walk equals a direct RK4 integration of the ODE (<= 1e-9)."""
    params = env.make_params("purcell")
    model = params.model
    rng = np.random.default_rng(3)
    acts = [(int(rng.integers(1, 3)), int(rng.choice([-1, 1]))) for _ in range(12)]
    r = env.rollout_moves("purcell", acts)
    d = np.array([model.hi, model.hi])
    pose = jnp.zeros(3)
    c0 = centroid(model, jnp.asarray(d), pose)  # the env starts with its centroid at the origin
    for i, (dof, roc) in enumerate(acts):
        k = dof - 1
        target = model.hi if roc > 0 else model.lo
        if d[k] != target:
            rate = np.zeros(2)
            rate[k] = roc
            pose = integrate_stroke(
                model,
                jnp.asarray(d),
                jnp.asarray(rate),
                model.duration,
                pose,
                method="rk4",
                n_sub=96,
            )
            d[k] = target
        c = centroid(model, jnp.asarray(d), pose) - c0
        assert abs(float(r.x[i]) - float(c[0])) <= 1e-9 * max(1.0, abs(float(c[0])))
        assert abs(float(r.y[i]) - float(c[1])) <= 1e-9
        assert abs(float(r.orientation[i]) - float(pose[2])) <= 1e-9


@pytest.mark.parametrize("d_max, ref", [(math.pi / 4, 0.12660803), (math.pi / 3, 0.19124724)])
def test_purcell_cycle_reference(d_max, ref):
    r = env.rollout_moves("purcell", PURCELL_PLUS_X * 3, d_max=d_max)
    x = np.asarray(r.x)
    np.testing.assert_allclose(x[3::4], ref * np.arange(1, 4), atol=2e-8)
    np.testing.assert_allclose(np.asarray(r.orientation)[3::4], 0.0, atol=1e-12)
    back = env.rollout_moves("purcell", [(d, -s) for d, s in reversed(PURCELL_PLUS_X)], d_max=d_max)
    assert float(back.x[-1]) == pytest.approx(-float(x[3]), abs=1e-13)


def test_ng_cycle_reference_both_directions():
    exact = ng.square_cycle_displacement(6.0, 10.0)
    r = env.rollout_moves("ng", NG_PLUS_X, init=(0, 0))
    assert abs(float(r.x[-1]) - exact) <= 1e-8 * exact
    back = env.rollout_moves("ng", [(1, 1), (2, 1), (1, -1), (2, -1)][::-1], init=(0, 0))
    # The reverse traversal of the loop from the same corner.
    rev = env.rollout_moves("ng", [(2, 1), (1, 1), (2, -1), (1, -1)], init=(0, 0))
    assert abs(float(rev.x[-1]) + exact) <= 1e-8 * exact
    assert back.stuck.any()  # starting with ROC -1 at the lower limit is stuck


def test_stuck_and_hold_moves():
    r = env.rollout_moves("purcell", [(1, 1), (2, 0), (1, -1)], init=(1, 1))
    assert list(np.asarray(r.stuck)) == [True, False, False]
    assert float(r.x[0]) == 0.0 and float(r.x[1]) == 0.0 and float(r.x[2]) != 0.0
    np.testing.assert_allclose(np.asarray(r.dofs[-1]), [-math.pi / 3, math.pi / 3])


def test_direction_sets_the_sign_of_progress():
    plus = env.rollout_moves("ng", NG_PLUS_X, init=(0, 0), direction="+x")
    minus = env.rollout_moves("ng", NG_PLUS_X, init=(0, 0), direction=-1)
    np.testing.assert_allclose(np.asarray(plus.progress), -np.asarray(minus.progress))
    np.testing.assert_allclose(np.asarray(plus.x), np.asarray(minus.x))


def test_all_four_initial_configurations_reachable_through_reset():
    inits = env.all_inits(2)
    assert sorted(inits) == [(0, 0), (0, 1), (1, 0), (1, 1)]
    for init in inits:
        p = env.make_params("purcell", init=init)
        s = env.reset(jax.random.PRNGKey(0), p)
        assert tuple(np.asarray(s.levels)) == init
    p = env.make_params("purcell", init="random")
    keys = jax.random.split(jax.random.PRNGKey(1), 64)
    levels = jax.vmap(env.reset, in_axes=(0, None))(keys, p).levels
    assert {tuple(v) for v in np.asarray(levels)} == set(inits)
    assert tuple(env.make_params("ng", init="+-").init) == (1, 0)


def test_noise_zero_reproduces_noiseless_and_mean_is_unbiased():
    acts = PURCELL_PLUS_X * 2
    clean = env.rollout_moves("purcell", acts)
    zero = env.rollout_moves("purcell", acts, zeta=0.0, key=7)
    np.testing.assert_array_equal(np.asarray(clean.x), np.asarray(zero.x))

    params = env.make_params("purcell", zeta=2.0)
    n = 20000
    keys = jax.random.split(jax.random.PRNGKey(0), n)
    s0 = jax.vmap(env.reset, in_axes=(0, None))(keys, params)
    a = jnp.full((n,), env.encode_action(2, -1))
    _, info = jax.vmap(env.step, in_axes=(0, 0, 0, None))(keys, s0, a, params)
    dx = np.asarray(info.dx)
    noiseless = float(clean.x[0])
    # dX (1 + zeta Y), Y ~ U[-1, 1]: mean dX, standard deviation |dX| zeta / sqrt(3).
    sem = abs(noiseless) * 2.0 / math.sqrt(3) / math.sqrt(n)
    assert abs(dx.mean() - noiseless) < 5 * sem
    assert dx.std() == pytest.approx(abs(noiseless) * 2.0 / math.sqrt(3), rel=0.03)
    lo, hi = sorted([noiseless * (1 - 2.0), noiseless * (1 + 2.0)])
    assert dx.min() >= lo - 1e-12 and dx.max() <= hi + 1e-12
    assert len(np.unique(dx)) > n * 0.99  # different keys differ
    # the noise does not touch the rotation
    np.testing.assert_allclose(np.asarray(_.theta), float(clean.orientation[0]))


def test_vmap_equals_individual_steps():
    params = env.make_params("purcell", zeta=0.7, init="random")
    b, steps = 4, 6  # each single step runs op by op: a few swimmers and steps suffice
    key = jax.random.PRNGKey(5)
    keys = jax.random.split(key, b)
    actions = jax.random.randint(jax.random.PRNGKey(6), (steps, b), 0, 6)
    step_b = jax.jit(jax.vmap(env.step, in_axes=(0, 0, 0, None)))
    states = jax.vmap(env.reset, in_axes=(0, None))(keys, params)
    singles = [env.reset(keys[i], params) for i in range(b)]
    for t in range(steps):
        ks = jax.random.split(jax.random.PRNGKey(100 + t), b)
        states, _ = step_b(ks, states, actions[t], params)
        for i in range(b):
            singles[i], _ = env.step(ks[i], singles[i], actions[t, i], params)
    for i in range(b):
        for field in env.EnvState._fields:
            np.testing.assert_allclose(
                np.asarray(getattr(states, field))[i],
                np.asarray(getattr(singles[i], field)),
                atol=1e-12,
            )


def test_vmap_over_noise_levels_and_directions():
    base = env.make_params("ng", init=(0, 0))
    zetas = jnp.array([0.0, 0.0, 1.0])
    dirs = jnp.array([1.0, -1.0, 1.0])

    def one(z, d):
        p = base.replace(zeta=z, direction=d)
        s = env.reset(jax.random.PRNGKey(0), p)
        s, info = env.step(jax.random.PRNGKey(1), s, env.encode_action(1, 1), p)
        return info.progress

    prog = np.asarray(jax.vmap(one)(zetas, dirs))
    assert prog[0] > 0 and prog[1] == pytest.approx(-prog[0]) and prog[2] != prog[0]


def test_middle_link_centre_is_exposed():
    p = env.make_params("purcell")
    s = env.reset(jax.random.PRNGKey(0), p)
    ref = np.asarray(env.reference_point(s, p))
    # At (+d, +d) the outer links both bend the same way: the centroid is off the middle link.
    assert abs(ref[1]) > 0.05 and abs(ref[0]) < 1e-12


def test_batched_rollout_shapes():
    acts = np.array([PURCELL_PLUS_X, PURCELL_PLUS_X[::-1]])
    r = env.rollout_moves("purcell", acts, zeta=0.5, key=3)
    assert r.x.shape == (2, 4) and r.dofs.shape == (2, 4, 2)


@pytest.mark.parametrize(
    "kwargs, word",
    [
        (dict(swimmer="eel"), "unknown swimmer"),
        (dict(swimmer="ng", d_min=10, d_max=6), "d_min"),
        (dict(swimmer="purcell", d_max=4.0), "d_max"),
        (dict(swimmer="purcell", d_max=0.0), "d_max"),
        (dict(swimmer="purcell", zeta=-0.1), "zeta"),
        (dict(swimmer="purcell", direction=2), "direction"),
        (dict(swimmer="purcell", init=(1, 2)), "init"),
        (dict(swimmer="ng", d_min=1.5), "d_min"),
    ],
)
def test_bad_parameters_name_the_parameter(kwargs, word):
    with pytest.raises(ConfigError, match=word):
        env.make_params(**kwargs)


@pytest.mark.parametrize(
    "actions, word",
    [
        ([(3, 1)], "dof"),
        ([(1, 2)], "roc"),
        ([(1,)], "pairs"),
        ([(1.5, 1)], "integers"),
    ],
)
def test_bad_actions_are_rejected(actions, word):
    with pytest.raises(ConfigError, match=word):
        env.rollout_moves("purcell", actions)


def test_step_batch_matches_vmapped_advance_and_carries_unit_rotation():
    params = env.make_params("purcell", zeta=1.5, init="random")
    b = 16
    keys = jax.random.split(jax.random.PRNGKey(2), b)
    states = jax.vmap(env.reset, in_axes=(0, None))(keys, params)
    singles = states
    # One compiled program, not ~75 eager dispatch compiles: the fast tier's budget.
    vmapped_advance = jax.jit(
        lambda s, a, y: jax.vmap(env.advance, in_axes=(0, 0, 0, None))(s, a, y, params)
    )
    for t in range(8):
        k = jax.random.PRNGKey(t)
        a = jax.random.randint(jax.random.fold_in(k, 1), (b,), 0, 6)
        states, _info = env.step_batch(k, states, a, params)
        y = env.noise(k, b).astype(jnp.float64)  # the draw step_batch documents
        singles, _ = vmapped_advance(singles, a, y)
    np.testing.assert_allclose(np.asarray(states.x), np.asarray(singles.x), atol=1e-14)
    # The carried rotation is the orientation's (cos, sin): no drift from composing rotations.
    th = np.asarray(states.theta)
    np.testing.assert_allclose(
        np.asarray(states.rot), np.stack([np.cos(th), np.sin(th)], -1), atol=1e-12
    )
