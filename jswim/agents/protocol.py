"""The paper's protocol as pure functions: no client, no event loop, no environment.

One decision of one run is two calls:

- [`request`][jswim.agents.protocol.request]: run state and history in, the prompt, the chat messages and the offered
  actions out;
- [`read_reply`][jswim.agents.protocol.read_reply]: a reply in, the action it names out, or the follow-up messages of a retry,
  or nothing (give up: the driver executes `NO_OP` and counts a
  failed step).

[`setup`][jswim.agents.protocol.setup] fixes what a run keeps for its whole length (n_ht, the swimmer's text, the prompt
knobs). The driver ([`jswim.agents.llm`][jswim.agents.llm]) does the I/O around these: it sends the messages,
steps the swimmers and records the history ([`jswim.agents.memory`][jswim.agents.memory]).
"""

from __future__ import annotations

import hashlib
import random
from dataclasses import dataclass
from typing import Any
from collections.abc import Sequence

from jswim.agents.defaults import default_clearing, default_max_tokens, default_n_ht, swimmer_text
from jswim.agents.memory import ClearingRule, MoveStats, render_summary
from jswim.agents.variants import LLMAgentConfig, LLMRunSpec
from jswim.prompt import (
    Action,
    HistoryRecord,
    PromptConfig,
    SwimmerText,
    allowed_actions,
    build_messages,
    parse_reply,
    render_prompt,
)
from jswim.swimmers.models import SwimmerModel


def derived_seed(*parts: Any) -> int:
    """A 31-bit seed from ``parts`` (run seed, step, purpose...): stable across runs and machines."""
    digest = hashlib.blake2b(repr(parts).encode(), digest_size=8).digest()
    return int.from_bytes(digest, "little") & 0x7FFFFFFF


def setup(
    spec: LLMRunSpec, model: SwimmerModel, cfg: LLMAgentConfig
) -> tuple[int, SwimmerText, PromptConfig]:
    """What a run keeps from start to end: ``(n_ht, swimmer text, prompt knobs)``.

    ``n_ht`` and the ROC set come from the spec, else from the swimmer's agent defaults
    (`jswim.agents.defaults`), on the spec's ROC lattice (``spec.roc_levels``).
    """
    n_ht = spec.n_ht if spec.n_ht is not None else default_n_ht(model, spec.direction)
    text = swimmer_text(model, spec.rocs, spec.roc_levels)
    prompt = PromptConfig(
        n_ht=n_ht,
        x_min=cfg.x_min,
        drop=spec.drop,
        action_set=cfg.action_set,
        template=cfg.template,
        system=cfg.system,
        summary=cfg.summary,
        shuffle=cfg.shuffle,
        order=cfg.order,
    )
    return n_ht, text, prompt


def clearing_rule(cfg: LLMAgentConfig, model: SwimmerModel) -> ClearingRule:
    """The run's clearing rule: the config's, else the swimmer's (`default_clearing`)."""
    return cfg.clearing if cfg.clearing is not None else default_clearing(model)


#: Tokens a constrained reply needs: ``[1, -1]`` takes up to ~6 tokens, the JSON-schema form
#: ``{"action": "[1, -1]"}`` up to ~12; the limit is raised to this where the format needs it.
CONSTRAINED_MIN_TOKENS = {"grammar": 10, "json_schema": 24, "json_object": 24}


def max_tokens(cfg: LLMAgentConfig, model: SwimmerModel, constraint: str = "none") -> int:
    """Reply length limit of a request: the config's, else the swimmer's (10 two DOFs, 20 more,
    the authors' code); raised to `CONSTRAINED_MIN_TOKENS` where a constrained format
    (``constraint``, the resolved mode) needs more."""
    base = cfg.max_tokens if cfg.max_tokens is not None else default_max_tokens(model)
    return max(base, CONSTRAINED_MIN_TOKENS.get(constraint, 0))


@dataclass(frozen=True)
class Request:
    """One decision's request.

    Attributes
    ----------
    prompt : str
        The user message's text.
    messages : list of dict
        Chat messages of the first attempt.
    allowed : list of Action
        Valid replies in (DOF, ROC) order: the grammar's order and what parsing accepts.
    options : list of Action
        The same actions in the order S5 lists them (shuffled by the ``shuffle`` variant).
    """

    prompt: str
    messages: list[dict[str, str]]
    allowed: list[Action]
    options: list[Action]

    @property
    def replies(self) -> list[str]:
        """The allowed replies as text, for constrained decoding (never shuffled)."""
        return [a.text() for a in self.allowed]


