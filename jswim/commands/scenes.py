"""The scene studies' own options (``jswim study wall`` / ``pair`` / ``school``) and their table.

Registered from :mod:`jswim.cli` with one call each: :func:`register` adds ``--heights`` to the
wall study, ``--separations``/``--phases``/``--pair-prompt`` to the pair study and
``--school-sizes``/``--separations``/``--formations`` to the school study; :func:`options` reads them into
:class:`jswim.studies.StudyOptions` keywords; :func:`print_table` prints the scene table after
the usual summary.
"""

from __future__ import annotations

import argparse
from typing import Any, Sequence

#: The studies that take the options below.
SCENE_STUDIES = ("wall", "pair", "school")

STUDY_HELP = {
    "wall": "one NG swimmer started at several heights above a no-slip wall: the square stroke's displacement per "
            "cycle against height, the fate of every run (trapped, escaped, gliding), LLM and baselines",
    "pair": "two coaxial NG swimmers D apart: alone versus together, the pair's speed against the strokes' phase "
            "offset and D, and whether an agent steering both finds a faster joint stroke",
    "school": "schools of N NG swimmers in a line or side by side D apart, every one doing the square stroke in "
              "turn: the school's speed against N and D, beside a lone swimmer's",
}

#: Each study's own options: (flag, StudyOptions field, parser, metavar, help).
_OPTIONS = {
    "school": (
        ("--school-sizes", "school_sizes", int, "N1,N2,...", "numbers of swimmers N (default 1,2,3,4,5)"),
        ("--separations", "separations", float, "D1,D2,...",
         "distances D between neighbouring swimmers' centres, in sphere radii (default 30,60; a line needs D > 22)"),
        ("--formations", "formations", str, "F1,F2", "line (one behind the other), side (side by side); default both"),
    ),
}


def _numbers(kind: type) -> Any:
    def parse(text: str) -> tuple:
        try:
            values = tuple(kind(v.strip()) for v in text.split(",") if v.strip())
        except ValueError:
            values = ()
        if not values:  # "" or "," would otherwise fall back to the defaults silently
            raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}")
        return values
    return parse


def register(q: argparse.ArgumentParser, name: str) -> None:
    """Add the scene options of study ``name`` to its parser (nothing for other studies)."""
    if name not in SCENE_STUDIES:
        return
    from jswim.agents.variants import PAIR_PROMPTS  # here: `jswim --help` imports this module, not the agents

    g = q.add_argument_group("scene")
    for flag, dest, kind, metavar, text in _OPTIONS.get(name, ()):
        g.add_argument(flag, dest=dest, type=_numbers(kind), default=None, metavar=metavar, help=text)
    if name in _OPTIONS:
        return
    if name == "wall":
        g.add_argument("--heights", type=_numbers(float), default=None, metavar="H1,H2,...",
                       help="starting heights of the middle sphere above the wall, in sphere radii "
                            "(default 3,5,7,10,20,50)")
    else:
        g.add_argument("--separations", type=_numbers(float), default=None, metavar="D1,D2,...",
                       help="starting distances D between the two swimmers' centres, in sphere radii (default 30,60)")
        g.add_argument("--phases", type=_numbers(int), default=None, metavar="P1,P2,...",
                       help="phase offsets of the two square strokes, in quarter cycles of swimmer 2 ahead "
                            "(default 0,1,2,3)")
        g.add_argument("--pair-prompt", choices=PAIR_PROMPTS, default=None,
                       help="how the LLM steers the pair: joint (default: one conversation, joint DOFs D1..D4) or "
                            "each (a variant: one conversation per swimmer, taking turns, each shown the other's "
                            "position)")


def options(args: argparse.Namespace) -> dict[str, Any]:
    """The StudyOptions keywords of the scene options given."""
    names = ("heights", "separations", "phases", "pair_prompt", "school_sizes", "formations")
    return {k: getattr(args, k) for k in names if getattr(args, k, None)}


def print_table(rows: Sequence[dict[str, Any]]) -> None:
    """The scene table of a study's rows (nothing when it has no scene runs)."""
    if not any(r.get("scene") for r in rows):
        return
    from jswim.console import print_table as show
    from jswim.studies.scenes import scene_summary, table, table_note

    summary = scene_summary(rows)
    cols, cells = table(summary)
    show(cols, cells, "scenes: displacement per stroke cycle, speed per step (second half), fates")
    if note := table_note(summary):
        print(note)
