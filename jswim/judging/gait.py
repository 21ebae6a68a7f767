"""Gait detection: the one success criterion shared by the LLM runs and the Q-learning baseline.

A run has *learned to swim* from step ``s`` when its executed actions from ``s`` to the end of the
run repeat one *qualifying cycle*, at least ``n_cycles`` (3) times in a row. A cycle of period
``p`` qualifies when

- every one of its ``p`` moves changes the shape (no ROC 0, no move pushed against a limit),
- it brings the shape back to where it started (a closed loop in DOF space), and
- every complete period of the segment moves the swimmer, exactly and without noise, by at least
  ``min_fraction`` (1/2) of the best displacement per step any closed cycle of length
  ``<= max_period`` achieves in the target direction.

What the paper's success adds (the horizon), how steps to learn are counted, how the stroke is
found and how displacements are replayed: docs/baselines.md, "The success criterion". The
numbers have one owner, [`Criterion`][jswim.judging.gait.Criterion].
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
from typing import Any, NamedTuple

import numpy as np

from jswim.env import EnvParams, decode_action, encode_action, start_orientation, step_table
from jswim.errors import ConfigError, check_direction
from jswim.swimmers.models import SwimmerModel
from jswim.judging import lattice

#: Displacements within this relative margin of the threshold count as reaching it (float64
#: composition of the same table entries in a different order differs in the last bits).
REL_TOL = 1e-9

#: Largest number of (DOF sequence, start corner) pairs [`best_cycles`][jswim.judging.gait.best_cycles] will enumerate.
_MAX_WALKS = 4_000_000


@dataclasses.dataclass(frozen=True)
class Cycle:
    """A closed cycle of shape-changing moves.

    Attributes
    ----------
    actions : tuple of int
        Action indices (see [`jswim.env.encode_action`][jswim.action_codes.encode_action]), one per step.
    start : tuple of int
        DOF levels (0 = lo, 1 = hi) the cycle starts from.
    displacement : float
        Displacement per period in the target direction, starting from orientation 0.
    rotation : float
        Net change of orientation per period (0 for the paper's swimmers).
    """

    actions: tuple[int, ...]
    start: tuple[int, ...]
    displacement: float
    rotation: float

    @property
    def period(self) -> int:
        return len(self.actions)

    @property
    def per_step(self) -> float:
        """Displacement per step in the target direction."""
        return self.displacement / self.period

    @property
    def moves(self) -> tuple[tuple[int, int], ...]:
        """The cycle as ``(dof, roc)`` pairs, ``dof`` 1-based as in the prompt."""
        return tuple(decode_action(a) for a in self.actions)

    @property
    def simple(self) -> bool:
        """No shape is visited twice within a period.

        A cycle that is not simple is a simple one with detours (e.g. a DOF moved out and straight
        back): without net rotation the detours add steps but no displacement.
        """
        levels = list(self.start)
        seen = {tuple(levels)}
        for dof, roc in self.moves:
            levels[dof - 1] = 1 if roc > 0 else 0
            seen.add(tuple(levels))
        return len(seen) == self.period


@dataclasses.dataclass(frozen=True)
class Criterion:
    """The success criterion's numbers; the one place they are written (paper's values default).

    Attributes
    ----------
    horizon : int
        Steps within which ``n_cycles`` cycles must be complete for ``success`` (paper: 50).
    n_cycles : int
        Consecutive repetitions of the qualifying cycle required (paper: 3).
    min_fraction : float
        Fraction of the best closed cycle's displacement per step that a cycle must reach to
        qualify (the speed threshold; 1/2).
    max_period : int or None
        Longest cycle considered; ``None``: [`default_max_period`][jswim.judging.gait.default_max_period] of the swimmer.

    Raises
    ------
    ConfigError
        For ``horizon``, ``n_cycles`` or ``max_period`` below 1, or ``min_fraction <= 0``.
    """

    horizon: int = 50
    n_cycles: int = 3
    min_fraction: float = 0.5
    max_period: int | None = None

    def __post_init__(self) -> None:
        if (
            self.horizon < 1
            or self.n_cycles < 1
            or (self.max_period is not None and self.max_period < 1)
        ):
            raise ConfigError("horizon, n_cycles and max_period must be >= 1")
        if not self.min_fraction > 0:
            raise ConfigError(f"min_fraction must be > 0, got {self.min_fraction}")

    def describe(self, steps: int | None = None) -> str:
        """One line for run metadata; ``steps``, the runs' length, is said where it is shorter
        than the horizon (the cycles must then be complete within the run)."""
        within = f"within {self.horizon} steps"
        if steps is not None and steps < self.horizon:
            within += f" (these runs have {steps})"
        return (
            f"{self.n_cycles} consecutive qualifying cycles (>= {self.min_fraction:g} of the best cycle's "
            f"speed) {within}, no later failure (jswim.judging.gait.judge)"
        )


#: The paper's criterion.
PAPER = Criterion()


class GaitReport(NamedTuple):
    """Verdict on a batch of runs (leading axis: runs).

    Attributes
    ----------
    learned : bool (B,)
        The run ends in at least ``n_cycles`` repetitions of a qualifying cycle.
    steps_to_learn : int (B,)
        The step, counted from 1 as in the paper, at which that final stroke starts (1: from the
        first action), or -1 when not learned.
    success : bool (B,)
        ``learned`` and the first ``n_cycles`` cycles are complete by step ``horizon``.
    period : int (B,)
        Period of the detected cycle (0 when not learned).
    cycle : int (B, max_period)
        The detected cycle's actions from its first step, padded with -1.
    per_step : float (B,)
        Exact displacement per step, in the target direction, of the stroke's first period (NaN
        when not learned).
    fraction : float (B,)
        ``per_step`` over the best cycle's displacement per step.
    stroke_start : int (B,)
        0-based index of the stroke's first action (``steps_to_learn - 1``), or -1.
    """

    learned: np.ndarray
    steps_to_learn: np.ndarray
    success: np.ndarray
    period: np.ndarray
    cycle: np.ndarray
    per_step: np.ndarray
    fraction: np.ndarray
    stroke_start: np.ndarray


def default_max_period(n_dof: int, roc_levels: int = 1) -> int:
    """Longest cycle considered: ``2**n_dof``, the longest cycle visiting each corner once, times
    ``K`` on a ``K``-level ROC lattice (the square gait walked in steps of ``1/K`` of the range).

    Without rotation a closed walk's displacement is the sum over the simple cycles it decomposes
    into, so no longer walk beats the best simple cycle per step; for two DOFs this is the square
    gait's 4 (``4 K`` on the lattice: the full square's perimeter in its smallest steps).
    """
    return 2**n_dof * roc_levels


@functools.lru_cache(maxsize=64)
def best_cycles(
    model: SwimmerModel, direction: int = 1, max_len: int | None = None
) -> tuple[Cycle, ...]:
    """Every closed cycle of shape-changing moves up to ``max_len`` steps, best first.

    Parameters
    ----------
    model : SwimmerModel
        The swimmer (``params.model``).
    direction : int
        +1 or -1: the target direction the displacement is measured in.
    max_len : int, optional
        Longest period (default [`default_max_period`][jswim.judging.gait.default_max_period]).

    Returns
    -------
    tuple of Cycle
        One entry per cycle up to cyclic shifts, each shown from the shift that goes furthest from
        orientation 0; repetitions of a shorter cycle are left out. Ranked by displacement per
        step, then by shorter period.

    Examples
    --------
    >>> from jswim.env import make_params
    >>> best = best_cycles(make_params("ng").model, +1)[0]
    >>> best.period, round(best.displacement, 6)
    (4, 0.156265)
    """
    n = model.n_dof
    max_len = default_max_period(n) if max_len is None else int(max_len)
    check_direction(direction)
    if max_len < 1:
        raise ConfigError(f"max_len must be >= 1, got {max_len}")
    if sum(n**length for length in range(2, max_len + 1, 2)) * 2**n > _MAX_WALKS:
        raise ConfigError(
            f"too many walks to enumerate for {n} DOFs up to length {max_len}; lower max_len"
        )
    table = step_table(model)[0].astype(np.float64)
    found: list[Cycle] = []
    for length in range(2, max_len + 1, 2):  # a closed walk flips every DOF an even number of times
        seqs = np.array(list(itertools.product(range(n), repeat=length)), np.int64).reshape(
            -1, length
        )
        seqs = seqs[_closed(seqs, n) & _primitive(seqs, n)]
        if not seqs.size:
            continue
        # Every (start corner, DOF sequence); a cycle is the class of its cyclic shifts, keyed by
        # the smallest code of (corner, sequence) over the shifts.
        c0 = np.repeat(np.arange(2**n), seqs.shape[0])
        seq = np.tile(seqs, (2**n, 1))
        corners, disp, rot = _walk(table, seq, c0)
        weights = n ** np.arange(length - 1, -1, -1)
        codes = [
            corners[:, k] * n**length + np.roll(seq, -k, axis=1) @ weights for k in range(length)
        ]
        key = np.min(np.stack(codes, 1), axis=1)
        value = direction * disp
        order = np.lexsort((-value, key))  # per class, the shift that goes furthest comes first
        first = order[np.r_[True, key[order][1:] != key[order][:-1]]]
        for row in first:
            levels = (int(c0[row]) >> np.arange(n)) & 1
            start = tuple(int(v) for v in levels)
            actions = []
            for k in seq[row]:
                actions.append(encode_action(int(k) + 1, 1 if levels[k] == 0 else -1))
                levels[k] ^= 1
            found.append(Cycle(tuple(actions), start, float(value[row]), float(rot[row])))
    return tuple(sorted(found, key=lambda c: (-c.per_step, c.period, c.actions)))


def best_per_step(model: SwimmerModel, direction: int = 1, max_len: int | None = None) -> float:
    """Best displacement per step in the target direction over closed cycles up to ``max_len``."""
    return best_cycles(model, direction, max_len)[0].per_step


def _closed(seqs: np.ndarray, n: int) -> np.ndarray:
    """DOF sequences that flip every DOF an even number of times (closed loops)."""
    return np.all(np.stack([(seqs == k).sum(1) % 2 == 0 for k in range(n)]), axis=0)


def _primitive(seqs: np.ndarray, n: int) -> np.ndarray:
    """Closed DOF sequences that are not a closed block repeated (e.g. the square gait twice)."""
    length = seqs.shape[1]
    keep = np.ones(seqs.shape[0], bool)
    for q in range(1, length):
        if length % q == 0:
            repeats = np.all(seqs == np.roll(seqs, q, axis=1), axis=1)
            keep &= ~(repeats & _closed(seqs[:, :q], n))
    return keep


def _walk(
    table: np.ndarray, seqs: np.ndarray, c0: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Corners before each step, x displacement and rotation of DOF sequences from corners ``c0``."""
    m, length = seqs.shape
    corner = np.asarray(c0, np.int64).copy()
    x = np.zeros(m)
    theta = np.zeros(m)
    corners = np.empty((m, length), np.int64)
    for t in range(length):
        corners[:, t] = corner
        inc = table[corner, seqs[:, t]]
        x += np.cos(theta) * inc[:, 0] - np.sin(theta) * inc[:, 1]
        theta += inc[:, 2]
        corner = corner ^ (1 << seqs[:, t])
    return corners, x, theta


