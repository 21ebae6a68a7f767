"""Study grids: each study's defaults and axes as one table (:data:`SPECS`), and :func:`build`,
which turns a study and its options into the list of runs (:class:`Plan`).

A study runs, per swimmer and target direction, a list of *cells* (one group of a table or
figure: a noise level, an n_ht, a dropped sentence, ...); a cell runs some agents, each
``runs`` (LLM) or ``q_runs`` (baselines) times. A run's seed is derived from the study seed
and the run's own id (:func:`run_seed`), never from its place in the grid: adding a noise
level or a repeat changes no existing run, and the same run id with the same study seed is the
same run in every folder.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass
from collections.abc import Callable, Iterable

from jswim.actions import ACTION_SETS, check_action_set, check_roc_levels
from jswim.agents.defaults import paper_init
from jswim.llm.settings import check_max_tokens, check_temperature
from jswim.agents.protocol import derived_seed
from jswim.agents.variants import (
    check_pair_prompt,
    init_label,
    pair_tag,
    roc_tag,
    run_id,
    variant_action_set,
)
from jswim.env import all_inits
from jswim.env.worlds import registered_worlds
from jswim.errors import ConfigError, check_size, check_zeta
from jswim.judging.gait import PAPER
from jswim.prompt import SENTENCES
from jswim.scenes import Scene
from jswim.scenes.params import check_start
from jswim.swimmers.models import SWIMMERS, make_model

AGENTS = ("llm", "qlearning", "random")
#: The continuous-action RL baseline (real ROCs; only the continuous study runs it).
CONTINUOUS_AGENT = "ppo"
#: A fixed stroke (the signature square gait, or two copies of it for a pair): the scene studies' reference.
STROKE_AGENT = "stroke"
#: Every agent a study may run (the default of :attr:`StudyOptions.agents`).
ALL_AGENTS = AGENTS + (CONTINUOUS_AGENT, STROKE_AGENT)
#: ROC lattices of the continuous study (``--roc-levels``; K = 1 is the paper's set).
DEFAULT_ROC_LEVELS = (1, 2, 5, 10)
DEFAULT_ZETAS = (0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0)
INIT_CHOICES = ("paper", "cycle", "random", "++", "+-", "-+", "--")

#: Protocol variant of the swim study's LLM runs; the paper studies always use "paper". Chosen
#: from the measured competence study (README): on the embedded SmolLM2-135M no variant beat the
#: random baseline (0 successes in 140 runs; the model moves D1 in >= 87% of steps under every
#: variant), so none earns the switch and the paper's protocol stays the default.
SWIM_VARIANT = "paper"

#: Variants the competence study runs by default (each next to the same baselines).
COMPETENCE_VARIANTS = (
    "paper",
    "summary",
    "shuffle",
    "shape-changing",
    "shape-changing+summary",
    "shape-changing+shuffle",
    "shape-changing+temperature",
)


@dataclass(frozen=True)
class StudyOptions:
    """Knobs of a study; ``None`` means the study's own default (:data:`SPECS`).

    Raises
    ------
    ConfigError
        For a value out of range or an unknown name (the message names the command-line option).
    """

    swimmers: tuple[str, ...] | None = None
    directions: tuple[int, ...] | None = None
    runs: int | None = None  # LLM runs per setting
    q_runs: int | None = None  # Q-learning and random runs per setting
    steps: int | None = None  # steps per run; None: the study's own (StudySpec.steps)
    horizon: int = PAPER.horizon  # of the success criterion (jswim.judging.gait.Criterion)
    n_ht: int | None = None
    n_hts: tuple[int, ...] = (1, 2, 3, 4, 5, 6, 7, 8)
    zeta: float = 0.0
    zetas: tuple[float, ...] = DEFAULT_ZETAS
    init: str | None = None
    seed: int = 0
    action_set: str = "all"
    prompt_file: str | None = None
    chunk: int | None = None  # LLM runs in progress at once (None: the client's concurrency)
    agents: tuple[str, ...] = ALL_AGENTS
    variant: str | None = None  # LLM protocol variant; None: the study's (SWIM_VARIANT or "paper")
    share_identical: bool = (
        False  # send identical temperature-0 requests of different runs once (runs become copies)
    )
    x_min: float = -2.5  # X_min of the position encoding (the paper's and the code's -2.5)
    max_tokens: int | None = None  # reply length limit; None: per swimmer (10 two DOFs, 20 more)
    variants: tuple[str, ...] | None = (
        None  # competence: the variants to compare (None: all default)
    )
    # Sweeps over LLM settings, grid axes of any study (each crosses the study's LLM cells; the
    # temperature study sweeps temperatures itself). None: the backend's temperature, the one prompt.
    temperatures: tuple[float, ...] | None = None
    prompt_files: tuple[str, ...] | None = None
    # Independent repeats of each LLM run's very setting (same start, same everything but the run
    # id and so its seed); the baselines' repeats are --q-runs. Pooled into the setting's row.
    samples: int = 1
    roc_levels: int = 1  # K of the ROC lattice (--roc-levels; 1 = the paper's -1, 0, 1)
    roc_levels_grid: tuple[int, ...] = DEFAULT_ROC_LEVELS  # the continuous study's K values
    # The scene studies' grids (jswim.studies.scenes): starting heights above the wall (a), the
    # pair's starting distances D (a) and the phase offsets of its two square strokes (quarter cycles).
    heights: tuple[float, ...] = (1.2, 1.5, 2.0, 3.0, 10.0, 50.0)
    separations: tuple[float, ...] = (30.0, 60.0)
    phases: tuple[int, ...] = (0, 1, 2, 3)
    # How the LLM steers a pair (--pair-prompt): "joint" (one conversation, D1..D4) or "each" (one
    # conversation per swimmer, a variant; jswim.agents.pair_prompt). Only pair cells read it.
    pair_prompt: str = "joint"
    # The school study's grids: the school sizes N and the formations (spacings: --separations).
    school_sizes: tuple[int, ...] = (1, 2, 3, 4, 5)
    formations: tuple[str, ...] = ("line", "side")

    def __post_init__(self) -> None:
        # A value given twice (--zetas 0,0.0,1, --swimmer purcell,purcell) names one setting once.
        for name in ("swimmers", "directions", "zetas", "n_hts", "variants"):
            values = getattr(self, name)
            if values is not None and len(set(values)) < len(values):
                object.__setattr__(self, name, tuple(dict.fromkeys(values)))
        for name in ("steps", "runs", "q_runs", "samples", "n_ht"):
            if getattr(self, name) is not None:
                check_size(name, getattr(self, name))
        for h in self.n_hts:
            check_size("n_ht", h, "--n-hts")
        if self.init is not None and self.init not in INIT_CHOICES:
            raise ConfigError(f"--init must be one of {', '.join(INIT_CHOICES)}, got {self.init!r}")
        check_action_set(self.action_set)
        for z in (self.zeta, *self.zetas):
            check_zeta(z, "--noise")
        if not math.isfinite(self.x_min):
            raise ConfigError(f"--x-min must be a finite number, got {self.x_min}")
        check_max_tokens(self.max_tokens)
        if self.chunk is not None and self.chunk < 1:
            raise ConfigError("--chunk must be >= 1")
        for sw in self.swimmers or ():
            if sw not in SWIMMERS + registered_worlds():
                raise ConfigError(
                    f"unknown swimmer {sw!r}; choose one of {', '.join(SWIMMERS + registered_worlds())}"
                )
        for name in ([self.variant] if self.variant else []) + list(self.variants or ()):
            variant_action_set(name)  # raises for an unknown name
        for t in self.temperatures or ():
            check_temperature(t, "--temperatures")
        for name, values in (
            ("--temperatures", self.temperatures),
            ("--prompt-files", self.prompt_files),
        ):
            if values is not None and (not values or len(set(values)) != len(values)):
                raise ConfigError(
                    f"{name} must list distinct values, got {','.join(map(str, values))}"
                )
        stems = [prompt_label(f) for f in self.prompt_files or ()]
        if len(set(stems)) != len(stems):
            raise ConfigError(
                "--prompt-files: two files have the same name (it names their runs); rename one"
            )
        if self.prompt_files and self.prompt_file:
            raise ConfigError("give --prompt-file or --prompt-files, not both")
        for k in (self.roc_levels, *self.roc_levels_grid):
            check_roc_levels(k)
        if not self.roc_levels_grid or len(set(self.roc_levels_grid)) != len(self.roc_levels_grid):
            raise ConfigError(f"--roc-levels needs distinct values, got {self.roc_levels_grid}")
        for name in ("heights", "separations", "phases"):
            values = getattr(self, name)
            if not values or len(set(values)) != len(values):
                raise ConfigError(
                    f"--{name} needs distinct values, got {','.join(map(str, values))}"
                )
        if any(not (math.isfinite(h) and h > 1.0) for h in self.heights):
            raise ConfigError(
                f"--heights must be above 1 sphere radius (the middle sphere touches the wall at 1), "
                f"got {','.join(map(str, self.heights))}"
            )
        if any(not (math.isfinite(d) and d > 0) for d in self.separations):
            raise ConfigError(
                f"--separations must be positive distances, got {','.join(map(str, self.separations))}"
            )
        if any(p not in (0, 1, 2, 3) for p in self.phases):
            raise ConfigError(
                f"--phases are quarter cycles 0, 1, 2 or 3, got {','.join(map(str, self.phases))}"
            )
        check_pair_prompt(self.pair_prompt)
        _check_school(self.school_sizes, self.formations)
        for f in (
            self.formations if max(self.school_sizes) > 1 else ()
        ):  # a pair is a line; a school each
            for d in self.separations:
                try:  # the scenes' own start check: the swimmers' geometry, written once
                    check_start(
                        "ng", Scene(medium="free", swimmers=2, separation=float(d), formation=f)
                    )
                except ConfigError as exc:
                    raise ConfigError(f"--separations {d:g} ({f}): {exc}") from None
        bad = sorted(set(self.agents) - set(ALL_AGENTS))
        if bad:
            raise ConfigError(f"unknown agents {bad}; choose from {', '.join(ALL_AGENTS)}")

    def llm_variant(self, study: str) -> str:
        """The protocol variant of the study's LLM runs (outside the competence study)."""
        return self.variant or (SWIM_VARIANT if study == "swim" else "paper")


