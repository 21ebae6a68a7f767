"""`build`, which turns a study (`jswim.studies.study.get`) and its options into the list of
runs ([`Plan`][jswim.studies.plans.Plan]), and the options a study refuses.

A study runs, per swimmer and target direction, a list of *cells* (one group of a table or
figure: a noise level, an n_ht, a dropped sentence, ...); a cell runs some agents, each
``runs`` (LLM) or ``q_runs`` (baselines) times.
"""

from __future__ import annotations

import json
from collections.abc import Iterable

from jswim.agents.variants import (
    pair_tag,
    roc_tag,
    run_id,
    variant_action_set,
)
from jswim.errors import ConfigError
from jswim.judging.gait import PAPER


from jswim.studies.options import (
    CONTINUOUS_AGENT,
    CONTROLLER_AGENT,
    MPC_AGENT,
    OPTIMAL_AGENT,
    PPO_SHARE,
    ZERMELO_AGENT,
    STROKE_AGENT,
    StudyOptions,
    prompt_label,
)
from jswim.studies.plans import Cell, Plan, initial, run_seed, sample_id
from jswim.studies.study import Study, get, names


#: Why a study may have no use for an option (`StudyOptions` field -> reason); the
#: command line refuses such an option instead of dropping it silently.
IGNORED = {
    "zetas": "only the noise study sweeps zeta; give one level with --noise",
    "n_hts": "only the history study sweeps n_ht; give one value with --n-ht",
    "zeta": "it sweeps zeta over --zetas",
    "n_ht": "it sweeps n_ht over --n-hts",
    "q_runs": "it has no Q-learning or random-policy runs",
    "init": "it runs each of the four initial configurations",
    "roc_levels_grid": "only the continuous study sweeps K; give one value with --roc-levels",
    "roc_levels": "it sweeps K over the --roc-levels list",
    "runs": "it runs fixed strokes only, no LLM",
    "directions": "its runs swim to targets, not along a direction",
}


def ignored_options(study: str, given: Iterable[str]) -> dict[str, str]:
    """The options in ``given`` (`StudyOptions` field names) that ``study`` has no use for,
    each with the reason (`IGNORED`)."""
    ignores = get(study).ignores
    return {k: IGNORED[k] for k in given if k in ignores}


#: Shortest closed stroke that moves a swimmer: two DOFs, each out and back (a non-reciprocal
#: cycle needs at least two DOFs, so at least four moves; the scallop theorem).
MIN_PERIOD = 4


def short_steps_warning(o: StudyOptions, study: str | None = None) -> str | None:
    """A warning when runs are too short for any of them to meet the success criterion (a
    study's own warning where it declares one, `jswim.studies.study.Study.short_steps`).

    Success needs ``n_cycles`` consecutive cycles of at least `MIN_PERIOD` steps each within
    the horizon ([`Criterion`][jswim.judging.gait.Criterion]), so a run of fewer steps fails whatever it does.
    """
    spec = get(study) if study is not None else None
    if spec is not None and spec.short_steps is not None:
        return spec.short_steps(o)
    if spec is not None and not spec.judged:
        return None
    need = PAPER.n_cycles * MIN_PERIOD
    if o.steps is not None and o.steps < need:
        return (
            f"--steps {o.steps} is shorter than {PAPER.n_cycles} stroke cycles of at least {MIN_PERIOD} steps "
            f"({need} steps): no run can meet the success criterion, so every success rate will be 0"
        )
    return None


def _sweeps(cell: Cell, o: StudyOptions) -> list[tuple[float | None, str | None]]:
    """The (temperature, prompt file) settings an LLM cell runs under: the cell's own temperature
    (the temperature study) or ``--temperatures``, crossed with ``--prompt-files``."""
    temps = [cell.temperature] if cell.temperature is not None else list(o.temperatures or [None])
    prompts = list(o.prompt_files or [None])
    return [(t, p) for t in temps for p in prompts]


