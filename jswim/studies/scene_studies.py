"""The scene studies (extensions of the paper): ``jswim study wall`` and ``jswim study pair``.

``wall``
    One NG swimmer started at each height ``h`` of ``--heights`` (a, the middle sphere's height
    above a no-slip wall; medium ``"wall"``) and each tilt of ``--tilts`` whose start clears the
    wall (rad, nose up; default level and 0.8, the nose-up start that escapes within the default
    horizon from 10 a; `jswim.studies.scene_grids.wall_groups`): the signature square stroke (agent ``stroke``), the
    LLM, Q-learning on (shape, height bin), the random policy and PPO (real ROCs). Measured: the stroke's
    displacement per cycle against ``h`` (next to the same stroke in the unbounded fluid of the
    same solver, medium ``"free"``: group ``free``), and every run's **fate** (`fate`).
    ``--swimmer purcell``: Purcell's swimmer in a plane ``h`` link lengths above the
    wall runs the same five agents per height (next to the paper's bulk fluid, group ``bulk``),
    judged by the paper's criterion on its D1/D2 moves; its height is fixed, so every fate is
    ``gliding`` at ``h``. A registered world ([`jswim.register_world`][jswim.env.registry.register_world]) runs them too, unjudged.
``pair``
    Two coaxial NG swimmers started ``D`` apart (``--separations``; medium ``"free"``: the
    point-force solve, in which the swimmers feel each other; the paper's formula has no
    interaction). Measured: two copies of the square stroke at each phase offset
    (``--phases``, quarter cycles of swimmer 2 ahead of swimmer 1), the lone swimmer's stroke in
    the same medium (group ``alone``), and whether the LLM, Q-learning, the random policy or PPO
    steering both (joint DOFs D1..D4) find a faster joint stroke.

Runs, rows, resume, figures, ``show`` and ``compare`` are the study folder's
([`jswim.studies.run`][jswim.studies.run]), and every run goes the one way of every study
([`baselines`][jswim.studies.baselines]: ``make``, the learner's one entry point, one row
builder); this module gives the scene's strokes, its judge of lattice moves per swimmer, its
columns (read from the runs' trace through the protocol: positions,
`height` and orientation, the step's stuck and contact) and
its summary table.

PPO's rows (agent ``ppo``, an extension): the continuous study's learner (same network,
[`PPOConfig`][jswim.agents.ppo.PPOConfig] and temperature) with the other scene agents' task and budget
(``--steps``, ``--q-runs`` learners per cell and direction, ``--noise`` the scene's); it moves one
arm of one swimmer per step by a real ROC (for a pair it steers both). Success is the study's
criterion in its real-valued form ([`evaluate_swimmers`][jswim.agents.ppo_judge.evaluate_swimmers]: the shape judge on
each swimmer's own moves, with the bulk swimmer's noiseless displacements; a pair succeeds when
both swimmers' own move sequences do); wall runs get their fate from the heights and contacts the
training run recorded; the moves are ``[dof, real ROC]``.
"""

from __future__ import annotations

import json
from typing import Any
from collections.abc import Sequence

import numpy as np

from jswim import env
from jswim.action_codes import decode_action, encode_action, n_actions
from jswim.console import Column
from jswim.env.base import Environment
from jswim.env.scene_world import ARMS
from jswim.judging.gait import Criterion, judge
from jswim.scenes import Scene
from jswim.swimmers.models import SWIMMERS
from jswim.results.row import RunRow, as_run_rows
from jswim.studies.rows import build_row, signs
from jswim.studies.options import STROKE_AGENT
from jswim.studies.plans import Plan


