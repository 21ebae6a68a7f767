"""A study kind as one object ([`Study`][jswim.studies.study.Study]) and the registry the rest of
jswim asks ([`get`][jswim.studies.study.get], [`names`][jswim.studies.study.names]), in the manner
of gymnax's ``make``: the runner, the folder, the page, ``jswim show``, ``compare``, the bench and
the command line read what a study declares here; nothing compares a study's name.

Each study kind is one module of `jswim.studies.kinds` that defines ``STUDY``; adding a module
there adds a study (docs/design.md, "Adding a study").
"""

from __future__ import annotations

import argparse
import dataclasses
import importlib
import pkgutil
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from jswim.errors import ConfigError

if TYPE_CHECKING:
    from jswim.studies.options import StudyOptions
    from jswim.studies.plans import Cell, Plan

__all__ = ["Study", "find", "get", "listed", "names"]

#: A study's success rule in words, from its plans, the judge's horizon and ``--steps``.
RuleFn = Callable[["Sequence[Plan]", "int | None", "int | None"], str]


def listed(kind: type) -> Callable[[str], tuple]:
    """An argparse ``type`` for a comma-separated list of ``kind`` (``"3,6"`` -> ``(3.0, 6.0)``);
    an empty item (``"3,,6"``, ``"3,"``) is refused, not dropped, and ``""`` is not the defaults.
    """

    def parse(text: str) -> tuple:
        items = [v.strip() for v in text.split(",")]
        try:
            values = tuple(kind(v) for v in items) if all(items) else ()
        except ValueError:
            values = ()
        if not values:
            what = "names" if kind is str else "numbers"
            raise argparse.ArgumentTypeError(
                f"expected comma-separated {what} without empty items, got {text!r}"
            )
        return values

    return parse


#: A study's own command-line options: ``(flag, argparse keywords)``, the flag's dest the
#: `StudyOptions` field it sets.
Flags = tuple[tuple[str, dict[str, Any]], ...]


