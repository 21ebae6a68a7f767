"""What a run's world holds, read from the folder's record, and how it is drawn (once, for every picture).

A run row says which world it swam in: a scene row carries ``scene`` (the scene's JSON: medium,
height, tilt, swimmers, separation, obstacles) and per-step, per-swimmer ``xs``, ``heights`` and
``tilts``; a row without one is the paper's bulk fluid, one swimmer starting at the origin.
`world_of` turns that record into a `World`, so the report page, ``jswim animate`` and
the figures that draw swimmers all draw the same things: every swimmer, the wall (the plane
``y = 0``, the scene's ``z = 0``), the obstacles, each swimmer's start pose at step 0 (for a wall
or a pair run: the middle sphere at ``y = h``, swimmer ``k`` at ``x = k D``), and a view that holds
every body whole. Keyed by the record only (no import of the environment), so a world recorded
the same way by another environment is drawn the same way.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace
from typing import Any
from collections.abc import Mapping, Sequence

import numpy as np

from jswim.env.flows import Flow
from jswim.figures.flow_plots import flow_label, flow_of, flow_text
from jswim.results.row import as_run_row

#: Colours of the world's fixed parts (shared by the page's canvas and matplotlib).
WALL_COLOR = "#6b5b45"
OBSTACLE_COLOR = "#9a8c7a"
#: Edge colours of swimmer 1, 2, ... (swimmer 1 keeps the agent's colour).
SECOND_SWIMMER = "#CC79A7"


@dataclass(frozen=True)
class World:
    """The fixed parts of a run's world and its start, from the run's record.

    Attributes
    ----------
    n_swimmers : int
    wall : bool
        A no-slip wall at ``y = 0`` (the scene's ``z = 0``); heights are above it.
    obstacles : tuple of (x, y, radius)
        Fixed spheres, in ``a``.
    start : tuple of (x, y, tilt)
        Each swimmer's start pose: the middle sphere's (or centroid's) position in ``a`` and the
        axis angle in rad.
    medium : str
        ``"bulk"`` (the paper's formula), ``"free"`` or ``"wall"``.
    targets : tuple of (x, y, radius)
        A navigation task's waypoints (one for a fixed or moving target) with the success radius,
        in ``a`` (docs/navigation.md); empty for the paper's task.
    target_velocity : tuple of float
        A moving target's velocity (``a`` per step): at step ``k`` it is at its start plus ``k``
        times this (`target_at`).
    flow : str
        A navigation run's background flow, the row's ``flow`` (canonical JSON,
        [`jswim.env.flows`][jswim.env.flows]); ``""`` in still fluid.
    flow_fraction : float or None
        Its speed over the swimming speed (the row's ``flow_fraction``).
    """

    n_swimmers: int = 1
    wall: bool = False
    obstacles: tuple[tuple[float, float, float], ...] = ()
    start: tuple[tuple[float, float, float], ...] = ((0.0, 0.0, 0.0),)
    medium: str = "bulk"
    separation: float | None = None
    extra: dict[str, Any] = field(default_factory=dict, compare=False)
    targets: tuple[tuple[float, float, float], ...] = ()
    target_velocity: tuple[float, float] = (0.0, 0.0)
    flow: str = ""
    flow_fraction: float | None = None

    def flow_object(self) -> Flow | None:
        """The background flow (`jswim.figures.flow_plots.flow_of`); ``None`` in still fluid."""
        return flow_of(self.flow)

    def target_at(self, step: int) -> list[tuple[float, float, float]]:
        """The targets at step ``step``: the waypoints, a moving target moved ``step`` times
        its velocity."""
        vx, vy = self.target_velocity
        return [(x + vx * step, y + vy * step, r) for x, y, r in self.targets]

    def describe(self) -> str:
        """A short line for captions: ``"wall, h = 3 a"``, ``"pair, D = 30 a"``, ``""`` for bulk."""
        bits = []
        if (
            self.extra.get("plane_height") is not None
        ):  # Purcell's swimmer above a wall, drawn from above
            bits.append(
                f"seen from above: its plane h = {self.extra['plane_height']:g} a above a wall"
            )
        if self.wall:
            bits.append(f"wall, h = {self.start[0][1]:g} a")
        if self.n_swimmers > 1:
            side = len({round(st[0], 9) for st in self.start}) == 1  # all at one x: side by side
            bits.append(
                f"{self.n_swimmers} swimmers{' side by side' if side else ''}, D = {self.separation:g} a"
            )
        if self.obstacles:
            bits.append(f"{len(self.obstacles)} obstacle(s)")
        if len(self.targets) > 1:
            bits.append(f"path of {len(self.targets)} waypoints")
        elif self.targets:
            x, y = (round(v, 6) + 0.0 for v in self.targets[0][:2])  # 1.8e-16 -> 0
            moving = "moving target from" if any(self.target_velocity) else "target at"
            bits.append(f"{moving} ({x:g}, {y:g}) a")
        if self.flow:
            bits.append(f"flow: {flow_label(self.flow_object(), self.flow_fraction)}")
        return ", ".join(bits)


@dataclass(frozen=True)
class Marker:
    """The stand-in model of a world with no outline of its own ([`jswim.register_world`][jswim.env.registry.register_world]'s):
    each swimmer one sphere of radius 1 at its observed position, its DOFs as places in [0, 1];
    the fields the pictures read of a [`jswim.swimmers.models.SwimmerModel`][jswim.swimmers.models.SwimmerModel]."""

    label: str
    n_dof: int
    lo: float = 0.0
    hi: float = 1.0
    planar: bool = False

    def outline(self, dofs: np.ndarray) -> np.ndarray:
        """The body in its own frame, ``(..., 1, 2)``: one point, at the position."""
        return np.zeros(np.shape(dofs)[:-1] + (1, 2))


def from_above(row: Mapping[str, Any]) -> bool:
    """Whether a scene row is drawn in the swimmer's own plane rather than the scene's vertical
    plane: its world recorded a plane parallel to a wall (``plane_height``, the world's
    [`Scenery`][jswim.env.base.Scenery]; its row's ``y`` and ``orientation`` are in that plane,
    with the wall beneath it), or its scene is the paper's bulk fluid (the paper's plane, the
    start at the origin)."""
    r = as_run_row(row)
    return bool(r.scene) and (r.plane_height is not None or r.medium == "bulk")


def world_of(row: Mapping[str, Any]) -> World:
    """The `World` a run row records (its ``scene``; none: the bulk fluid), with its navigation
    target (its ``target``) where it has one."""
    world = _scene_world(row)
    r = as_run_row(row)
    raw = r.target
    if r.flow:  # a navigation run in a background flow (drawn under its track)
        world = replace(world, flow=str(r.flow), flow_fraction=r.flow_fraction)
    if not raw:
        return world
    try:
        t = json.loads(raw)
        radius = float(t.get("radius", 0.25))
        if t.get("points"):
            pts = [(float(p[0]), float(p[1])) for p in t["points"]]
        else:
            b = math.radians(float(t.get("bearing", 0.0)))
            pts = [(float(t["distance"]) * math.cos(b), float(t["distance"]) * math.sin(b))]
        v = tuple(float(u) for u in (t.get("velocity") or (0.0, 0.0)))
    except (TypeError, ValueError, KeyError):
        return world
    return replace(world, targets=tuple((x, y, radius) for x, y in pts), target_velocity=v)


def _scene_world(row: Mapping[str, Any]) -> World:
    r = as_run_row(row)
    raw = r.scene
    if not raw:
        return World()
    try:
        sc = json.loads(raw) if isinstance(raw, str) else dict(raw)
    except (TypeError, ValueError):
        return World()
    if from_above(row):
        plane = r.plane_height
        return World(
            medium=str(sc.get("medium", "bulk")),
            extra={} if plane is None else {"plane_height": float(plane)},
        )
    n = int(sc.get("swimmers") or 1)
    h = float(sc.get("height", 0.0) or 0.0)
    tilt = float(sc.get("tilt", 0.0) or 0.0)
    d = float(sc.get("separation", 0.0) or 0.0)
    obstacles = tuple((float(o[0]), float(o[1]), float(o[2])) for o in sc.get("obstacles") or ())
    side = (
        sc.get("formation") == "side"
    )  # a school side by side: each one D higher (else in a line, D ahead)
    return World(
        n_swimmers=n,
        wall=sc.get("medium") == "wall",
        obstacles=obstacles,
        start=tuple(((0.0, h + k * d) if side else (k * d, h)) + (tilt,) for k in range(n)),
        medium=str(sc.get("medium", "bulk")),
        separation=d if n > 1 else None,
    )


def per_swimmer(row: Mapping[str, Any], key: str, n: int, n_swimmers: int) -> np.ndarray | None:
    """A per-step, per-swimmer record (``xs``, ``heights``, ``tilts``) as an (n, S) array, or None."""
    v = row.get(key)
    if not isinstance(v, list) or len(v) < n:
        return None
    try:
        a = np.asarray(
            [[float(u) for u in (s if isinstance(s, list) else [s])] for s in v[:n]], np.float64
        )
    except (TypeError, ValueError):
        return None
    return a if a.ndim == 2 and a.shape[1] == n_swimmers else None


def view_box(
    bodies: Sequence[np.ndarray], worlds: Sequence[World], spheres: bool, pad: float = 1.5
) -> tuple[float, float, float, float]:
    """``(xmin, xmax, ymin, ymax)`` holding every body (each (N + 1, S, P, 2)) at every step, the
    wall's line and the obstacles, with ``pad`` (``a``) around."""
    pts = np.concatenate([b.reshape(-1, 2) for b in bodies]) if bodies else np.zeros((1, 2))
    r = 1.0 if spheres else 0.0
    lo = pts.min(axis=0) - pad - r
    hi = pts.max(axis=0) + pad + r
    for w in worlds:
        if w.wall:
            lo[1] = min(lo[1], -0.6)
        for ox, oy, orad in w.obstacles:
            lo = np.minimum(lo, [ox - orad - pad, oy - orad - pad])
            hi = np.maximum(hi, [ox + orad + pad, oy + orad + pad])
        n = len(bodies[0]) if bodies else 0
        for ox, oy, orad in w.target_at(0) + w.target_at(n):
            lo = np.minimum(lo, [ox - orad - pad / 2, oy - orad - pad / 2])
            hi = np.maximum(hi, [ox + orad + pad / 2, oy + orad + pad / 2])
    return float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1])


def body_extent(bodies: np.ndarray, spheres: bool) -> float:
    """The longest a swimmer gets along x over the run (``a``, sphere radii included)."""
    span = bodies[..., 0].max(axis=-1) - bodies[..., 0].min(axis=-1)  # (N + 1, S)
    return float(span.max()) + (2.0 if spheres else 0.0)


def follow_width(bodies: np.ndarray, spheres: bool, at_least: float) -> float:
    """The width of a view that follows a swimmer and always holds it whole (``a``)."""
    return max(at_least, body_extent(bodies, spheres) + 4.0)


def draw_fixed(ax: Any, world: World, xlim: tuple[float, float] | None = None) -> list[Any]:
    """Draw the world's wall and obstacles on a matplotlib axis; returns the artists."""
    from matplotlib.patches import Circle, Rectangle

    out: list[Any] = []
    if (
        world.extra.get("plane_height") is not None
    ):  # the wall beneath the swimmer's plane, seen from above
        ax.set_facecolor("#efe9e1")
    if world.wall:
        x0, x1 = xlim if xlim is not None else ax.get_xlim()
        big = max(abs(x0), abs(x1)) * 4 + 1e3  # wide enough for a view that follows the swimmer
        out.append(
            ax.add_patch(
                Rectangle(
                    (-big, -50.0), 2 * big, 50.0, fc="#d9cfc2", ec="none", zorder=1.5, hatch="///"
                )
            )
        )
        out.append(ax.axhline(0.0, color=WALL_COLOR, lw=1.6, zorder=1.6))
    for ox, oy, orad in world.obstacles:
        out.append(
            ax.add_patch(Circle((ox, oy), orad, fc=OBSTACLE_COLOR, ec=WALL_COLOR, lw=0.8, zorder=3))
        )
    return out


def draw_targets(ax: Any, world: World, step: int = 0) -> list[Any]:
    """Draw a navigation task's targets at step ``step`` (each waypoint a cross in a circle of
    the success radius, numbered along a path); returns the artists (a moving target's are
    redrawn each frame)."""
    from matplotlib.patches import Circle

    out: list[Any] = []
    pts = world.target_at(step)
    for k, (x, y, r) in enumerate(pts, 1):
        out.append(ax.add_patch(Circle((x, y), r, fc="none", ec=TARGET_COLOR, lw=1.0, zorder=3)))
        out += ax.plot([x], [y], marker="x", color=TARGET_COLOR, ms=5, zorder=3)
        if len(pts) > 1:
            out.append(ax.annotate(str(k), (x, y), xytext=(4, 4), textcoords="offset points"))
    return out


#: The colour of navigation targets (the report page's too).
TARGET_COLOR = "#B00000"
#: Width over height of the report page's run canvas (``report.js``: 900 x 340 pixels).
CANVAS_ASPECT = 900 / 340


def payload(
    world: World, box: Sequence[float] | None = None, aspect: float = CANVAS_ASPECT
) -> dict[str, Any]:
    """What the page's canvas needs to draw the world's fixed parts (and a navigation task's
    targets: ``targets`` as (x, y, radius), ``target_v`` a moving target's velocity); in a
    background flow also ``flow`` (`flow_arrows` over ``box``, the run's view)."""
    out = {
        "targets": [list(t) for t in world.targets],
        "target_v": list(world.target_velocity),
        "wall": world.wall,
        "obstacles": [list(o) for o in world.obstacles],
        "n_swimmers": world.n_swimmers,
        "world": world.describe(),
    }
    if world.flow and box is not None:
        out["flow"] = flow_arrows(world, box, aspect)
    return out


def flow_arrows(
    world: World,
    box: Sequence[float],
    aspect: float = CANVAS_ASPECT,
    rows: int = 9,
    most: int = 900,
) -> dict[str, Any]:
    """The page's picture of a run's background flow: its velocity at the points of a square
    lattice (``arrows``: ``[x, y, ux, uy]``, ``a`` and ``a / step``) over ``box`` widened to the
    canvas's shape (``aspect``, width over height: the canvas shows more than the box along one
    side), about ``rows`` across its height and at most ``most`` points; its lattice ``spacing``,
    the fastest speed on it (``max``), a short ``label`` and the ``legend`` line under the canvas.
    """
    flow = world.flow_object()
    label = flow_label(flow, world.flow_fraction)
    legend = "background flow: " + flow_text(flow)
    if flow is None or not flow.speed:
        return {"label": label, "legend": legend, "arrows": [], "spacing": 1.0, "max": 0.0}
    x0, x1, y0, y1 = (float(v) for v in box)
    w, h = x1 - x0, y1 - y0
    w, h = max(w, h * aspect), max(h, w / aspect)
    cx, cy = (x0 + x1) / 2, (y0 + y1) / 2
    step = max(h / rows, 1e-6)
    while (w / step + 2) * (h / step + 2) > most:
        step *= 1.25
    # On multiples of the spacing: the arrows sit still when the view follows a swimmer.
    xs = np.arange(math.floor((cx - w / 2) / step), math.ceil((cx + w / 2) / step) + 1) * step
    ys = np.arange(math.floor((cy - h / 2) / step), math.ceil((cy + h / 2) / step) + 1) * step
    X, Y = np.meshgrid(xs, ys)
    uv = np.asarray(flow.velocity(np.stack([X, Y], axis=-1)), np.float64)
    arrows = np.stack([X, Y, uv[..., 0], uv[..., 1]], axis=-1).reshape(-1, 4)
    return {
        "label": label,
        "legend": legend + f"; arrows: its velocity on a {step:.3g} a lattice",
        "arrows": np.round(arrows, 5).tolist(),
        "spacing": float(step),
        "max": float(np.hypot(uv[..., 0], uv[..., 1]).max()),
    }