def _is_pair(scene: str) -> bool:
    """Whether a cell's scene (canonical JSON, ``""`` for none) holds two swimmers."""
    return bool(scene) and json.loads(scene).get("swimmers") == 2


def build(study: str, o: StudyOptions) -> list[Plan]:
    """The runs of ``study`` for options ``o``, in a fixed order (seeds follow it).

    Parameters
    ----------
    study : str
        One of `jswim.studies.names()`.
    o : StudyOptions
        The grid and agent knobs (``None`` fields resolve to the study's `jswim.studies.study.Study`).

    Returns
    -------
    list of Plan
        One per run, each with a unique run id; its seed comes from the study seed and the id.

    Raises
    ------
    ConfigError
        For an unknown study, or an option the study has no use for.
    """
    spec = get(study)
    _check_grids(spec, o)
    # Outside the competence study every LLM run uses one variant; its action set (if it sets
    # one) applies to the baselines too, so they are offered what the model is offered.
    variant = o.variant or spec.variant
    baseline_set = variant_action_set(variant, o.action_set)
    runs = {"llm": spec.runs if o.runs is None else o.runs}
    runs["qlearning"] = runs["random"] = spec.q_runs if o.q_runs is None else o.q_runs
    # A stroke is deterministic without noise: one run says it all (--q-runs of them under noise).
    runs[STROKE_AGENT] = runs["qlearning"] if o.zeta > 0 else min(1, runs["qlearning"])
    runs[CONTROLLER_AGENT] = runs[STROKE_AGENT]  # the steering controller is deterministic too
    runs[ZERMELO_AGENT] = min(1, runs["qlearning"])  # an optimal path: one says it all
    runs[OPTIMAL_AGENT] = min(1, runs["qlearning"])  # the swimmer's optimum: one sequence
    runs[MPC_AGENT] = runs[STROKE_AGENT]  # re-plans from its state: one run unless noisy
    plans: list[Plan] = []
    for sw in o.swimmers or spec.swimmers:
        for d in o.directions or spec.directions:
            for cell in spec.cells(o, sw):
                for agent in (a for a in cell.agents if a in o.agents):
                    plans += _agent_plans(spec, o, cell, agent, sw, d, variant, baseline_set, runs)
    ids = [p.run_id for p in plans]
    assert len(set(ids)) == len(ids), "run ids must be unique"
    return plans


def _check_grids(spec: Study, o: StudyOptions) -> None:
    """Refuse an option that the study would drop (it would still name the folder)."""
    others = [sw for sw in o.swimmers or () if sw not in spec.swimmers]
    if spec.swimmers_why and others:
        raise ConfigError(
            f"the {spec.name} study steers {spec.swimmers_why.format(swimmer=others[0])}; leave "
            "--swimmer out"
        )
    if o.pair_prompt != "joint" and not (
        "llm" in o.agents
        and any(
            "llm" in c.agents and _is_pair(c.scene)
            for sw in spec.swimmers
            for c in spec.cells(o, sw)
        )
    ):
        # It would be dropped here, yet it names the folder (identity): refuse it, as the CLI refuses
        # an option a study has no use for.
        raise ConfigError(
            f"the {spec.name} study has no use for --pair-prompt {o.pair_prompt} (pair_prompt: only "
            "LLM runs on a pair of swimmers read it, as in jswim study pair with the llm agent); "
            "leave it out"
        )
    defaults = StudyOptions()
    for name in own_options():
        if name in spec.own_options or name == "pair_prompt":
            continue
        value, default = getattr(o, name), getattr(defaults, name)
        if (tuple(value) if isinstance(value, (list, tuple)) else value) != default:
            flag = name.replace("_", "-")
            who = " and ".join(f"jswim study {s}" for s in owners(name))
            raise ConfigError(
                f"the {spec.name} study has no use for --{flag} (only {who} reads it); leave it out"
            )


