"""What defines an LLM run: its spec and id, the agent's settings, and the named protocol variants.

Variants of the paper's protocol (all off by default, each a field of [`LLMAgentConfig`][jswim.agents.variants.LLMAgentConfig]
recorded in every transcript and result row): the action set (every action, or only the moves
that change the shape), the observed-progress summary sentence, the order of the options in S5
shuffled per step (exposes position bias), and a per-request temperature with a seed derived
from the run's seed, the step and the attempt (reproducible sampling; never cached). None of them
chooses for the model: the model always has every allowed option (at least two), and nothing is
ranked or pruned by observed value.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from dataclasses import dataclass
from typing import Any
from collections.abc import Iterable

from jswim.action_codes import check_action_set, check_roc_levels
from jswim.agents.memory import ClearingRule
from jswim.errors import ConfigError, check_choice
from jswim.llm.settings import check_max_tokens, check_temperature
from jswim.prompt import (
    DEFAULT_TEMPLATE,
    ORDERS,
    PAPER_SYSTEM,
    Action,
    PromptTemplate,
    normalize_mask,
)


def init_label(init: tuple[int, ...] | str | None) -> str:
    """An initial configuration as text: levels as signs (``"+-"``; ``"?"`` for a random DOF),
    ``"random"`` as is, ``None`` (every DOF at hi) as ``"default"``."""
    if init is None:
        return "default"
    if isinstance(init, str):
        return init
    return "".join("+" if v == 1 else "-" if v == 0 else "?" for v in init)


def run_id(
    agent: str,
    swimmer: str,
    direction: int,
    init: tuple[int, ...] | str | None,
    zeta: float,
    *,
    n_ht: int | None = None,
    drop: Iterable[str] = (),
    tag: str = "",
    repeat: int | None = None,
    seed: int | None = None,
) -> str:
    """The one builder of run ids (study folders' rows and transcript file names).

    ``llm-purcell-px-i++-z0-h4-noS4-shape-changing-r0``: agent, swimmer, target direction,
    initial configuration, noise level, then only what is set: n_ht, the dropped sentences, a
    ``tag`` (a variant or an action set), the repeat ``r`` and the seed ``s``. Study folders
    store these ids, so the format is part of a folder's identity: change it only with a
    reader for the old one.
    """
    parts = [agent, swimmer, "px" if direction > 0 else "mx", f"i{init_label(init)}", f"z{zeta:g}"]
    if n_ht is not None:
        parts.append(f"h{n_ht}")
    drop = sorted(drop)
    if drop:
        parts.append("no" + "".join(drop))
    if tag:
        parts.append(tag)
    if repeat is not None:
        parts.append(f"r{repeat}")
    if seed is not None:
        parts.append(f"s{seed}")
    return "-".join(parts)


def roc_tag(roc_levels: int) -> str:
    """The run-id tag of a ROC lattice: ``""`` for the paper's (K = 1), else ``"K<K>"``."""
    return "" if roc_levels == 1 else f"K{roc_levels}"


def target_tag(target: str) -> str:
    """The run-id tag of a navigation target (canonical JSON, ``""``: none): its kind and a
    short hash of the spec, e.g. ``nav-fixed-3f2a9c1b``."""
    if not target:
        return ""
    digest = hashlib.sha256(target.encode()).hexdigest()[:8]
    return f"nav-{json.loads(target).get('kind', 'target')}-{digest}"


#: How an LLM steers a pair of swimmers (``--pair-prompt``): ``"joint"`` (default), one conversation
#: for both through joint DOFs D1..D4; ``"each"`` (a variant), one conversation per swimmer, each
#: with its own D1, D2, history and clearing, the two taking turns ([`jswim.agents.pair_prompt`][jswim.agents.pair_prompt]).
PAIR_PROMPTS = ("joint", "each")


def check_pair_prompt(value: str) -> str:
    """``value`` if it is one of `PAIR_PROMPTS`.

    Raises
    ------
    ConfigError
        For any other value.
    """
    return check_choice(value, PAIR_PROMPTS, "--pair-prompt")


def pair_tag(pair_prompt: str) -> str:
    """The run-id tag of a pair's prompt: ``""`` for the joint one (the default), else its name."""
    return "" if pair_prompt == "joint" else pair_prompt


#: Executed when the model gives no valid action: hold still.
NO_OP = Action(1, 0)

DEFAULT_RETRY_PROMPT = "That reply names no valid action. Answer only with one of {allowed}."


@dataclass(frozen=True)
class LLMRunSpec:
    """One run: a swimmer, a task and the prompt knobs that may differ between runs.

    Attributes
    ----------
    swimmer : str
        ``"purcell"``, ``"ng"``, ... (see [`jswim.env.make_params`][jswim.env.params.make_params]).
    swimmer_options : tuple of (str, value)
        Model options, e.g. ``(("d_max", math.pi / 4),)``.
    direction : {+1, -1}
        Target direction.
    init : tuple of int, str or None
        Initial DOF levels (see [`jswim.env.parse_init`][jswim.start_levels.parse_init]); ``None``: all at ``hi``.
    zeta : float
        Noise level.
    seed : int
        Seed of the run's noise and random initial configuration.
    n_steps : int
        Steps to run.
    n_ht : int or None
        History records in the prompt; ``None``: the swimmer's default.
    drop : frozenset of str
        Sentences left out of the prompt.
    rocs : tuple of int or None
        ROCs offered; ``None``: the swimmer's default.
    roc_levels : int
        ``K`` of the ROC lattice: a reply's ROC ``k`` in ``-K..K`` moves the DOF by ``k/K`` of its
        range (1: the paper's -1, 0, 1; above 1 an extension, named in the run id as ``K<K>``).
    run_id : str or None
        Name of the run (transcript file name); default from the fields above.
    scene : str
        A scene (walls, obstacles, pairs) as canonical JSON of ``Scene.to_dict()``
        ([`jswim.studies.scene_grids.scene_json`][jswim.studies.scene_grids.scene_json]); ``""``: the paper's lone swimmer in bulk fluid.
    pair_prompt : {"joint", "each"}
        A pair's prompt (`PAIR_PROMPTS`): one joint conversation, or one per swimmer
        (``"each"`` needs a scene of two or more swimmers; named ``each`` in the default run id).
    target : str
        A navigation task (an extension; docs/navigation.md) as canonical JSON of the target
        spec's ``to_dict()`` ([`jswim.env.targets`][jswim.env.targets]); ``""``: the paper's
        task along ``direction``. The run ends when the target is reached or after ``n_steps``
        (the target's budget in a study), whichever is first.
    flow : str
        A navigation task's background flow (an extension; canonical JSON of the flow's
        ``to_dict()``, [`jswim.env.flows`][jswim.env.flows]); ``""``: still fluid. The records
        then show the local flow (docs/navigation.md, *Flows*).
    """

    swimmer: str = "purcell"
    swimmer_options: tuple[tuple[str, Any], ...] = ()
    direction: int = 1
    init: tuple[int, ...] | str | None = None
    zeta: float = 0.0
    seed: int = 0
    n_steps: int = 50
    n_ht: int | None = None
    drop: frozenset[str] = frozenset()
    rocs: tuple[int, ...] | None = None
    run_id: str | None = None
    roc_levels: int = 1
    scene: str = ""
    pair_prompt: str = "joint"
    target: str = ""
    flow: str = ""

    def __post_init__(self) -> None:
        object.__setattr__(self, "drop", normalize_mask(self.drop))
        if self.n_steps < 1:
            raise ConfigError(f"n_steps must be >= 1, got {self.n_steps}")
        check_roc_levels(self.roc_levels)
        check_pair_prompt(self.pair_prompt)
        if self.pair_prompt == "each" and (
            not self.scene or json.loads(self.scene).get("swimmers", 1) < 2
        ):
            raise ConfigError("--pair-prompt each needs a scene with two or more swimmers")

    def label(self) -> str:
        """``run_id``, or one built from the fields by [`run_id`][jswim.agents.variants.run_id] (seed in place of a repeat)."""
        if self.run_id:
            return self.run_id
        return run_id(
            "llm",
            self.swimmer,
            self.direction,
            self.init,
            self.zeta,
            n_ht=self.n_ht,
            drop=self.drop,
            tag="-".join(
                t
                for t in (
                    pair_tag(self.pair_prompt),
                    roc_tag(self.roc_levels),
                    target_tag(self.target),
                )
                if t
            ),
            seed=self.seed,
        )


@dataclass(frozen=True)
class LLMAgentConfig:
    """Study-wide agent settings (the paper's values are the defaults).

    Attributes
    ----------
    action_set : {"all", "shape-changing"}
        Actions offered in S5 and by constrained decoding (`jswim.action_codes.ACTION_SETS`).
    x_min : float
        Lower bound of X for the integer position encoding.
    template : PromptTemplate
        Prompt text.
    system : str or None
        System message: a single space as in the authors' code (the paper names none); ``None``
        sends none.
    clearing : ClearingRule or None
        History clearing scheme; ``None``: the swimmer's, as in the authors' code
        (`jswim.agents.defaults.default_clearing`).
    parse_retries : int
        Extra requests after a reply without a valid action.
    retry_prompt : str
        Follow-up message of such a retry (``{allowed}`` is filled in).
    share_identical : bool
        Off (the paper's independent repeats): every run makes its own calls, and the response
        cache only answers a run with its own earlier reply to the same step (resume). On (a
        cost saving): identical temperature-0 requests of different runs are sent once and
        shared, and the cache answers any run; runs from one start are then copies of one run.
    summary : bool
        Add the observed-progress sentence (`jswim.prompt.render_summary`).
    shuffle : bool
        List the allowed actions in S5 in a new random order at every step (seeded by the run's
        seed and the step); the grammar is unchanged.
    temperature : float or None
        Sampling temperature of every request; ``None`` keeps the client's (paper: 0). Above 0
        each request carries a seed derived from the run's seed, step and attempt.
    order : {"paper", "cache"}
        Sentence order: the paper's S1..S5, or the prefix-cache friendly one
        ([`jswim.prompt.PromptConfig`][jswim.prompt.PromptConfig]).
    max_tokens : int or None
        Reply length limit; ``None``: the swimmer's (10 for two DOFs, 20 for more, the authors'
        code), raised where a constrained format needs more ([`jswim.agents.protocol.max_tokens`][jswim.agents.protocol.max_tokens]).
    variant : str
        Name of this combination of knobs (a label for tables; ``"paper"`` = the paper's).
    """

    action_set: str = "all"
    x_min: float = -2.5
    template: PromptTemplate = DEFAULT_TEMPLATE
    system: str | None = PAPER_SYSTEM
    clearing: ClearingRule | None = None
    parse_retries: int = 2
    retry_prompt: str = DEFAULT_RETRY_PROMPT
    share_identical: bool = False
    summary: bool = False
    shuffle: bool = False
    temperature: float | None = None
    order: str = "paper"
    max_tokens: int | None = None
    variant: str = "paper"

    def __post_init__(self) -> None:
        check_action_set(self.action_set)
        check_choice(self.order, ORDERS, "order")
        check_max_tokens(self.max_tokens)
        if self.temperature is not None:
            check_temperature(self.temperature)

    def sampling_temperature(self, client_temperature: float) -> float:
        """The temperature requests go out with: this config's, else the client's."""
        return self.temperature if self.temperature is not None else client_temperature

    def knobs(self, client_temperature: float) -> dict[str, Any]:
        """The variant switches as flat values (result rows, summaries)."""
        return {
            "variant": self.variant,
            "action_set": self.action_set,
            "summary": self.summary,
            "shuffle": self.shuffle,
            "temperature": float(self.sampling_temperature(client_temperature)),
            "order": self.order,
            "share_identical": self.share_identical,
        }

    def metadata(self) -> dict[str, Any]:
        d = dataclasses.asdict(self)
        t = self.template
        d["template"] = {"layout": t.layout, "sentences": dict(t.sentences), "record": t.record}
        return d


#: Named protocol variants: the [`LLMAgentConfig`][jswim.agents.variants.LLMAgentConfig] fields each one sets ("paper" sets none).
#: Every switch is honest in the sense of the project: the model always sees every allowed
#: option (at least two), nothing is ranked or pruned by observed value, and the summary reports
#: observed data only.
VARIANTS: dict[str, dict[str, Any]] = {
    "paper": {},
    "cache-order": {"order": "cache"},
    "shape-changing": {"action_set": "shape-changing"},
    "summary": {"summary": True},
    "shape-changing+summary": {"action_set": "shape-changing", "summary": True},
    "shuffle": {"shuffle": True},
    "shape-changing+shuffle": {"action_set": "shape-changing", "shuffle": True},
    "temperature": {"temperature": 0.7},
    "shape-changing+temperature": {"action_set": "shape-changing", "temperature": 0.7},
    "shape-changing+summary+temperature": {
        "action_set": "shape-changing",
        "summary": True,
        "temperature": 0.7,
    },
}


def variant_config(name: str, **fields: Any) -> LLMAgentConfig:
    """The agent config of variant ``name``: ``fields`` first, then the variant's switches.

    Raises
    ------
    ConfigError
        For an unknown name.
    """
    return LLMAgentConfig(**{**fields, **_switches(name), "variant": name})


def variant_action_set(name: str, default: str = "all") -> str:
    """The action set variant ``name`` uses (``default`` when it leaves it alone).

    Raises
    ------
    ConfigError
        For an unknown name.
    """
    return _switches(name).get("action_set", default)


def _switches(name: str) -> dict[str, Any]:
    if name not in VARIANTS:
        raise ConfigError(f"unknown variant {name!r}; choose one of {', '.join(VARIANTS)}")
    return VARIANTS[name]
