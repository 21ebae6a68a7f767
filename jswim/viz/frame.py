"""One picture of a world's state as an RGB array: the frames of the Gymnasium door's
``render_mode="rgb_array"`` (`jswim.gym`). The bodies are the pictures' one outline
(`jswim.viz.tracks.outline`, placed by `jswim.viz.tracks.place`), the wall and the
obstacles `jswim.viz.worlds.draw_fixed`'s, the colours the report page's."""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.patches import Circle

from jswim.viz.tracks import outline, place
from jswim.viz.worlds import SECOND_SWIMMER, Marker, World, draw_fixed

#: Colour of swimmer 1's body (the others: `jswim.viz.worlds.SECOND_SWIMMER`).
BODY_COLOR = "#0072B2"
#: Fluid background.
FLUID = "#f4f8fb"


def draw_state(
    ax: Any,
    model: Any,
    dofs: np.ndarray,
    positions: np.ndarray,
    orientations: np.ndarray,
    world: World,
    caption: str = "",
    half_width: float = 6.0,
) -> None:
    """Draw every swimmer of one state on ``ax``, the view centred on their mean position.

    Parameters
    ----------
    model : SwimmerModel or Marker
        One swimmer's model (every swimmer of a scene has the same).
    dofs : array (S, n_dof / S)
        Each swimmer's DOF values (rad or ``a``).
    positions : array (S, 2)
        Each swimmer's centroid, in ``a``; above a wall ``y`` is the height.
    orientations : array (S,)
        Each swimmer's orientation (rad).
    world : World
        The fixed parts (wall, obstacles).
    caption : str
        A line drawn at the top left (step, x).
    half_width : float
        Half the smallest view width, in ``a``.
    """
    bodies = [
        place(outline(model, d), p[0], p[1], th)
        for d, p, th in zip(dofs, positions, orientations, strict=True)
    ]
    pts = np.concatenate(bodies)
    centre = pts.mean(axis=0)
    spheres = not getattr(model, "planar", True)
    half = max(half_width, 0.6 * float(np.ptp(pts[:, 0])) + (2.0 if spheres else 0.5))
    ax.set_facecolor(FLUID)
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - 0.75 * half, centre[1] + 0.75 * half)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xticks([])
    ax.set_yticks([])
    draw_fixed(ax, world, (centre[0] - half, centre[0] + half))
    for s, body in enumerate(bodies):
        color = BODY_COLOR if s == 0 else SECOND_SWIMMER
        if spheres:
            ax.plot(body[:, 0], body[:, 1], "-", color=color, lw=0.8, zorder=4)
            for c in body:
                ax.add_patch(Circle(c, 1.0, fc="white", ec=color, lw=1.2, zorder=5))
        else:
            ax.plot(body[:, 0], body[:, 1], "-", color=color, lw=2.5, solid_capstyle="round")
            ax.plot(body[1:-1, 0], body[1:-1, 1], "o", color=color, ms=3)
    if caption:
        ax.text(0.02, 0.96, caption, transform=ax.transAxes, va="top", fontsize=8, color="0.2")


def rgb_frame(*args: Any, size: tuple[int, int] = (480, 360), **kwargs: Any) -> np.ndarray:
    """`draw_state` on a fresh off-screen figure, as an ``(height, width, 3)`` uint8 array
    of ``size = (width, height)`` pixels."""
    dpi = 80
    fig = Figure(figsize=(size[0] / dpi, size[1] / dpi), dpi=dpi)
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    draw_state(ax, *args, **kwargs)
    canvas.draw()
    return np.asarray(canvas.buffer_rgba())[..., :3].copy()


def show_frame(frame: np.ndarray, fps: float, state: dict[str, Any]) -> None:
    """Show ``frame`` in a matplotlib window (``render_mode="human"``), kept in ``state`` between
    calls, for ``1 / fps`` seconds."""
    import matplotlib.pyplot as plt  # the user's window backend, chosen only when one is asked for

    if "image" not in state:
        plt.ion()
        fig, ax = plt.subplots()
        ax.set_axis_off()
        state["fig"], state["image"] = fig, ax.imshow(frame)
    else:
        state["image"].set_data(frame)
    state["fig"].canvas.draw_idle()
    plt.pause(1.0 / fps)


def state_frame(world: Any, env_state: Any, params: Any, t: int) -> np.ndarray:
    """The picture of a world's state (`rgb_frame`): the paper's swimmers by their outline
    (above a wall, its plane seen from above), a scene's swimmers, wall and obstacles, a world of
    `jswim.register_world` as markers; the caption gives the step ``t`` and the mean x."""
    obs = world.observe(env_state, params)
    s = world.n_swimmers
    scenery = world.scenery()
    model: Any = scenery.model
    if model is None:
        model = Marker(type(world).__name__, world.n_dof // s)
    extra = {} if scenery.plane_height is None else {"plane_height": scenery.plane_height}
    fixed = World(n_swimmers=s, wall=scenery.wall, obstacles=scenery.obstacles, extra=extra)
    position = np.asarray(obs.position, np.float64)
    dofs = np.asarray(obs.dofs, np.float64).reshape(s, -1)
    caption = f"step {t}   x = {position[:, 0].mean():+.4f} a"
    return rgb_frame(model, dofs, position, np.asarray(obs.orientation, np.float64), fixed, caption)
