"""Each study's own options (today the scene studies': ``jswim study wall`` / ``jswim study pair``)
and the scene table printed after the usual summary.

`OPTIONS` is the table: study -> its options, each ``(flag, argparse keywords)`` whose dest is
the [`jswim.studies.StudyOptions`][jswim.studies.options.StudyOptions] field it sets; `register` adds them to the study's
parser, `options` reads them back. A study's new option is one row here.
"""

from __future__ import annotations

import argparse
from typing import Any
from collections.abc import Sequence

from jswim.console import print_table as show

STUDY_HELP = {
    "wall": "one NG swimmer started at several heights and tilts above a no-slip wall: the square stroke's displacement per "
    "cycle against height, the fate of every run (trapped, escaped, gliding), LLM and baselines; "
    "--swimmer purcell: Purcell's swimmer in a plane parallel to the wall (stroke, Q-learning, random)",
    "pair": "two coaxial NG swimmers D apart: alone versus together, the pair's speed against the strokes' phase "
    "offset and D, and whether an agent steering both finds a faster joint stroke",
    "school": "schools of N NG swimmers in a line or side by side D apart, every one doing the square stroke in "
    "turn: the school's speed against N and D, beside a lone swimmer's",
    "navigate": "Purcell's swimmer steered to targets at several distances and bearings, along a path and after "
    "a moving target (K = 2 unless --roc-levels), in still fluid or a background flow (--flow): the LLM, "
    "Q-learning, PPO, the steering controller, the model-predictive agent (mpc) and random, measured "
    "against the swimmer's own optimum (optimal: its least-time strokes; and Zermelo's point steerer in "
    "a flow); success, steps to the target, time over the optimum's, path over straight distance, "
    "energy and energy per distance",
}


def _numbers(kind: type) -> Any:
    def parse(text: str) -> tuple:
        items = [v.strip() for v in text.split(",")]
        try:  # an empty item ("3,,6", "3,") is refused, not dropped; "" is not the defaults
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


#: study -> its own options: (flag, argparse keywords); ``choices="PAIR_PROMPTS"`` is read from
#: [`jswim.agents.variants`][jswim.agents.variants] when the parser is built (`jswim --help` never imports the agents).
OPTIONS: dict[str, tuple[tuple[str, dict[str, Any]], ...]] = {
    "wall": (
        (
            "--heights",
            dict(
                type=_numbers(float),
                metavar="H1,H2,...",
                help="starting heights of the middle sphere above the wall, in sphere radii "
                "(default 1.2,1.5,2,3,10,50); Purcell's: of its plane, in link lengths",
            ),
        ),
        (
            "--tilts",
            dict(
                type=_numbers(float),
                metavar="T1,T2,...",
                help="start tilts of the NG swimmer's axis from the wall, in rad, nose up positive "
                "(default 0,0.8); each height runs at each tilt whose start clears the wall "
                "(0.8 needs h > 8.3); Purcell's swimmer starts level only",
            ),
        ),
    ),
    "pair": (
        (
            "--separations",
            dict(
                type=_numbers(float),
                metavar="D1,D2,...",
                help="starting distances D between the two swimmers' centres, in sphere radii "
                "(default 30,60)",
            ),
        ),
        (
            "--phases",
            dict(
                type=_numbers(int),
                metavar="P1,P2,...",
                help="phase offsets of the two square strokes, in quarter cycles of swimmer 2 ahead "
                "(default 0,1,2,3)",
            ),
        ),
        (
            "--pair-prompt",
            dict(
                choices="PAIR_PROMPTS",
                help="how the LLM steers the pair: joint (default: one conversation, joint DOFs "
                "D1..D4) or each (a variant: one conversation per swimmer, taking turns, each "
                "shown the other's position)",
            ),
        ),
    ),
    "school": (
        (
            "--school-sizes",
            dict(
                type=_numbers(int),
                metavar="N1,N2,...",
                help="numbers of swimmers N (default 1,2,3,4,5)",
            ),
        ),
        (
            "--separations",
            dict(
                type=_numbers(float),
                metavar="D1,D2,...",
                help="distances D between neighbouring swimmers' centres, in sphere radii (default 30,60; "
                "one that would overlap the swimmers is refused, naming the least D)",
            ),
        ),
        (
            "--formations",
            dict(
                type=_numbers(str),
                metavar="F1,F2",
                help="line (one behind the other), side (side by side); default both",
            ),
        ),
    ),
    "navigate": (
        (
            "--distances",
            dict(
                type=_numbers(float),
                metavar="D1,D2,...",
                help="distances of the fixed targets, in link lengths (default 3)",
            ),
        ),
        (
            "--bearings",
            dict(
                type=_numbers(float),
                metavar="B1,B2,...",
                help="bearings of the fixed targets, degrees counterclockwise from the start heading "
                "(default 0,90,180)",
            ),
        ),
        (
            "--flow",
            dict(
                choices=("uniform", "shear", "poiseuille", "taylor-green"),
                metavar="KIND",
                help="a background flow (an extension): uniform (across the start heading), shear "
                "(u = rate y), poiseuille (a channel along x) or taylor-green (vortex cells); "
                "Zermelo's point steerer (no turning limit, the flow at its centre) joins the "
                "agents as a yardstick, and every row gets its time over his beside its time over "
                "the swimmer's own optimum",
            ),
        ),
        (
            "--flows",
            dict(
                type=_numbers(float),
                metavar="F1,F2,...",
                help="the flow's speeds, fractions of the swimming speed 0.0478 a per step, at most 2 "
                "(default 0,0.5,0.9; past 1 some targets are unreachable and the rows say so); "
                "a grid size: more speeds on an existing folder add their runs to it",
            ),
        ),
        (
            "--starts",
            dict(
                type=int,
                metavar="N",
                help="seeded starts of every agent, the same for each (start 0 the study's own, "
                "(hi, hi) headed along +x; the others a heading within 45 degrees of +x and a "
                "corner of the shape square, drawn from --seed); each multiplies every agent's "
                "runs, pooled into the cell's row (default 1); a grid size: more starts on an "
                "existing folder add their runs to it",
            ),
        ),
        (
            "--train-episodes",
            dict(
                type=int,
                metavar="N",
                help="episodes of each target's budget that Q-learning and PPO train for (default 400)",
            ),
        ),
    ),
}


