"""Animations of runs: the swimmer's true shape moving through the fluid, runs side by side.

Each panel is one run: its body to scale (links of length ``a``, spheres of radius ``a``) at the
recorded pose after each step, the centroid's trail (the steps of the stroke the success
criterion found drawn thick), the start line, a navigation run's background flow as streamlines
under the swimmer (named at the panel's top right), and under it the step counter, the action
``[DOF, ROC]``, ``X/a``, the events of the step (stuck, history cleared, a failed reply, which cycle
of the stroke) and, for LLM runs, the reply the model gave. One frame per step: the states between
two recorded steps are not drawn (nothing is invented between them). Panels share one scale and
one view, so runs compare at a glance (the LLM next to Q-learning and random from the same start,
or one run per noise level).

Writes GIF with Pillow (always available) and MP4 when an ffmpeg is at hand: the one inside the
``imageio-ffmpeg`` wheel (``pip install 'jswim[video]'``) or one on ``PATH``.
"""

from __future__ import annotations

import base64
import dataclasses
import os
import shutil
import tempfile
import textwrap
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from collections.abc import Mapping, Sequence

import numpy as np

from jswim import reprs
from jswim._io.permissions import file_mode  # the study folders' rule (owner-only under umask 022)
from jswim.errors import ConfigError
from jswim.figures.flow_plots import draw_flow, flow_label
from jswim.figures.panels import panel_keys
from jswim.figures.style import RC
from jswim.results.orders import AGENT_ORDER
from jswim.results import as_run_rows, read_metadata, read_run_rows, read_transcript, writing
from jswim.viz import worlds
from jswim.viz.bench_page import read_bench, part_folders
from jswim.viz.tracks import Track, fmt_action, track, view_box

#: Colours of the agents (the figures' Okabe-Ito palette, `jswim.figures.style.AGENT_STYLE`).
#: Each agent's colour: the figures' (jswim.figures.style.AGENT_STYLE), the square stroke in black.
AGENT_COLORS = {
    "llm": "#0072B2",
    "qlearning": "#D55E00",
    "random": "#555555",
    "ppo": "#009E73",
    "stroke": "#000000",
    "zermelo": "#CC79A7",
}
FLUID = "#EAF3FA"
STROKE_COLOR = "#009E73"

#: Keys a run can be told apart by when several are shown.
DISTINGUISH = ("agent", "zeta", "n_ht", "group", "variant", "init", "direction", "swimmer")


@dataclass
class Animation:
    """Runs drawn side by side, ready to save or to show in a notebook.

    Attributes
    ----------
    tracks : list of Track
    fps : float
        Steps per second.
    title : str
        What the animation shows (study, model), written across its top.
    """

    tracks: list[Track]
    fps: float = 4.0
    title: str = ""
    dpi: int = 80

    @property
    def n_frames(self) -> int:
        """Frames: step 0, one per step, and a short hold on the last (1 s)."""
        return max(t.n_steps for t in self.tracks) + 1 + round(self.fps)

    def figure(self):
        """The figure and its update function ``draw(frame)`` (matplotlib)."""
        return _build(self)

    def frame_png(self, frame: int, dpi: int | None = None) -> bytes:
        """One frame as PNG bytes (e.g. for a README)."""
        import io

        import matplotlib.pyplot as plt

        fig, draw = _build(self)
        draw(frame)
        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=dpi or self.dpi)
        plt.close(fig)
        return buf.getvalue()

    def save(self, path: str | os.PathLike) -> Path:
        """Write the animation to ``path`` (``.gif`` or ``.mp4``), atomically; returns the path.

        Raises
        ------
        ConfigError
            Another suffix, or ``.mp4`` without an ffmpeg (one line naming the package to install).
        """
        import matplotlib.pyplot as plt
        from matplotlib import animation

        path = Path(path)
        suffix = path.suffix.lower()
        if suffix not in (".gif", ".mp4"):
            raise ConfigError(
                f"{path}: an animation is written as .gif or .mp4, not {suffix or 'no suffix'!r}"
            )
        if suffix == ".mp4":
            exe = ffmpeg_exe()
            if exe is None:
                raise ConfigError(
                    "MP4 needs an ffmpeg: pip install 'jswim[video]' (imageio-ffmpeg ships one), "
                    "or write a .gif"
                )
            plt.rcParams["animation.ffmpeg_path"] = exe
            writer: Any = animation.FFMpegWriter(
                fps=self.fps, codec="libx264", extra_args=["-pix_fmt", "yuv420p", "-crf", "28"]
            )
        else:
            writer = animation.PillowWriter(fps=self.fps)
        fig, draw = _build(self)
        with writing(path, "choose a writable --out path"):
            path.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=suffix)
            os.close(fd)
            try:
                anim = animation.FuncAnimation(fig, draw, frames=self.n_frames, blit=False)
                anim.save(tmp, writer=writer, dpi=self.dpi)
                self.frames_written = _count_frames(tmp, suffix, self.n_frames)
                os.chmod(tmp, _file_mode())
                os.replace(tmp, path)
            except BaseException:
                Path(tmp).unlink(missing_ok=True)
                raise
            finally:
                plt.close(fig)
        return path

    #: Frames the last `save` wrote: a GIF merges identical frames (the hold on the last step
    #: becomes one longer frame), so it may hold fewer than `n_frames`.
    frames_written: int | None = None

    def to_gif_bytes(self) -> bytes:
        with tempfile.TemporaryDirectory() as tmp:
            path = self.save(Path(tmp) / "run.gif")
            return path.read_bytes()

    def __repr__(self) -> str:
        return reprs.animation_text(self)

    def _repr_html_(self) -> str:  # Jupyter shows the GIF inline
        data = base64.b64encode(self.to_gif_bytes()).decode()
        return f'<img src="data:image/gif;base64,{data}" alt="{_esc(self.title)}"/>'


