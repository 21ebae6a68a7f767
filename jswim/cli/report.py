"""``jswim report FOLDER``: write the folder's ``report.html`` (see `jswim.viz.page`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from jswim._io.paths import path_kind
from jswim.errors import ConfigError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "report",
        help="write a study folder's report.html (one self-contained page)",
        description="Write FOLDER/report.html: the settings, the summary table, the figures and a "
        "run browser that replays each run with its prompts and replies. Works on "
        "finished and unfinished folders; writes the page and nothing else. Open it "
        "in any browser, offline.",
    )
    p.add_argument(
        "folder",
        help="a study folder written by jswim swim / jswim study, or a bench folder "
        "(jswim bench: its leaderboard page and each part's page)",
    )
    p.add_argument(
        "--figures",
        default="auto",
        choices=("auto", "files", "draw", "none"),
        help="auto (default): the folder's figures if they are newer than its runs, else drawn now; "
        "files; draw; none",
    )
    p.add_argument(
        "--out",
        default=None,
        metavar="FILE.html",
        help="write the page here instead (e.g. for a read-only folder)",
    )
    p.set_defaults(command_main=main, reads_folder=True)


def main(args: argparse.Namespace) -> int:
    from jswim.viz.bench_page import (
        is_bench,
        write_bench_report,
    )  # lazy: start-up (the pages load matplotlib)
    from jswim.viz.page import write_report  # lazy: as above

    if not Path(args.folder).is_dir():
        raise ConfigError(f"{args.folder}: {path_kind(args.folder, 'a study folder')}")
    if is_bench(args.folder):  # the bench's page and each of its study folders' pages
        # With --out (a read-only bench, say) only that page is written: the parts' pages are
        # the bench folder's own files, left as they are.
        path = write_bench_report(
            args.folder,
            figures="none" if args.figures == "none" else "draw",
            out=args.out,
            parts=args.out is None,
        )
        also = " and each part's page" if args.out is None else ""
        print(
            f"bench report: {path} ({path.stat().st_size / 1024:.0f} KB){also}; open it in a "
            f"browser (file://{path.resolve()})"
        )
        return 0
    path = write_report(args.folder, figures=args.figures, out=args.out)
    print(
        f"report: {path} ({path.stat().st_size / 1024:.0f} KB); open it in a browser (file://{path.resolve()})"
    )
    return 0
