"""A study's result rows ([`jswim.results.RunRow`][jswim.results.RunRow]), built in one place.

[`build_row`][jswim.studies.rows.build_row] is the one builder: a plan's columns, the x series and what follows from it,
the judge's verdict and the columns a world adds (a scene's: `jswim.studies.scene_studies.scene_row`).
[`judged_rows`][jswim.studies.rows.judged_rows] judges a batch of bulk runs (Q-learning, random, PPO, an LLM run) and builds
their rows; [`with_llm`][jswim.studies.rows.with_llm] merges an LLM run's own fields (its calls, tokens, switches) into its
judged row, in the bulk world and in a scene alike.
"""

from __future__ import annotations

import dataclasses
from typing import Any
from collections.abc import Mapping, Sequence

import numpy as np

from jswim import env
from jswim.agents.llm import RunResult
from jswim.env.work import lighthill_efficiency
from jswim.judging import lattice
from jswim.judging.gait import Criterion, GaitReport, judge
from jswim.results.row import SWITCHES, RunRow
from jswim.studies.plans import Plan


#: An LLM run's switches that are columns of their own: the plan's (its value stands) and the typed ones.
_PLAN = ("variant", "action_set") + SWITCHES


def signs(levels: Sequence[float]) -> str:
    """A start as text: ``+`` for each DOF at its upper bound, ``-`` at its lower one."""
    return "".join("+" if v > 0 else "-" for v in levels)


def build_row(
    plan: Plan,
    x: Sequence[float],
    actions: list[list[float]],
    verdict: Mapping[str, Any],
    *,
    init: str,
    work: Sequence[float] | None = None,
    **columns: Any,
) -> RunRow:
    """The row of one judged run of ``plan``.

    Parameters
    ----------
    x : sequence of float
        Centroid x after each step (a; a scene: the swimmers' mean); gives ``steps``,
        ``final_x``, ``signed_final_x`` and ``progress``.
    actions : list of list
        Each step's ``[dof, roc]``.
    verdict : mapping
        ``success``, ``learned``, ``steps_to_learn``, ``period`` ([`jswim.judging.gait.judge`][jswim.judging.gait.judge]
        or the real-valued agent's own judge).
    init : str
        The start as the row shows it ([`signs`][jswim.studies.rows.signs]).
    work : sequence of float, optional
        Each step's work ([`StepInfo.work`][jswim.env.base.StepInfo]); gives ``energy``,
        ``energy_per_distance`` and ``efficiency`` ([`energy_columns`][jswim.studies.rows.energy_columns]).
    **columns
        Further [`RunRow`][jswim.results.RunRow] columns: ``y``, ``orientation``, a scene's.
    """
    x = [float(v) for v in x]
    end = x[-1] if x else 0.0
    prog = np.diff(np.concatenate([[0.0], np.asarray(x, np.float64)])) * plan.direction
    return RunRow(
        run_id=plan.run_id,
        agent=plan.agent,
        swimmer=plan.swimmer,
        direction=plan.direction,
        init=init,
        zeta=plan.zeta,
        seed=plan.seed,
        n_ht=plan.n_ht,
        drop=",".join(sorted(plan.drop)),
        action_set=plan.action_set,
        group=plan.group,
        variant=plan.variant,
        steps=len(x),
        final_x=end,
        signed_final_x=plan.direction * end,
        **verdict,
        roc_levels=plan.roc_levels,
        sample=None if plan.scene else plan.sample,
        x=x,
        actions=actions,
        progress=[float(v) for v in prog],
        **energy_columns(plan.swimmer, end, work),
        **columns,
    )


def energy_columns(
    swimmer: str, displacement: float, work: Sequence[float] | None
) -> dict[str, Any]:
    """A run's ``energy`` (total work), ``energy_per_distance`` (``energy / |X|``) and Lighthill
    ``efficiency`` ([`jswim.env.work.lighthill_efficiency`][jswim.env.work.lighthill_efficiency],
    ``C`` = the swimmer's links or spheres), from its per-step work and its displacement ``X``
    along x. All None when no work is given or any step's is not a number (a world that does not
    count work); ``energy_per_distance`` None when ``X = 0``, ``efficiency`` None when the work is 0."""
    none = dict.fromkeys(("energy", "energy_per_distance", "efficiency"))
    if work is None or len(work) == 0:
        return none
    w = np.asarray(work, np.float64)
    if not np.all(np.isfinite(w)):
        return none
    total = float(np.sum(w))
    bodies = env.make_params(swimmer).model.n_dof + 1
    return {
        "energy": total,
        "energy_per_distance": total / abs(displacement) if displacement != 0 else None,
        "efficiency": lighthill_efficiency(displacement, total, len(w), bodies)
        if total > 0
        else None,
    }


