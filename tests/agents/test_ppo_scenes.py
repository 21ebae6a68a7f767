"""PPO on scenes: jswim.agents.ppo.train in a scene world, and its judge per swimmer."""

from __future__ import annotations

import jax
import jax.numpy as jnp
import numpy as np
import pytest

from jswim.agents import ppo
from jswim.env.registry import make
from jswim.env.scene_world import SceneTask, SceneWorld
from jswim.scenes import Scene, scene_advance, scene_params, scene_reset

STEPS = 8


def _replay_x(params, actions):
    """Mean centroid x after each step, the actions replayed by hand through scene_advance
    (noiseless): swimmer dof // 2, arm dof % 2, ROC the non-zero entry."""
    state = scene_reset(params)

    def centroid(s):
        return float(
            np.mean(
                np.asarray(s.centre[:, 0])
                + (np.asarray(s.arms[:, 1]) - np.asarray(s.arms[:, 0]))
                * np.cos(np.asarray(s.tilt))
                / 3.0
            )
        )

    x0, out = centroid(state), []
    for a in actions:
        j = int(np.argmax(np.abs(a)))
        state, _ = scene_advance(
            params, state, (j // 2, j % 2, float(a[j])), np.zeros(params.n_swimmers)
        )
        out.append(centroid(state) - x0)
    return np.array(out)


@pytest.mark.slow  # one compilation (~40 s of CPU)
def test_wall_scene_run_records_the_scene_progress():
    with jax.enable_x64(False):
        params = scene_params("ng", Scene(medium="wall", height=10.0))
        keys = jax.random.split(jax.random.PRNGKey(0), 3)
        config = ppo.PPOConfig(steps=STEPS)
        world = SceneWorld(Scene(medium="wall", height=10.0))
        task = SceneTask(params, jnp.array([1.0, -1.0, 1.0]))
        run = ppo.train(world, task, keys, config)
        start = world.observe(world.reset(keys[0], task), task).position
        run = run._replace(x=run.x - jnp.mean(start[:, 0]))
        assert (
            run.x.shape == (3, STEPS)
            and run.dofs.shape == (3, STEPS, 2)
            and run.actions.shape == (3, STEPS, 2)
        )
        for field in (run.x, run.progress, run.dofs, run.y, run.orientation):
            assert np.all(np.isfinite(np.asarray(field)))
        # One arm per step, within [d_min, d_max]; the swimmer's height changes near a wall.
        assert np.all(np.count_nonzero(np.asarray(run.actions), axis=-1) <= 1)
        assert np.all((np.asarray(run.dofs) >= 6.0 - 1e-5) & (np.asarray(run.dofs) <= 10.0 + 1e-5))
        # Progress is the scene's: direction times the step of the mean centroid x, and x is what
        # the actions give when replayed through the scene by hand.
        x = np.asarray(run.x, np.float64)
        dx = np.diff(np.concatenate([np.zeros((3, 1)), x], axis=1), axis=1)
        np.testing.assert_allclose(
            np.asarray(run.progress), dx * np.array([1, -1, 1])[:, None], atol=1e-5
        )
        for i in range(3):
            np.testing.assert_allclose(
                x[i], _replay_x(params, np.asarray(run.actions[i])), atol=2e-4
            )
        report = ppo.evaluate_swimmers(run, world.judge_view(task), np.array([1, -1, 1]))
        assert np.asarray(report.success).shape == (3,)


def _hand_made(codes_per_run):
    """A PPORun of lattice moves played by hand on a pair's joint arms (no training): code c moves
    joint DOF c // 3 by ROC c % 3 - 1 (the whole range), clipped to [6, 10], from (10, 6, 10, 6)."""
    actions, dofs, dof = [], [], []
    for codes in codes_per_run:
        arms = np.array([10.0, 6.0, 10.0, 6.0])
        a_run, d_run = [], []
        for c in codes:
            j, roc = c // 3, c % 3 - 1
            a = np.zeros(4)
            a[j] = roc
            arms = arms.copy()
            arms[j] = np.clip(arms[j] + 4.0 * roc, 6.0, 10.0)
            a_run.append(a)
            d_run.append(arms)
        actions.append(a_run)
        dofs.append(d_run)
        dof.append([c // 3 + 1 for c in codes])
    actions, dofs = np.array(actions), np.array(dofs)
    z = np.zeros(actions.shape[:2])
    return ppo.PPORun(
        actions,
        np.array(dof, np.int8),
        z,
        z,
        dofs,
        np.broadcast_to([10.0, 6.0, 10.0, 6.0], dofs[:, 0].shape),
        z,
        z,
    )


def test_pair_judge_on_hand_made_strokes():
    # The real-valued pair judge against the lattice one of the studies (jswim.judging.gait.judge on each
    # swimmer's own codes, an independent code path) on corner moves, where the two must agree.
    from jswim.studies import scene_studies
    from jswim.studies.plans import Plan

    world, task = make(
        "ng", Scene(medium="free", swimmers=2, separation=30.0), init=(1, 0)
    )  # paper's (10, 6)
    pair = world.judge_view(task)
    both = scene_studies.stroke_codes("phase0", 1, 30, 2)  # two squares, alternating moves
    late = np.r_[
        np.ones(6, np.int64), both[:24]
    ]  # 6 holds of swimmer 1 ([1, 0]), then 3 squares each
    only_one = scene_studies.stroke_codes("square", 1, 30, 1)  # swimmer 2 never moves
    lopsided = np.r_[
        scene_studies.stroke_codes("square", 1, 27, 1), [7, 6, 7]
    ]  # swimmer 2: 3 moves
    runs = [both, late, only_one, lopsided, scene_studies.stroke_codes("phase0", -1, 30, 2)]
    rep = ppo.evaluate_swimmers(_hand_made(runs), pair, np.array([1, 1, 1, 1, 1]))
    assert rep.success.tolist() == [True, True, False, False, False]
    assert rep.learned.tolist() == [True, True, False, False, False]
    assert rep.period.tolist() == [8, 8, 0, 0, 0]  # 4 own moves each
    assert rep.steps_to_learn.tolist() == [
        1,
        7,
        -1,
        -1,
        -1,
    ]  # in own moves: swimmer 1's stroke starts at its 7th
    plan = Plan("r", "ppo", "ng", 1, (1, 0), 0.0, 0, 30)
    for i, codes in enumerate(runs):
        lattice = scene_studies._judge(list(codes), plan, 2, 50)
        assert (lattice["success"], lattice["learned"]) == (rep.success[i], rep.learned[i])
        assert lattice["steps_to_learn"] == (int(rep.steps_to_learn[i]) if rep.learned[i] else None)
    # The -x target is met by the time-reversed strokes, not by the +x ones.
    back = ppo.evaluate_swimmers(
        _hand_made([scene_studies.stroke_codes("phase0", -1, 30, 2), both]),
        pair,
        np.array([-1, -1]),
    )
    assert back.success.tolist() == [True, False]


def test_a_run_from_another_world_is_judged_on_its_moves_replayed_in_the_bulk():
    """PPO on Purcell above a wall is judged as the scene studies judge lattice moves: on the bulk
    swimmer's displacements (``replay=True``), not on the run's own x. The square from (+, +) at
    full ROCs is the corner stroke, 0.19124724 l per cycle in the bulk (DESIGN.md)."""
    from types import SimpleNamespace

    from jswim import env

    lo, hi = -np.pi / 3, np.pi / 3
    rocs = np.array(
        [[0.0, -1.0], [-1.0, 0.0], [0.0, 1.0], [1.0, 0.0]] * 4
    )  # D2 down, D1 down, D2 up, D1 up
    dofs = np.array([[hi, lo], [lo, lo], [lo, hi], [hi, hi]] * 4)
    run = SimpleNamespace(
        actions=rocs[None],
        dofs=dofs[None],
        dofs0=np.array([[hi, hi]]),
        x=np.zeros((1, 16)),
        dof=np.argmax(rocs != 0, -1)[None] + 1,
    )
    bulk = env.make_params("purcell", init=(1, 1))
    rep = ppo.evaluate(run, bulk, replay=True)
    assert bool(rep.success[0]) and int(rep.period[0]) == 4
    assert float(rep.per_step[0]) * 4 == pytest.approx(0.19124724, abs=1e-7)
    # the run's own x (here: it never moved) is what is judged without replay
    assert not bool(ppo.evaluate(run, bulk).learned[0])
    # The world's judge's view says the same: Purcell's swimmer above a wall is judged as the bulk
    # swimmer from the run's start.
    world, task = make("purcell", Scene(medium="wall", height=3.0), init=(1, 1))
    view = world.judge_view(task)
    assert len(view) == 1 and view[0].model == bulk.model
    again = ppo.evaluate_swimmers(run, view, 1)
    assert bool(again.success[0]) and float(again.per_step[0]) == float(rep.per_step[0])
