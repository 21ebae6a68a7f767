"""Every study's defaults and cells as one table (`SPECS`), and `build`, which turns
a study and its options into the list of runs ([`Plan`][jswim.studies.plans.Plan]).

A study runs, per swimmer and target direction, a list of *cells* (one group of a table or
figure: a noise level, an n_ht, a dropped sentence, ...); a cell runs some agents, each
``runs`` (LLM) or ``q_runs`` (baselines) times.
"""

from __future__ import annotations

import dataclasses
import json
from dataclasses import dataclass
from collections.abc import Callable, Iterable, Mapping

from jswim.action_codes import ACTION_SETS
from jswim.agents.variants import (
    init_label,
    pair_tag,
    roc_tag,
    run_id,
    variant_action_set,
)
from jswim.env import all_inits
from jswim.errors import ConfigError
from jswim.judging.gait import PAPER
from jswim.prompt import SENTENCES


from jswim.studies.options import (
    COMPETENCE_VARIANTS,
    DEFAULT_ROC_LEVELS,
    CONTINUOUS_AGENT,
    CONTROLLER_AGENT,
    MPC_AGENT,
    OPTIMAL_AGENT,
    ZERMELO_AGENT,
    SCENE_GRIDS,
    STROKE_AGENT,
    WITH_BASELINES,
    StudyOptions,
    continuous_agent_available,
    prompt_label,
)
from jswim.studies.plans import Cell, Plan, initial, run_seed, sample_id
from jswim.studies import navigate
from jswim.studies.scene_grids import study_cells


def _single(o: StudyOptions) -> list[Cell]:
    return [Cell("", WITH_BASELINES, n_ht=o.n_ht)]


def _noise(o: StudyOptions) -> list[Cell]:
    return [Cell(f"zeta={z:g}", WITH_BASELINES, zeta=z, n_ht=o.n_ht) for z in o.zetas]


def _history(o: StudyOptions) -> list[Cell]:
    return [Cell(f"n_ht={h}", ("llm",), n_ht=h) for h in o.n_hts]


def _ablation(o: StudyOptions) -> list[Cell]:
    drops = [frozenset()] + [frozenset({s}) for s in SENTENCES]
    return [
        Cell("full" if not d else f"-{next(iter(d))}", ("llm",), n_ht=o.n_ht, drop=d) for d in drops
    ]


def _inits(o: StudyOptions) -> list[Cell]:
    return [
        Cell(f"init {init_label(i)}", ("llm",), n_ht=o.n_ht, init=init_label(i))
        for i in all_inits(2)
    ]


#: The temperature study's grid (the paper's "next thing to study": T = 0 was its only setting).
DEFAULT_TEMPERATURES = (0.0, 0.25, 0.5, 0.75, 1.0)


def _temperature(o: StudyOptions) -> list[Cell]:
    return [
        Cell(f"T={t:g}", ("llm",), n_ht=o.n_ht, temperature=t)
        for t in o.temperatures or DEFAULT_TEMPERATURES
    ]


def _continuous(o: StudyOptions) -> list[Cell]:
    # Each lattice for the LLM and both tabular baselines, then the real-valued RL baseline once.
    lattices = [
        Cell(f"K={k}", WITH_BASELINES, n_ht=o.n_ht, roc_levels=k) for k in o.roc_levels_grid
    ]
    real = (
        [Cell("continuous", (CONTINUOUS_AGENT,), roc_levels=0)]
        if continuous_agent_available()
        else []
    )
    return lattices + real


def _competence(o: StudyOptions) -> list[Cell]:
    llm = [Cell(v, ("llm",), n_ht=o.n_ht, variant=v) for v in o.variants or COMPETENCE_VARIANTS]
    return llm + [
        Cell(s, (agent,), action_set=s) for agent in ("random", "qlearning") for s in ACTION_SETS
    ]


@dataclass(frozen=True)
class StudySpec:
    """A study's defaults and its cells (what ``None`` in `StudyOptions` resolves to)."""

    cells: Callable[[StudyOptions], list[Cell]]
    runs: int  # LLM runs per cell
    init: str = "cycle"
    swimmers: tuple[str, ...] = ("purcell", "ng")
    directions: tuple[int, ...] = (1,)
    q_runs: int = 100  # baseline runs per cell
    steps: int = 50  # steps per run (the paper's horizon)
    steps_text: str | None = None  # --steps' default in words, where the cells set their own
    judged: bool = True  # success is the paper's criterion (a stroke found), not a target reached
    ignores: tuple[str, ...] = (
        "zetas",
        "n_hts",
        "roc_levels_grid",
    )  # StudyOptions fields the study has no use for (IGNORED)
    constrain: str | None = (
        None  # decoding when the backend says "auto" (None: the backend's own choice)
    )
    # An option's help in this study's own words (flag -> text), where the general wording
    # (jswim.cli.run_options.FLAGS) would name another default or offer what the study refuses.
    option_help: Mapping[str, str] = dataclasses.field(default_factory=dict)


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


