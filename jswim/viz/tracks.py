"""A run step by step, as a folder records it: pose, DOF values, the body in the lab frame, events.

Everything is read from what a study folder holds, never recomputed from the agent: the run's row
in ``runs.jsonl`` (``x``, ``y``, ``orientation`` and ``actions`` per step, ``init``, the judge's
``steps_to_learn`` and ``period``) and, for LLM runs, its transcript (``dofs_after``, the replies,
clears). DOF values come from a row's own per-step ``dofs`` when it has them, else from the
transcript, else they are replayed from the start shape and the actions: a step moves its DOF by
``ROC x (hi - lo)`` (ROC ``k / K`` for a recorded integer ``k`` on the K-level lattice,
``roc_levels``), stopping at a limit (for ROC in {-1, 0, 1} from a corner this is the corner
the environment steps to; real-valued ROCs follow the same rule). Folders written before ``y``
and ``orientation`` were recorded get them from a noiseless replay of the actions (exact for
``zeta = 0``; with noise only ``x`` is the recorded value), and the track says so (``replayed``).

The body outline (`outline`) is the swimmer's true shape to scale in units of ``a``: link
end points for the link swimmers (links of length 1), sphere centres for the sphere swimmers
(spheres of radius 1), placed so that its geometric centroid sits at the recorded ``(x, y)`` and
its reference link (the middle one, [`jswim.env.start_orientation`][jswim.env.state.start_orientation]) points along the recorded
orientation.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any
from collections.abc import Mapping, Sequence

import numpy as np

from jswim.results.row import as_run_row
from jswim.swimmers.models import SWIMMERS, SwimmerModel, make_model
from jswim.swimmers.outline import outline as _outline
from jswim.viz.worlds import Marker, World, per_swimmer, world_of
from jswim.viz import worlds

#: A step whose |dX| is below this is "stuck" (the prompt's rule, [`jswim.prompt`][jswim.prompt]).
STUCK_TOL = 1e-6


def place(points: np.ndarray, x: Any, y: Any, theta: Any) -> np.ndarray:
    """Body-frame ``points`` (..., P, 2) rotated by ``theta`` and moved to ``(x, y)`` (each (...,))."""
    x, y, theta = (np.asarray(v, np.float64)[..., None] for v in (x, y, theta))
    c, s = np.cos(theta), np.sin(theta)
    px, py = points[..., 0], points[..., 1]
    return np.stack([x + c * px - s * py, y + s * px + c * py], axis=-1)


def start_theta(model: SwimmerModel, d0: np.ndarray) -> float:
    """Start orientation of the reference link for start shape ``d0`` (the rule of
    [`jswim.env.start_orientation`][jswim.env.state.start_orientation]: chains of more than three links start symmetric about x)."""
    if not model.planar or model.n_dof <= 2:
        return 0.0
    cum = np.concatenate([[0.0], np.cumsum(d0)])
    return float(-(cum.mean() - cum[model.n_dof // 2]))


@dataclass
class Track:
    """One run, steps ``0..N`` (state before the first step, then after each step).

    Attributes
    ----------
    run_id, agent, swimmer : str
    model : SwimmerModel
    direction : int
        Target direction (+1 or -1).
    x, y, theta : ndarray (N + 1,)
        Centroid (in ``a``) and orientation of the reference link (rad).
    dofs : ndarray (N + 1, n_dof)
    points : ndarray (N + 1, P, 2)
        The body in the lab frame (see `outline`).
    actions : list of (dof, roc), length N
    stuck, cleared, failed : ndarray (N,) bool
        No displacement; the LLM's history cleared after that step; the reply named no valid
        action (the hold was played).
    replies : list of str or None, length N
        The LLM's last reply text of each step (``None`` for baselines).
    stroke : (start, period) or None
        Where the success criterion found the stroke: its 0-based first step and period.
    success : bool
    replayed : bool
        ``y``/``orientation`` were not recorded and come from a noiseless replay.
    row : dict
        The run's record (``runs.jsonl``).
    steps_log : list of dict
        The transcript's step records (LLM runs; empty otherwise).
    """

    run_id: str
    agent: str
    swimmer: str
    model: SwimmerModel
    direction: int
    x: np.ndarray
    y: np.ndarray
    theta: np.ndarray
    dofs: np.ndarray
    points: np.ndarray
    actions: list[tuple[int, float]]
    stuck: np.ndarray
    cleared: np.ndarray
    failed: np.ndarray
    replies: list[str | None]
    stroke: tuple[int, int] | None
    success: bool
    replayed: bool = False
    row: dict[str, Any] = field(default_factory=dict, repr=False)
    steps_log: list[dict[str, Any]] = field(default_factory=list, repr=False)
    #: The run's world (`jswim.viz.worlds`): swimmers, wall, obstacles, start poses.
    world: World = field(default_factory=World, repr=False)
    #: Every swimmer's body in the lab frame, (N + 1, S, P, 2); ``points`` is swimmer 1's.
    bodies: np.ndarray | None = field(default=None, repr=False)
    #: Every swimmer's reference position (centroid; a scene's middle sphere), (N + 1, S, 2).
    positions: np.ndarray | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        if self.bodies is None:
            self.bodies = self.points[:, None]
        if self.positions is None:
            self.positions = np.stack([self.x, self.y], axis=-1)[:, None]

    @property
    def n_swimmers(self) -> int:
        return int(self.bodies.shape[1])

    @property
    def dof_names(self) -> list[str]:
        """``D1..Dk``: every DOF the actions move (a pair: both swimmers')."""
        return [f"D{i + 1}" for i in range(self.dofs.shape[1])]

    @property
    def n_steps(self) -> int:
        return len(self.actions)

    @property
    def label(self) -> str:
        """``LLM``, ``Q-learning`` or ``random policy`` (the figures' names) with the model for LLM runs."""
        name = {
            "llm": "LLM",
            "qlearning": "Q-learning",
            "random": "random policy",
            "ppo": "PPO (real ROC)" if not self.row.get("roc_levels") else "PPO (categorical)",
            "stroke": "square stroke",
            "controller": "steering controller",
            "zermelo": "Zermelo (least-time point steerer)",
        }.get(self.agent, self.agent)
        model = self.row.get("model")
        return f"{name} ({model})" if model and self.agent == "llm" else name

    def in_stroke(self, step: int) -> bool:
        """Whether step ``step`` (1-based) belongs to the stroke the criterion found."""
        return self.stroke is not None and step - 1 >= self.stroke[0]


def outline(model: SwimmerModel | Marker, dofs: np.ndarray) -> np.ndarray:
    """The body of ``model`` at ``dofs`` in its own frame, ``(..., P, 2)``
    ([`jswim.swimmers.outline.outline`][jswim.swimmers.outline.outline]; a `Marker`: one point)."""
    return model.outline(dofs) if isinstance(model, Marker) else _outline(model, dofs)


def model_of(row: Mapping[str, Any], n_dof: int | None = None) -> SwimmerModel | Marker:
    """The swimmer model of a run row (the default geometry of its kind; ``n_dof`` picks the
    chain length of ``nlink``/``nsphere`` runs when their DOF count is known); a swimmer that is
    none of the paper's (a registered world) gets a `Marker`."""
    kind = str(as_run_row(row).swimmer or "purcell")
    if kind.lower() not in SWIMMERS:
        return Marker(kind, n_dof or 2)
    kw: dict[str, Any] = {}
    if n_dof is not None and kind in ("nlink", "nsphere"):
        kw["n_links" if kind == "nlink" else "n_spheres"] = n_dof + 1
    return make_model(kind, **kw)


def _levels(init: Any) -> list[float] | None:
    if isinstance(init, str) and init and not set(init) - {"+", "-"}:
        return [1.0 if c == "+" else 0.0 for c in init]
    if isinstance(init, (list, tuple)) and all(isinstance(v, (int, float)) for v in init):
        return [float(v) for v in init]
    return None


def _replay_dofs(
    model: SwimmerModel, d0: np.ndarray, actions: Sequence[tuple[int, float]], roc_levels: int = 1
) -> np.ndarray:
    """DOF values after each action; on the K-level lattice (``roc_levels`` K) a recorded ROC ``k``
    is ``k / K`` of the range."""
    out = [d0.copy()]
    d = d0.copy()
    span = (model.hi - model.lo) / max(1, roc_levels)
    for dof, roc in actions:
        if 1 <= dof <= d.size and roc:
            d[dof - 1] = min(model.hi, max(model.lo, d[dof - 1] + float(roc) * span))
        out.append(d.copy())
    return np.asarray(out)


def _roc(v: Any) -> float:
    """A recorded ROC: an int for the paper's {-1, 0, 1}, a float for real-valued ones."""
    f = float(v)
    return int(f) if f.is_integer() else f


def _floats(seq: Any, n: int) -> np.ndarray | None:
    if not isinstance(seq, list) or len(seq) < n or any(v is None for v in seq[:n]):
        return None
    return np.asarray(seq[:n], np.float64)


def track(row: Mapping[str, Any], transcript: Sequence[Mapping[str, Any]] | None = None) -> Track:
    """The `Track` of one run from its row and (LLM runs) its transcript records.

    Parameters
    ----------
    row : mapping
        A run record as in ``runs.jsonl`` ([`jswim.results.read_runs`][jswim.results.read_runs]).
    transcript : sequence of mapping, optional
        The records of ``transcripts/RUN.jsonl`` ([`jswim.results.read_transcript`][jswim.results.read_transcript]); its
        ``meta`` record gives the start levels, its ``step`` records the DOF values and replies.
    """
    r0 = as_run_row(
        row
    )  # typed reads; Track.row stays a plain dict (animate labels it with the model)
    row = dict(row)
    recs = list(transcript or [])
    meta = next((r for r in recs if r.get("type") == "meta"), {})
    steps_log = [r for r in recs if r.get("type") == "step"]
    xs = [float(v) for v in (r0.x or [])]
    n = len(xs)
    actions = [(int(a[0]), _roc(a[1])) for a in (r0.actions or [])[:n]]
    while len(actions) < n:
        actions.append((1, 0))
    # DOF values: the row's own, the transcript's, or replayed from the start shape.
    dofs = r0.other.get("dofs")  # not a RunRow column: rows of hand-made or other tools' folders
    levels0 = _levels(meta.get("levels0")) or _levels(r0.init)
    n_dof = (
        (len(dofs[0]) if isinstance(dofs, list) and dofs and isinstance(dofs[0], list) else None)
        or (len(levels0) if levels0 else None)
        or max((a[0] for a in actions), default=2)
    )
    world = world_of(r0)
    n_sw = world.n_swimmers
    if n_sw > 1 and n_dof is not None and not levels0:
        n_dof = -(
            -n_dof // n_sw
        )  # the actions name joint DOFs: D1..D4 for a pair of 2-DOF swimmers
    model = model_of(r0, n_dof)
    if levels0 is None:
        levels0 = [1.0] * model.n_dof
    d0 = np.array([model.lo + (model.hi - model.lo) * v for v in levels0], np.float64)
    if n_sw > 1 and d0.size == model.n_dof:
        d0 = np.tile(d0, n_sw)  # every swimmer starts from the same shape (the scene's rule)
    if isinstance(dofs, list) and len(dofs) >= n and dofs and isinstance(dofs[0], list):
        arr = np.asarray(dofs, np.float64)
        d = np.concatenate([d0[None], arr[-n:]]) if len(arr) == n else arr[: n + 1]
    elif len(steps_log) >= n and all(isinstance(s.get("dofs_after"), list) for s in steps_log[:n]):
        d = np.concatenate(
            [d0[None], np.asarray([s["dofs_after"] for s in steps_log[:n]], np.float64)]
        )
    else:
        d = _replay_dofs(model, d0, actions, int(r0.roc_levels or 1))
    theta0 = start_theta(model, d0)
    ys, th = _floats(r0.y, n), _floats(r0.orientation, n)
    replayed = False
    if n and (ys is None or th is None):
        ys2, th2 = _replay_pose(r0, model, levels0, actions)
        replayed = True
        ys = ys if ys is not None else ys2
        th = th if th is not None else th2
    x = np.concatenate([[0.0], xs])
    side = bool(r0.scene) and not worlds.from_above(r0)  # a scene drawn in its vertical plane
    y0 = world.start[0][1] if side else 0.0  # a scene's step 0 is at its start height
    if side:
        theta0 = world.start[0][2]
    y = np.concatenate([[y0], ys if ys is not None else np.full(n, y0)])
    theta = np.concatenate([[theta0], th if th is not None else np.full(n, theta0)])
    if side:
        bodies, positions = _scene_bodies(r0, world, model, d, n)
        pts = bodies[:, 0]
    else:
        pts = place(outline(model, d), x, y, theta)
        bodies, positions = pts[:, None], np.stack([x, y], axis=-1)[:, None]
    stuck = np.abs(np.diff(x)) < STUCK_TOL
    if isinstance(r0.stuck, list) and len(r0.stuck) >= n:
        stuck = np.asarray([bool(v) for v in r0.stuck[:n]])
    cleared = np.zeros(n, bool)
    failed = np.zeros(n, bool)
    replies: list[str | None] = [None] * n
    for i, s in enumerate(steps_log[:n]):
        cleared[i] = bool(s.get("cleared"))
        failed[i] = bool(s.get("failed"))
        if "stuck" in s:
            stuck[i] = bool(s["stuck"])
        attempts = s.get("attempts") or []
        replies[i] = str(attempts[-1].get("text", "")) if attempts else None
    stroke = None
    stl = r0.steps_to_learn
    learned = (
        r0.success if r0.learned is None else r0.learned
    )  # rows from before ``learned``: success
    if learned and isinstance(stl, (int, float)) and r0.period:
        stroke = (int(stl) - 1, int(r0.period))
    return Track(
        run_id=str(r0.run_id or ""),
        agent=str(r0.agent or ""),
        swimmer=str(r0.swimmer or ""),
        model=model,
        direction=int(r0.direction or 1),
        x=x,
        y=y,
        theta=theta,
        dofs=d,
        points=pts,
        actions=actions,
        stuck=stuck,
        cleared=cleared,
        failed=failed,
        replies=replies,
        stroke=stroke,
        success=bool(r0.success),
        replayed=replayed,
        row=row,
        steps_log=steps_log,
        world=world,
        bodies=bodies,
        positions=positions,
    )


def _scene_bodies(
    row: Mapping[str, Any], world: World, model: SwimmerModel, d: np.ndarray, n: int
) -> tuple[np.ndarray, np.ndarray]:
    """Every swimmer of a scene run, (N + 1, S, P, 2), and their middle spheres, (N + 1, S, 2).

    A scene records per step and swimmer the x displacement from its start (``xs``), the middle
    sphere's height (``heights``) and the axis tilt (``tilts``); step 0 is the world's start pose.
    """
    s_n = world.n_swimmers
    start = np.asarray(world.start, np.float64)  # (S, 3)
    row = as_run_row(row)
    dx = per_swimmer(row, "xs", n, s_n)
    if dx is None:
        dx = np.repeat(np.asarray(row.x or [0.0] * n, np.float64)[:n, None], s_n, axis=1)
    hz = per_swimmer(row, "heights", n, s_n)
    if hz is None:
        hz = np.repeat(np.asarray(row.y or [start[0, 1]] * n, np.float64)[:n, None], s_n, axis=1)
    tl = per_swimmer(row, "tilts", n, s_n)
    if tl is None:
        tl = np.repeat(start[None, :, 2], n, axis=0)
    px = start[None, :, 0] + np.concatenate([np.zeros((1, s_n)), dx])
    pz = np.concatenate([start[None, :, 1], hz])
    pt = np.concatenate([start[None, :, 2], tl])
    k = model.n_dof
    bodies = []
    for s in range(s_n):
        shape = outline(model, d[:, s * k : (s + 1) * k] if d.shape[1] >= (s + 1) * k else d[:, :k])
        if (
            isinstance(model, SwimmerModel) and not model.planar
        ):  # a scene places the middle sphere (not the centroid) at its position
            shape = shape - shape[..., 1:2, :]
        bodies.append(place(shape, px[:, s], pz[:, s], pt[:, s]))
    return np.stack(bodies, axis=1), np.stack([px, pz], axis=-1)


def _replay_pose(
    row: Mapping[str, Any],
    model: SwimmerModel,
    levels0: Sequence[float],
    actions: Sequence[tuple[int, float]],
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """``y`` and orientation after each step from a noiseless replay (folders that lack them)."""
    if not model.planar:
        n = len(actions)
        return np.zeros(n), np.zeros(n)
    try:
        from jswim import env  # lazy: JAX only for folders written before the pose was recorded

        if any(float(r) not in (-1.0, 0.0, 1.0) for _, r in actions) or any(
            v not in (0.0, 1.0) for v in levels0
        ):
            return None, None
        row = as_run_row(row)
        r = env.rollout_moves(
            str(row.swimmer),
            [(int(a), int(b)) for a, b in actions],
            init=[int(v) for v in levels0],
            direction=int(row.direction or 1),
        )
        return np.asarray(r.y, np.float64), np.asarray(r.orientation, np.float64)
    except Exception:  # an unknown swimmer or an API that moved: no pose, not a broken page
        return None, None


def view_box(tracks: Sequence[Track], pad: float = 1.5) -> tuple[float, float, float, float]:
    """``(xmin, xmax, ymin, ymax)`` holding every body of every swimmer of ``tracks`` at every step,
    the wall and the obstacles, with ``pad`` (`jswim.viz.worlds.view_box`)."""

    return worlds.view_box(
        [t.bodies for t in tracks],
        [t.world for t in tracks],
        bool(tracks) and not tracks[0].model.planar,
        pad,
    )


def fmt_action(action: tuple[int, float]) -> str:
    """``[DOF, ROC]`` as in the prompt (integers stay integers)."""
    dof, roc = action
    r = int(roc) if float(roc).is_integer() else roc
    return f"[{dof}, {r:g}]" if isinstance(r, float) else f"[{dof}, {r}]"
