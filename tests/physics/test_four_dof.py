"""Four-link and four-sphere swimmers (three DOFs): gaits, symmetry, and the N = 3 limits."""

import itertools

import numpy as np
import pytest

from jswim import env

from jswim.judging import gait
from jswim.agents.defaults import default_n_ht, default_rocs
from jswim.agents.llm import LLMAgentConfig, LLMRunSpec, run_batch
from jswim.llm import ClientSettings
from jswim.swimmers import ng
from tests.fakeserver import FakeServer


@pytest.mark.parametrize(
    "swimmer, per_step, per_cycle",
    [
        (
            "nlink",
            0.0519,
            None,
        ),  # README: the best four-link cycle (period 6) moves 0.0519 a per step
        (
            "nsphere",
            0.0674,
            0.404209,
        ),  # README: 0.0674 a per step; the authors' code: 0.404209 per cycle
    ],
)
@pytest.mark.slow  # the gait search over three-DOF tables (35 s for both under load 8)
def test_best_cycle_swims_and_its_reverse_swims_back(swimmer, per_step, per_cycle):
    model = env.make_params(swimmer).model
    assert model.n_dof == 3 and default_rocs(model) == (-1, 1) and default_n_ht(model) == 20
    best = gait.best_cycles(model, 1)[0]
    assert best.period == 6 and abs(best.rotation) < 1e-12
    assert best.per_step == pytest.approx(per_step, abs=5e-5)  # the README's 4 decimals
    if per_cycle is not None:
        assert best.displacement == pytest.approx(per_cycle, abs=5e-7)  # the code's 6 decimals
    # A second integrator (RK4 on the velocity ODE, not the step table) gives the same cycle.
    from tests.physics.test_physics import run_cycle

    start = [model.hi if v else model.lo for v in best.start]
    moves = [(dof - 1, roc) for dof, roc in best.moves]
    (dx, _), _ = run_cycle(
        model, moves, start, method="rk4", n_sub=96
    )  # (the four-link cycle drifts in y)
    assert dx == pytest.approx(best.displacement, rel=1e-8)
    moves = list(best.moves)
    fwd = env.rollout_moves(swimmer, moves * 2, init=best.start)
    assert float(fwd.x[-1]) == pytest.approx(2 * best.displacement, rel=1e-6)
    # Reversed: the same loop backwards, from the corner where the forward cycle ends (= starts).
    back = [(dof, -roc) for dof, roc in reversed(moves)]
    rev = env.rollout_moves(swimmer, back, init=best.start)
    assert float(rev.x[-1]) == pytest.approx(-best.displacement, rel=1e-6)
    # The best -x cycle is as fast as the best +x one (mirror symmetry of the stroke set).
    assert gait.best_cycles(model, -1)[0].per_step == pytest.approx(best.per_step, rel=1e-9)


@pytest.mark.parametrize("swimmer", ["nlink", "nsphere"])
# both swimmers at DOF 2 in the fast tier; DOF 1 and 3 (a compile each, ~3 s) in the slow tier
@pytest.mark.parametrize(
    "dof", [pytest.param(1, marks=pytest.mark.slow), 2, pytest.param(3, marks=pytest.mark.slow)]
)
def test_reciprocal_stroke_goes_nowhere(swimmer, dof):
    init = (0, 1, 1)  # asymmetric, so that each half-stroke moves the body
    first = 1 if init[dof - 1] == 0 else -1
    r = env.rollout_moves(swimmer, [(dof, first), (dof, -first)] * 3, init=init)
    assert abs(float(r.x[-1])) < 1e-12 and abs(float(r.y[-1])) < 1e-12
    assert abs(float(r.x[0])) > 1e-4  # each half-stroke does move the body


@pytest.mark.parametrize("swimmer", ["nlink", "nsphere"])
def test_detours_add_steps_but_no_displacement(swimmer):
    # Without net rotation a closed walk's displacement is the sum over the simple cycles it
    # decomposes into; a back-and-forth detour is a reciprocal stroke and contributes nothing.
    cycles = gait.best_cycles(env.make_params(swimmer).model, 1)
    best = cycles[0]
    assert best.simple
    detoured = [c for c in cycles if not c.simple and c.period == best.period + 2]
    # The best cycle with one detour inserted: the same displacement per period to 1e-9.
    assert any(abs(c.displacement - best.displacement) < 1e-9 for c in detoured)


def test_three_link_case_equals_purcell_and_three_sphere_cycle_equals_ng():
    purcell = env.step_table(env.make_params("purcell").model)[0]
    three = env.step_table(env.make_params("nlink", n_links=3, d_max=np.pi / 3).model)[0]
    np.testing.assert_allclose(three, purcell, atol=1e-12)
    cyc = [(1, 1), (2, 1), (1, -1), (2, -1)]
    r = env.rollout_moves("nsphere", cyc * 2, n_spheres=3, init=(0, 0))
    assert float(r.x[3]) == pytest.approx(ng.square_cycle_displacement(6, 10), rel=1e-9)
    assert float(r.x[0]) != pytest.approx(float(env.rollout_moves("ng", cyc, init=(0, 0)).x[0]))


def test_llm_run_on_a_three_dof_swimmer_uses_the_general_path(tmp_path):
    """Prompt names D1..D3 and offers ROC -1/1; a model that plays the best cycle succeeds."""
    model = env.make_params("nlink").model
    best = gait.best_cycles(model, 1)[0]
    start = "".join("+" if v else "-" for v in best.start)
    moves = [f"[{d}, {r}]" for d, r in best.moves]

    spec = LLMRunSpec("nlink", init=best.start, n_steps=3 * best.period, n_ht=40)
    sent = itertools.count()  # one run, valid replies only: the n-th request is step n
    with FakeServer(reply=lambda body: moves[next(sent) % len(moves)]) as srv:
        (res,) = run_batch([spec], ClientSettings(base_url=srv.url, model="fake"), LLMAgentConfig())
        prompt = srv.requests[0]["messages"][-1]["content"]
    assert "D3" in prompt and "the changed DOF 1, 2 or 3 and the ROC -1 or 1." in prompt
    params = env.make_params("nlink", init=start)
    rep = gait.judge(np.array(res.actions), params)
    assert rep.success[0] and rep.period[0] == best.period and rep.steps_to_learn[0] == 1