#: Every study (``jswim study NAME``; ``swim`` is ``jswim swim``), its defaults in one place.
SPECS: dict[str, StudySpec] = {
    # X/a against step n: LLM, Q-learning and random policy, both swimmers (Fig. 2)
    "curves": StudySpec(_single, runs=1, init="paper"),
    # the n_ht sweep, both directions, both swimmers (Fig. 3)
    "history": StudySpec(
        _history,
        runs=1,
        init="paper",
        directions=(1, -1),
        ignores=("zetas", "n_ht", "q_runs", "roc_levels_grid"),
    ),
    # mean X/a and success rate p against zeta (Fig. 4)
    "noise": StudySpec(_noise, runs=10, ignores=("zeta", "n_hts", "roc_levels_grid")),
    # the full prompt and the prompt without each of S1..S5 (Fig. 5)
    # (free-text replies unless --constrain says otherwise: with a grammar, removing S5 removes nothing)
    "ablation": StudySpec(
        _ablation,
        runs=10,
        ignores=("zetas", "n_hts", "q_runs", "roc_levels_grid"),
        constrain="none",
    ),
    # all four initial configurations, both directions
    "inits": StudySpec(
        _inits,
        runs=1,
        directions=(1, -1),
        ignores=("zetas", "n_hts", "q_runs", "init", "roc_levels_grid"),
    ),
    # the main job: a few LLM runs next to Q-learning and random learners
    "swim": StudySpec(_single, runs=4, init="paper", swimmers=("purcell",)),
    # every protocol variant next to random and Q-learning baselines on both action sets
    "competence": StudySpec(_competence, runs=10),
    # p and steps to learn against the sampling temperature T, both swimmers and directions
    "temperature": StudySpec(
        _temperature,
        runs=5,
        init="paper",
        directions=(1, -1),
        ignores=("zetas", "n_hts", "q_runs", "roc_levels_grid"),
    ),
    # continuous strokes (an extension): the LLM, lattice Q-learning and random at K in {1, 2, 5, 10},
    # and the real-valued RL baseline, both swimmers, both directions (README "Continuous strokes")
    "continuous": StudySpec(
        _continuous,
        runs=2,
        init="paper",
        directions=(1, -1),
        ignores=("zetas", "n_hts", "roc_levels"),
        option_help={
            "--roc-levels": "the ROC levels K to compare (an extension): a reply's ROC k in -K..K "
            "moves the DOF by k/K of its range, for the LLM and the lattice baselines alike "
            f"(default {','.join(map(str, DEFAULT_ROC_LEVELS))}; 1 is the paper's -1, 0, 1)"
        },
    ),
}


# The wall study's horizon, 400 steps (100 square cycles), is set by the measured drift
# (docs/scenes.md, "Fates above the wall"): an NG swimmer's height changes by ~0.02 a in 50 steps,
# so at 50 steps every run reads as gliding; at 400, from tilt 0, h0 = 1.2 and 1.5 a touch the wall
# (7 and 29 cycles) and h0 = 2-50 a glide (from 2-10 a on orbits of ~800-900 cycles).
SPECS["wall"] = StudySpec(
    study_cells("wall"),
    runs=1,
    steps=400,
    init="paper",
    swimmers=("ng",),
    q_runs=10,
    ignores=("zetas", "n_hts", "roc_levels_grid", "init"),
)
SPECS["pair"] = StudySpec(
    study_cells("pair"),
    runs=1,
    init="paper",
    swimmers=("ng",),
    q_runs=10,
    ignores=("zetas", "n_hts", "roc_levels_grid", "init"),
)
# Schools: N NG swimmers in a line or side by side, fixed strokes only.
SPECS["school"] = StudySpec(
    study_cells("school"),
    runs=0,
    init="paper",
    swimmers=("ng",),
    q_runs=1,
    ignores=("zetas", "n_hts", "roc_levels_grid", "init", "runs"),
)


# Navigation (an extension): targets at several distances and bearings, a path and a
# moving target; each cell's runs have the target's budget (jswim.studies.navigate).
#: Seeds of the navigation study's learners and random policy per cell (``--q-runs``): 16,
#: trained together (vmapped), so that a cell's success and time ratio carry an interval.
NAV_SEEDS = 16
SPECS["navigate"] = StudySpec(
    navigate.cells,
    runs=1,
    init="paper",
    swimmers=("purcell",),
    q_runs=NAV_SEEDS,
    ignores=("zetas", "n_hts", "roc_levels_grid", "init", "directions"),
    steps_text=(
        "each target's step budget; it is the length of an LLM run and of each training episode "
        "of Q-learning and PPO, while the controller and the random policy keep the budget"
    ),
    judged=False,
    option_help={
        "--swimmer": "purcell only (the default): navigation needs a swimmer that turns in its "
        "plane; sphere swimmers move on a line",
        "--roc-levels": "ROC on K levels, K >= 2 (an extension): a reply's ROC k in -K..K moves "
        f"the DOF by k/K of its range (default {navigate.NAV_ROC_LEVELS}; the paper's K = 1 corner world "
        "cannot turn, and is refused)",
        "--n-ht": "history records in the prompt (default 3, Purcell's)",
        "--x-min": "X_min of the position encoding (X - X_min) * 1000 (default -2.5, the paper's); "
        "each run lowers it to a whole number of link lengths below every place its target can "
        "be, so that no position is sent as a negative number",
    },
)


