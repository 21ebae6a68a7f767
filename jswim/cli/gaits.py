"""``jswim gaits SWIMMER``: closed stroke cycles ranked by displacement per step (corners, or the
K-level ROC lattice with ``--roc-levels K``)."""

from __future__ import annotations

import argparse
from typing import Any
from collections.abc import Callable, Sequence

from jswim.action_codes import check_roc_levels
from jswim.studies import flags
from jswim.errors import ConfigError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "gaits",
        help="closed stroke cycles ranked by displacement per step",
        description="Enumerate closed stroke cycles on the corners of the DOF cube, integrate "
        "each exactly and rank them by displacement per step.",
    )
    p.add_argument(
        "swimmer",
        choices=flags.SWIMMERS,
        help="purcell, ng, nlink (N links) or nsphere (N spheres)",
    )
    p.add_argument("--n", type=int, default=None, help="links/spheres of nlink/nsphere (default 4)")
    p.add_argument(
        "--direction",
        type=flags.direction,
        default=(1,),
        metavar="DIR",
        help="rank by displacement toward +x, -x or both (default +x)",
    )
    p.add_argument(
        "--max-len",
        type=int,
        default=None,
        help="longest cycle (default 2**n_dof; 4 with --roc-levels above 1)",
    )
    p.add_argument(
        "--roc-levels",
        type=int,
        default=1,
        metavar="K",
        help="search the K-level ROC lattice: one DOF per move, ROC k/K of the range, k in -K..K "
        "(default 1: the paper's corners)",
    )
    p.add_argument("--top", type=int, default=8, help="cycles shown (default 8)")
    p.add_argument(
        "--out", default=None, metavar="FOLDER", help="also write a figure of the best cycles here"
    )
    p.set_defaults(command_main=main)


def main(args: argparse.Namespace) -> int:
    from jswim.judging import gait  # lazy: JAX loads only for commands that run
    from jswim.swimmers.models import make_model  # lazy: as above

    kw = {}
    if args.n is not None:
        if args.swimmer not in ("nlink", "nsphere"):
            raise ConfigError("--n applies to nlink and nsphere only")
        kw["n_links" if args.swimmer == "nlink" else "n_spheres"] = args.n
    model = make_model(args.swimmer, **kw)
    if args.roc_levels != 1:
        return _lattice_gaits(args, model)
    if model.n_dof > 5 and args.max_len is None:
        raise ConfigError("more than 5 DOFs: give --max-len to bound the enumeration")
    for d in args.direction:
        cycles = gait.best_cycles(model, d, args.max_len)
        print(
            f"{model.label} swimmer, target {'+x' if d > 0 else '-x'}: {len(cycles)} closed cycles; best first"
        )
        _print_cycles(cycles[: args.top], lambda c: "".join("+" if v else "-" for v in c.start), 5)
        print(
            "simple: no shape visited twice per period; the others add detours that go back and forth"
        )
        if args.out:
            from jswim.figures.panels import (
                save,
            )  # lazy: matplotlib only when a figure is asked for
            from jswim.figures.sketches import gaits_figure  # lazy: as above

            paths = save(
                gaits_figure(model, cycles),
                args.out,
                f"gaits-{args.swimmer}-{'px' if d > 0 else 'mx'}",
            )
            print(f"figure: {paths[0]}")
        print()
    return 0


def _print_cycles(cycles: Sequence[Any], start: Callable[[Any], str], width: int) -> None:
    """The ranked table both listings print; ``start`` writes a cycle's first shape (``width`` wide)."""
    print(
        f"{'rank':>4} {'period':>6} {'X/a per step':>13} {'X/a per cycle':>14} {'rotation':>9} simple"
        "  start  moves (DOF, ROC)"
    )
    for i, c in enumerate(cycles, 1):
        moves = " ".join(f"[{dof}, {roc}]" for dof, roc in c.moves)
        print(
            f"{i:4d} {c.period:6d} {c.per_step:+13.6f} {c.displacement:+14.6f} {c.rotation:+9.4f} "
            f"{'yes' if c.simple else 'no':>6}  {start(c):{width}}  {moves}"
        )


def _lattice_gaits(args: argparse.Namespace, model: Any) -> int:
    """``jswim gaits SWIMMER --roc-levels K``: closed strokes on the K-level lattice, best first."""
    from jswim.judging import lattice  # lazy: JAX loads only for commands that run

    k = check_roc_levels(args.roc_levels)
    if args.out:
        raise ConfigError("--out draws corner cycles only; leave it out with --roc-levels above 1")
    length = 4 if args.max_len is None else args.max_len
    for d in args.direction:
        cycles = lattice.best_lattice_cycles(model, d, k, length)
        print(
            f"{model.label} swimmer, target {'+x' if d > 0 else '-x'}, ROC on {k} levels (k/{k} of the range, "
            f"one DOF per move): {len(cycles)} closed strokes up to {length} moves; best first"
        )
        _print_cycles(
            cycles[: args.top], lambda c: "(" + ", ".join(str(v) for v in c.start) + f")/{k}", 7
        )
        print(
            f"start: each DOF's place on the lattice, j/{k} of its range from lo; moves that reach past a limit "
            "and runs of moves of one DOF (equal to one move) are not listed"
        )
        print()
    return 0