@dataclass(frozen=True)
class Plan:
    """One run of a study."""

    run_id: str
    agent: str
    swimmer: str
    direction: int
    init: tuple[int, ...] | str
    zeta: float
    seed: int
    steps: int
    n_ht: int | None = None
    drop: frozenset[str] = frozenset()
    action_set: str = "all"
    group: str = ""
    variant: str = (
        "paper"  # LLM protocol variant (jswim.agents.variants.VARIANTS); "" for baselines
    )
    temperature: float | None = None  # LLM sampling temperature of a sweep (None: the backend's)
    prompt_file: str | None = (
        None  # LLM prompt template of a --prompt-files sweep (None: the study's)
    )
    roc_levels: int = (
        1  # K of the ROC lattice (1: the paper's); the continuous agent's real ROCs: 0
    )
    sample: int = 0  # which independent repeat of this very setting (--samples; 0: the run itself)
    scene: str = ""  # canonical JSON of the run's Scene (:func:`scene_json`); "": the bulk fluid
    pair_prompt: str = (
        "joint"  # an LLM run on a pair: one joint conversation or one per swimmer ("each")
    )


def sample_id(run: str, sample: int) -> str:
    """The run id of sample ``sample`` of run ``run``: sample 0 is the run itself (so a folder made
    before ``--samples`` extends), later ones end in ``-sample<k>``."""
    return run if sample == 0 else f"{run}-sample{sample}"


