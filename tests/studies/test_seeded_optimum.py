"""A study's optimum is seeded with every run of its cell that reached the target.

The search alone is not exact (docs/navigation.md, *The swimmer's own optimum*): in shear at
0.9 v PPO reached the 90-degree target in 99 steps where the search found 148. A cell's optimum
is therefore searched from the cell's own runs as well, so no agent's run in the cell is shorter.
"""

from __future__ import annotations

import numpy as np
import pytest

from jswim.agents import optimal
from jswim.errors import ConfigError
from jswim.judging import lattice
from jswim.results.row import RunRow
from jswim.studies.kinds import navigate
from jswim.studies.options import StudyOptions


def _row(agent: str, actions: list, reached: bool = True, **kw) -> RunRow:
    base = RunRow.from_dict(
        {
            "run_id": f"{agent}-{len(actions)}-{kw.get('seed', 0)}",
            "agent": agent,
            "swimmer": "purcell",
            "init": kw.pop("init", "++"),
            "seed": kw.pop("seed", 0),
            "group": "g",
            "roc_levels": 2,
            "actions": actions,
            "x": [0.0] * len(actions),
            "success": reached,
        }
    )
    import dataclasses

    return dataclasses.replace(
        base,
        target=kw.pop("target", '{"kind": "fixed"}'),
        flow=kw.pop("flow", ""),
        reached=reached,
        steps_to_target=len(actions) if reached else None,
    )


@pytest.fixture(autouse=True)
def _fresh_seeds():
    navigate._SEEDS.clear()
    yield
    navigate._SEEDS.clear()


def test_a_cells_reached_runs_become_its_seeds_as_action_codes():
    moves = [[1, 2], [2, -1], [1, 0], [2, 2]]
    navigate.seed_optimum([_row("qlearning", moves)])
    (cell,) = navigate._SEEDS
    assert cell == ('{"kind": "fixed"}', "", 2, "++")
    assert navigate._SEEDS[cell] == (tuple(lattice.encode(d, k, 2) for d, k in moves),)


def test_a_new_session_forgets_an_earlier_studys_seeds():
    navigate.seed_optimum([_row("qlearning", [[1, 1], [2, 1]])])
    assert navigate._SEEDS
    navigate.clear_seeds()
    assert navigate._SEEDS == {}


def test_only_runs_that_reached_and_are_not_yardsticks_seed_it():
    moves = [[1, 1], [2, 1]]
    navigate.seed_optimum(
        [
            _row("qlearning", moves, reached=False),
            _row("optimal", moves),
            _row("mpc", moves),
            _row("zermelo", moves),
            _row("ppo", [[1, 0.5]]),  # off the K lattice: no code names it
        ]
    )
    assert navigate._SEEDS == {}


def test_seeds_are_kept_per_cell_shortest_first_and_capped():
    for n in range(navigate.MAX_SEEDS + 6, 0, -1):
        navigate.seed_optimum([_row("random", [[1, 1]] * n, seed=n)])
    navigate.seed_optimum([_row("random", [[1, 1]] * 3, init="+-")])
    runs = navigate._SEEDS[('{"kind": "fixed"}', "", 2, "++")]
    assert [len(q) for q in runs] == list(range(1, navigate.MAX_SEEDS + 1))
    assert len(navigate._SEEDS[('{"kind": "fixed"}', "", 2, "+-")]) == 1


def test_an_incumbent_that_is_not_action_codes_is_refused_in_one_line():
    import jswim
    from jswim.env.targets import FixedTarget

    env, params = jswim.make("purcell", roc_levels=2, target=FixedTarget(3.0, 90.0))
    for bad in ([[0, 1], [2, 3]], [0, env.n_actions], [-1], [0.5, 1.0], np.zeros((2, 2))):
        with pytest.raises(ConfigError, match="incumbent") as err:
            optimal.solve(env, params, incumbents=[bad])
        assert "\n" not in str(err.value)


@pytest.mark.slow  # a small study with the optimum: about a minute each
@pytest.mark.parametrize("agent", ["controller", "llm"])
def test_no_run_of_a_cell_beats_its_optimum_even_where_the_search_alone_would_miss(
    agent, tmp_path, monkeypatch
):
    """A search crippled to a beam of one, no estimate of the time to go and no seeds of its
    own never reaches the target; seeded with the cell's runs, the cell's optimum is never
    longer than any run. The LLM's runs (a fake server answering with the reference rule) come
    after the baselines: the optimum is searched after them."""
    import jax.numpy as jnp

    from jswim.llm.backend import Backend
    from jswim.llm.reference import completion
    from jswim.results import as_run_rows, read_runs
    from jswim.studies.run import run_study
    from tests.fakeserver import FakeServer

    def blind(state, params):
        return jnp.zeros((), jnp.float32)

    monkeypatch.setattr(optimal, "heuristic", lambda env, params: blind)
    monkeypatch.setattr(optimal, "_dp", lambda *a, **k: np.zeros(0, np.int64))
    monkeypatch.setattr(optimal, "_controller", lambda *a, **k: [])
    monkeypatch.setattr(optimal, "_closed_loop", lambda *a, **k: np.zeros(0, np.int64))
    solve = optimal.solve
    monkeypatch.setattr(optimal, "solve", lambda *a, **k: solve(*a, **{**k, "beam": 1}))
    navigate._optimal.cache_clear()
    opts = StudyOptions(bearings=(90.0,), agents=(agent, "optimal"))
    with FakeServer(reply=lambda body: completion(body)["choices"][0]["message"]["content"]) as srv:
        backend = Backend(base_url=srv.url, model="fake") if agent == "llm" else None
        run_study("navigate", opts, backend, tmp_path / "f", progress=False)
    rows = as_run_rows(read_runs(tmp_path / "f"))
    navigate._optimal.cache_clear()
    cells: dict[str, list] = {}
    for r in rows:
        cells.setdefault(r.group, []).append(r)
    assert len(cells) == 3
    for group, g in cells.items():
        (best,) = [r for r in g if r.agent == "optimal"]
        (ctrl,) = [r for r in g if r.agent == agent]
        assert ctrl.reached, group
        assert best.reached and best.steps_to_target <= ctrl.steps_to_target, group
        assert ctrl.optimal_steps == best.steps_to_target == best.optimal_steps, group
        assert ctrl.time_ratio >= 1.0, group