def own_options() -> tuple[str, ...]:
    """Every `StudyOptions` field some study has as its own (`jswim.studies.study.Study.flags`)."""
    return tuple(dict.fromkeys(f for s in names() for f in get(s).own_options))


def owners(field: str) -> tuple[str, ...]:
    """The studies that have ``field`` (a `StudyOptions` field) as their own, in listing order."""
    return tuple(s for s in names() if field in get(s).own_options)


def _agent_plans(
    spec: Study,
    o: StudyOptions,
    cell: Cell,
    agent: str,
    sw: str,
    d: int,
    variant: str,
    baseline_set: str,
    runs: dict[str, int],
) -> list[Plan]:
    """The plans of one agent in one cell, for swimmer ``sw`` toward direction ``d``: its
    repeats, the LLM's sweeps (temperatures, prompt files) and samples."""
    out: list[Plan] = []
    llm = agent == "llm"
    v = (cell.variant or variant) if llm else (cell.stroke if agent == STROKE_AGENT else "")
    action_set = variant_action_set(v, o.action_set) if llm else (cell.action_set or baseline_set)
    if agent == CONTINUOUS_AGENT:
        action_set = "all"  # PPO is offered every arm and every real ROC; it has no smaller set
    # The run id names what differs from the study's own setting.
    tag = (v if v != "paper" else "") if llm else (action_set if action_set != o.action_set else "")
    levels = o.roc_levels if cell.roc_levels is None else cell.roc_levels
    # A pair's LLM runs under --pair-prompt each are named so (never a joint run's id).
    pair = o.pair_prompt if llm and _is_pair(cell.scene) else "joint"
    tag = "-".join(
        t
        for t in (
            tag,
            pair_tag(pair),
            "real" if levels == 0 else roc_tag(levels),
            cell.tag,
        )
        if t
    )
    zeta = float(o.zeta if cell.zeta is None else cell.zeta)
    n_ht = cell.n_ht if llm else None
    drop = cell.drop if llm else frozenset()
    for temp, prompt in _sweeps(cell, o) if llm else [(None, None)]:
        # A sweep's setting names its runs (run id) and its rows (group).
        tags = "-".join(
            t
            for t in [
                tag,
                f"T{temp:g}" if temp is not None else "",
                f"p-{prompt_label(prompt)}" if prompt else "",
            ]
            if t
        )
        swept = ([f"T={temp:g}"] if temp is not None and cell.temperature is None else []) + (
            [f"prompt={prompt_label(prompt)}"] if prompt else []
        )
        group = ", ".join(g for g in [cell.group, *swept] if g)
        steps = o.steps if o.steps is not None else cell.steps or spec.steps
        episodes = 1
        if cell.target and o.steps is None:
            steps = None  # the target's budget: its world measures it (navigate.with_budgets)
        if cell.target and agent in ("qlearning", CONTINUOUS_AGENT):
            # learners train over many episodes (PPO a half: each of its steps
            # moves 16 swimmers; jswim.studies.kinds.navigate)
            share = PPO_SHARE if agent == CONTINUOUS_AGENT else 1
            episodes = max(1, o.train_episodes // share)
            steps = None if steps is None else steps * episodes
        for k in range(runs.get(agent, runs["qlearning"])):
            init = initial(cell.init or o.init or spec.init, k, sw)
            base = run_id(agent, sw, d, init, zeta, n_ht=n_ht, drop=drop, tag=tags, repeat=k)
            for s in range(o.samples if llm else 1):
                rid = sample_id(base, s)
                out.append(
                    Plan(
                        rid,
                        agent,
                        sw,
                        d,
                        init,
                        zeta,
                        run_seed(o.seed, rid),
                        steps,
                        n_ht,
                        drop,
                        action_set,
                        group,
                        v,
                        temp,
                        prompt,
                        levels,
                        s,
                        cell.scene,
                        pair,
                        cell.target,
                        episodes=episodes,
                        flow=cell.flow,
                        flow_fraction=cell.flow_fraction,
                    )
                )
    return out