def verdict(rep: GaitReport, i: int) -> dict[str, Any]:
    """Run ``i``'s verdict in a judge's report (the keys [`build_row`][jswim.studies.rows.build_row] takes)."""
    return {
        "success": bool(rep.success[i]),
        "learned": bool(rep.learned[i]),
        "steps_to_learn": int(rep.steps_to_learn[i]) if rep.learned[i] else None,
        "period": int(rep.period[i]),
    }


def judged_rows(
    plans: Sequence[Plan],
    actions: np.ndarray,
    xs: np.ndarray,
    levels0: np.ndarray,
    horizon: int,
    pose: tuple[np.ndarray, np.ndarray] | None = None,
    report: GaitReport | None = None,
    moves: Sequence[list[list[float]]] | None = None,
    work: np.ndarray | None = None,
) -> list[RunRow]:
    """Rows for a batch of runs of one swimmer and ROC lattice, judged by the shared success criterion.

    ``levels0`` holds the starts' lattice positions (levels on the paper's K = 1). ``pose``
    gives the centroid y and the orientation after each step, shape ``(runs, steps)`` each, for
    the trajectories (an LLM run brings its own: [`with_llm`][jswim.studies.rows.with_llm]). The real-valued agent brings
    its own ``report`` ([`jswim.agents.ppo.evaluate`][jswim.agents.ppo_judge.evaluate]) and ``moves`` (``[dof, roc]`` per step).
    ``work`` ``(runs, steps)`` is each step's work (the energy columns; None: not counted)."""
    k = plans[0].roc_levels
    params = env.make_params(plans[0].swimmer).replace(
        direction=np.array([p.direction for p in plans], float)
    )
    rep = (
        report
        if report is not None
        else judge(
            actions, params, levels0=levels0, criterion=Criterion(horizon=horizon), roc_levels=k
        )
    )
    return [
        build_row(
            p,
            xs[i],
            moves[i]
            if moves is not None
            else [list(lattice.decode(int(a), max(k, 1))) for a in actions[i]],
            verdict(rep, i),
            init=signs(levels0[i]),
            work=None if work is None else work[i],
            **(
                {}
                if pose is None
                else {
                    "y": [float(v) for v in pose[0][i]],
                    "orientation": [float(v) for v in pose[1][i]],
                }
            ),
        )
        for i, p in enumerate(plans)
    ]


def with_llm(row: RunRow, r: RunResult) -> RunRow:
    """``row`` (an LLM run's judged row) with the run's own fields: its status and error, calls,
    tokens, cost, replies cut or retried, the agent's switches (`RunResult.knobs`), and its
    trajectory's y and orientation where the row has none (the bulk world's)."""
    u = r.usage
    return dataclasses.replace(
        row,
        status=r.status,
        error=r.error,
        failed_steps=r.failed_steps,
        parse_retries=r.parse_retries,
        truncated=r.truncated,
        cut_thinking=r.cut_thinking,
        reasoning_tokens=u.reasoning_tokens,
        http_retries=u.retries,
        n_clears=r.n_clears,
        calls=u.calls,
        billed_calls=u.billed_calls,
        cache_hits=u.cache_hits,
        prompt_tokens=u.prompt_tokens,
        completion_tokens=u.completion_tokens,
        cached_tokens=u.cached_tokens,
        cost_usd=u.cost_usd,
        tokens_seen=r.tokens_seen,
        replayed_calls=r.replayed_calls,
        below_x_min=r.below_x_min,
        **{k: r.knobs.get(k) for k in SWITCHES},
        other={k: v for k, v in r.knobs.items() if k not in _PLAN},
        y=r.y if row.y is None else row.y,
        orientation=r.orientation if row.orientation is None else row.orientation,
    )
