"""The K-level ROC lattice: exact moves, the judge on the lattice, the gait search.

Reference numbers are independent of the lattice code: the paper's square-gait displacements
(0.19124724 Purcell, 0.15626494 NG, per cycle), RK4 integration, and rate independence (a side
walked in one move or in K moves gives the same motion).
"""

from __future__ import annotations

import numpy as np
import pytest

from jswim.action_codes import n_actions
from jswim.judging import lattice
from jswim.env import make_params, step_table
from jswim.judging.gait import judge
from jswim.swimmers.models import make_model

SQUARE = {"purcell": 0.19124724, "ng": 0.15626494}


def square(model_name: str, k: int, sub: int = 1) -> list[int]:
    """Square gait toward +x from (lo, lo) walked in ``sub`` moves per side, as lattice codes."""
    step = k // sub
    if model_name == "purcell":
        order = [(2, step), (1, step), (2, -step), (1, -step)]
    else:
        order = [(1, step), (2, step), (1, -step), (2, -step)]
    return [lattice.encode(d, r, k) for d, r in order for _ in range(sub)]


def test_codes_round_trip_and_k1_codes_are_the_environment_codes():
    from jswim.env import encode_action

    for k in (1, 2, 5):
        for dof in (1, 2):
            for r in range(-k, k + 1):
                assert lattice.decode(lattice.encode(dof, r, k), k) == (dof, r)
    assert [lattice.encode(d, r, 1) for d in (1, 2) for r in (-1, 0, 1)] == [
        encode_action(d, r) for d in (1, 2) for r in (-1, 0, 1)
    ]
    assert n_actions(2, 5) == 22


@pytest.mark.parametrize("name", ["purcell", "ng"])
def test_k1_table_is_the_corner_table(name):
    model = make_model(name)
    tab = lattice.move_table(model, 1)
    inc, _ = step_table(model)
    for c in range(4):
        for d in range(2):
            k = 1 if (c >> d) & 1 == 0 else -1
            target, motion, moved = lattice.move(tab, c, d, k)
            np.testing.assert_allclose(motion, inc[c, d], rtol=0, atol=1e-14)
            assert target == c ^ (1 << d) and moved
            assert (
                not lattice.move(tab, c, d, 0)[2] and not lattice.move(tab, c, d, -k)[2]
            )  # hold, stuck


@pytest.mark.parametrize("name", ["purcell", "ng"])
@pytest.mark.parametrize("k,sub", [(2, 1), (2, 2), (4, 4), (5, 5)])
def test_rate_independence_square_in_any_number_of_moves(name, k, sub):
    model = make_model(name)
    acts = np.array(square(name, k, sub))[:, None]
    rp = lattice.replay(acts, model, k, np.zeros((1, 2), np.int64))
    assert rp.corner[-1, 0] == 0  # closed
    assert abs(rp.x[-1, 0] - SQUARE[name]) < 5e-9  # the paper's value (8 digits)
    full = lattice.replay(
        np.array(square(name, 1))[:, None], model, 1, np.zeros((1, 2), np.int64)
    ).x[-1, 0]
    assert abs(rp.x[-1, 0] - full) < 1e-12 * abs(full)


@pytest.mark.parametrize("name", ["purcell", "ng"])
def test_reversed_loop_goes_exactly_back(name):
    model = make_model(name)
    k = 4
    fwd = square(name, k, 2)
    back = [lattice.encode(d, -r, k) for d, r in (lattice.decode(c, k) for c in reversed(fwd))]
    x = [
        lattice.replay(np.array(s)[:, None], model, k, np.zeros((1, 2), np.int64)).x[-1, 0]
        for s in (fwd, back)
    ]
    assert abs(x[0] + x[1]) < 1e-12 * abs(x[0])


def test_half_amplitude_square_agrees_with_rk4():
    """Sides from lo + range/4 to hi - range/4 (K = 4, points 1..3), against RK4 composed by hand."""
    import jax
    import jax.numpy as jnp

    from jswim.integrate import centroid, integrate_stroke

    model = make_model("purcell")
    k = 4
    moves = [(2, 2), (1, 2), (2, -2), (1, -2)]
    got = lattice.replay(
        np.array([lattice.encode(d, r, k) for d, r in moves])[:, None],
        model,
        k,
        np.ones((1, 2), np.int64),
    ).x[-1, 0]
    rk4 = jax.jit(
        lambda d, rate, dur, pose: integrate_stroke(
            model, d, rate, dur, pose0=pose, n_sub=400, method="rk4"
        )
    )
    with jax.enable_x64(True):
        vals = lattice.values(model, k)
        d = jnp.array([vals[1], vals[1]])
        pose = jnp.zeros(3)
        start = centroid(model, d, pose)
        span = model.hi - model.lo
        for dof, r in moves:
            rate = jnp.zeros(2).at[dof - 1].set(np.sign(r))
            dur = abs(r) / k * span
            pose = rk4(d, rate, dur, pose)
            d = d + rate * dur
        want = float(centroid(model, d, pose)[0] - start[0])
    assert abs(got - want) < 1e-10 * abs(want)


