"""The prompt's knobs: [`PromptConfig`][jswim.prompt.PromptConfig] (n_ht, X_min, the sentence mask,
the allowed set, the template and order) and the sentence mask's parser.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from jswim.action_codes import check_action_set
from jswim.errors import ConfigError, check_size
from jswim.prompt.template import (
    CACHE_LAYOUT,
    CACHE_LAYOUT_LATE,
    DEFAULT_TEMPLATE,
    PAPER_LAYOUT,
    SENTENCES,
    PromptTemplate,
)


#: Prompt orders (`PromptConfig.order`).
ORDERS = ("paper", "cache")


#: The system message of the authors' code: a single space (the paper uses no system prompt).
PAPER_SYSTEM = " "


def normalize_mask(mask: Iterable[str] | Sequence[bool] | None) -> frozenset[str]:
    """Sentence names to drop, from names (``{"S4"}``) or five keep-flags (``(1, 1, 1, 0, 1)``)."""
    if mask is None:
        return frozenset()
    items = list(mask)
    if items and all(isinstance(v, (bool, int)) and not isinstance(v, str) for v in items):
        if len(items) != len(SENTENCES):
            raise ConfigError(
                f"a keep-mask needs {len(SENTENCES)} flags (S1..S5), got {len(items)}"
            )
        return frozenset(n for n, keep in zip(SENTENCES, items) if not keep)
    names = frozenset(str(v).upper() for v in items)
    bad = names - set(SENTENCES)
    if bad:
        raise ConfigError(f"unknown sentence names {sorted(bad)} in the mask; use {SENTENCES}")
    return names


@dataclass(frozen=True)
class PromptConfig:
    """Prompt knobs (the paper's values are the defaults, ``n_ht`` aside, which it tunes).

    Attributes
    ----------
    n_ht : int
        History records shown.
    x_min : float
        Lower bound of X for the integer encoding.
    drop : frozenset of str
        Sentences to leave out (see [`normalize_mask`][jswim.prompt.normalize_mask]).
    action_set : {"all", "shape-changing"}
        Which actions S5 (and constrained decoding) offers (`jswim.action_codes.ACTION_SETS`).
    template : PromptTemplate
        The text.
    system : str, optional
        A system message (the authors' code sends a single space, `PAPER_SYSTEM`).
    summary : bool
        Add the observed-progress sentence ([`jswim.agents.memory.render_summary`][jswim.agents.memory.render_summary]); off in the paper.
    shuffle : bool
        S5 lists the options in an order that changes per step (set by the caller through
        ``options``); in the cache order, moves S5 behind the history.
    order : {"paper", "cache"}
        Sentence order when the template keeps the default layout: the paper's S1..S5 (history
        third), or every fixed sentence first for prefix caching (`ORDERS`).
    """

    n_ht: int = 3
    x_min: float = -2.5
    drop: frozenset[str] = frozenset()
    action_set: str = "all"
    template: PromptTemplate = DEFAULT_TEMPLATE
    system: str | None = None
    summary: bool = False
    shuffle: bool = False
    order: str = "paper"

    def __post_init__(self) -> None:
        object.__setattr__(self, "drop", normalize_mask(self.drop))
        if self.order not in ORDERS:
            raise ConfigError(f"order must be one of {', '.join(ORDERS)}, got {self.order!r}")
        check_size("n_ht", self.n_ht)
        check_action_set(self.action_set)

    @property
    def layout(self) -> str:
        """The layout used: the template's; with ``order="cache"`` and the default layout,
        `CACHE_LAYOUT`, or `CACHE_LAYOUT_LATE` when S5 or the summary change from
        step to step."""
        layout = self.template.layout
        if self.order == "cache" and layout == PAPER_LAYOUT:
            layout = CACHE_LAYOUT
        if layout == CACHE_LAYOUT and (self.action_set != "all" or self.shuffle or self.summary):
            return CACHE_LAYOUT_LATE
        return layout
