"""A study's runs: one `Plan` per run, the `Cell` (group) it belongs to, and what
makes a run itself: its start (`initial`) and its seed (`run_seed`), derived from the
study seed and the run's own id, never from its place in the grid, so adding a noise level or a
repeat changes no existing run, and the same run id with the same study seed is the same run in
every folder.
"""

from __future__ import annotations

from dataclasses import dataclass

from jswim.agents.defaults import paper_init
from jswim.agents.protocol import derived_seed
from jswim.env import all_inits
from jswim.env.registry import registered_worlds
from jswim.errors import ConfigError
from jswim.swimmers.models import make_model


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
    # Steps of the run; None: ``episodes`` of its navigation target's budget, which the world
    # measures when it is made (`jswim.studies.kinds.navigate.with_budgets` fills it in before the
    # runs start: planning computes no physics).
    steps: int | None
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
    scene: str = ""  # canonical JSON of the run's Scene (`scene_json`); "": the bulk fluid
    pair_prompt: str = (
        "joint"  # an LLM run on a pair: one joint conversation or one per swimmer ("each")
    )
    target: str = ""  # a navigation target (canonical JSON of its spec); "": the paper's task
    episodes: int = 1  # budgets a navigation learner trains for (steps None: of its target's)
    flow: str = ""  # a navigation run's background flow (canonical JSON, flow_json); "": still
    flow_fraction: float | None = None  # that flow's speed over the swimming speed (--flows)


def sample_id(run: str, sample: int) -> str:
    """The run id of sample ``sample`` of run ``run``: sample 0 is the run itself (so a folder made
    before ``--samples`` extends), later ones end in ``-sample<k>``."""
    return run if sample == 0 else f"{run}-sample{sample}"


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
    scene: str = ""  # a scene (jswim.studies.scene_studies), canonical JSON; "": the bulk fluid
    tag: str = ""  # what names this cell's runs (a scene's height or distance, a stroke's phase)
    stroke: str = ""  # the stroke agent's stroke (jswim.studies.scene_studies.stroke_codes), its plans' variant
    target: str = ""  # a navigation target (jswim.studies.kinds.navigate), canonical JSON; "": none
    steps: int | None = None  # the cell's own steps per run; None: the study's (a target's budget)
    flow: str = ""  # a navigation cell's background flow (canonical JSON); "": still fluid
    flow_fraction: float | None = None  # its speed over the swimming speed (--flows)


def initial(choice: str, k: int, swimmer: str = "purcell") -> tuple[int, ...] | str:
    """Initial configuration of repeat ``k`` of ``swimmer`` (default model options).

    ``paper``: the authors' start (`jswim.agents.defaults.paper_init`: Purcell (+, +),
    NG (10, 6), four-sphere (6, 10, 10), four-link every hinge at +2pi/9); ``cycle`` goes
    through every corner of the DOF cube; ``random``; or a sign string (``"+-"``), one sign
    per DOF.

    Raises
    ------
    ConfigError
        A sign string whose length is not the swimmer's number of DOFs.

    A world of [`register_world`][jswim.env.registry.register_world] starts where it starts: ``"default"``.
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