@dataclass(frozen=True)
class Study:
    """One study kind: what it runs, how it is judged, what it shows.

    Attributes
    ----------
    name : str
        ``jswim study NAME`` (``jswim swim`` where ``command`` is ``"swim"``).
    help : str
        One line for ``jswim study --help``.
    cells : callable
        ``cells(options, swimmer) -> list[Cell]``: its grid for one swimmer.
    runs : int
        LLM runs per cell when ``--runs`` is not given.
    success : callable
        ``success(plans, horizon, steps) -> str``: the rule its runs are judged by, in words
        (recorded in the folder's metadata; `jswim.studies.success`).
    short_steps : callable or None
        ``short_steps(options) -> str or None``: a warning when ``--steps`` is too short for its
        runs to succeed (``None``: the paper's criterion's, `jswim.studies.specs.short_steps_warning`).
    order : int
        Its place in listings (the paper's figures first).
    init, swimmers, directions, q_runs, steps
        Defaults of ``--init``, ``--swimmer``, ``--direction``, ``--q-runs`` and ``--steps``.
    swimmers_why : str
        Where set, the study runs its ``swimmers`` only and refuses any other, saying this
        (``{swimmer}`` is the one refused).
    steps_text : str or None
        ``--steps``' default in words, where each run has its own budget (navigation).
    judged : bool
        Success is the paper's criterion (a stroke found), not a target reached.
    ignores : tuple of str
        `StudyOptions` fields it has no use for: the command line refuses them
        (`jswim.studies.specs.IGNORED` says why).
    flags : tuple
        Its own command-line options (`Flags`: ``(flag, argparse keywords)``, each flag's dest a
        `StudyOptions` field no run option sets): a study without them refuses them, and the page
        shows them for this one only (`own_options`).
    constrain : str or None
        Decoding when the backend says ``"auto"`` (the ablation's free text: ``"none"``).
    option_help : mapping
        An option's help in this study's words (flag -> text), where the general wording would
        name another default.
    command : str
        ``"study"`` (``jswim study NAME``) or ``"swim"`` (its own command, ``jswim swim``).
    variant : str
        The protocol variant of its LLM runs when ``--variant`` is not given.
    variants_grid : bool
        Its LLM cells are the protocol variants (``--variant`` takes a list, recorded in the
        folder's identity and metadata).
    own_budgets : bool
        Each run has its target's own step budget unless ``--steps`` is given.
    min_roc_levels : int
        The fewest ROC levels K it steers with, and ``roc_levels_why`` why.
    temperatures : tuple of float
        The sampling temperatures its cells sweep when ``--temperatures`` is not given.
    tables : tuple of str
        Its tables (`jswim.studies.overview.TABLES`), its summary first: the console's after a
        run, ``jswim show``'s and the report page's.
    figures : tuple of str
        Its figure sets (`jswim.figures.registry`), in order of importance.
    figure_order : tuple of str
        Figure files (without extension) shown first, in this order; the others by name.
    setting_notes : mapping
        A setting's value as the study reads it, where that differs from the number recorded
        (setting -> text with ``{v}``), for the report page.
    """

    name: str
    help: str
    cells: Callable[[StudyOptions, str], list[Cell]]
    runs: int
    success: RuleFn
    order: int
    short_steps: Callable[[StudyOptions], str | None] | None = None
    init: str = "cycle"
    swimmers: tuple[str, ...] = ("purcell", "ng")
    swimmers_why: str = ""
    directions: tuple[int, ...] = (1,)
    q_runs: int = 100
    steps: int = 50  # the paper's horizon
    steps_text: str | None = None
    judged: bool = True
    ignores: tuple[str, ...] = ("zetas", "n_hts", "roc_levels_grid")
    flags: Flags = ()
    constrain: str | None = None
    option_help: Mapping[str, str] = dataclasses.field(default_factory=dict)
    command: str = "study"
    variant: str = "paper"
    variants_grid: bool = False
    own_budgets: bool = False
    min_roc_levels: int = 1
    roc_levels_why: str = ""
    temperatures: tuple[float, ...] = ()
    tables: tuple[str, ...] = ("runs",)
    figures: tuple[str, ...] = ()
    figure_order: tuple[str, ...] = ()
    setting_notes: Mapping[str, str] = dataclasses.field(default_factory=dict)

    @property
    def own_options(self) -> tuple[str, ...]:
        """The `StudyOptions` fields of its own flags (``--school-sizes`` -> ``school_sizes``)."""
        return tuple(flag.lstrip("-").replace("-", "_") for flag, _ in self.flags)

    @property
    def strokes_only(self) -> bool:
        """Whether it runs fixed strokes alone (no LLM, no learner: it has no use for ``--runs``)."""
        return "runs" in self.ignores


_REGISTRY: dict[str, Study] = {}


def _load() -> dict[str, Study]:
    """Every module of `jswim.studies.kinds` with a ``STUDY``, imported once, in `Study.order`."""
    if not _REGISTRY:
        from jswim.studies import kinds  # lazy: every kind imports this module

        found = []
        for info in pkgutil.iter_modules(kinds.__path__):
            study = getattr(importlib.import_module(f"{kinds.__name__}.{info.name}"), "STUDY", None)
            if isinstance(study, Study):
                found.append(study)
        for study in sorted(found, key=lambda s: (s.order, s.name)):
            _REGISTRY[study.name] = study
    return _REGISTRY


def names() -> tuple[str, ...]:
    """Every study kind's name, in listing order (``swim`` included: ``jswim swim``)."""
    return tuple(_load())


def find(name: str) -> Study | None:
    """The study kind ``name``, ``None`` for one this version does not know (a folder written
    by a later jswim)."""
    return _load().get(name)


def get(name: str) -> Study:
    """The study kind ``name``.

    Raises
    ------
    ConfigError
        For a name no module of `jswim.studies.kinds` declares (one line naming the valid ones).
    """
    studies = _load()
    if name not in studies:
        raise ConfigError(f"unknown study {name!r}; choose one of {', '.join(studies)}")
    return studies[name]
