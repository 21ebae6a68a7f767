"""``jswim plot``, ``jswim show``, ``jswim compare`` and ``jswim migrate``: a study folder's
figures redrawn, its status, settings, cost and tables read (never written) by show and compare,
and an earlier version's folder rewritten in today's form by migrate."""

from __future__ import annotations

import argparse
from pathlib import Path

from jswim.cli import bench
from jswim.console import terminal_width
from jswim.errors import ConfigError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "plot",
        help="redraw the figures of a study folder",
        description="Redraw a study folder's figures into FOLDER/figures (an unfinished study's "
        "figures say so).",
    )
    p.add_argument("folder", help="a study folder written by jswim swim / jswim study")
    p.set_defaults(command_main=plot, reads_folder=True)
    p = sub.add_parser(
        "show",
        help="a study folder: status, settings, cost, summary table, figures",
        description="Print what a study folder holds: complete or how many runs are done, the "
        "model and settings, LLM usage and cost, the summary table and the figures. "
        "Only reads, so it works on interrupted and read-only folders.",
    )
    p.add_argument("folder", help="a study folder written by jswim swim / jswim study")
    p.set_defaults(command_main=show, reads_folder=True)
    p = sub.add_parser(
        "compare",
        help="studies side by side (e.g. two models on the same grid)",
        description="For every setting (agent, swimmer, direction, group) present in all the "
        "given study folders: success rate p with its 95%% Wilson interval, mean X/a "
        "with a bootstrap interval, median steps to learn, tokens per step and cost, "
        "one row per study. Only reads.",
    )
    p.add_argument("folders", nargs="+", metavar="FOLDER", help="two or more study folders")
    p.set_defaults(command_main=compare, reads_folder=True)
    p = sub.add_parser(
        "migrate",
        help="rewrite a study folder an earlier jswim wrote in today's form",
        description="Rewrite FOLDER's metadata.json and runs.jsonl in today's form, each file "
        "atomically, under the folder's lock. Every jswim reads an earlier folder as it is; this "
        "only stores it in today's form. Its runs, answered calls and money ledger stay usable: "
        "the same command resumes it.",
    )
    p.add_argument("folder", help="a study folder written by jswim swim / jswim study")
    p.set_defaults(command_main=migrate)


def plot(args: argparse.Namespace) -> int:
    from jswim.studies.overview import StudyFolder  # lazy: JAX loads only for commands that run
    from jswim.results import unfinished_note  # lazy: as above
    from jswim.figures.plots import draw_figures  # lazy: matplotlib, for this command only

    study = StudyFolder(args.folder)
    if not study.rows:
        raise ConfigError(f"{args.folder} has no finished runs yet")
    note = unfinished_note(study.meta.get("status"), len(study.rows), study.planned)
    try:
        paths = draw_figures(study.study, study.rows, Path(args.folder) / "figures", note=note)
    except OSError as exc:
        raise ConfigError(
            f"cannot write the figures into {Path(args.folder) / 'figures'} ({exc.strerror or exc}); "
            "jswim show FOLDER reads a read-only folder"
        ) from None
    for f in paths:
        print(f"figure: {f}")
    return 0


def show(args: argparse.Namespace) -> int:
    from jswim.studies.overview import (
        show_text,
    )  # lazy: start-up (the study folders' readers load NumPy)

    folder = Path(args.folder)
    if (folder / "bench.json").is_file() and not (
        folder / "metadata.json"
    ).exists():  # a bench's folder
        print(bench.show_text(folder, width=terminal_width()))
        return 0
    print(show_text(args.folder, width=terminal_width()))
    return 0


def compare(args: argparse.Namespace) -> int:
    from jswim.studies.overview import (
        compare_text,
    )  # lazy: start-up (the study folders' readers load NumPy)

    print(compare_text(args.folders, width=terminal_width()))
    return 0


def migrate(args: argparse.Namespace) -> int:
    from jswim.results.store import migrate_folder  # lazy: start-up, as for the readers above

    done = migrate_folder(args.folder)
    for line in done or [f"{args.folder} is already in today's form; nothing rewritten"]:
        print(line)
    return 0
