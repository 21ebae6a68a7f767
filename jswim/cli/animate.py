"""``jswim animate FOLDER``: runs of a study folder as a GIF or MP4 (see `jswim.viz.animate`)."""

from __future__ import annotations

import argparse
from pathlib import Path

from jswim._io.paths import path_kind
from jswim.errors import ConfigError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "animate",
        help="animate runs of a study folder (GIF, or MP4 with imageio-ffmpeg)",
        description="Draw runs of a study folder side by side as they swam: the swimmer's true "
        "shape to scale at each step, its trail, the step, action, X/a, stuck and clear "
        "events and the LLM's reply. Default: one run per agent from the same start. "
        "Only reads the folder (the animation goes to --out).",
    )
    p.add_argument(
        "folder",
        help="a study folder written by jswim swim / jswim study, or a bench folder "
        "(one run per model, the reference rule and the baselines)",
    )
    p.add_argument(
        "--part",
        default=None,
        metavar="NAME",
        help="on a bench folder: the suite part to show (default its first)",
    )
    p.add_argument(
        "--run",
        action="append",
        default=None,
        metavar="ID",
        help="a run id to show (repeat for several, side by side); see jswim report or runs.csv",
    )
    p.add_argument(
        "--by",
        default="agent",
        choices=("agent", "zeta", "n_ht", "group", "variant", "init", "direction"),
        help="without --run: one run per value of this setting from the study's first panel "
        "(default agent: the LLM next to Q-learning and random from the same start; zeta: one "
        "run per noise level)",
    )
    p.add_argument(
        "--max", type=int, default=4, metavar="N", help="runs at most without --run (default 4)"
    )
    p.add_argument("--fps", type=float, default=4.0, help="steps per second (default 4)")
    p.add_argument("--dpi", type=int, default=80, help="resolution (default 80)")
    p.add_argument(
        "--out",
        default=None,
        metavar="FILE",
        help="FILE.gif or FILE.mp4 (default FOLDER/animations/runs.gif; MP4 needs "
        "pip install 'jswim[video]')",
    )
    p.set_defaults(command_main=main, reads_folder=True)


def main(args: argparse.Namespace) -> int:

    if args.max < 1:
        raise ConfigError(f"--max must be >= 1, got {args.max}")
    if not 20 <= args.dpi <= 400:
        raise ConfigError(f"--dpi must lie in [20, 400], got {args.dpi}")
    if not Path(args.folder).is_dir():
        raise ConfigError(f"{args.folder}: {path_kind(args.folder, 'a study folder')}")
    from jswim.viz.animate import (
        build,
        build_bench,
    )  # lazy: start-up (the pictures load matplotlib)
    from jswim.viz.bench_page import is_bench  # lazy: as above

    if is_bench(
        args.folder
    ):  # one run per model, the reference rule and the baselines, from one setting
        if args.run:
            raise ConfigError(
                "--run names runs of a study folder; on a bench folder use --part NAME"
            )
        anim = build_bench(args.folder, args.part, most=args.max, fps=args.fps, dpi=args.dpi)
    else:
        anim = build(args.folder, args.run, by=args.by, most=args.max, fps=args.fps, dpi=args.dpi)
    out = Path(args.out) if args.out else Path(args.folder) / "animations" / "runs.gif"
    path = anim.save(out)
    frames = anim.frames_written or anim.n_frames
    steps = max(t.n_steps for t in anim.tracks)
    print(
        f"{len(anim.tracks)} runs ({', '.join(t.run_id for t in anim.tracks)}), {steps} steps at {args.fps:g} "
        f"steps/s, {frames} frames in the file (the start, a frame per step that changes, the last held 1 s): "
        f"{path} ({path.stat().st_size / 1024:.0f} KB)"
    )
    return 0
