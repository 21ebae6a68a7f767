"""``jswim study wall`` (an extension; README "Walls, obstacles and pairs"): one NG swimmer
started at several heights and tilts above a no-slip wall.

Its horizon, 400 steps (100 square cycles), is set by the measured drift (docs/scenes.md, "Fates
above the wall"): an NG swimmer's height changes by ~0.02 a in 50 steps, so at 50 steps every run
reads as gliding; at 400, from tilt 0, h0 = 1.2 and 1.5 a touch the wall (7 and 29 cycles) and
h0 = 2-50 a glide (from 2-10 a on orbits of ~800-900 cycles).
"""

from __future__ import annotations

from jswim.studies.scene_grids import wall_cells
from jswim.studies.study import Study, listed
from jswim.studies.success import wall_rule

STUDY = Study(
    name="wall",
    help="one NG swimmer started at several heights and tilts above a no-slip wall: the square "
    "stroke's displacement per cycle against height, the fate of every run (trapped, escaped, "
    "gliding), LLM and baselines; --swimmer purcell: Purcell's swimmer in a plane parallel to the "
    "wall (stroke, Q-learning, random)",
    cells=wall_cells,
    runs=1,
    steps=400,
    init="paper",
    swimmers=("ng",),
    q_runs=10,
    ignores=("zetas", "n_hts", "roc_levels_grid", "init"),
    success=wall_rule,
    order=10,
    tables=("runs", "scenes"),
    figures=("wall",),
    flags=(
        (
            "--heights",
            dict(
                type=listed(float),
                metavar="H1,H2,...",
                help="starting heights of the middle sphere above the wall, in sphere radii "
                "(default 1.2,1.5,2,3,10,50); Purcell's: of its plane, in link lengths",
            ),
        ),
        (
            "--tilts",
            dict(
                type=listed(float),
                metavar="T1,T2,...",
                help="start tilts of the NG swimmer's axis from the wall, in rad, nose up positive "
                "(default 0,0.8); each height runs at each tilt whose start clears the wall "
                "(0.8 needs h > 8.3); Purcell's swimmer starts level only",
            ),
        ),
    ),
)