def prompt_label(path: str) -> str:
    """A prompt file's label in run ids and groups: its name without the suffix."""
    from pathlib import Path

    return Path(path).stem.replace(" ", "_") or "prompt"


@dataclass(frozen=True)
class Cell:
    """One group of a study: the agents it runs (in this order) and what differs from the
    study's defaults (``zeta``, ``n_ht``, ``drop``, ``init``, ``variant``, ``action_set``)."""

    group: str
    agents: tuple[str, ...]
    zeta: float | None = None  # None: the options' zeta
    n_ht: int | None = None  # LLM runs only
    drop: frozenset[str] = frozenset()
    init: str | None = None  # None: the study's init choice
    variant: str | None = None  # LLM runs only; None: the options' variant
    action_set: str | None = None  # baselines only; None: the LLM variant's action set
    temperature: float | None = None  # LLM runs only (the temperature study)
    roc_levels: int | None = None  # None: the options' roc_levels; 0 for real-valued ROCs
    scene: str = ""  # a scene (jswim.studies.scenes), canonical JSON; "": the bulk fluid
    tag: str = ""  # what names this cell's runs (a scene's height or distance, a stroke's phase)
    stroke: str = (
        ""  # the stroke agent's stroke (jswim.studies.scenes.stroke_codes), its plans' variant
    )