STUDIES = tuple(SPECS)


def ignored_options(study: str, given: Iterable[str]) -> dict[str, str]:
    """The options in ``given`` (`StudyOptions` field names) that ``study`` has no use for,
    each with the reason (`IGNORED`)."""
    spec = SPECS.get(study)
    return {k: IGNORED[k] for k in given if spec is not None and k in spec.ignores}


#: Shortest closed stroke that moves a swimmer: two DOFs, each out and back (a non-reciprocal
#: cycle needs at least two DOFs, so at least four moves; the scallop theorem).
MIN_PERIOD = 4


def short_steps_warning(o: StudyOptions, study: str | None = None) -> str | None:
    """A warning when runs are too short for any of them to meet the success criterion (none
    for a ``study`` whose success is not the paper's criterion: navigation's is the target).

    Success needs ``n_cycles`` consecutive cycles of at least `MIN_PERIOD` steps each within
    the horizon ([`Criterion`][jswim.judging.gait.Criterion]), so a run of fewer steps fails whatever it does.
    """
    if study in SPECS and not SPECS[study].judged:
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


#: The scene studies' grids as StudyOptions gives them (a changed one on another study is refused).
_DEFAULT_GRIDS = {
    f.name: f.default for f in dataclasses.fields(StudyOptions) if f.name in SCENE_GRIDS
}


def build(study: str, o: StudyOptions) -> list[Plan]:
    """The runs of ``study`` for options ``o``, in a fixed order (seeds follow it).

    Parameters
    ----------
    study : str
        One of `STUDIES`.
    o : StudyOptions
        The grid and agent knobs (``None`` fields resolve to the study's `StudySpec`).

    Returns
    -------
    list of Plan
        One per run, each with a unique run id; its seed comes from the study seed and the id.

    Raises
    ------
    ConfigError
        For an unknown study, or an option the study has no use for.
    """
    if study not in SPECS:
        raise ConfigError(f"unknown study {study!r}; choose one of {', '.join(STUDIES)}")
    spec = SPECS[study]
    _check_grids(study, spec, o)
    # Outside the competence study every LLM run uses one variant; its action set (if it sets
    # one) applies to the baselines too, so they are offered what the model is offered.
    variant = o.llm_variant(study)
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
            for cell in spec.cells(o, sw) if study == "wall" else spec.cells(o):
                for agent in (a for a in cell.agents if a in o.agents):
                    plans += _agent_plans(spec, o, cell, agent, sw, d, variant, baseline_set, runs)
    ids = [p.run_id for p in plans]
    assert len(set(ids)) == len(ids), "run ids must be unique"
    return plans


def _check_grids(study: str, spec: StudySpec, o: StudyOptions) -> None:
    """Refuse an option that ``study`` would drop (it would still name the folder)."""
    others = [sw for sw in o.swimmers or () if sw != "purcell"]
    if study == "navigate" and others:
        raise ConfigError(
            f"the navigate study steers Purcell's swimmer only (--swimmer {others[0]}: the steering "
            "controller, the targets' budgets and the turning loops are Purcell's); leave --swimmer out"
        )
    if o.pair_prompt != "joint" and not (
        "llm" in o.agents and any("llm" in c.agents and _is_pair(c.scene) for c in spec.cells(o))
    ):
        # It would be dropped here, yet it names the folder (identity): refuse it, as the CLI refuses
        # an option a study has no use for.
        raise ConfigError(
            f"the {study} study has no use for --pair-prompt {o.pair_prompt} (pair_prompt: only LLM "
            "runs on a pair of swimmers read it, as in jswim study pair with the llm agent); leave it out"
        )
    if study != "navigate" and o.starts != 1:
        raise ConfigError(
            f"the {study} study has no use for --starts (only jswim study navigate reads it); leave it out"
        )
    if study != "navigate" and o.flow:
        raise ConfigError(
            f"the {study} study has no use for --flow (only jswim study navigate reads it); leave it out"
        )
    for name, owners in (
        ("heights", ("wall",)),
        ("tilts", ("wall",)),
        ("separations", ("pair", "school")),
        ("phases", ("pair",)),
        ("school_sizes", ("school",)),
        ("formations", ("school",)),
        ("distances", ("navigate",)),
        ("bearings", ("navigate",)),
        ("flows", ("navigate",)),
    ):
        if (
            study not in owners and tuple(getattr(o, name)) != _DEFAULT_GRIDS[name]
        ):  # a scene grid another study would drop
            flag, who = name.replace("_", "-"), " and ".join(f"jswim study {w}" for w in owners)
            raise ConfigError(
                f"the {study} study has no use for --{flag} (only {who} reads it); leave it out"
            )


def _agent_plans(
    spec: StudySpec,
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
            # moves 16 swimmers; jswim.studies.navigate)
            share = navigate.PPO_SHARE if agent == CONTINUOUS_AGENT else 1
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
