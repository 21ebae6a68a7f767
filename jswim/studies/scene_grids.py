"""The scene studies' grids (``wall``, ``pair``, ``school``): scenes as canonical JSON (what plans
and run ids carry) and each scene study's cells.
"""

from __future__ import annotations

import json
from collections.abc import Callable

from jswim.errors import ConfigError
from jswim.scenes import Scene


from jswim.studies.options import (
    CONTINUOUS_AGENT,
    STROKE_AGENT,
    WITH_BASELINES,
    StudyOptions,
    continuous_agent_available,
)
from jswim.studies.plans import Cell


def scene_json(scene: Scene) -> str:
    """A scene as canonical JSON (``Scene.to_dict()``, sorted keys): the form plans and run ids carry."""
    return json.dumps(scene.to_dict(), sort_keys=True)


def wall_scene(h: float) -> str:
    return scene_json(Scene(medium="wall", height=float(h), swimmers=1))


def pair_scene(d: float | None = None) -> str:
    """Two coaxial swimmers ``d`` apart in the unbounded fluid of the point-force solve; ``None``:
    one swimmer alone there."""
    if d is None:
        return scene_json(Scene(medium="free", swimmers=1))
    return scene_json(Scene(medium="free", swimmers=2, separation=float(d)))


def scene_cells(study: str, o: StudyOptions, swimmer: str = "ng") -> list[Cell]:
    """The cells of ``study`` (``"wall"`` or ``"pair"``) for the options' grids. Every swimmer's
    wall cells run the same agents at each height: the stroke, the LLM, Q-learning, random and
    PPO. Only the reference differs: Purcell's swimmer above a wall swims in a plane
    parallel to it, so its reference is the paper's bulk fluid (group ``bulk``); NG's (and a
    registered world's) is the unbounded fluid of the scene solver (group ``free``)."""
    if study == "wall":
        ref = "bulk" if swimmer == "purcell" else "free"
        out = [
            Cell(
                ref, (STROKE_AGENT,), scene=scene_json(Scene(medium=ref)), stroke="square", tag=ref
            )
        ]
        for h in o.heights:
            out.append(
                Cell(
                    f"h={h:g}",
                    (STROKE_AGENT, *WITH_BASELINES),
                    n_ht=o.n_ht,
                    scene=wall_scene(h),
                    stroke="square",
                    tag=f"h{h:g}",
                )
            )
            out += _ppo_cells(f"h={h:g}", wall_scene(h), f"h{h:g}")
        return out
    out = [Cell("alone", (STROKE_AGENT,), scene=pair_scene(), stroke="square", tag="alone")]
    for d in o.separations:
        for ph in o.phases:
            out.append(
                Cell(
                    f"D={d:g}, phase {ph}",
                    (STROKE_AGENT,),
                    scene=pair_scene(d),
                    stroke=f"phase{ph}",
                    tag=f"D{d:g}-ph{ph}",
                )
            )
        out.append(
            Cell(f"D={d:g}", WITH_BASELINES, n_ht=o.n_ht, scene=pair_scene(d), tag=f"D{d:g}")
        )
        out += _ppo_cells(f"D={d:g}", pair_scene(d), f"D{d:g}")
    return out


def school_scene(n: int, d: float, formation: str = "line") -> str:
    """``n`` swimmers ``d`` apart in a line or side by side, in the unbounded fluid of the
    point-force solve (one swimmer: alone there)."""
    if n == 1:
        return pair_scene()
    return scene_json(
        Scene(medium="free", swimmers=int(n), separation=float(d), formation=formation)
    )


def school_cells(o: StudyOptions) -> list[Cell]:
    """The school study's cells: every swimmer doing the square stroke, in turn and in phase
    (stroke ``phase0``), for each formation, spacing and size (a lone swimmer once)."""
    out = (
        [Cell("alone", (STROKE_AGENT,), scene=pair_scene(), stroke="square", tag="alone")]
        if 1 in o.school_sizes
        else []
    )
    for f in o.formations:
        for d in o.separations:
            out += [
                Cell(
                    f"{f}, D={d:g}, N={n}",
                    (STROKE_AGENT,),
                    scene=school_scene(n, d, f),
                    stroke="phase0",
                    tag=f"{f}-D{d:g}-N{n}",
                )
                for n in o.school_sizes
                if n > 1
            ]
    return out


def _ppo_cells(group: str, scene: str, tag: str) -> list[Cell]:
    """The continuous RL baseline's cell next to the other agents of a group (same group name,
    real ROCs: run ids ``ppo-...-real-<tag>-r<k>``; `scenes`)."""
    if not continuous_agent_available():
        return []
    return [Cell(group, (CONTINUOUS_AGENT,), scene=scene, roc_levels=0, tag=tag)]


def study_cells(name: str) -> Callable[[StudyOptions], list[Cell]]:
    """The cell builder of the scene study ``name`` (``"wall"``, ``"pair"`` or ``"school"``).

    Raises
    ------
    ConfigError
        When the options ask for ``--roc-levels`` other than 1 (the scene rows read K = 1 codes).
    """

    def cells(o: StudyOptions, swimmer: str = "ng") -> list[Cell]:
        if o.roc_levels != 1:  # the scene rows read and judge K = 1 codes; PPO has real ROCs anyway
            raise ConfigError(
                f"the {name} study has no use for --roc-levels {o.roc_levels} (its LLM, Q-learning, "
                "random and stroke runs use the paper's ROCs -1, 0, 1 and its PPO runs real ROCs in "
                "[-1, 1]); leave it out"
            )
        return school_cells(o) if name == "school" else scene_cells(name, o, swimmer)

    return cells


# Walls and pairs (extensions): NG swimmers only (jswim.studies.scene_studies, README "Walls,
# obstacles and pairs"); --init is the paper's NG start (10, 6), the scene's start.