WITH_BASELINES = ("llm", "qlearning", "random")


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


def continuous_agent_available() -> bool:
    """Whether the real-valued RL baseline (:mod:`jswim.agents.ppo`) is installed."""
    import importlib.util

    return importlib.util.find_spec("jswim.agents.ppo") is not None


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
    """A study's defaults and its cells (what ``None`` in :class:`StudyOptions` resolves to)."""

    cells: Callable[[StudyOptions], list[Cell]]
    runs: int  # LLM runs per cell
    init: str = "cycle"
    swimmers: tuple[str, ...] = ("purcell", "ng")
    directions: tuple[int, ...] = (1,)
    q_runs: int = 100  # baseline runs per cell
    steps: int = 50  # steps per run (the paper's horizon)
    ignores: tuple[str, ...] = (
        "zetas",
        "n_hts",
        "roc_levels_grid",
    )  # StudyOptions fields the study has no use for (IGNORED)
    constrain: str | None = (
        None  # decoding when the backend says "auto" (None: the backend's own choice)
    )


#: Why a study may have no use for an option (:class:`StudyOptions` field -> reason); the
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
        _temperature, runs=5, init="paper", directions=(1, -1), ignores=("zetas", "n_hts", "q_runs")
    ),
    # continuous strokes (an extension): the LLM, lattice Q-learning and random at K in {1, 2, 5, 10},
    # and the real-valued RL baseline, both swimmers, both directions (README "Continuous strokes")
    "continuous": StudySpec(
        _continuous,
        runs=2,
        init="paper",
        directions=(1, -1),
        ignores=("zetas", "n_hts", "roc_levels"),
    ),
}


def scene_json(scene: Scene) -> str:
    """A scene as canonical JSON (``Scene.to_dict()``, sorted keys): the form plans and run ids carry."""
    return json.dumps(scene.to_dict(), sort_keys=True)


def wall_scene(h: float) -> str:
    return scene_json(Scene(medium="wall", height=float(h), swimmers=1))


def pair_scene(d: float | None = None) -> str:
    """Two coaxial swimmers ``d`` apart in the unbounded fluid of the point-force solve; ``None``:
    one swimmer alone there."""
    if d is None:
        return scene_json(Scene(medium="free", swimmers=1))
    return scene_json(Scene(medium="free", swimmers=2, separation=float(d)))


def scene_cells(study: str, o: StudyOptions, swimmer: str = "ng") -> list[Cell]:
    """The cells of ``study`` (``"wall"`` or ``"pair"``) for the options' grids. Every swimmer's
    wall cells run the same agents at each height: the stroke, the LLM, Q-learning, random and
    PPO. Only the reference differs: Purcell's swimmer above a wall (issue 34) swims in a plane
    parallel to it, so its reference is the paper's bulk fluid (group ``bulk``); NG's (and a
    registered world's) is the unbounded fluid of the scene solver (group ``free``)."""
    if study == "wall":
        ref = "bulk" if swimmer == "purcell" else "free"
        out = [
            Cell(
                ref, (STROKE_AGENT,), scene=scene_json(Scene(medium=ref)), stroke="square", tag=ref
            )
        ]
        for h in o.heights:
            out.append(
                Cell(
                    f"h={h:g}",
                    (STROKE_AGENT, *WITH_BASELINES),
                    n_ht=o.n_ht,
                    scene=wall_scene(h),
                    stroke="square",
                    tag=f"h{h:g}",
                )
            )
            out += _ppo_cells(f"h={h:g}", wall_scene(h), f"h{h:g}")
        return out
    out = [Cell("alone", (STROKE_AGENT,), scene=pair_scene(), stroke="square", tag="alone")]
    for d in o.separations:
        for ph in o.phases:
            out.append(
                Cell(
                    f"D={d:g}, phase {ph}",
                    (STROKE_AGENT,),
                    scene=pair_scene(d),
                    stroke=f"phase{ph}",
                    tag=f"D{d:g}-ph{ph}",
                )
            )
        out.append(
            Cell(f"D={d:g}", WITH_BASELINES, n_ht=o.n_ht, scene=pair_scene(d), tag=f"D{d:g}")
        )
        out += _ppo_cells(f"D={d:g}", pair_scene(d), f"D{d:g}")
    return out