def _dest(flag: str) -> str:
    return flag.lstrip("-").replace("-", "_")


def register(q: argparse.ArgumentParser, name: str) -> None:
    """Add study ``name``'s own options (`OPTIONS`) to its parser (nothing for other studies)."""
    if name not in OPTIONS:
        return
    from jswim.agents import (
        variants,
    )  # lazy: start-up (`jswim --help` imports this module, not the agents)

    g = q.add_argument_group("navigation" if name == "navigate" else "scene")
    for flag, kw in OPTIONS[name]:
        if isinstance(kw.get("choices"), str):
            kw = {**kw, "choices": getattr(variants, kw["choices"])}
        g.add_argument(flag, default=None, **kw)


def options(args: argparse.Namespace) -> dict[str, Any]:
    """The StudyOptions keywords of the study's own options given."""
    return {
        d: getattr(args, d)
        for d in {_dest(f) for rows in OPTIONS.values() for f, _ in rows}
        if getattr(args, d, None) is not None
    }


def _print_nav_table(rows: Sequence[Any]) -> None:
    """The navigation table (`jswim.studies.overview.nav_table`) and its note."""
    from jswim.studies.overview import nav_overview_table, nav_table  # lazy: JAX, for a study

    cols, cells, note = nav_overview_table(rows)
    show(cols, cells, "agents x flows: success, time over the swimmer's optimum, energy")
    print(note)
    cols, cells, note = nav_table(rows)
    show(cols, cells, "navigation: targets reached, steps to the target, path ratio, energy")
    print(note)


def print_table(rows: Sequence[dict[str, Any]]) -> None:
    """The scene table of a study's rows (nothing when it has no scene runs)."""
    from jswim.results import as_run_rows  # lazy: start-up (results loads NumPy)

    rows = as_run_rows(rows)
    if any(r.target for r in rows):
        _print_nav_table(rows)
    if not any(r.scene for r in rows):
        return
    from jswim.studies.scene_studies import (
        columns_note,
        scene_summary,
        table,
        table_note,
    )  # lazy: JAX loads only for a study

    summary = scene_summary(rows)
    cols, cells = table(summary)
    show(cols, cells, "scenes: displacement per stroke cycle, speed per step (second half)")
    print(columns_note(cols))
    if note := table_note(summary):
        print(note)
