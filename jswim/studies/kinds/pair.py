"""``jswim study pair`` (an extension; README "Walls, obstacles and pairs"): two coaxial NG
swimmers D apart, alone versus together."""

from __future__ import annotations

from jswim.agents.variants import PAIR_PROMPTS
from jswim.studies.scene_grids import pair_cells, separations_flag
from jswim.studies.study import Study, listed
from jswim.studies.success import scene_rule

STUDY = Study(
    name="pair",
    help="two coaxial NG swimmers D apart: alone versus together, the pair's speed against the "
    "strokes' phase offset and D, and whether an agent steering both finds a faster joint stroke",
    cells=pair_cells,
    runs=1,
    init="paper",
    swimmers=("ng",),
    q_runs=10,
    ignores=("zetas", "n_hts", "roc_levels_grid", "init"),
    success=scene_rule,
    order=11,
    tables=("runs", "scenes"),
    figures=("pair",),
    flags=(
        separations_flag(
            "starting distances D between the two swimmers' centres, in sphere radii "
            "(default 30,60)"
        ),
        (
            "--phases",
            dict(
                type=listed(int),
                metavar="P1,P2,...",
                help="phase offsets of the two square strokes, in quarter cycles of swimmer 2 ahead "
                "(default 0,1,2,3)",
            ),
        ),
        (
            "--pair-prompt",
            dict(
                choices=PAIR_PROMPTS,
                help="how the LLM steers the pair: joint (default: one conversation, joint DOFs "
                "D1..D4) or each (a variant: one conversation per swimmer, taking turns, each "
                "shown the other's position)",
            ),
        ),
    ),
)