def school_scene(n: int, d: float, formation: str = "line") -> str:
    """``n`` swimmers ``d`` apart in a line or side by side, in the unbounded fluid of the
    point-force solve (one swimmer: alone there)."""
    if n == 1:
        return pair_scene()
    return scene_json(
        Scene(medium="free", swimmers=int(n), separation=float(d), formation=formation)
    )


def school_cells(o: StudyOptions) -> list[Cell]:
    """The school study's cells: every swimmer doing the square stroke, in turn and in phase
    (stroke ``phase0``), for each formation, spacing and size (a lone swimmer once)."""
    out = (
        [Cell("alone", (STROKE_AGENT,), scene=pair_scene(), stroke="square", tag="alone")]
        if 1 in o.school_sizes
        else []
    )
    for f in o.formations:
        for d in o.separations:
            out += [
                Cell(
                    f"{f}, D={d:g}, N={n}",
                    (STROKE_AGENT,),
                    scene=school_scene(n, d, f),
                    stroke="phase0",
                    tag=f"{f}-D{d:g}-N{n}",
                )
                for n in o.school_sizes
                if n > 1
            ]
    return out


def _check_school(sizes: tuple[int, ...], formations: tuple[str, ...]) -> None:
    from jswim.scenes.scene import (
        FORMATIONS,
        MAX_SWIMMERS,
    )  # lazy: start-up (the CLI's outline loads no scenes)

    if (
        not sizes
        or len(set(sizes)) != len(sizes)
        or any(isinstance(n, bool) or n not in range(1, MAX_SWIMMERS + 1) for n in sizes)
    ):
        raise ConfigError(
            f"--school-sizes needs distinct swimmer counts in 1..{MAX_SWIMMERS}, got "
            f"{','.join(map(str, sizes))}"
        )
    if (
        not formations
        or len(set(formations)) != len(formations)
        or set(formations) - set(FORMATIONS)
    ):
        raise ConfigError(
            f"--formations needs distinct values of {', '.join(FORMATIONS)}, got {','.join(formations)}"
        )


def _ppo_cells(group: str, scene: str, tag: str) -> list[Cell]:
    """The continuous RL baseline's cell next to the other agents of a group (same group name,
    real ROCs: run ids ``ppo-...-real-<tag>-r<k>``; :mod:`jswim.studies.scenes`)."""
    if not continuous_agent_available():
        return []
    return [Cell(group, (CONTINUOUS_AGENT,), scene=scene, roc_levels=0, tag=tag)]


def _scene_cells(name: str) -> Callable[[StudyOptions], list[Cell]]:
    def cells(o: StudyOptions, swimmer: str = "ng") -> list[Cell]:
        if o.roc_levels != 1:  # the scene rows read and judge K = 1 codes; PPO has real ROCs anyway
            raise ConfigError(
                f"the {name} study has no use for --roc-levels {o.roc_levels} (its LLM, Q-learning, "
                "random and stroke runs use the paper's ROCs -1, 0, 1 and its PPO runs real ROCs in "
                "[-1, 1]); leave it out"
            )
        return school_cells(o) if name == "school" else scene_cells(name, o, swimmer)

    return cells


