"""The stated ranges of the scene physics, and the one warning a model used outside its range gives.

Each model with a range in docs/scenes.md has one rule here; `range_notes` says which rules a
scene breaks, `warn_out_of_range` warns once per rule and process (a study builds a model per
cell: its console shows the line once), and a study page lists the same notes from its rows.
"""

from __future__ import annotations

import warnings

from jswim.errors import JswimWarning
from jswim.scenes.scene import Scene

__all__ = [
    "POINT_PAIR_MIN_GAP",
    "RPB_MIN_HEIGHT",
    "WALL_RFT_MAX_HEIGHT",
    "ModelRangeWarning",
    "range_notes",
    "warn_out_of_range",
]

#: Local RFT above a wall is a guide for h below about one link length (docs/scenes.md,
#: "Purcell's swimmer above a wall"); above it its 1/h approach to the bulk is an artefact.
WALL_RFT_MAX_HEIGHT = 1.0

#: The Rotne-Prager-Blake self terms are within 1 % of Brenner's normal factor above ~3.2 sphere
#: radii and are not zero at contact (docs/scenes.md, self mobilities).
RPB_MIN_HEIGHT = 3.2

#: Point-force pair blocks (the default ``mobility="point"``) are the far field, first order in
#: a/d (docs/scenes.md): the Rotne-Prager terms they leave out are ~(2/3)(a/d)^2 of the coupling,
#: 3 % at d = 5 sphere radii. Closer than that between spheres of two swimmers, the numbers
#: mislead by more than the school's own effects at the studies' separations.
POINT_PAIR_MIN_GAP = 5.0

_POINT_PAIR = (
    "spheres of two swimmers within ~5 sphere radii with mobility='point' (the default) are outside "
    "the point-force model's range (docs/scenes.md): it leaves out the Rotne-Prager terms, ~3 % of "
    "the coupling there; mobility='rpy' adds them"
)

_WALL_RFT = (
    "Purcell's swimmer above a wall with wall_model='local-rft' (the default) is outside the model's "
    f"range above ~{WALL_RFT_MAX_HEIGHT:g} link length (docs/scenes.md): its 1/h approach to the bulk "
    "is an artefact there; wall_model='beads' holds at any height"
)
_RPB = (
    "self_mobility='rpb' within ~3.2 sphere radii of the wall is outside its range (docs/scenes.md): "
    "its normal factor is not zero at contact; the default 'exact' holds there"
)


class ModelRangeWarning(JswimWarning):
    """A physics model is used outside the range its docs give (the numbers may mislead)."""


def closest_gap(scene: Scene, d_max: float = 10.0) -> float | None:
    """The closest two spheres of different swimmers come (sphere radii, centre to centre) when
    every arm is at its longest ``d_max``: ``separation - 2 d_max`` in a line, ``separation`` side
    by side; ``None`` for one swimmer."""
    if scene.swimmers < 2:
        return None
    return scene.separation - (2.0 * d_max if scene.formation == "line" else 0.0)


def range_notes(
    swimmer: str, scene: Scene, wall_model: str = "local-rft", d_max: float = 10.0
) -> tuple[str, ...]:
    """The range rules ``scene`` breaks for ``swimmer`` (``"purcell"`` or ``"ng"``), one line each.

    Parameters
    ----------
    swimmer : str
        The swimmer's name (``"purcell"``: the wall models; else the sphere models).
    scene : Scene
        Its scene; ``height`` in link lengths (Purcell) or sphere radii (spheres).
    wall_model : str
        Purcell's wall model (``"local-rft"`` or ``"beads"``).
    d_max : float
        The sphere swimmers' longest arm (sphere radii; the paper's 10), for the closest gap
        between swimmers (`closest_gap`).

    Returns
    -------
    tuple of str
        Empty where every model is inside its range.
    """
    if swimmer == "purcell":
        out = scene.medium == "wall" and wall_model == "local-rft"
        return (_WALL_RFT,) if out and scene.height > WALL_RFT_MAX_HEIGHT else ()
    notes = []
    wall = scene.medium == "wall"
    if wall and getattr(scene, "self_mobility", "exact") == "rpb" and scene.height < RPB_MIN_HEIGHT:
        notes.append(_RPB)
    gap = closest_gap(scene, d_max)
    if scene.medium in ("free", "wall") and scene.mobility == "point" and gap is not None:
        if gap < POINT_PAIR_MIN_GAP:
            notes.append(_POINT_PAIR)
    return tuple(notes)


#: The rules warned of in this process (`warn_out_of_range`).
_warned: set[str] = set()


def warn_out_of_range(
    swimmer: str, scene: Scene, wall_model: str = "local-rft", d_max: float = 10.0
) -> None:
    """A `ModelRangeWarning` for each rule of `range_notes` that ``scene`` breaks, the first time
    this process breaks it (JAX's context managers reset Python's own once-per-place registry)."""
    for note in range_notes(swimmer, scene, wall_model, d_max):
        if note not in _warned:
            _warned.add(note)
            warnings.warn(note, ModelRangeWarning, stacklevel=3)