def test_small_squares_scale_with_area():
    model = make_model("ng")
    k = 80  # squares of side 4 and 2 units (0.2 and 0.1 a) centred on the middle shape
    x = []
    for side in (4, 2):
        moves = [(1, side), (2, side), (1, -side), (2, -side)]
        acts = np.array([lattice.encode(d, r, k) for d, r in moves])[:, None]
        x.append(lattice.replay(acts, model, k, np.full((1, 2), 40 - side // 2, np.int64)).x[-1, 0])
    assert abs(x[0] / x[1] - 4) < 0.04


def test_moves_stop_at_the_limit():
    model = make_model("ng")
    tab = lattice.move_table(model, 5)
    p = lattice.point_index(np.array([4, 0]), 5)
    # D1 at 4/5 of the range: +5 moves one unit only, the same motion as +1.
    target, motion, _ = lattice.move(tab, p, 0, 5)
    assert lattice.point_coords(target, 2, 5).tolist() == [5, 0]
    np.testing.assert_array_equal(motion, lattice.move(tab, p, 0, 1)[1])
    top = lattice.point_index(np.array([5, 0]), 5)
    ks = np.arange(-5, 6)
    moved = lattice.move(tab, np.full(11, top), np.zeros(11, np.int64), ks)[2]
    assert moved.tolist() == [True] * 5 + [False] * 6


def test_lattices_too_large_for_the_tables_are_refused():
    from jswim.errors import ConfigError

    with pytest.raises(ConfigError, match="--roc-levels 500"):
        lattice.move_table(make_model("ng"), 500)


@pytest.mark.parametrize("name", ["purcell", "ng"])
def test_judge_on_the_lattice(name):
    k = 2
    params = make_params(name)
    full = square(name, k) * 10
    half = square(name, k, 2) * 5
    wrong = [
        lattice.encode(*(lambda d, r: (d, -r))(*lattice.decode(c, k)), k)
        for c in reversed(square(name, k))
    ] * 10
    acts = np.array([full, half[:40], wrong])
    rep = judge(acts, params, levels0=np.zeros((3, 2), np.int64), roc_levels=k)
    assert rep.learned.tolist() == [True, True, False]
    assert rep.period.tolist()[:2] == [4, 8]
    assert rep.steps_to_learn.tolist()[:2] == [1, 1]
    # Half steps walk the same loop in twice the moves: half the best speed, exactly the threshold.
    assert abs(rep.fraction[0] - 1) < 1e-12 and abs(rep.fraction[1] - 0.5) < 1e-12
    assert rep.success.tolist() == [True, True, False]


@pytest.mark.parametrize("name", ["purcell", "ng"])
def test_k1_replay_matches_the_corner_replay(name):
    from jswim.judging.gait import replay

    model = make_model(name)
    rng = np.random.default_rng(0)
    acts = rng.integers(0, 6, (60, 30))
    levels0 = rng.integers(0, 2, (30, 2))
    a, b = replay(acts, model, levels0), lattice.replay(acts, model, 1, levels0)
    np.testing.assert_array_equal(a.corner, b.corner)
    np.testing.assert_array_equal(a.moved, b.moved)
    np.testing.assert_allclose(a.x, b.x, rtol=0, atol=1e-12)


def test_gait_search_finds_the_full_square():
    for name in ("purcell", "ng"):
        model = make_model(name)
        for k, length in ((1, 4), (2, 8), (3, 6)):
            best = lattice.best_lattice_cycles(model, 1, k, length)
            assert best[0].period == 4 and abs(best[0].displacement - SQUARE[name]) < 5e-9
            assert all(abs(m[1]) == k for m in best[0].moves)  # every side the whole range
            assert best[1].per_step < best[0].per_step - 1e-6
        assert lattice.best_per_step(model, -1, 2) == pytest.approx(SQUARE[name] / 4, abs=2e-9)
