"""``jswim study school`` (an extension): schools of N NG swimmers in a line or side by side,
every one doing the square stroke; fixed strokes only."""

from __future__ import annotations

from jswim.studies.scene_grids import school_cells, separations_flag
from jswim.studies.study import Study, listed
from jswim.studies.success import scene_rule

STUDY = Study(
    name="school",
    help="schools of N NG swimmers in a line or side by side D apart, every one doing the square "
    "stroke in turn: the school's speed against N and D, beside a lone swimmer's",
    cells=school_cells,
    runs=0,
    init="paper",
    swimmers=("ng",),
    q_runs=1,
    ignores=("zetas", "n_hts", "roc_levels_grid", "init", "runs"),
    success=scene_rule,
    order=12,
    tables=("runs", "scenes"),
    figures=("school",),
    flags=(
        (
            "--school-sizes",
            dict(
                type=listed(int),
                metavar="N1,N2,...",
                help="numbers of swimmers N (default 1,2,3,4,5)",
            ),
        ),
        separations_flag(
            "distances D between neighbouring swimmers' centres, in sphere radii "
            "(default 30,60; one that would overlap the swimmers is refused, naming the least D)"
        ),
        (
            "--formations",
            dict(
                type=listed(str),
                metavar="F1,F2",
                help="line (one behind the other), side (side by side); default both",
            ),
        ),
    ),
)