# Walls and pairs (issue 19, extensions): NG swimmers only (jswim.studies.scenes, README "Walls,
# obstacles and pairs"); --init is the paper's NG start (10, 6), the scene's start.
# Their horizon, 400 steps (100 square cycles), is set by the measured drift (docs/scenes.md, "Fates
# above the wall"): an NG swimmer's height changes by ~0.02 a in 50 steps, so at 50 steps every run
# reads as gliding; at 400, from tilt 0, h0 = 1.2 and 1.5 a touch the wall (7 and 29 cycles) and
# h0 = 2-50 a glide (from 2-10 a on orbits of ~800-900 cycles).
SPECS["wall"] = StudySpec(
    _scene_cells("wall"),
    runs=1,
    steps=400,
    init="paper",
    swimmers=("ng",),
    q_runs=10,
    ignores=("zetas", "n_hts", "roc_levels_grid", "init"),
)
SPECS["pair"] = StudySpec(
    _scene_cells("pair"),
    runs=1,
    init="paper",
    swimmers=("ng",),
    q_runs=10,
    ignores=("zetas", "n_hts", "roc_levels_grid", "init"),
)
# Schools (issue 34): N NG swimmers in a line or side by side, fixed strokes only.
SPECS["school"] = StudySpec(
    _scene_cells("school"),
    runs=0,
    init="paper",
    swimmers=("ng",),
    q_runs=1,
    ignores=("zetas", "n_hts", "roc_levels_grid", "init"),
)

STUDIES = tuple(SPECS)


def ignored_options(study: str, given: Iterable[str]) -> dict[str, str]:
    """The options in ``given`` (:class:`StudyOptions` field names) that ``study`` has no use for,
    each with the reason (:data:`IGNORED`)."""
    spec = SPECS.get(study)
    return {k: IGNORED[k] for k in given if spec is not None and k in spec.ignores}


#: Shortest closed stroke that moves a swimmer: two DOFs, each out and back (a non-reciprocal
#: cycle needs at least two DOFs, so at least four moves; the scallop theorem).
MIN_PERIOD = 4


def short_steps_warning(o: StudyOptions) -> str | None:
    """A warning when runs are too short for any of them to meet the success criterion.

    Success needs ``n_cycles`` consecutive cycles of at least :data:`MIN_PERIOD` steps each within
    the horizon (:class:`jswim.judging.gait.Criterion`), so a run of fewer steps fails whatever it does.
    """
    need = PAPER.n_cycles * MIN_PERIOD
    if o.steps is not None and o.steps < need:
        return (
            f"--steps {o.steps} is shorter than {PAPER.n_cycles} stroke cycles of at least {MIN_PERIOD} steps "
            f"({need} steps): no run can meet the success criterion, so every success rate will be 0"
        )
    return None


def initial(choice: str, k: int, swimmer: str = "purcell") -> tuple[int, ...] | str:
    """Initial configuration of repeat ``k`` of ``swimmer`` (default model options).

    ``paper``: the authors' start (:func:`jswim.agents.defaults.paper_init`: Purcell (+, +),
    NG (10, 6), four-sphere (6, 10, 10), four-link every hinge at +2pi/9); ``cycle`` goes
    through every corner of the DOF cube; ``random``; or a sign string (``"+-"``), one sign
    per DOF.

    Raises
    ------
    ConfigError
        A sign string whose length is not the swimmer's number of DOFs.

    A world of :func:`jswim.register_world` starts where it starts: ``"default"``.
    """
    if swimmer in registered_worlds():
        return "default"
    model = make_model(swimmer)
    if choice == "paper":
        return paper_init(model)
    if choice == "cycle":
        corners = all_inits(model.n_dof)
        return corners[k % len(corners)]
    if choice == "random":
        return "random"
    if len(choice) != model.n_dof or set(choice) - {"+", "-"}:
        raise ConfigError(
            f"--init {choice}: {swimmer} has {model.n_dof} DOFs; give one sign per DOF, "
            "or paper, cycle or random"
        )
    return tuple(1 if ch == "+" else 0 for ch in choice)


def run_seed(study_seed: int, run: str) -> int:
    """The seed of run ``run`` (its id) in a study seeded ``study_seed``: a 31-bit hash of both.

    Any integer study seed works (negative, huge); the result fits every PRNG key.
    """
    return derived_seed("run-seed", int(study_seed), run)


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
    f.name: f.default
    for f in dataclasses.fields(StudyOptions)
    if f.name in ("heights", "separations", "phases", "school_sizes", "formations")
}