def request(
    cfg: LLMAgentConfig,
    text: SwimmerText,
    prompt: PromptConfig,
    *,
    direction: int,
    seed: int,
    step: int,
    records: Sequence[HistoryRecord],
    dofs: Sequence[float],
    x: float,
    stats: MoveStats,
    target: tuple[float, float] | None = None,
    waypoint: int = 1,
) -> Request:
    """The request of decision ``step`` (1-based) of a run.

    Parameters
    ----------
    cfg : LLMAgentConfig
        Agent settings (variant switches).
    text, prompt : SwimmerText, PromptConfig
        From [`setup`][jswim.agents.protocol.setup].
    direction : {+1, -1}
        Target direction.
    seed : int
        The run's seed (orders the shuffled options; the same run replays exactly).
    records : sequence of HistoryRecord
        History since the last clear ([`jswim.agents.memory.History`][jswim.agents.memory.History]).
    dofs : sequence of float
        Current DOF values.
    x : float
        Current X.
    stats : MoveStats
        Observed progress so far (read only by the summary variant).
    target : tuple of float, optional
        A navigation task's target now (``text.nav`` set), ``(x, y)``.
    waypoint : int
        Which waypoint of a path it is (1-based).
    """
    allowed = allowed_actions(text, cfg.action_set, dofs)
    options = list(allowed)
    if cfg.shuffle:  # same set, new order; seeded per run and step so a run replays exactly
        random.Random(derived_seed(seed, step, "shuffle")).shuffle(options)
    summary = render_summary(text, stats, dofs, options, direction) if cfg.summary else ""
    body = render_prompt(
        text,
        prompt,
        direction,
        records,
        dofs,
        x,
        options=options,
        summary=summary,
        target=target,
        waypoint=waypoint,
    )
    return Request(body, build_messages(body, cfg.system), allowed, options)


def sample_seed(run_seed: int, step: int, attempt: int, temperature: float) -> int | None:
    """Seed of a sampled request (``None`` at temperature 0): one per run, step and attempt, so
    runs differ and each replays."""
    return derived_seed(run_seed, step, attempt, "sample") if temperature > 0 else None


@dataclass(frozen=True)
class Reply:
    """What a reply means: an ``action``, or the ``follow_up`` messages of a retry, or neither
    (retries used up: the step fails)."""

    action: Action | None
    follow_up: list[dict[str, str]] | None = None


#: Follow-up of a reply the server cut off at ``max_tokens`` (``{allowed}`` is filled in).
CUTOFF_PROMPT = (
    "Your reply was cut off before it named an action. Answer only with one of {allowed}."
)

#: The assistant turn of a follow-up when the cut-off reply had no answer text at all.
CUTOFF_TURN = "(reply cut off)"


def valid_reply(req: Request, reply: str) -> bool:
    """Whether ``reply`` (an answer, reasoning already split off) names one of the allowed actions."""
    return parse_reply(reply, req.allowed) is not None


def read_reply(
    req: Request,
    messages: Sequence[dict[str, str]],
    reply: str,
    attempt: int,
    cfg: LLMAgentConfig,
    *,
    truncated: bool = False,
) -> Reply:
    """Read the reply to ``messages`` (attempt ``attempt``, 0-based) of request ``req``.

    ``reply`` is the answer, after any reasoning (the client splits reasoning off; it is never
    parsed). A reply cut off at ``max_tokens`` (``truncated``) has no answer, whatever its text:
    it could stop in the middle of "not [1, 1] but ...". A reply without a valid action gets a
    short corrective follow-up (a new request, so a deterministic server is never sent the same
    request again and temperature-0 caching cannot replay the bad reply) while
    ``attempt < cfg.parse_retries``.
    """
    action = None if truncated else parse_reply(reply, req.allowed)
    if action is not None:
        return Reply(action)
    if attempt >= cfg.parse_retries:
        return Reply(None)
    offered = ", ".join(a.text() for a in req.options)
    ask = CUTOFF_PROMPT if truncated else cfg.retry_prompt
    return Reply(
        None,
        list(messages)
        + [
            {"role": "assistant", "content": reply or (CUTOFF_TURN if truncated else "")},
            {"role": "user", "content": ask.format(allowed=offered)},
        ],
    )
