"""``Scene``: the fluid, the swimmers' starts and the obstacles of a sphere-swimmer environment."""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from jswim.errors import ConfigError
from jswim.reals import plain

#: Media: the paper's first-order formula, the point-force solve without and with a wall.
MEDIA = ("bulk", "free", "wall")

#: Most swimmers a scene holds (a school: a pair's physics, N swimmers; the cost of a step grows
#: as N^2, see docs/scenes.md "Schools").
MAX_SWIMMERS = 16

#: How a school's swimmers are placed: ``"line"``, one behind the other on the x axis D apart;
#: ``"side"``, side by side, D apart along z (perpendicular to their axes, in their common plane).
FORMATIONS = ("line", "side")


@dataclasses.dataclass(frozen=True)
class Scene:
    """Where the swimmers swim. Hashable; a static parameter of the scene environment.

    Lengths are in sphere radii ``a``; angles in radians.

    Attributes
    ----------
    medium : str
        ``"bulk"``: the paper's first-order velocity formula, each swimmer on its own (today's
        environment, the same numbers); ``"free"``: every sphere coupled through the point-force
        (Oseen) mobility in the unbounded fluid; ``"wall"``: the same above Blake's no-slip wall
        at z = 0.
    height : float
        Initial height of each swimmer's middle sphere above the wall (``"wall"``; elsewhere it is
        just the starting z).
    tilt : float
        Initial angle of each swimmer's axis from the wall plane (positive: nose up), rad.
    swimmers : int
        1 to `MAX_SWIMMERS`. Swimmer ``s`` (0-based) starts at [`start_offsets`][jswim.scenes.scene.Scene.start_offsets] ``[s]``
        times the separation from swimmer 0's middle sphere, all parallel to x.
    separation : float
        D, distance between neighbouring swimmers' middle spheres.
    obstacles : tuple of (x, z, radius)
        Fixed spheres (zero velocity, unknown force); ``"free"`` and ``"wall"`` only.
    mobility : str
        Pair mobility between spheres (``"free"`` and ``"wall"``): ``"point"`` (point forces,
        Oseen / Blake; the default and every number of the README's tables) or ``"rpy"``
        (finite-size spheres: Rotne-Prager-Yamakawa in the unbounded fluid, Rotne-Prager-Blake
        above the wall, Swan & Brady 2007; above the wall obstacles must then have radius 1).
        Omitted from [`to_dict`][jswim.scenes.scene.Scene.to_dict] when ``"point"``, so the canonical JSON of earlier scenes
        (and the run ids built from it) is unchanged.
    formation : str
        Where a school's swimmers start (`FORMATIONS`): ``"line"`` (the default; coaxial,
        swimmer ``s`` at ``x = s D``, ahead in the swimming direction) or ``"side"`` (side by side,
        swimmer ``s`` at ``z = height + s D``: above a wall, each one D higher). Omitted from
        [`to_dict`][jswim.scenes.scene.Scene.to_dict] when ``"line"`` (earlier scenes' JSON unchanged).
    self_mobility : str
        Each sphere's own mobility above the wall (`jswim.swimmers.mobility.SELF_MOBILITIES`):
        ``"exact"`` (the default: Brenner's series normal to the wall, near-contact asymptotics
        joined to Faxen's series along it) or ``"rpb"`` (the Rotne-Prager-Blake series in a/h,
        3.2 times too mobile normal to the wall at h = 1.1 a). The default because a swimmer's
        fate (trapped, escaping) is decided near contact; see docs/scenes.md. Written by
        [`to_dict`][jswim.scenes.scene.Scene.to_dict] for medium ``"wall"`` only (it changes nothing elsewhere), so a wall
        scene's run id says which.
    """

    medium: str = "bulk"
    height: float = 10.0
    tilt: float = 0.0
    swimmers: int = 1
    separation: float = 30.0
    obstacles: tuple[tuple[float, float, float], ...] = ()
    mobility: str = "point"
    formation: str = "line"
    self_mobility: str = "exact"

    def __post_init__(self) -> None:
        # Normalise for hashing and equality: floats and nested tuples whatever was passed; a NumPy
        # number (np.float32(5.0), a value read from an array) is the plain float it holds.
        for name in ("height", "tilt", "separation", "swimmers"):
            object.__setattr__(self, name, plain(getattr(self, name)))
        try:
            obs = tuple(tuple(float(v) for v in o) for o in self.obstacles)
        except (TypeError, ValueError):
            return  # left as given: validate() names the problem
        object.__setattr__(self, "obstacles", obs)

    def validate(self) -> Scene:
        """``self`` if every field is valid.

        Raises
        ------
        ValueError
            (a [`jswim.errors.ConfigError`][jswim.errors.ConfigError]) naming the first bad field, in one line.
        """
        if self.medium not in MEDIA:
            raise ConfigError(
                f"scene medium must be one of {', '.join(MEDIA)}; got {self.medium!r}"
            )
        for name in ("height", "tilt", "separation"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ConfigError(f"scene {name} must be a finite number, got {v!r}")
        if self.medium == "wall" and not self.height > 1.0:
            raise ConfigError(
                f"scene height must exceed 1 (a sphere radius) above the wall, got {self.height!r}"
            )
        if not abs(self.tilt) < math.pi / 2:
            raise ConfigError(f"scene tilt must lie in (-pi/2, pi/2), got {self.tilt!r}")
        if isinstance(self.swimmers, bool) or self.swimmers not in range(1, MAX_SWIMMERS + 1):
            raise ConfigError(
                f"scene swimmers must be an integer in 1..{MAX_SWIMMERS}, got {self.swimmers!r}"
            )
        if self.formation not in FORMATIONS:
            raise ConfigError(
                f"scene formation must be one of {', '.join(FORMATIONS)}; got {self.formation!r}"
            )
        if self.swimmers > 1 and not self.separation > 0:
            raise ConfigError(f"scene separation must be positive, got {self.separation!r}")
        if not isinstance(self.obstacles, tuple):
            raise ConfigError(
                f"scene obstacles must be (x, z, radius) triples, got {self.obstacles!r}"
            )
        for o in self.obstacles:
            if len(o) != 3 or not all(math.isfinite(v) for v in o):
                raise ConfigError(
                    f"each obstacle must be three finite numbers (x, z, radius), got {o!r}"
                )
            if not o[2] > 0:
                raise ConfigError(f"an obstacle's radius must be positive, got {o!r}")
            if self.medium == "wall" and not o[1] > o[2]:
                raise ConfigError(f"obstacle {o!r} reaches the wall (its z must exceed its radius)")
        if self.obstacles and self.medium == "bulk":
            raise ConfigError(
                "obstacles need medium 'free' or 'wall' (the bulk formula has no hydrodynamic coupling)"
            )
        from jswim.swimmers.mobility import (  # lazy: start-up (a Scene is built before JAX loads)
            MOBILITIES,
            SELF_MOBILITIES,
        )

        if self.self_mobility not in SELF_MOBILITIES:
            raise ConfigError(
                f"scene self_mobility must be one of {', '.join(SELF_MOBILITIES)}; got {self.self_mobility!r}"
            )

        if self.mobility not in MOBILITIES:
            raise ConfigError(
                f"scene mobility must be one of {', '.join(MOBILITIES)}; got {self.mobility!r}"
            )
        if self.mobility != "point" and self.medium == "bulk":
            raise ConfigError(
                "mobility 'rpy' needs medium 'free' or 'wall' (the bulk formula has no pair mobility)"
            )
        if (
            self.mobility == "rpy"
            and self.medium == "wall"
            and any(o[2] != 1.0 for o in self.obstacles)
        ):
            raise ConfigError(
                "mobility 'rpy' above a wall is built for spheres of one radius: obstacles need radius 1"
            )
        return self

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-ready dict (obstacles as lists)."""
        out = dataclasses.asdict(self)
        out["obstacles"] = [list(o) for o in self.obstacles]
        if self.mobility == "point":
            del out["mobility"]  # the default: earlier scenes' JSON (and run ids) unchanged
        if self.formation == "line":
            del out["formation"]  # likewise
        if self.medium != "wall":
            del out["self_mobility"]  # no effect without the wall
        return out

    def start_offsets(self) -> Any:
        """Each swimmer's start offset from swimmer 0 per unit separation, NumPy ``(S, 2)``
        (``(x, z)``): ``(s, 0)`` in a line, ``(0, s)`` side by side."""
        import numpy as np  # lazy: start-up (a Scene is built before NumPy is needed)

        s = np.arange(self.swimmers, dtype=np.float64)
        zero = np.zeros_like(s)
        return np.stack([s, zero] if self.formation == "line" else [zero, s], -1)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Scene:
        """Inverse of [`to_dict`][jswim.scenes.scene.Scene.to_dict] (unknown keys are an error); validated."""
        if not isinstance(data, dict):
            raise ConfigError(f"a scene must be a JSON object, got {type(data).__name__}")
        names = {f.name for f in dataclasses.fields(cls)}
        extra = sorted(set(data) - names)
        if extra:
            raise ConfigError(
                f"unknown scene field(s): {', '.join(extra)}; known: {', '.join(sorted(names))}"
            )
        fields = dict(data)
        if "obstacles" in fields:
            try:
                fields["obstacles"] = tuple(tuple(float(v) for v in o) for o in fields["obstacles"])
            except (TypeError, ValueError):
                raise ConfigError(
                    f"scene obstacles must be (x, z, radius) triples, got {data['obstacles']!r}"
                ) from None
        for name in ("height", "tilt", "separation"):
            if (
                name in fields
                and isinstance(fields[name], int)
                and not isinstance(fields[name], bool)
            ):
                fields[name] = float(fields[name])
        return cls(**fields).validate()
