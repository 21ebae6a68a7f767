"""A study's options: the knobs a user turns (`StudyOptions`, each checked once, the
command line's option named in every error) and the agents a study may run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from jswim.action_codes import check_action_set, check_roc_levels
from jswim.llm.settings import check_max_tokens, check_temperature
from jswim.agents.variants import (
    check_pair_prompt,
    variant_action_set,
)
from jswim.env.registry import registered_worlds
from jswim.env.flows import FLOWS
from jswim.env.targets import MAX_BEARING, MAX_DISTANCE
from jswim.errors import ConfigError, check_size, check_zeta
from jswim.judging.gait import PAPER
from jswim.results.orders import STROKE_AGENT
from jswim.scenes import Scene
from jswim.scenes.scene_parameters import check_start
from jswim.swimmers.models import SWIMMERS


AGENTS = ("llm", "qlearning", "random")
#: The PPO baseline: real-valued ROCs in the continuous and scene studies, categorical over the
#: K-level codes in navigation.
CONTINUOUS_AGENT = "ppo"
#: PPO trains for ``train_episodes / PPO_SHARE`` episodes (of its first swimmer; it pools 16,
#: `jswim.studies.kinds.navigate.nav_ppo_config`): 200 at the default, 51,200 steps
#: at 90 degrees, about 15 s for one learner on the shared CPU; it reached the 90-degree target
#: in 13 of 16 seeds after 40,000 steps (docs/navigation.md).
PPO_SHARE = 2
#: A fixed stroke (the signature square gait, or two copies of it for a pair): the scene studies' reference.
#: The steering controller (turn with an off-centre loop, then the square gait): the navigation
#: study's reference stroke (jswim.agents.steering).
CONTROLLER_AGENT = "controller"
#: Zermelo's point steerer (jswim.agents.zermelo): the time-optimal path through a flow at the
#: swimming speed, the navigation study's yardstick in a flow (its rows' time ratios).
ZERMELO_AGENT = "zermelo"
#: The swimmer's own optimum (jswim.agents.optimal): the least-time sequence of the world's own
#: actions, the navigation study's yardstick (its rows' time ratios).
OPTIMAL_AGENT = "optimal"
#: The model-predictive agent (jswim.agents.mpc): the optimum re-planned from its own state.
MPC_AGENT = "mpc"
#: The agents of a paper study's cells that run next to the LLM.
WITH_BASELINES = ("llm", "qlearning", "random")
#: Every agent a study may run (the default of `StudyOptions.agents`).
ALL_AGENTS = AGENTS + (
    CONTINUOUS_AGENT,
    STROKE_AGENT,
    CONTROLLER_AGENT,
    ZERMELO_AGENT,
    OPTIMAL_AGENT,
    MPC_AGENT,
)
#: The navigation study's flow speeds (``--flows``), fractions of the swimming speed, and the
#: largest it takes.
DEFAULT_FLOWS = (0.0, 0.5, 0.9)
MAX_FLOW = 2.0
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

#: The scene and navigation studies' grids (`StudyOptions` fields, each some study's own
#: option, `jswim.studies.study.Study.flags`): sizes of the grid (a folder grows when one grows).
SCENE_GRIDS = (
    "heights",
    "tilts",
    "separations",
    "phases",
    "school_sizes",
    "formations",
    "distances",
    "bearings",
    "flows",
)


@dataclass(frozen=True)
class StudyOptions:
    """Knobs of a study; ``None`` means the study's own default (`jswim.studies.study.Study`).

    Raises
    ------
    ConfigError
        For a value out of range or an unknown name (the message names the command-line option).
    """

    swimmers: tuple[str, ...] | None = None
    directions: tuple[int, ...] | None = None
    runs: int | None = None  # LLM runs per setting
    q_runs: int | None = None  # Q-learning and random runs per setting
    steps: int | None = None  # steps per run; None: the study's own (Study.steps)
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
    variant: str | None = None  # LLM protocol variant; None: the study's (Study.variant)
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
    # The scene studies' grids (jswim.studies.scene_studies): starting heights above the wall (a), the
    # pair's starting distances D (a) and the phase offsets of its two square strokes (quarter cycles).
    heights: tuple[float, ...] = (1.2, 1.5, 2.0, 3.0, 10.0, 50.0)
    # The wall study's start tilts (rad, nose up; NG only): each height runs at each tilt whose
    # start clears the wall. 0.8 is the nose-up start chosen from the measured drift so that one
    # default run escapes within the default 400 steps (h = 10 a; docs/scenes.md, "Fates above the wall").
    tilts: tuple[float, ...] = (0.0, 0.8)
    separations: tuple[float, ...] = (30.0, 60.0)
    phases: tuple[int, ...] = (0, 1, 2, 3)
    # How the LLM steers a pair (--pair-prompt): "joint" (one conversation, D1..D4) or "each" (one
    # conversation per swimmer, a variant; jswim.agents.pair_prompt). Only pair cells read it.
    pair_prompt: str = "joint"
    # The school study's grids: the school sizes N and the formations (spacings: --separations).
    school_sizes: tuple[int, ...] = (1, 2, 3, 4, 5)
    formations: tuple[str, ...] = ("line", "side")
    # The navigation study's grid (jswim.studies.kinds.navigate): fixed targets at these distances (a)
    # crossed with these bearings (degrees from the start heading, counterclockwise).
    distances: tuple[float, ...] = (3.0,)
    bearings: tuple[float, ...] = (0.0, 90.0, 180.0)
    # The navigation study in a background flow (jswim.env.flows.study_flow): its kind ("": still
    # fluid) and its speeds, fractions of the swimming speed (a grid: each target at each).
    flow: str = ""
    flows: tuple[float, ...] = DEFAULT_FLOWS
    # Episodes of each target's budget that Q-learning and PPO train for in the navigation study.
    train_episodes: int = 400
    # Seeded starts of every navigation agent (heading and shape; jswim.studies.kinds.navigate.seeded_start),
    # the same for every agent: start 0 is the study's own, (hi, hi) headed along +x.
    starts: int = 1

    def __post_init__(self) -> None:
        # A value given twice (--zetas 0,0.0,1, --swimmer purcell,purcell) names one setting once.
        for name in (
            "swimmers",
            "directions",
            "zetas",
            "n_hts",
            "variants",
            "distances",
            "bearings",
        ):
            values = getattr(self, name)
            if values is not None and len(set(values)) < len(values):
                object.__setattr__(self, name, tuple(dict.fromkeys(values)))
        for name in ("steps", "runs", "q_runs", "samples", "n_ht", "train_episodes", "starts"):
            if getattr(self, name) is not None:
                check_size(name, getattr(self, name))
        if any(not (math.isfinite(d) and 0.25 < d <= MAX_DISTANCE) for d in self.distances):
            raise ConfigError(
                f"--distances must be beyond the success radius 0.25 a and at most {MAX_DISTANCE:g} a, "
                "got " + ",".join(map(str, self.distances))
            )
        if any(not (math.isfinite(b) and abs(b) <= MAX_BEARING) for b in self.bearings):
            raise ConfigError(
                f"--bearings must be degrees in -{MAX_BEARING:g}..{MAX_BEARING:g}, "
                f"got {','.join(map(str, self.bearings))}"
            )
        self._check_flows()
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
        for name in ("heights", "tilts", "separations", "phases"):
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
        if any(not (math.isfinite(t) and abs(t) < math.pi / 2) for t in self.tilts):
            raise ConfigError(
                f"--tilts must be angles in (-pi/2, pi/2) rad (nose up positive), "
                f"got {','.join(map(str, self.tilts))}"
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

    def _check_flows(self) -> None:
        if self.flow and self.flow not in FLOWS:
            raise ConfigError(f"--flow must be one of {', '.join(FLOWS)}, got {self.flow!r}")
        if (
            any(
                isinstance(f, bool) or not isinstance(f, (int, float)) or not 0 <= f <= MAX_FLOW
                for f in self.flows
            )
            or not self.flows
        ):
            raise ConfigError(
                f"--flows must be fractions of the swimming speed in 0..{MAX_FLOW:g}, "
                f"got {','.join(map(str, self.flows))}"
            )
        if len(set(self.flows)) < len(self.flows):
            object.__setattr__(self, "flows", tuple(dict.fromkeys(self.flows)))
        if not self.flow and tuple(self.flows) != DEFAULT_FLOWS:
            raise ConfigError("--flows sets the speeds of a flow: give its kind with --flow KIND")


def prompt_label(path: str) -> str:
    """A prompt file's label in run ids and groups: its name without the suffix."""
    from pathlib import Path

    return Path(path).stem.replace(" ", "_") or "prompt"


def continuous_agent_available() -> bool:
    """Whether the real-valued RL baseline ([`ppo`][jswim.agents.ppo]) is installed."""
    import importlib.util

    return importlib.util.find_spec("jswim.agents.ppo") is not None


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