def _count_frames(path: str, suffix: str, drawn: int) -> int:
    """Frames in a written animation (a GIF's own count; an MP4 holds every drawn frame)."""
    if suffix != ".gif":
        return drawn
    from PIL import Image

    with Image.open(path) as im:
        return int(getattr(im, "n_frames", 1))


def _file_mode() -> int:
    return file_mode()


def _esc(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace('"', "&quot;")


def ffmpeg_exe() -> str | None:
    """An ffmpeg binary: imageio-ffmpeg's (a wheel that ships one), else one on ``PATH``."""
    try:
        import imageio_ffmpeg  # optional: pip install 'jswim[video]'

        return imageio_ffmpeg.get_ffmpeg_exe()
    except Exception:  # not installed, or its binary missing on this platform
        return shutil.which("ffmpeg")


# -- choosing runs -------------------------------------------------------------------------------


def pick_runs(
    rows: Sequence[Mapping[str, Any]], by: str = "agent", most: int = 4
) -> list[Mapping[str, Any]]:
    """Runs worth showing side by side: one per value of ``by`` in the first panel of the study.

    The first panel is the first (swimmer, target direction) in the figures' order; within it
    the runs are held to the first start and (unless ``by`` is it) the first noise level, n_ht,
    group and variant, and the first replicate of each value of ``by`` is kept (at most ``most``).
    """
    done = [r for r in as_run_rows(rows) if (r.status or "done") == "done" and r.x]
    if not done:
        return []
    sw, d = panel_keys(done)[0]
    sel = [r for r in done if r.swimmer == sw and int(r.direction or 1) == d]
    fixed = [k for k in ("init", "zeta", "n_ht", "group", "variant") if k != by]
    ref = next((r for r in sel if r.agent == "llm"), sel[0])
    for k in fixed:
        narrowed = [r for r in sel if r.get(k) == ref.get(k)]
        # The baselines carry no n_ht/variant and a group of their own: hold a key fixed only
        # where it leaves more than one value of `by` to show.
        if len({r.get(by) for r in narrowed}) > 1 or len({r.get(by) for r in sel}) == 1:
            sel = narrowed
    out: dict[Any, Mapping[str, Any]] = {}
    order = {a: i for i, a in enumerate(AGENT_ORDER)}
    for r in sorted(sel, key=lambda r: (order.get(r.agent, 9), str(r.get(by)), str(r.run_id))):
        out.setdefault(r.get(by), r)
    return list(out.values())[:most]


def build(
    folder_or_study: Any,
    run_ids: Sequence[str] | None = None,
    *,
    by: str = "agent",
    most: int = 4,
    fps: float = 4.0,
    dpi: int = 80,
) -> Animation:
    """An `Animation` of runs of a study folder (or a [`jswim.results.Study`][jswim.results.Study]).

    Parameters
    ----------
    folder_or_study : path or Study
    run_ids : sequence of str, optional
        The runs to show, left to right; default `pick_runs` (``by``, ``most``).
    fps : float
        Steps per second.

    Raises
    ------
    ConfigError
        An unknown run id (the message lists some that exist), or a folder without finished runs.
    """
    folder = Path(getattr(folder_or_study, "folder", folder_or_study))
    meta = read_metadata(folder)
    rows = read_run_rows(folder)
    by_id = {r.run_id: r for r in rows}
    if run_ids:
        missing = [i for i in run_ids if i not in by_id]
        if missing:
            some = ", ".join(list(by_id)[:4])
            raise ConfigError(f"{folder} has no run {missing[0]!r}; its runs are named like {some}")
        chosen = [by_id[i] for i in run_ids]
    else:
        chosen = pick_runs(rows, by=by, most=most)
    chosen = [r for r in chosen if r.x]
    if not chosen:
        raise ConfigError(f"{folder} has no finished runs to animate yet")
    if not (0 < fps <= 60):
        raise ConfigError(f"--fps must lie in (0, 60], got {fps}")
    tracks = [
        track(r, read_transcript(folder, r.run_id) if r.agent == "llm" else None) for r in chosen
    ]
    model = (meta.get("identity", {}).get("backend") or {}).get("model")
    for t in tracks:
        if t.agent == "llm" and model and "model" not in t.row:
            t.row["model"] = model
    status = meta.get("status")
    title = (
        f"jswim {meta.get('study', '')} study"
        + (f" · LLM: {model}" if model and any(t.agent == "llm" for t in tracks) else "")
        + ("" if status == "complete" else f" · UNFINISHED ({status})")
    )
    return Animation(tracks, fps=fps, title=title, dpi=dpi)


def build_bench(
    folder: str | Path, part: str | None = None, *, most: int = 4, fps: float = 4.0, dpi: int = 80
) -> Animation:
    """An `Animation` of a bench folder: one run per model, the reference rule, Q-learning and
    random, from the same setting of one part (default the suite's first), left to right.

    Raises
    ------
    ConfigError
        An unknown part, or a part without finished runs.
    """
    folder = Path(folder)
    meta, _ = read_bench(folder)
    found = part_folders(folder, meta)
    names = list(dict.fromkeys(p for _, _, p, _ in found))
    if part is None and names:
        part = names[0]
    if part not in names:
        raise ConfigError(
            f"{folder}: the bench has no finished part {part!r}; its parts: {', '.join(names) or 'none'}"
        )
    sources = [(label, kind, sub) for label, kind, p, sub in found if p == part]
    rows_of = {
        label: [r for r in read_run_rows(sub) if r.x and (r.status or "done") == "done"]
        for label, _, sub in sources
    }
    first = next((rs[0] for rs in rows_of.values() if rs), None)
    if first is None:
        raise ConfigError(f"{folder}: part {part!r} has no finished runs to animate yet")
    same = lambda r: (
        (r.swimmer, r.direction, r.zeta) == (first.swimmer, first.direction, first.zeta)
    )
    tracks = []
    for label, kind, sub in sources:
        agents = ("qlearning", "random") if kind == "baseline" else ("llm",)
        for agent in agents:
            r = next(
                (
                    r
                    for r in sorted(rows_of[label], key=lambda r: str(r.run_id))
                    if r.agent == agent and same(r)
                ),
                None,
            )
            if r is None:
                continue
            if (
                agent == "llm"
            ):  # the track's label names the model (a column of no run row: in ``other``)
                r = dataclasses.replace(
                    r,
                    other={**r.other, "model": "reference rule" if kind == "reference" else label},
                )
            tracks.append(track(r, read_transcript(sub, r.run_id) if agent == "llm" else None))
    if not (0 < fps <= 60):
        raise ConfigError(f"--fps must lie in (0, 60], got {fps}")
    suite = (meta.get("suite") or {}).get("name", "?")
    return Animation(tracks[:most], fps=fps, title=f"jswim bench {suite} · {part}", dpi=dpi)


def animate(study: Any, run_ids: str | Sequence[str] | None = None, **kw: Any) -> Animation:
    """Runs of a study as an animation; in Jupyter it shows inline (a GIF).

    ``jswim.animate(jswim.load(folder), "llm-purcell-px-i++-z0-r0")``, or with no run ids one run
    per agent from the same start (`pick_runs`). ``.save("runs.gif")`` or ``.mp4`` writes it.
    Keywords: ``by``, ``most``, ``fps``, ``dpi`` (see `build`).
    """
    if isinstance(run_ids, str):
        run_ids = [run_ids]
    return build(study, run_ids, **kw)


# -- drawing -------------------------------------------------------------------------------------


def _caption(t: Track, others: Sequence[Track]) -> str:
    """A panel's name: the agent (and model) plus whatever tells it apart from the other panels."""
    parts = [t.label]
    for k in DISTINGUISH[1:]:
        # A key is named where it tells apart panels of one agent (the baselines carry no n_ht).
        same = [o for o in others if o.agent == t.agent]
        if len({str(o.row.get(k)) for o in same}) > 1 and t.row.get(k) not in (None, ""):
            v = t.row.get(k)
            parts.append(f"\u03b6 = {v:g}" if k == "zeta" else f"{k} {v}")
    return ", ".join(parts)


def _build(anim: Animation):
    """The figure of ``anim`` (one panel per track, its lines under it) and ``draw(frame)``."""
    import matplotlib.pyplot as plt

    tracks = anim.tracks
    box = view_box(tracks)
    width = box[1] - box[0]
    spheres = not tracks[0].model.planar
    # A long run: the view follows the swimmers, always wide enough for the whole body (an NG
    # swimmer at arms (10, 10) is 22 a long); a pair is shown whole (both swimmers in view).
    hold = max(worlds.follow_width(t.bodies, spheres, 12.0) for t in tracks)
    follow = width > max(16.0, hold + 4.0) and all(t.n_swimmers == 1 for t in tracks)
    view_w = hold if follow else width
    view_h = max(box[3] - box[2], 4.0)
    n = len(tracks)
    panel_w = float(np.clip(1.1 + view_w * 0.28, 3.0, 4.2))
    panel_h = panel_w * view_h / view_w
    # The lines under each panel, wrapped to its width, and room for the most any frame has:
    # a caption never runs into the next panel or off the figure's foot.
    columns = _text_columns(panel_w * (1 - 0.015 * n))  # from i/n + 0.015 to the next panel
    texts = [[_frame_text(t, k, columns) for k in range(t.n_steps + 1)] for t in tracks]
    n_lines = max(text.count("\n") + 1 for per in texts for text in per)
    text_h = max(0.85, n_lines * LINE_IN + 0.2)  # lines of 8.5 pt: >= 9 px at the default 80 dpi
    with plt.rc_context(RC):
        fig = plt.figure(figsize=(panel_w * n, panel_h + text_h + 0.35))
    fig.patch.set_facecolor("white")
    top = 1 - 0.35 / fig.get_figheight()
    bottom = text_h / fig.get_figheight()
    fig.text(
        0.5,
        1 - 0.06 / fig.get_figheight(),
        anim.title,
        ha="center",
        va="top",
        fontsize=10,
        color="#B00000" if "UNFINISHED" in anim.title else "black",
    )
    state = []
    for i, t in enumerate(tracks):
        ax = fig.add_axes([i / n + 0.01, bottom, 1 / n - 0.02, top - bottom])
        goal = _panel(ax, t, tracks, box, view_w, view_h, panel_w)
        artists, centre = _swimmer_artists(ax, t)
        txt = fig.text(
            i / n + 0.015,
            bottom - 0.03,
            "",
            ha="left",
            va="top",
            fontsize=TEXT_PT,
            family="monospace",
        )
        state.append((t, ax, artists, centre, txt, goal, texts[i]))

    def draw(frame: int):
        for t, ax, artists, centre, txt, goal, text in state:
            k = min(frame, t.n_steps)
            if any(t.world.target_velocity):  # a moving target: where it is at this step
                for a in goal:
                    a.remove()
                goal[:] = worlds.draw_targets(ax, t.world, k)
            for j, (trail, stroke, body, joints, spheres) in enumerate(artists):
                pts, pos = t.bodies[k, j], t.positions[:, j]
                trail.set_data(pos[: k + 1, 0], pos[: k + 1, 1])
                if t.stroke is not None and k > t.stroke[0]:
                    s0 = t.stroke[0]
                    stroke.set_data(pos[s0 : k + 1, 0], pos[s0 : k + 1, 1])
                else:
                    stroke.set_data([], [])
                if t.agent == "zermelo":  # a point's path: no body (jswim.agents.zermelo)
                    pts = pts[:0]
                body.set_data(pts[:, 0], pts[:, 1])
                if joints is not None:
                    joints.set_data(pts[1:-1, 0], pts[1:-1, 1])
                for c, p in zip(spheres, pts):
                    c.center = (float(p[0]), float(p[1]))
            centre.set_data([t.positions[k, 0, 0]], [t.positions[k, 0, 1]])
            if follow:
                x0 = float(np.clip(t.positions[k, 0, 0] - view_w / 2, box[0], box[1] - view_w))
                ax.set_xlim(x0, x0 + view_w)
            txt.set_text(text[k])
        return []

    draw(0)
    return fig, draw


def _panel(
    ax: Any,
    t: Track,
    tracks: Sequence[Track],
    box: Sequence[float],
    view_w: float,
    view_h: float,
    panel_w: float,
) -> list[Any]:
    """Draw the still parts of ``t``'s panel (the fluid, a scale bar of one a, the world's walls
    and targets, the caption, the target direction); the targets' artists (a moving target's
    are drawn again each frame)."""
    ax.set_facecolor(FLUID)
    ax.set_xlim(box[0], box[0] + view_w)
    ax.set_ylim(box[2], box[2] + view_h)
    ax.set_aspect("equal", adjustable="box")
    ax.set_xticks([])
    ax.set_yticks([])
    # Scale bar: one a (link length, sphere radius); the start line is X = 0.
    ax.plot([0.04, 0.04 + 1.0 / view_w], [0.06, 0.06], transform=ax.transAxes, color="0.25", lw=1.2)
    ax.text(
        0.04 + 0.5 / view_w,
        0.09,
        "a",
        transform=ax.transAxes,
        fontsize=8,
        ha="center",
        color="0.25",
    )
    for s in ax.spines.values():
        s.set_color("0.7")
    ax.axvline(0, color="0.55", lw=0.6, ls=":", zorder=1)
    flow = t.world.flow_object()
    if t.world.flow:  # a background flow: its streamlines under the swimmer, over the whole view
        view = (box[0], max(box[1], box[0] + view_w), box[2], box[2] + view_h)  # a follow's too
        for a in draw_flow(ax, flow, view, density=0.6, arrowsize=1.0):
            a.set_gid("flow")
        ax.text(
            0.97,
            0.95,
            "flow: " + flow_label(flow, t.world.flow_fraction),
            transform=ax.transAxes,
            ha="right",
            va="top",
            fontsize=7,
            color="#4d7aa3",
            gid="flow-label",
            bbox=dict(fc=FLUID, ec="none", alpha=0.85, pad=1.0),
            zorder=7,
        )
    worlds.draw_fixed(ax, t.world, (box[0], box[1]))
    goal = worlds.draw_targets(ax, t.world, 0)  # a navigation task's targets (else none)
    # Every panel names its agent in that agent's colour (the figures' colours).
    ax.set_title(
        textwrap.shorten(
            _caption(t, tracks), _text_columns(panel_w, TITLE_PT, 0.5), placeholder="..."
        ),
        fontsize=TITLE_PT,
        pad=2,
        color=AGENT_COLORS.get(t.agent, "black"),
    )
    if not t.world.targets:  # the paper's task: the target direction (navigation: drawn)
        ax.annotate(
            "",
            xy=(0.97, 0.06),
            xytext=(0.82, 0.06),
            xycoords="axes fraction",
            arrowprops=dict(arrowstyle="->", color="0.35", lw=0.8)
            if t.direction > 0
            else dict(arrowstyle="<-", color="0.35", lw=0.8),
        )
        ax.text(
            0.895,
            0.09,
            "target",
            transform=ax.transAxes,
            fontsize=7,
            ha="center",
            color="0.35",
        )
    return goal


def _swimmer_artists(ax: Any, t: Track) -> tuple[list[tuple[Any, ...]], Any]:
    """The moving artists of ``t``'s swimmers, empty until drawn: per swimmer (trail, stroke,
    body, joints, spheres), then the first swimmer's centroid marker."""
    from matplotlib.patches import Circle

    color = AGENT_COLORS.get(t.agent, "C0")
    artists = []
    for j in range(t.n_swimmers):  # every swimmer of the world, swimmer 2 in its own edge colour
        c_j = color if j == 0 else worlds.SECOND_SWIMMER
        (trail,) = ax.plot([], [], "-", color=c_j, lw=0.8, alpha=0.6, zorder=2)
        (stroke,) = ax.plot([], [], "-", color=STROKE_COLOR, lw=2.0, alpha=0.8, zorder=2)
        if t.model.planar:
            (body,) = ax.plot([], [], "-", color="black", lw=2.4, solid_capstyle="round", zorder=4)
            (joints,) = ax.plot([], [], "o", color=c_j, ms=3, zorder=5)
            spheres: list[Any] = []
        else:
            (body,) = ax.plot([], [], "-", color="0.3", lw=0.8, zorder=3)
            joints = None
            spheres = [
                ax.add_patch(Circle((0, 0), 1.0, fc="white", ec=c_j, lw=1.2, zorder=4))
                for _ in range(t.bodies.shape[2])
            ]
        artists.append((trail, stroke, body, joints, spheres))
    (centre,) = ax.plot([], [], "+", color=color, ms=5, zorder=6)
    return artists, centre


#: The panel texts' sizes (pt), and a line's height (in) at the text's size.
TEXT_PT, TITLE_PT = 8.5, 9.0
LINE_IN = TEXT_PT * 1.2 / 72


def _text_columns(panel_in: float, size_pt: float = TEXT_PT, em: float = 0.6) -> int:
    """Characters that fit across a panel ``panel_in`` inches wide at ``size_pt`` (a monospace
    character is 0.6 em wide; ``em`` 0.5 is an average proportional one), with a margin."""
    return max(20, int((panel_in - 0.12) * 72 / (em * size_pt)))


def _frame_text(t: Track, k: int, width: int = 10**6) -> str:
    """The lines under a panel at step ``k``, each wrapped to ``width`` characters."""
    return "\n".join(
        "\n".join(textwrap.wrap(line, width, subsequent_indent="  ") or [""])
        for line in _frame_lines(t, k)
    )


def _frame_lines(t: Track, k: int) -> list[str]:
    """The lines under a panel at step ``k``, unwrapped."""
    # The page's convention: X/a toward the target direction, labelled with it.
    disp = "X/a toward " + ("+x" if t.direction > 0 else "-x")
    lines = [f"step {k:>3}/{t.n_steps}  {disp} {t.direction * t.x[k]:+.4f}"]
    if t.world.targets:  # navigation: where it is and how far the target (the current waypoint's)
        here = np.array([t.x[k], t.y[k]])
        gap = min(np.hypot(gx - here[0], gy - here[1]) for gx, gy, _ in t.world.target_at(k))
        lines = [
            f"step {k:>3}/{t.n_steps}  nearest target {gap:.3f} a",
            f"(x, y) = ({here[0]:+.3f}, {here[1]:+.3f}) a",
        ]
    if k == 0:
        lines.append(
            "start "
            + ("(" + ", ".join(f"{n} {v:.3g}" for n, v in zip(t.dof_names, t.dofs[0])) + ")")
        )
    else:
        i = k - 1
        events = []
        if t.stuck[i]:
            events.append("stuck")
        if t.cleared[i]:
            events.append("history cleared")
        if t.failed[i]:
            events.append("no valid reply: hold")
        if t.in_stroke(k):
            s0, p = t.stroke  # type: ignore[misc]
            events.append(f"stroke cycle {(i - s0) // p + 1} (criterion)")
        if t.agent == "zermelo":  # a point steering at the swimming speed: no strokes
            lines.append("a point steering at the swimming speed")
        else:
            lines.append(f"action {fmt_action(t.actions[i])}  " + "  ".join(events))
        if t.replies[i] is not None:
            reply = " ".join(str(t.replies[i]).split())
            lines.append("reply: " + textwrap.shorten(reply, 38, placeholder="..."))
    if t.replayed:
        lines.append("(pose replayed: not in this folder)")
    return lines