class Replay(NamedTuple):
    """Noiseless replay of executed actions, time-major (leading axes: steps, then runs)."""

    corner: np.ndarray  # int (T + 1, B): corner index before each step, then the final one
    moved: np.ndarray  # bool (T, B): the step changed the shape
    x: np.ndarray  # float64 (T + 1, B): exact centroid x before each step, then the final one


def replay(actions: np.ndarray, model: SwimmerModel, levels0: np.ndarray) -> Replay:
    """Replay action indices without noise from ``levels0``, its start orientation
    ([`jswim.env.start_orientation`][jswim.env.state.start_orientation]) and the origin.

    Parameters
    ----------
    actions : int array (T, B)
        Executed action indices, time-major.
    model : SwimmerModel
        The swimmer.
    levels0 : int array (B, n_dof)
        Initial DOF levels (0 = lo, 1 = hi).
    """
    steps, b = actions.shape
    n = model.n_dof
    a = actions.astype(np.intp)
    dof1, roc = decode_action(np.arange(3 * n, dtype=np.int8))
    dof, roc = (dof1 - 1)[a], roc[a]
    itype = np.int16 if steps < 16_000 else np.int32
    stamp = 2 * np.arange(1, steps + 1, dtype=itype)[:, None]  # 2 (t + 1): room for one bit
    # A DOF's level is set by the last nonzero ROC applied to it (a stuck move leaves it where it
    # already is), so levels follow from a running maximum of time stamps that carry the ROC's
    # sign in their lowest bit: no loop over steps.
    corner = np.zeros((steps + 1, b), np.int32)
    level = np.zeros((steps, b), np.int8)  # level of the moved DOF before each step
    for k in range(n):
        touched = (dof == k) & (roc != 0)
        last = np.maximum.accumulate(touched * (stamp + (roc > 0)), axis=0)
        lk = np.empty((steps + 1, b), np.int8)
        lk[0] = levels0[:, k]
        lk[1:] = np.where(last > 0, last & 1, lk[0])
        corner[1:] += lk[1:].astype(np.int32) << k
        corner[0] += lk[0].astype(np.int32) << k
        level = np.where(dof == k, lk[:-1], level)
    moved = roc == 1 - 2 * level  # +1 from lo or -1 from hi
    idx = np.where(moved, corner[:-1] * n + dof, 2**n * n)  # still -> an all-zero row
    table = np.concatenate(
        [step_table(model)[0].astype(np.float64).reshape(-1, 3), np.zeros((1, 3))]
    )
    x = np.zeros((steps + 1, b))
    if model.planar:
        # Orientation before each step as a unit complex number: a running product of the
        # steps' rotations is cheaper than cos and sin of a running sum.
        turn = np.exp(1j * table[:, 2])[idx]
        heading = np.empty((steps, b), np.complex128)
        if steps:  # a run the server failed at its first step has none
            heading[0] = np.exp(1j * start_orientation(model, np.asarray(levels0), np))
        np.cumprod(turn[:-1], axis=0, out=heading[1:])
        heading[1:] *= heading[:1]  # the start orientation (nonzero for chains of 3+ hinges)
        dx = (heading * (table[:, 0] + 1j * table[:, 1])[idx]).real
        np.cumsum(dx, axis=0, out=x[1:])
    else:
        np.cumsum(table[idx, 0], axis=0, out=x[1:])
    return Replay(corner, moved, x)


