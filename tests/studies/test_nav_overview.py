"""The navigation study's first table (`nav_overview`, `nav_overview_table`): cells pooled per
agent, flow and target kind, in the study's order, and a note wherever a run was shorter than
the search's optimum (its answer is an upper bound on the least time, not a proof)."""

from __future__ import annotations

from jswim.results.row import RunRow
from jswim.studies.kinds.navigate import nav_overview
from jswim.studies.overview import nav_overview_table


def _row(agent: str, group: str, steps: int | None, optimum: int, i: int = 0) -> RunRow:
    reached = steps is not None
    return RunRow(
        run_id=f"{agent}-{group}-{i}",
        agent=agent,
        swimmer="purcell",
        direction=1,
        init="++",
        zeta=0.0,
        seed=i,
        n_ht=None,
        drop=[],
        action_set="all",
        group=group,
        variant="",
        steps=steps or 100,
        final_x=0.0,
        signed_final_x=0.0,
        success=reached,
        learned=reached,
        steps_to_learn=steps,
        period=0,
        roc_levels=2,
        x=[],
        actions=[],
        progress=[],
        target='{"kind": "fixed"}',
        reached=reached,
        steps_to_target=steps,
        optimal_steps=optimum,
        time_ratio=None if steps is None else steps / optimum,
    )


def _rows(ppo_steps):
    rows = [_row("optimal", g, 100, 100) for g in ("fixed d=3 b=90", "fixed d=3 b=180")]
    rows += [_row("ppo", "fixed d=3 b=90", s, 100, i) for i, s in enumerate(ppo_steps)]
    rows += [_row("ppo", "fixed d=3 b=180", 120, 100, i) for i in range(3)]
    return rows


def test_cells_follow_the_grid_and_count_the_runs():
    table = nav_overview(_rows([110, 120, None]))
    assert [(t["target"], t["agent"]) for t in table] == [
        ("fixed d=3 b=90", "ppo"),
        ("fixed d=3 b=90", "optimal"),
        ("fixed d=3 b=180", "ppo"),
        ("fixed d=3 b=180", "optimal"),
    ]  # 90 before 180 (numbers, not text); agents in the study's order
    ppo = table[0]
    assert (ppo["n"], ppo["reached"], ppo["n_ratio"], ppo["n_below"]) == (3, 2, 2, 0)
    assert ppo["time_ratio"] == 1.15


def test_a_run_below_the_optimum_is_named_in_the_note():
    _, _, clean = nav_overview_table(_rows([110, 120, None]))
    assert "upper bound" not in clean
    table = nav_overview(_rows([90, 120, 95]))
    assert table[0]["n_below"] == 2
    _, _, note = nav_overview_table(_rows([90, 120, 95]))
    assert "upper bound" in note and "ppo 2/3 in still fixed d=3 b=90" in note
