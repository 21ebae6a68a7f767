"""The continuous-action RL baseline (jswim.agents.ppo) and the real-valued judge (jswim.judging.shape_judge)."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jswim.env.swimmer_world import SwimmerWorld
from jswim import env

from jswim.judging import gait
from jswim.agents import ppo
from jswim.agents.defaults import paper_init
from jswim.errors import ConfigError
from jswim.judging.shape_judge import judge_shapes

B = 32

# Training compiles once per batch size (~20 s of CPU each): the fixture's tests are `slow`.
slow = pytest.mark.slow


def _params(swimmer: str = "purcell", direction: int = 1) -> env.EnvParams:
    return env.make_params(
        swimmer, direction=direction, init=paper_init(env.make_params(swimmer).model)
    )


@pytest.fixture(scope="module")
def trained():
    """32 learners, the default config (200 steps), Purcell toward +x, in the default dtype."""
    with jax.enable_x64(False):
        params = _params()
        keys = jax.random.split(jax.random.PRNGKey(3), B)
        world = SwimmerWorld(params.model)
        run = ppo.train(world, params, keys, ppo.PPOConfig())
        again = ppo.train(world, params, keys, ppo.PPOConfig())
        pair = ppo.train(world, params, keys[:2], ppo.PPOConfig())
        jaxprs = [
            str(
                jax.make_jaxpr(
                    lambda k, p: ppo._train(
                        k,
                        p,
                        ppo._structure(ppo.PPOConfig()),
                        ppo._numbers(ppo.PPOConfig()),
                        SwimmerWorld(params.model),
                    )
                )(jax.random.split(jax.random.PRNGKey(0), n), env.broadcast_params(params, n))
            )
            for n in (2, 5)
        ]
        return params, keys, run, again, pair, jaxprs


@slow
def test_shapes_and_dtypes(trained):
    params, _, run, *_ = trained
    steps = ppo.PPOConfig().steps
    assert run.actions.shape == (B, steps, 2) and run.actions.dtype == jnp.float32
    assert run.dof.shape == (B, steps) and run.dof.dtype == jnp.int8
    for field in (run.x, run.progress, run.y, run.orientation):
        assert field.shape == (B, steps) and field.dtype == jnp.float32
    assert run.dofs.shape == (B, steps, 2) and run.dofs0.shape == (B, 2)
    # The paper's Purcell start: both hinges at +pi/3.
    np.testing.assert_allclose(np.asarray(run.dofs0), np.pi / 3, rtol=1e-6)
    # DOF values stay within the limits; progress is the step's x increment toward +x.
    d = np.asarray(run.dofs)
    assert d.min() >= params.lo - 1e-6 and d.max() <= params.hi + 1e-6
    np.testing.assert_allclose(
        np.cumsum(np.asarray(run.progress, np.float64), 1), np.asarray(run.x), atol=1e-5
    )


@slow
def test_actions_are_one_dof_rocs_in_range(trained):
    _, _, run, *_ = trained
    a = np.asarray(run.actions)
    assert np.all(np.abs(a) <= 1.0)
    assert np.all((a != 0).sum(-1) <= 1)  # one DOF at a time (S2)
    dof = np.asarray(run.dof)
    moved = a[np.arange(B)[:, None], np.arange(a.shape[1])[None], dof - 1]
    assert np.all(np.abs(a).sum(-1) == np.abs(moved))  # the chosen DOF carries the ROC
    # Not a degenerate policy: both DOFs, both signs, some ROCs strictly inside (-1, 1).
    assert set(np.unique(dof)) == {1, 2}
    assert (
        (moved > 0).any()
        and (moved < 0).any()
        and ((np.abs(moved) > 0) & (np.abs(moved) < 1)).any()
    )


@slow
def test_deterministic_per_key(trained):
    _, _, run, again, *_ = trained
    for a, b in zip(run, again):
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b))


@slow
def test_batch_rows_do_not_depend_on_the_batch(trained):
    # Learner i of a batch of 32 is learner i of a batch of 2 (vmapped == per seed).
    _, _, run, _, pair, _ = trained
    np.testing.assert_array_equal(np.asarray(run.dof[:2]), np.asarray(pair.dof))
    np.testing.assert_allclose(np.asarray(run.actions[:2]), np.asarray(pair.actions), atol=1e-6)
    np.testing.assert_allclose(np.asarray(run.x[:2]), np.asarray(pair.x), atol=1e-5)


@slow
def test_no_python_loop_over_learners(trained):
    # The traced program is the same for 2 and 5 learners, up to the batch size in the shapes.
    *_, jaxprs = trained
    assert jaxprs[0].count("\n") == jaxprs[1].count("\n")
    assert "[5,200]" in jaxprs[1] and "[2,200]" in jaxprs[0]


def _random_progress(key, params, steps: int, n: int) -> np.ndarray:
    """Mean X after ``steps`` of a uniformly random DOF and ROC in [-1, 1], per swimmer."""
    keys = jax.random.split(key, n)
    states = jax.vmap(env.reset)(keys, env.broadcast_params(params, n))
    u = jax.random.uniform(key, (steps, n, 2))

    def body(s, u):
        dof = (u[:, 0] * 2).astype(jnp.int32)
        roc = 2 * u[:, 1] - 1
        a = jnp.where(jnp.arange(2)[None] == dof[:, None], roc[:, None], 0.0)
        s, info = jax.vmap(lambda s, a: env.advance(s, a, 0.0, params))(s, a)
        return s, info.progress

    return np.asarray(jax.lax.scan(body, states, u)[1]).sum(0)


@slow
def test_beats_the_random_policy(trained):
    params, _, run, *_ = trained
    with jax.enable_x64(False):
        rand = _random_progress(jax.random.PRNGKey(7), params, ppo.PPOConfig().steps, 256)
    learned = np.asarray(run.progress, np.float64).sum(1)
    se = np.hypot(learned.std() / np.sqrt(learned.size), rand.std() / np.sqrt(rand.size))
    assert learned.mean() > rand.mean() + 4 * se, (learned.mean(), rand.mean(), se)


@slow
def test_evaluate_reads_the_run(trained):
    params, _, run, *_ = trained
    report = ppo.evaluate(run, params)
    assert report.learned.shape == (B,)
    # Learners judged learned end in a stroke at least half as fast as the square gait.
    ok = report.learned
    assert np.all(report.fraction[ok] >= 0.5 - 1e-9)
    assert np.all(report.steps_to_learn[~ok] == -1)


def test_shape_judge_agrees_with_the_discrete_judge_on_corner_runs():
    params = env.make_params("purcell", direction=-1, init=(0, 0))
    square = [(1, 1), (2, 1), (1, -1), (2, -1)]  # the best cycle toward -x from (lo, lo)
    rng = np.random.default_rng(0)
    runs = []
    for prefix in (0, 3, 9, 17):
        head = [(int(rng.integers(1, 3)), int(rng.integers(-1, 2))) for _ in range(prefix)]
        runs.append(head + square * 12)
    runs.append([(1, 1), (1, -1)] * 24 + [(1, 1)] * 2)  # reciprocal: goes nowhere
    length = min(len(r) for r in runs)
    runs = [r[:length] for r in runs]
    with jax.enable_x64(True):
        roll = env.rollout_moves("purcell", np.array(runs), direction=-1, init=(0, 0))
    discrete = gait.judge(env.validate_actions(np.array(runs), 2), params)
    shapes = judge_shapes(roll.dofs, roll.x, params, dofs0=np.full((len(runs), 2), params.lo))
    assert shapes.learned[:4].all() and not shapes.learned[4]
    np.testing.assert_array_equal(shapes.steps_to_learn, discrete.steps_to_learn)
    np.testing.assert_array_equal(shapes.success, discrete.success)
    np.testing.assert_allclose(shapes.per_step[:4], discrete.per_step[:4], rtol=1e-9)


def test_shape_judge_tolerance():
    # A stroke of ROC +-0.999 from a limit returns to within 0.1 % of the range: a cycle at the
    # default tolerance, not at a tighter one.
    params = env.make_params("purcell", direction=-1, init=(0, 0))
    side = 0.999
    moves = [(1, 1.0), (2, 1.0), (1, -side), (2, -side), (1, side), (2, side)] + [
        (1, -side),
        (2, -side),
        (1, side),
        (2, side),
    ] * 10
    with jax.enable_x64(True):
        roll = env.rollout_moves("purcell", moves, direction=-1, init=(0, 0))
    d0 = np.full((1, 2), params.lo)
    loose = judge_shapes(roll.dofs[None], roll.x[None], params, dofs0=d0)
    tight = judge_shapes(roll.dofs[None], roll.x[None], params, dofs0=d0, tol=1e-5)
    assert loose.learned[0] and loose.period[0] == 4
    assert tight.learned[0]  # exact returns: the limit stops each push at the same shape
    with pytest.raises(ConfigError):
        judge_shapes(roll.dofs[None], roll.x[None], params, dofs0=d0, tol=0.0)


@pytest.mark.parametrize(
    "field,value",
    [
        ("steps", 0),
        ("rollout", 1.5),
        ("discount", 1.0),
        ("clip", 0.0),
        ("entropy_coef", -1.0),
        ("anneal_start", 2.0),
    ],
)
def test_config_is_validated(field, value):
    with pytest.raises(ConfigError):
        ppo.PPOConfig(**{field: value})