def build(study: str, o: StudyOptions) -> list[Plan]:
    """The runs of ``study`` for options ``o``, in a fixed order (seeds follow it).

    Raises
    ------
    ConfigError
        For an unknown study.
    """
    if study not in SPECS:
        raise ConfigError(f"unknown study {study!r}; choose one of {', '.join(STUDIES)}")
    spec = SPECS[study]
    if o.pair_prompt != "joint" and not (
        "llm" in o.agents and any("llm" in c.agents and _is_pair(c.scene) for c in spec.cells(o))
    ):
        # It would be dropped here, yet it names the folder (identity): refuse it, as the CLI refuses
        # an option a study has no use for.
        raise ConfigError(
            f"the {study} study has no use for --pair-prompt {o.pair_prompt} (pair_prompt: only LLM "
            "runs on a pair of swimmers read it, as in jswim study pair with the llm agent); leave it out"
        )
    for name, owners in (
        ("heights", ("wall",)),
        ("separations", ("pair", "school")),
        ("phases", ("pair",)),
        ("school_sizes", ("school",)),
        ("formations", ("school",)),
    ):
        if (
            study not in owners and tuple(getattr(o, name)) != _DEFAULT_GRIDS[name]
        ):  # a scene grid another study would drop
            flag, who = name.replace("_", "-"), " and ".join(f"jswim study {w}" for w in owners)
            raise ConfigError(
                f"the {study} study has no use for --{flag} (only {who} reads it); leave it out"
            )
    # Outside the competence study every LLM run uses one variant; its action set (if it sets
    # one) applies to the baselines too, so they are offered what the model is offered.
    variant = o.llm_variant(study)
    baseline_set = variant_action_set(variant, o.action_set)
    runs = {"llm": spec.runs if o.runs is None else o.runs}
    runs["qlearning"] = runs["random"] = spec.q_runs if o.q_runs is None else o.q_runs
    # A stroke is deterministic without noise: one run says it all (--q-runs of them under noise).
    runs[STROKE_AGENT] = runs["qlearning"] if o.zeta > 0 else min(1, runs["qlearning"])
    plans: list[Plan] = []
    for sw in o.swimmers or spec.swimmers:
        for d in o.directions or spec.directions:
            for cell in spec.cells(o, sw) if study == "wall" else spec.cells(o):
                for agent in (a for a in cell.agents if a in o.agents):
                    llm = agent == "llm"
                    v = (
                        (cell.variant or variant)
                        if llm
                        else (cell.stroke if agent == STROKE_AGENT else "")
                    )
                    action_set = (
                        variant_action_set(v, o.action_set)
                        if llm
                        else (cell.action_set or baseline_set)
                    )
                    if agent == CONTINUOUS_AGENT:
                        action_set = "all"  # PPO is offered every arm and every real ROC; it has no smaller set
                    # The run id names what differs from the study's own setting.
                    tag = (
                        (v if v != "paper" else "")
                        if llm
                        else (action_set if action_set != o.action_set else "")
                    )
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
                        swept = (
                            [f"T={temp:g}"] if temp is not None and cell.temperature is None else []
                        ) + ([f"prompt={prompt_label(prompt)}"] if prompt else [])
                        group = ", ".join(g for g in [cell.group, *swept] if g)
                        for k in range(runs.get(agent, runs["qlearning"])):
                            init = initial(cell.init or o.init or spec.init, k, sw)
                            base = run_id(
                                agent, sw, d, init, zeta, n_ht=n_ht, drop=drop, tag=tags, repeat=k
                            )
                            for s in range(o.samples if llm else 1):
                                rid = sample_id(base, s)
                                plans.append(
                                    Plan(
                                        rid,
                                        agent,
                                        sw,
                                        d,
                                        init,
                                        zeta,
                                        run_seed(o.seed, rid),
                                        spec.steps if o.steps is None else o.steps,
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
                                    )
                                )
    ids = [p.run_id for p in plans]
    assert len(set(ids)) == len(ids), "run ids must be unique"
    return plans
