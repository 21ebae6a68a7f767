"""Each swimmer of a pair (or a school) its own LLM conversation (``--pair-prompt each``;
a variant of the joint prompt, which stays the default).

Each conversation is kept as the paper keeps a lone swimmer's (its own D1, D2 and X, its own last
``n_ht`` records and clearing rule; S2 and every record also name the others,
`jswim.prompt.OWN_PAIR_SENTENCE`), with the same request, parsing, follow-ups and no-op on
failure as every LLM run ([`jswim.agents.protocol`][jswim.agents.protocol]). Swimmer ``k`` of ``N`` decides at steps
``k, k + N, ...``; the run's row is the joint one (joint action codes, ``x`` the swimmers' mean,
whose progress is the reward). The prompt's text and the turns: docs/scenes.md, "Pair: one prompt
per swimmer".

Everything here is pure (no client, no environment): the driver ([`jswim.agents.llm`][jswim.agents.llm]) keeps
one [`Conversation`][jswim.agents.pair_prompt.Conversation] per swimmer on a run and asks [`turn`][jswim.agents.pair_prompt.turn] whose step it is.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any
from collections.abc import Sequence

import numpy as np

from jswim.agents import protocol, world_view
from jswim.agents.memory import History, MoveStats, shape_key
from jswim.agents.variants import LLMAgentConfig, LLMRunSpec
from jswim.prompt import Action, HistoryRecord, PromptConfig, SceneView, SwimmerText
from jswim.swimmers.models import SwimmerModel

#: Arms (DOFs) of one swimmer of a pair or school (swimmer ``s`` owns DOFs ``2s + 1, 2s + 2``).
ARMS = 2


@dataclass
class Conversation:
    """One swimmer's conversation: its prompt text, knobs, history and what it sees now.

    The fields the driver reads have the names of its own run state (``text``, ``prompt``,
    ``history``, ``stats``, ``dofs``, ``x``), so one request path serves both prompts.
    """

    swimmer: int  # 0-based
    text: SwimmerText
    prompt: PromptConfig
    history: History
    dofs: np.ndarray  # its own two arms, float64 (2,)
    x: float = 0.0  # its own position (a, displacement from its start)
    stats: MoveStats = field(default_factory=MoveStats)


def conversations(
    spec: LLMRunSpec,
    model: SwimmerModel,
    cfg: LLMAgentConfig,
    dofs: Sequence[float],
    view: SceneView,
) -> list[Conversation]:
    """The conversations of a ``pair_prompt="each"`` run in a world of ``view.swimmers`` swimmers
    whose joint DOFs start at ``dofs`` (``(ARMS N,)``): each with the lone swimmer's n_ht and
    clearing rule ([`protocol.setup`][jswim.agents.protocol.setup], [`protocol.clearing_rule`][jswim.agents.protocol.clearing_rule]) and its own text and
    template ([`jswim.agents.world_view.text`][jswim.agents.world_view.text] with ``own``)."""
    _, base, prompt = protocol.setup(spec, model, cfg)
    out = []
    for s in range(view.swimmers):
        text, template = world_view.text(base, prompt.template, len(dofs), view, own=s + 1)
        out.append(
            Conversation(
                s,
                text,
                dataclasses.replace(prompt, template=template),
                History(protocol.clearing_rule(cfg, model)),
                np.asarray(dofs, np.float64)[ARMS * s : ARMS * (s + 1)].copy(),
            )
        )
    return out


def turn(step: int, swimmers: int = 2) -> int:
    """The swimmer (0-based) whose conversation decides step ``step`` (1-based): swimmer ``k``
    (1-based) at steps ``k, k + N, ...``."""
    return (step - 1) % swimmers


def to_joint(swimmer: int, action: Action) -> Action:
    """A swimmer's own reply ``[d, roc]`` (d in 1, 2) as the joint action ``[d + 2 swimmer, roc]``."""
    return Action(action.dof + ARMS * swimmer, action.roc)


def swimmer_of(action: Action) -> int:
    """The swimmer (0-based) a joint action moves."""
    return (action.dof - 1) // ARMS


def own_record(rec: HistoryRecord, swimmer: int) -> HistoryRecord:
    """A joint step's record as ``swimmer`` sees it: its own arms, its own action and its own X
    (the joint record's scene fields keep every swimmer's position, for the others' X)."""
    own = slice(ARMS * swimmer, ARMS * (swimmer + 1))
    return dataclasses.replace(
        rec,
        dofs_before=tuple(rec.dofs_before[own]),
        dofs_after=tuple(rec.dofs_after[own]),
        action=Action(rec.action.dof - ARMS * swimmer, rec.action.roc),
        x_before=rec.xs_before[swimmer],
        x_after=rec.xs_after[swimmer],
    )


def record(convs: Sequence[Conversation], rec: HistoryRecord, direction: int) -> bool:
    """Enter the joint step ``rec`` into the conversation of the swimmer it moved (its record, its
    observed progress, its clearing rule), and move the others' view on (their positions change
    too: the swimmers feel each other). Returns whether the mover's history was cleared."""
    s = swimmer_of(rec.action)
    mine = own_record(rec, s)
    progress = direction * mine.dx
    c = convs[s]
    c.stats.add(shape_key(c.text, mine.dofs_before), mine.action, progress)
    cleared = c.history.add(mine, progress)
    for k, conv in enumerate(convs):
        conv.dofs = np.asarray(rec.dofs_after[ARMS * k : ARMS * (k + 1)], np.float64)
        conv.x = float(rec.xs_after[k])
    return cleared


def metadata(convs: Sequence[Conversation]) -> dict[str, Any]:
    """What a transcript's first line records of the conversations."""
    n = len(convs)
    turns = (
        "swimmer 1 at odd steps, swimmer 2 at even steps"
        if n == 2
        else f"swimmer k at steps k, k + {n}, ..."
    )
    return {
        "pair_prompt": "each",
        "turns": turns,
        "conversations": [
            {"swimmer": c.swimmer + 1, "n_ht": c.prompt.n_ht, "clearing": c.history.rule.describe()}
            for c in convs
        ],
    }
