"""The scene studies' grids (``wall``, ``pair``, ``school``): scenes as canonical JSON (what plans
and run ids carry) and each scene study's cells.
"""

from __future__ import annotations

import json

from jswim.errors import ConfigError
from jswim.scenes import Scene


from jswim.studies.options import (
    CONTINUOUS_AGENT,
    STROKE_AGENT,
    WITH_BASELINES,
    StudyOptions,
    continuous_agent_available,
)
from jswim.scenes.scene_parameters import check_start
from jswim.studies.plans import Cell, initial
from jswim.studies.study import listed

_DISTANCES = listed(float)


def separations_flag(help: str) -> tuple[str, dict]:
    """``--separations`` (`StudyOptions.separations`), one option of the pair and the school
    studies: the same parsing in both, the help each study's own."""
    return "--separations", dict(type=_DISTANCES, metavar="D1,D2,...", help=help)


def scene_json(scene: Scene) -> str:
    """A scene as canonical JSON (``Scene.to_dict()``, sorted keys): the form plans and run ids carry."""
    return json.dumps(scene.to_dict(), sort_keys=True)


def wall_scene(h: float, tilt: float = 0.0) -> str:
    """One swimmer started ``h`` above the wall (a), its axis ``tilt`` rad from the wall plane
    (nose up); tilt 0 is the scene's default, so a level start's JSON, and its runs' ids, do not
    depend on the tilt axis."""
    return scene_json(Scene(medium="wall", height=float(h), tilt=float(tilt), swimmers=1))


def wall_start_clears(h: float, tilt: float) -> bool:
    """Whether NG's wall-study start (the paper's arms (10, 6)) at height ``h`` and ``tilt``
    keeps every sphere clear of the wall by the scenes' contact gap (a steep start near the
    wall puts its rear sphere into it: at 0.8 rad that needs h > 8.3 a)."""
    try:
        check_start(
            "ng",
            Scene(medium="wall", height=float(h), tilt=float(tilt)),
            init=initial("paper", 0, "ng"),
        )
    except ConfigError:
        return False
    return True


def wall_groups(o: StudyOptions, swimmer: str = "ng") -> list[tuple[str, str, str]]:
    """The wall study's (group, scene, tag) per start: each height of ``o.heights`` at each tilt
    of ``o.tilts`` whose start clears the wall (`wall_start_clears`); a level start is named by
    its height alone (``h=3``, tag ``h3``), a tilted one adds its tilt (``h=10, tilt=0.8``, tag
    ``h10-t0.8``). Only NG starts tilted: Purcell's swimmer swims in a plane parallel to the
    wall, and a registered world's start is its own, so they run the level starts alone.

    Raises
    ------
    ConfigError
        When no (height, tilt) of the grid clears the wall.
    """
    out = []
    for h in o.heights:
        for t in o.tilts:
            if t == 0.0:
                out.append((f"h={h:g}", wall_scene(h), f"h{h:g}"))
            elif swimmer == "ng" and wall_start_clears(h, t):
                out.append((f"h={h:g}, tilt={t:g}", wall_scene(h, t), f"h{h:g}-t{t:g}"))
    if not out:
        raise ConfigError(
            f"no start of --heights {','.join(f'{h:g}' for h in o.heights)} and --tilts "
            f"{','.join(f'{t:g}' for t in o.tilts)} clears the wall"
            + ("" if swimmer == "ng" else f" ({swimmer} starts level only: add 0 to --tilts)")
        )
    return out


def pair_scene(d: float | None = None) -> str:
    """Two coaxial swimmers ``d`` apart in the unbounded fluid of the point-force solve; ``None``:
    one swimmer alone there."""
    if d is None:
        return scene_json(Scene(medium="free", swimmers=1))
    return scene_json(Scene(medium="free", swimmers=2, separation=float(d)))


def wall_cells(o: StudyOptions, swimmer: str = "ng") -> list[Cell]:
    """The wall study's cells for the options' grids. Every swimmer's wall cells run the same
    agents at each height: the stroke, the LLM, Q-learning, random and PPO. Only the reference
    differs: Purcell's swimmer above a wall swims in a plane parallel to it, so its reference is
    the paper's bulk fluid (group ``bulk``); NG's (and a registered world's) is the unbounded
    fluid of the scene solver (group ``free``)."""
    check_lattice("wall", o)
    ref = "bulk" if swimmer == "purcell" else "free"
    out = [
        Cell(ref, (STROKE_AGENT,), scene=scene_json(Scene(medium=ref)), stroke="square", tag=ref)
    ]
    for group, scene, tag in wall_groups(o, swimmer):
        out.append(
            Cell(
                group,
                (STROKE_AGENT, *WITH_BASELINES),
                n_ht=o.n_ht,
                scene=scene,
                stroke="square",
                tag=tag,
            )
        )
        out += _ppo_cells(group, scene, tag)
    return out


def pair_cells(o: StudyOptions, swimmer: str = "ng") -> list[Cell]:
    """The pair study's cells: one swimmer alone, then at each separation D the two square
    strokes at each phase offset, and the agents steering both."""
    check_lattice("pair", o)
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


def school_cells(o: StudyOptions, swimmer: str = "ng") -> list[Cell]:
    """The school study's cells: every swimmer doing the square stroke, in turn and in phase
    (stroke ``phase0``), for each formation, spacing and size (a lone swimmer once)."""
    check_lattice("school", o)
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


def check_lattice(study: str, o: StudyOptions) -> None:
    """Refuse ``--roc-levels`` other than 1: the scene rows read and judge K = 1 codes (PPO has
    real ROCs anyway).

    Raises
    ------
    ConfigError
        One line naming ``study``.
    """
    if o.roc_levels != 1:
        raise ConfigError(
            f"the {study} study has no use for --roc-levels {o.roc_levels} (its LLM, Q-learning, "
            "random and stroke runs use the paper's ROCs -1, 0, 1 and its PPO runs real ROCs in "
            "[-1, 1]); leave it out"
        )
