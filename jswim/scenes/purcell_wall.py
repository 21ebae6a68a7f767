"""Purcell's swimmer in a scene: its plane parallel to a wall at ``Scene.height`` (link lengths).

The links stay at that height (no force normal to the wall, [`jswim.swimmers.wall_rft`][jswim.swimmers.wall_rft]), so
the world is the paper's planar world ([`jswim.env.swimmer_world.SwimmerWorld`][jswim.env.swimmer_world.SwimmerWorld]: exact
corner steps, drift-free positions, JAX's default float) with wall-corrected drag coefficients.
This module is the model (the scene physics, below the worlds): ``jswim.make("purcell",
scene=...)`` and [`jswim.env.scene_rollout`][jswim.env.scene_rollouts.scene_rollout] build
their world from [`model`][jswim.scenes.purcell_wall.model]. What is
not built is refused in one line: a second swimmer, obstacles, a tilt, ``mobility="rpy"`` or
medium ``"free"`` (resistive force theory has no interactions to solve; ``"bulk"`` is the paper's
world).
"""

from __future__ import annotations

from typing import Any

from jswim.errors import ConfigError
from jswim.scenes.scene import Scene
from jswim.swimmers import purcell_beads
from jswim.swimmers.models import SwimmerModel
from jswim.swimmers.wall_rft import LINK_RADIUS
from jswim.swimmers.wall_rft import wall_model as local_rft_model
from jswim.scenes.ranges import warn_out_of_range

#: Models of Purcell's swimmer above a wall: ``"local-rft"`` ([`jswim.swimmers.wall_rft`][jswim.swimmers.wall_rft]:
#: each link's drag corrected by its own averaged image; range b << h, h below ~l) and
#: ``"beads"`` ([`jswim.swimmers.purcell_beads`][jswim.swimmers.purcell_beads]: every link's flow and image, all heights
#: with h > 2 b; its plane held, its heave and pitch left out).
WALL_MODELS = ("local-rft", "beads")


def is_purcell(swimmer: Any) -> bool:
    """Whether ``swimmer`` names Purcell's three-link swimmer (``"purcell"``)."""
    return isinstance(swimmer, str) and swimmer.lower() == "purcell"


def check_scene(scene: Scene) -> Scene:
    """``scene`` if Purcell's swimmer can swim in it above a wall, else a one-line ConfigError."""
    scene.validate()
    if scene.medium == "bulk":
        raise ConfigError(
            "Purcell's swimmer swims alone and untilted in medium 'bulk' (the paper's world): "
            "leave swimmers and tilt at the default (resistive force theory has no interactions "
            "to solve)"
        )
    if scene.medium != "wall":
        raise ConfigError(
            f"Purcell's swimmer swims in medium 'bulk' (the paper's world) or 'wall', not "
            f"{scene.medium!r} (resistive force theory has no interactions to solve)"
        )
    bad = [
        name
        for name, off in (
            ("swimmers", scene.swimmers != 1),
            ("obstacles", bool(scene.obstacles)),
            ("tilt", scene.tilt != 0.0),
            ("mobility", scene.mobility != "point"),
        )
        if off
    ]
    if bad:
        raise ConfigError(
            f"Purcell's swimmer above a wall is one swimmer in a plane parallel to it: leave "
            f"{', '.join(bad)} at the default"
        )
    return scene


def model(
    scene: Scene,
    *,
    link_radius: float = LINK_RADIUS,
    d_max: float | None = None,
    wall_model: str = "local-rft",
    **other: Any,
) -> SwimmerModel:
    """The wall-corrected Purcell model of ``scene`` (height in link lengths): ``wall_model`` one
    of `WALL_MODELS` (``"beads"`` takes ``beads`` per link too); an option it does not take
    (``other``) is a one-line ConfigError rather than dropped."""
    h = check_scene(scene).height
    warn_out_of_range("purcell", scene, wall_model)
    if wall_model == "beads":
        beads = other.pop("beads", purcell_beads.BEADS_PER_LINK)
        if not other:
            return purcell_beads.wall_model(h, link_radius, beads, d_max=d_max)
    if wall_model not in WALL_MODELS:
        raise ConfigError(f"wall_model must be one of {', '.join(WALL_MODELS)}, got {wall_model!r}")
    if other:
        raise ConfigError(
            f"Purcell's swimmer above a wall takes link_radius, d_max and wall_model (beads with "
            f"'beads'), not {', '.join(sorted(other))}"
        )
    return local_rft_model(h, link_radius, d_max=d_max)