def _last_true(mask: np.ndarray) -> np.ndarray:
    """Index along axis 0 of the last True per column, -1 where none (time-major arrays)."""
    itype = np.int16 if mask.shape[0] < 32_000 else np.int32
    idx = np.arange(1, mask.shape[0] + 1, dtype=itype)[:, None]
    return (mask * idx).max(axis=0, initial=0).astype(np.int64) - 1


def trailing_strokes(
    differs: Any,
    closed: Any,
    moved: np.ndarray,
    x: np.ndarray,
    direction: np.ndarray,
    threshold: np.ndarray,
    max_period: int,
    n_cycles: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The final qualifying stroke of each run: ``(start, period, displacement per step)``.

    Shared by [`judge`][jswim.judging.gait.judge] (action sequences on corners or the K lattice) and
    [`jswim.judging.shape_judge.judge_shapes`][jswim.judging.shape_judge.judge_shapes] (shapes within a tolerance): they differ only in what
    "repeats with period p" means.

    ``differs(p)`` (bool ``(T - p, B)``): step ``t`` and step ``t + p`` differ; ``closed(sc, p)``
    (bool ``(B,)``): the shape after the period starting at ``sc`` is the shape before it;
    ``moved`` (bool ``(T, B)``); ``x`` (float64 ``(T + 1, B)``) the exact centroid x before each
    step and at the end. No stroke: start ``T + 1``, period 0.
    """
    steps, b = moved.shape
    rows = np.arange(b)
    # A qualifying stroke starts after the last step that did not change the shape.
    s_move = _last_true(~moved) + 1
    out_s = np.full(b, steps + 1, np.int64)
    out_p = np.zeros(b, np.int64)
    out_disp = np.full(b, np.nan)  # displacement per step of the stroke's first period
    for p in range(1, max_period + 1):
        # Start of the trailing segment that repeats with period p.
        s = np.maximum(_last_true(differs(p)) + 1, s_move)
        ok = steps - s >= n_cycles * p
        sc = np.minimum(s, steps - p)
        ok &= closed(sc, p)  # closed loop
        # Every complete period of the segment must go far enough: per residue class of the
        # period's start mod p, the last period that falls short must start before s.
        short = direction * (x[p:] - x[:-p]) < threshold * p  # (steps - p + 1, B)
        last_short = np.stack([_last_true(short[r::p]) * p + r for r in range(p)], axis=1)
        last_short = np.where(last_short < 0, -1, last_short)
        ok &= last_short[rows, s % p] < s
        first = direction * (x[sc + p, rows] - x[sc, rows]) / p
        better = ok & (s < out_s)
        out_s = np.where(better, s, out_s)
        out_p = np.where(better, p, out_p)
        out_disp = np.where(better, first, out_disp)
    return out_s, out_p, out_disp


def judge(
    actions: Any,
    params: EnvParams,
    *,
    levels0: Any = None,
    criterion: Criterion = PAPER,
    roc_levels: int = 1,
) -> GaitReport:
    """Find, per run, the final stroke and whether it is a qualifying cycle (see module docs).

    On a ``K``-level ROC lattice (``roc_levels = K > 1``) the same rules hold with lattice points
    for corners, the threshold relative to [`jswim.judging.lattice.best_per_step`][jswim.judging.lattice.best_per_step] and cycles up
    to ``2**n_dof K`` moves (docs/continuous.md, "Judging continuous strokes").

    Parameters
    ----------
    actions : int array-like (T,) or (B, T)
        Executed action indices, one run per row.
    params : EnvParams
        The runs' environment; ``direction`` (scalar or (B,)) and ``init`` (``(n_dof,)`` or
        ``(B, n_dof)``) may be batched. Noise plays no part: the judge measures exact
        displacements.
    levels0 : int array-like (n_dof,) or (B, n_dof), optional
        Actual initial levels; required when ``params.init`` asks for a random start. On a ROC
        lattice: the start's lattice positions ``j`` in ``0..K`` (a corner is ``level * K``).
    criterion : Criterion
        Horizon, cycle count and speed threshold (default: the paper's, `PAPER`).
    roc_levels : int
        ``K``: ``actions`` are lattice codes ([`jswim.judging.lattice.encode`][jswim.judging.lattice.encode]); 1 (default) the
        paper's action indices.

    Returns
    -------
    GaitReport
        Arrays over runs (a 1-D ``actions`` is treated as one run).

    Raises
    ------
    ConfigError
        For actions that are not valid indices, or a random start without ``levels0``.
    """
    model = params.model
    n = model.n_dof
    c = criterion
    k_levels = int(roc_levels)
    max_period = default_max_period(n, k_levels) if c.max_period is None else int(c.max_period)
    a = np.asarray(actions)
    if a.ndim == 1:
        a = a[None]
    if a.ndim != 2 or not np.issubdtype(a.dtype, np.integer):
        raise ConfigError("actions must be integer action indices of shape (T,) or (runs, T)")
    n_codes = n * (2 * k_levels + 1)
    if a.size and (a.min() < 0 or a.max() >= n_codes):
        raise ConfigError(
            f"action indices must lie in [0, {n_codes}) for a {n}-DOF swimmer"
            + (f" on {k_levels} ROC levels" if k_levels > 1 else "")
        )
    b, steps = a.shape
    init = np.asarray(params.init if levels0 is None else levels0).astype(np.int64)
    init = np.broadcast_to(init, (b, n))
    if np.any(init < 0):
        raise ConfigError("params.init asks for a random start: pass the actual levels0 to judge")
    direction = np.broadcast_to(np.sign(np.asarray(params.direction, np.float64)), (b,))
    at = np.ascontiguousarray(a.T)  # time-major: reductions along time run over contiguous rows
    if k_levels == 1:
        best = np.where(
            direction > 0, best_per_step(model, 1, max_period), best_per_step(model, -1, max_period)
        )
        rp = replay(at, model, init)
    else:
        if levels0 is None:  # params.init holds levels: the corner's lattice positions
            init = init * k_levels
        if np.any(init > k_levels):
            raise ConfigError(f"levels0 on {k_levels} ROC levels must lie in 0..{k_levels}")
        best = np.where(
            direction > 0,
            lattice.best_per_step(model, 1, k_levels),
            lattice.best_per_step(model, -1, k_levels),
        )
        rp = lattice.replay(at, model, k_levels, init)
    threshold = c.min_fraction * best - REL_TOL * np.abs(best)

    rows = np.arange(b)
    out_s, out_p, out_disp = trailing_strokes(
        lambda p: at[:-p] != at[p:],
        lambda sc, p: rp.corner[sc + p, rows] == rp.corner[sc, rows],
        rp.moved,
        rp.x,
        direction,
        threshold,
        min(max_period, steps // c.n_cycles),
        c.n_cycles,
    )

    return stroke_report(out_s, out_p, out_disp, best, c, a, max_period)


def stroke_report(
    out_s: np.ndarray,
    out_p: np.ndarray,
    out_disp: np.ndarray,
    best: np.ndarray,
    criterion: Criterion,
    per_step_label: np.ndarray,
    max_period: int,
) -> GaitReport:
    """The [`GaitReport`][jswim.judging.gait.GaitReport] of [`trailing_strokes`][jswim.judging.gait.trailing_strokes]' output, shared with
    [`jswim.judging.shape_judge.judge_shapes`][jswim.judging.shape_judge.judge_shapes]; ``per_step_label`` (B, T) fills ``cycle``."""
    learned = out_p > 0
    steps_to_learn = np.where(learned, out_s + 1, -1)  # 1-based, the paper's count
    success = learned & (out_s + criterion.n_cycles * out_p <= criterion.horizon)
    cycle = np.full((out_p.shape[0], max_period), -1, np.int64)
    for p in np.unique(out_p[learned]):
        sel = np.flatnonzero(out_p == p)
        cycle[sel, :p] = per_step_label[sel[:, None], out_s[sel, None] + np.arange(p)[None]]
    per_step = np.where(learned, out_disp, np.nan)
    return GaitReport(
        learned,
        steps_to_learn,
        success,
        out_p,
        cycle,
        per_step,
        per_step / best,
        np.where(learned, out_s, -1),
    )