def square(start: Sequence[int], direction: int) -> tuple[int, int, int, int]:
    """The square stroke of a swimmer's first two DOFs from their start corner ``start`` (0 = lo,
    1 = hi), as codes ``(dof - 1) * 3 + roc + 1``: toward +x D2 to its other limit, D1 to its
    other limit, D2 back, D1 back; toward -x its time reverse (Purcell's from (+, +): D2 down, D1
    down, D2 up, D1 up; NG's from (10, 6): D2 up, D1 down, D2 down, D1 up)."""
    flip = [1 - 2 * int(v) for v in start[:2]]  # the ROC that leaves each DOF's start limit
    moves = (
        ((2, flip[1]), (1, flip[0]), (2, -flip[1]), (1, -flip[0]))
        if direction > 0
        else ((1, flip[0]), (2, flip[1]), (1, -flip[0]), (2, -flip[1]))
    )
    return tuple(int(encode_action(d, r)) for d, r in moves)


#: The fate rule's thresholds (`fate`), in sphere radii.
TRAP_HEIGHT = 1.5  # the middle sphere within half a radius of the wall
ESCAPE_FACTOR = 2.0  # at twice the starting height or more

FATES = ("trapped", "escaped", "gliding")


# -- fates ---------------------------------------------------------------------------------------


def fate(
    heights: Sequence[float], h0: float, contact: Sequence[bool] | None = None
) -> tuple[str, float]:
    """A wall run's fate from its height after each step (a, swimmer 1's middle sphere) and start.

    Over the run's second half (the last ``ceil(T / 2)`` steps):

    - ``trapped``: a sphere touched the wall (``contact``) or the height fell below
      `TRAP_HEIGHT`;
    - ``escaped``: the final height is at least `ESCAPE_FACTOR` times the start (a rise alone
      is not enough: from tilt 0 at 2.5-10 a the NG swimmer glides on orbits of ~800-900 square
      cycles whose rising limb lasts hundreds of cycles; docs/scenes.md, "Fates above the wall");
    - ``gliding`` otherwise, at the mean height of the second half (returned; for every fate).

    Returns
    -------
    (fate, mean_height)
    """
    h = np.asarray(heights, np.float64)
    if h.size == 0:
        return "gliding", float(h0)
    late = h[h.size // 2 :]
    touched = contact is not None and bool(np.any(np.asarray(contact, bool)[h.size // 2 :]))
    mean = float(late.mean())
    if touched or late.min() < TRAP_HEIGHT:
        return "trapped", mean
    if h[-1] >= ESCAPE_FACTOR * h0:
        return "escaped", mean
    return "gliding", mean


# -- strokes -------------------------------------------------------------------------------------


def stroke_codes(
    variant: str,
    direction: int,
    steps: int,
    swimmers: int,
    start: Sequence[int] = (1, 0),
    width: int = n_actions(ARMS),
) -> np.ndarray:
    """The joint codes of a stroke plan: ``"square"`` (swimmer 1 alone; the lone `square` gait
    from its start corner ``start``, default NG's (10, 6)), or ``"phase<p>"`` for a pair: swimmer
    2 first makes ``p`` moves of its square (so it runs ``p`` quarter cycles ahead), then the two
    alternate, one move each, swimmer 1 first. Swimmer ``s``'s codes are swimmer 1's plus
    ``s * width`` (its DOFs' codes: 6 for two DOFs)."""
    sq = square(start, direction)
    if swimmers == 1:
        return np.array([sq[t % 4] for t in range(steps)], np.int32)
    if swimmers > 2:  # a school ("phase0"): every swimmer in turn makes the same move of its square
        t = np.arange(steps)
        return (np.asarray(sq)[(t // swimmers) % 4] + width * (t % swimmers)).astype(np.int32)
    ph = int(variant.removeprefix("phase"))
    b = [c + width for c in sq]
    seq = [b[j] for j in range(ph)]
    j = 0
    while len(seq) < steps:
        seq += [sq[j % 4], b[(j + ph) % 4]]
        j += 1
    return np.array(seq[:steps], np.int32)


def per_cycle(x: Sequence[float], variant: str, swimmers: int) -> float | None:
    """A stroke run's displacement per stroke cycle (a): over its complete cycles after the
    warm-up (a pair's cycle is 8 steps, one square of each swimmer; its ``x`` is their mean)."""
    x = np.concatenate([[0.0], np.asarray(x, np.float64)])
    warm = (
        int(variant.removeprefix("phase")) if swimmers == 2 and variant.startswith("phase") else 0
    )
    period = 4 * swimmers
    n = (x.size - 1 - warm) // period
    if n < 1:
        return None
    return float((x[warm + n * period] - x[warm]) / n)


def late_speed(x: Sequence[float], direction: int, swimmers: int) -> float | None:
    """Mean progress per step (a, target direction) over the run's second half, cut to whole
    stroke cycles of ``4 * swimmers`` steps: a single NG move goes about +-1 a while a cycle nets
    0.17 a, so a window with a partial cycle would measure the partial cycle. Comparable across
    agents: a stroke's value is its displacement per cycle over the cycle's length."""
    x = np.concatenate([[0.0], np.asarray(x, np.float64)])
    period = 4 * swimmers
    n = (x.size - 1) // 2 // period * period
    if n < period:
        n = (x.size - 1) // period * period
    if n < 1:
        return None
    return float(direction * (x[-1] - x[-1 - n]) / n)


# -- rows ----------------------------------------------------------------------------------------


def ppo_judged(
    run: Any, plans: Sequence[Plan], world: Environment, task: Any, horizon: int
) -> list[dict[str, Any] | None]:
    """PPO's verdicts per plan, as `_judge` judges lattice moves: the shape judge per swimmer,
    through the world's judge's view ([`evaluate_swimmers`][jswim.agents.ppo_judge.evaluate_swimmers]:
    each swimmer's moves replayed in the paper's bulk world); a registered world unjudged
    (`_unjudged`)."""
    from jswim.agents import ppo  # lazy: start-up (optax's PPO, for PPO runs only)

    unjudged = [_unjudged(p) for p in plans]
    if unjudged[0] is not None:
        return unjudged
    rep = ppo.evaluate_swimmers(
        run,
        world.judge_view(task),
        [p.direction for p in plans],
        criterion=Criterion(horizon=horizon),
    )
    return [
        {
            "success": bool(rep.success[i]),
            "learned": bool(rep.learned[i]),
            "steps_to_learn": int(rep.steps_to_learn[i]) if rep.learned[i] else None,
            # a pair's period is 0, as the lattice judge of the pair rows gives it
            "period": int(rep.period[i]) if world.n_swimmers == 1 else 0,
        }
        for i in range(len(plans))
    ]


def _unjudged(plan: Plan) -> dict[str, Any] | None:
    """``None`` for the paper's swimmers (`scene_row` judges them); a registered world's run
    is not judged (the criterion's threshold is the paper swimmer's best stroke): ``None`` verdicts."""
    if plan.swimmer in SWIMMERS:
        return None
    return {"success": None, "learned": None, "steps_to_learn": None, "period": 0}


def _judge(codes: Sequence[int], plan: Plan, swimmers: int, horizon: int) -> dict[str, Any]:
    """The paper's success criterion ([`jswim.judging.gait.judge`][jswim.judging.gait.judge], bulk displacements) on each
    swimmer's own moves: one swimmer as in the bulk studies; a pair succeeds when both
    swimmers' move sequences do (each judged on its own moves, with the same horizon)."""
    params = env.make_params(plan.swimmer, direction=plan.direction, init=plan.init)
    codes = np.asarray(codes, np.int64)
    per = []
    for s in range(swimmers):
        own = codes[(decode_action(codes)[0] - 1) // ARMS == s] - n_actions(ARMS) * s
        if own.size < 4:
            per.append(None)
            continue
        rep = judge(own[None], params, criterion=Criterion(horizon=horizon))
        per.append(rep)
    ok = all(r is not None and bool(r.success[0]) for r in per)
    learned = all(r is not None and bool(r.learned[0]) for r in per)
    stl = [int(r.steps_to_learn[0]) for r in per if r is not None and r.learned[0]]
    return {
        "success": ok,
        "learned": learned,
        "steps_to_learn": (max(stl) if learned and stl else None),
        "period": int(per[0].period[0]) if swimmers == 1 and per[0] is not None else 0,
    }


def scene_row(
    plan: Plan,
    codes: list[int],
    x: list[float],
    extra: dict[str, Any],
    horizon: int,
    *,
    z0: np.ndarray,
    tilt0: np.ndarray,
    judged: dict[str, Any] | None = None,
    moves: list[list[float]] | None = None,
    plane_height: float | None = None,
) -> RunRow:
    """One row of a scene run ([`jswim.studies.rows.build_row`][jswim.studies.rows.build_row]): the bulk studies' columns
    (success by `_judge` on the lattice ``codes``, or the real-valued agent's own verdict
    ``judged`` and ``moves``; a registered world's runs unjudged, `_unjudged`) and the scene's: the scene, its medium, start height or distance,
    the per-step tracks ``extra`` holds (``xs``, ``heights``, ``tilts``, ``contact``, ``stuck``),
    ``fate``, ``mean_height``, ``speed`` (`late_speed`), for strokes ``per_cycle``, and the
    world's ``plane_height`` ([`Scenery`][jswim.env.base.Scenery]: how its pictures are drawn).
    ``y`` and ``orientation`` of the trajectories table are swimmer 1's height and tilt."""
    scene = Scene.from_dict(json.loads(plan.scene))
    wall = scene.medium == "wall"
    sw = scene.swimmers
    h1 = [float(h[0]) for h in extra.get("heights") or []]
    f, mean_h = (
        fate(h1, float(z0[0]), [bool(c) for c in extra.get("contact") or []])
        if wall
        else (None, None)
    )
    return build_row(
        plan,
        x,
        moves if moves is not None else [list(decode_action(int(c))) for c in codes],
        judged if judged is not None else _unjudged(plan) or _judge(codes, plan, sw, horizon),
        init=signs(plan.init) if not isinstance(plan.init, str) else plan.init,
        scene=plan.scene,
        medium=scene.medium,
        n_swimmers=sw,
        start_height=float(z0[0]) if wall else None,
        separation=float(scene.separation) if sw > 1 else None,
        fate=f,
        mean_height=mean_h,
        speed=late_speed(x, plan.direction, sw),
        per_cycle=per_cycle(x, plan.variant, sw) if plan.agent == STROKE_AGENT else None,
        plane_height=plane_height,
        y=h1 or [float(z0[0])] * len(x),
        orientation=[float(t[0]) for t in extra.get("tilts") or []] or [float(tilt0[0])] * len(x),
        **{k: extra.get(k) for k in ("xs", "heights", "tilts", "contact", "stuck")},
    )


def scene_summary(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per (agent, group) of a scene study: runs, mean displacement per cycle (strokes), mean
    speed per step over the second half (both in the target direction), the fates seen and the mean height of the second half,
    and ``vs_stroke``: that mean speed over the best square stroke's in the same scene and
    direction (a wall: the stroke from that height and tilt; a pair: the fastest phase offset at that D), so
    above 1 is a faster stroke than the square one (for a pair, than two copies of it)."""
    rows = as_run_rows(rows)
    out: dict[tuple, list[dict[str, Any]]] = {}
    for r in rows:
        if r.scene:
            out.setdefault((r.agent, r.direction, r.group), []).append(r)
    table = []
    for (agent, d, group), g in out.items():
        fates = [r.fate for r in g if r.fate]
        # in the target direction, as speed, the figures and the main table's X/a end (a row's own
        # per_cycle is the signed x)
        pc = [(d or 1) * r.per_cycle for r in g if r.per_cycle is not None]
        hs = [r.mean_height for r in g if r.mean_height is not None]
        sp = [r.speed for r in g if r.speed is not None]
        table.append(
            {
                "agent": agent,
                "direction": d,
                "group": group,
                "n": len(g),
                "per_cycle": float(np.mean(pc)) if pc else None,
                "speed": float(np.mean(sp)) if sp else None,
                "fates": ", ".join(f"{f} {fates.count(f)}" for f in FATES if f in fates) or None,
                "mean_height": float(np.mean(hs)) if hs else None,
                "start_height": g[0].start_height,
                "start_tilt": start_tilt(g[0].scene),
                "separation": g[0].separation,
                "medium": g[0].medium,
            }
        )
    best: dict[tuple, float] = {}
    for t in table:
        if t["agent"] == STROKE_AGENT and t["speed"] is not None:
            k = _scene_key(t)
            best[k] = max(best.get(k, -np.inf), t["speed"])
    for t in table:
        b = best.get(_scene_key(t))
        t["vs_stroke"] = (
            t["speed"] / b if t["speed"] is not None and b is not None and b > 0 else None
        )
    return table


def _scene_key(t: dict[str, Any]) -> tuple:
    return (
        t.get("direction"),
        t.get("medium"),
        t.get("start_height"),
        t.get("start_tilt"),
        t.get("separation"),
    )


def start_tilt(scene: str | None) -> float | None:
    """A wall run's start tilt (rad, nose up) from its scene's canonical JSON; ``None`` off the wall."""
    if not scene:
        return None
    data = json.loads(scene)
    return float(data.get("tilt", 0.0)) if data.get("medium") == "wall" else None


#: What each of `table`'s measured columns means (`columns_note` lists those a table shows).
_COLUMN_NOTES = {
    "X/a per cycle": "X/a per cycle and per step: in the target direction",
    "fates": "fates: trapped, escaped or gliding (the wall study's rule)",
    "mean height": "mean height: the middle sphere over the second half, in a",
    "x stroke": "x stroke: speed over the best square stroke's in the same scene",
}
#: Columns that only a scene above a wall fills (a pair's or school's rows leave them out).
_WALL_COLUMNS = ("fates", "mean height")


def columns_note(cols: Sequence[Any]) -> str:
    """The line under `table` that says what its columns are, naming only those it shows."""
    headers = {c.header for c in cols}
    return "; ".join(t for h, t in _COLUMN_NOTES.items() if h in headers) + "."


def table(summary: Sequence[dict[str, Any]]) -> tuple[list[Any], list[list[str]]]:
    """Columns and cells of `scene_summary` for ``jswim study``'s output, ``jswim show`` and the
    report page. The wall's columns (fates, mean height) appear only when some row is above a
    wall."""

    def fmt(v: Any, spec: str) -> str:
        return "-" if v is None else format(v, spec)

    cols = [
        Column("agent", False),
        Column("dir", False),
        Column("group", False),
        Column("medium", False),
        Column("n"),
        Column("X/a per cycle"),
        Column("X/a per step"),
        Column("fates", False),
        Column("mean height"),
        Column("x stroke"),
    ]
    order = sorted(
        summary,
        key=lambda s: (
            s.get("separation") or 0.0,
            s.get("start_height") or 0.0,
            s.get("start_tilt") or 0.0,
            str(s["group"]),
            str(s["agent"]),
        ),
    )
    body = [
        [
            str(s["agent"]),
            "+x" if (s.get("direction") or 1) > 0 else "-x",
            str(s["group"]),
            str(s.get("medium") or ""),
            str(s["n"]),
            fmt(s.get("per_cycle"), ".5f"),
            fmt(s.get("speed"), ".5f"),
            s.get("fates") or "-",
            fmt(s.get("mean_height"), ".2f"),
            fmt(s.get("vs_stroke"), ".3f"),
        ]
        for s in order
    ]
    if not any(s.get("fates") or s.get("mean_height") is not None for s in summary):
        keep = [i for i, c in enumerate(cols) if c.header not in _WALL_COLUMNS]
        cols = [cols[i] for i in keep]
        body = [[row[i] for i in keep] for row in body]
    return cols, body


def table_note(summary: Sequence[dict[str, Any]]) -> str | None:
    """A line under `table` when some speeds are blank: the runs hold no whole stroke cycle."""
    if all(t.get("speed") is not None for t in summary):
        return None
    return (
        "-: no whole stroke cycle in the run (4 steps alone, 8 for a pair, after a phase's warm-up moves): "
        "no X/a per cycle, X/a per step or x stroke; give more --steps"
    )
