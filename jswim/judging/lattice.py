"""The ROC lattice of ``--roc-levels K``: DOF values on ``K + 1`` points, exact moves between them.

An action is a DOF and an integer ROC ``k`` in ``-K..K``, code ``(dof - 1) (2K + 1) + (k + K)``
(``K = 1``: the environment's codes); started on a corner each DOF stays on the points
``lo + j (hi - lo) / K``, and lattice points are indexed ``sum_d j_d (K + 1)**d`` (``K = 1``: the
corner index). Exact motion: at zero Reynolds number a one-DOF move depends only on its path, so
the move from ``j`` to ``j'`` is ``G(j)^-1 G(j')``, ``G`` composed from unit segments each
integrated once in float64 ([`move_table`][jswim.judging.lattice.move_table]), in the centroid frame of
`jswim.env.step_table`. The judge, the gait search and the lattice baselines read it
(docs/continuous.md, "Finer ROCs for the agents").
"""

from __future__ import annotations

import functools
import itertools
from typing import NamedTuple

import numpy as np

from jswim.errors import ConfigError, check_direction
from jswim.action_codes import check_roc_levels, decode_action, encode_action
from jswim.swimmers.models import SwimmerModel
from jswim.env import start_orientation
from jswim.integrate import centroid, integrate_stroke

#: Unit segments integrated per compiled call of [`move_table`][jswim.judging.lattice.move_table].
_CHUNK = 128

#: Largest number of (start point, move sequence) pairs [`best_lattice_cycles`][jswim.judging.lattice.best_lattice_cycles] enumerates.
MAX_WALKS = 20_000_000


def encode(dof: int, k: int, roc_levels: int) -> int:
    """Code of the action ``[dof, k]`` (``dof`` 1-based, ``k`` in ``-K..K``): [`jswim.action_codes.encode_action`][jswim.action_codes.encode_action]."""
    return encode_action(dof, k, roc_levels)


def decode(code: int, roc_levels: int) -> tuple[int, int]:
    """``(dof, k)`` of an action code: [`jswim.action_codes.decode_action`][jswim.action_codes.decode_action]."""
    return decode_action(int(code), roc_levels)


def values(model: SwimmerModel, roc_levels: int) -> np.ndarray:
    """The ``K + 1`` values a DOF takes on the lattice, ``lo + j (hi - lo) / K`` (float64)."""
    k = check_roc_levels(roc_levels)
    return model.lo + (model.hi - model.lo) * np.arange(k + 1) / k


def point_index(j: np.ndarray, roc_levels: int) -> np.ndarray:
    """Lattice index ``sum_d j_d (K + 1)**d`` of per-DOF positions ``j`` (last axis: DOFs)."""
    j = np.asarray(j, np.int64)
    return j @ ((roc_levels + 1) ** np.arange(j.shape[-1], dtype=np.int64))


def point_coords(index: np.ndarray, n_dof: int, roc_levels: int) -> np.ndarray:
    """Per-DOF positions ``j`` (last axis) of lattice indices."""
    index = np.asarray(index, np.int64)
    return (index[..., None] // (roc_levels + 1) ** np.arange(n_dof)) % (roc_levels + 1)


class MoveTable(NamedTuple):
    """The motions of a ``K``-level lattice, stored as ``G``: every move is ``G(j)^-1 G(j')``.

    [`move`][jswim.judging.lattice.move] reads any move from it; ``(K+1)**n n`` entries instead of ``2K + 1`` times as
    many.

    Attributes
    ----------
    prefix : float64 ((K+1)**n, n, 3)
        ``G[p, d]``: the rigid motion ``(dx, dy, dtheta)`` (centroid frame) of moving DOF ``d``
        from its lower limit to its value at point ``p``, the other DOFs as at ``p``.
    roc_levels : int
        ``K``.
    """

    prefix: np.ndarray
    roc_levels: int


def move(
    tab: MoveTable, point: np.ndarray, dof: np.ndarray, k: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Moves ``[dof + 1, k]`` from lattice points (arrays broadcast together).

    Returns
    -------
    target : int64
        The lattice point after the move (a move past a limit stops at it).
    motion : float64 (..., 3)
        ``(dx, dy, dtheta)`` in the body frame at the start (exactly 0 where nothing moves).
    moved : bool
        The move changed the shape (``k != 0`` and the DOF not already at that limit).
    """
    big_k = tab.roc_levels
    point, dof, k = (np.asarray(v, np.int64) for v in (point, dof, k))
    stride = (big_k + 1) ** dof
    j = (point // stride) % (big_k + 1)
    new_j = np.clip(j + k, 0, big_k)
    target = point + (new_j - j) * stride
    return target, between(tab, point, dof, target), new_j != j


def between(tab: MoveTable, start: np.ndarray, dof: np.ndarray, end: np.ndarray) -> np.ndarray:
    """Motion of the one-DOF move from lattice point ``start`` to ``end`` (differing in ``dof``
    only): ``G[start]^-1 G[end]``, exactly 0 where they are equal."""
    g0, g1 = tab.prefix[start, dof], tab.prefix[end, dof]
    motion = _compose(_inverse(g0), g1)
    motion[np.asarray(start) == np.asarray(end)] = 0.0
    return motion


#: Largest lattice the tabular tools take (judge, gait search, lattice Q-learning): ``(K+1)**n_dof``
#: points (K = 200 for two DOFs).
MAX_POINTS = 40_401


def check_size(n_dof: int, roc_levels: int) -> None:
    """[`ConfigError`][jswim.errors.ConfigError] when the lattice has more than `MAX_POINTS` points."""
    if (roc_levels + 1) ** n_dof > MAX_POINTS:
        raise ConfigError(
            f"--roc-levels {roc_levels}: the {n_dof}-DOF lattice has {(roc_levels + 1) ** n_dof:,} "
            f"points, more than the {MAX_POINTS:,} the tabular tools (judge, lattice Q-learning, "
            "gait search) take; use fewer levels"
        )


def _compose(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Motion ``a`` then ``b`` (SE(2): ``b``'s translation is in the frame ``a`` ends in)."""
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack(
        [
            a[..., 0] + c * b[..., 0] - s * b[..., 1],
            a[..., 1] + s * b[..., 0] + c * b[..., 1],
            a[..., 2] + b[..., 2],
        ],
        axis=-1,
    )


def _inverse(a: np.ndarray) -> np.ndarray:
    c, s = np.cos(a[..., 2]), np.sin(a[..., 2])
    return np.stack(
        [-(c * a[..., 0] + s * a[..., 1]), s * a[..., 0] - c * a[..., 1], -a[..., 2]], axis=-1
    )


@functools.lru_cache(maxsize=16)
def _segment_fn(model: SwimmerModel):
    """Jitted, vmapped motion of straight segments ``(start shape, unit rate, duration)`` (float64)."""
    import jax
    import jax.numpy as jnp

    def one(a, r, span):
        pose = integrate_stroke(model, a, r, span, n_sub=32)
        disp = centroid(model, a + r * span, pose) - centroid(model, a, jnp.zeros(3))
        return jnp.concatenate([disp, pose[2:]])

    return jax.jit(jax.vmap(one))


@functools.lru_cache(maxsize=16)
def move_table(model: SwimmerModel, roc_levels: int) -> MoveTable:
    """The exact [`MoveTable`][jswim.judging.lattice.MoveTable] of ``model`` on ``roc_levels`` levels (built once, float64).

    ``(K+1)**n n`` unit segments go through the integrator; ``G`` composes them, and every move
    is read as ``G(j)^-1 G(j')`` ([`move`][jswim.judging.lattice.move], see the module docstring). ``K = 1`` reproduces
    `jswim.env.step_table` (tested).

    Raises
    ------
    ConfigError
        For a lattice of more than `MAX_POINTS` points.
    """
    import jax
    import jax.numpy as jnp

    k = check_roc_levels(roc_levels)
    n = model.n_dof
    check_size(n, k)
    m = (k + 1) ** n
    coords = point_coords(np.arange(m), n, k)  # (m, n)
    grid = values(model, k)
    with jax.ensure_compile_time_eval(), jax.enable_x64(True):
        d0 = jnp.asarray(np.repeat(grid[coords], n, axis=0))  # (m n, n): every point, every DOF
        rate = jnp.asarray(np.tile(np.eye(n), (m, 1)))
        # In fixed chunks through one compiled function per model: every K reuses it.
        segment = _segment_fn(model)
        rows = d0.shape[0]
        pad = -rows % _CHUNK
        d0 = jnp.concatenate([d0, jnp.broadcast_to(d0[:1], (pad, n))])
        rate = jnp.concatenate([rate, jnp.broadcast_to(rate[:1], (pad, n))])
        span = jnp.full((_CHUNK,), model.duration / k, jnp.float64)
        parts = [
            np.asarray(segment(d0[i : i + _CHUNK], rate[i : i + _CHUNK], span))
            for i in range(0, rows + pad, _CHUNK)
        ]
        seg = np.concatenate(parts)[:rows].reshape(m, n, 3)  # j_d -> j_d + 1 (unused at j_d = K)
    # G[p, d]: motion from j_d = 0 to p's j_d along DOF d, composed segment by segment.
    g = np.zeros((m, n, 3))
    stride = (k + 1) ** np.arange(n)
    for d in range(n):
        for j in range(1, k + 1):
            at = np.flatnonzero(coords[:, d] == j)
            g[at, d] = _compose(g[at - stride[d], d], seg[at - stride[d], d])
    return MoveTable(g, k)


# -- replay and gait search ----------------------------------------------------------------------


class LatticeReplay(NamedTuple):
    """Noiseless replay of lattice actions, time-major (leading axes: steps, then runs)."""

    corner: np.ndarray  # int64 (T + 1, B): lattice index before each step, then the final one
    moved: np.ndarray  # bool (T, B): the step changed the shape
    x: np.ndarray  # float64 (T + 1, B): exact centroid x before each step, then the final one


def replay(
    actions: np.ndarray, model: SwimmerModel, roc_levels: int, points0: np.ndarray
) -> LatticeReplay:
    """Replay action codes without noise from lattice positions ``points0`` (B, n_dof), their start
    orientation ([`jswim.env.start_orientation`][jswim.env.state.start_orientation]) and the origin.

    Parameters
    ----------
    actions : int array (T, B)
        Executed action codes ([`encode`][jswim.judging.lattice.encode]), time-major.
    model : SwimmerModel
        The swimmer.
    roc_levels : int
        ``K``.
    points0 : int array (B, n_dof)
        Start positions ``j`` per DOF (a corner: ``level * K``).
    """
    tab = move_table(model, roc_levels)
    width = 2 * roc_levels + 1
    steps, b = actions.shape
    a = np.asarray(actions, np.int64)
    dof, kk = a // width, a % width
    p = np.empty((steps + 1, b), np.int64)
    p[0] = point_index(points0, roc_levels)
    stride = (roc_levels + 1) ** dof
    shift = kk - roc_levels
    for t in range(steps):  # clipping makes the point path sequential
        j = (p[t] // stride[t]) % (roc_levels + 1)
        p[t + 1] = p[t] + (np.clip(j + shift[t], 0, roc_levels) - j) * stride[t]
    inc = between(tab, p[:-1], dof, p[1:])  # (T, B, 3)
    moved = p[1:] != p[:-1]
    x = np.zeros((steps + 1, b))
    if model.planar:
        heading = np.empty((steps, b), np.complex128)
        if steps:
            heading[0] = np.exp(1j * start_orientation(model, np.asarray(points0) / roc_levels, np))
            np.cumprod(np.exp(1j * inc[:-1, :, 2]), axis=0, out=heading[1:])
            heading[1:] *= heading[0]
        np.cumsum((heading * (inc[..., 0] + 1j * inc[..., 1])).real, axis=0, out=x[1:])
    else:
        np.cumsum(inc[..., 0], axis=0, out=x[1:])
    return LatticeReplay(p, moved, x)


class LatticeCycle(NamedTuple):
    """A closed stroke on the lattice: moves that each change the shape, back to the start point.

    ``start`` holds the per-DOF positions ``j`` (0..K); ``moves`` the ``(dof, k)`` pairs;
    ``displacement`` is per period in the target direction from orientation 0.
    """

    moves: tuple[tuple[int, int], ...]
    start: tuple[int, ...]
    displacement: float
    rotation: float
    roc_levels: int

    @property
    def period(self) -> int:
        return len(self.moves)

    @property
    def per_step(self) -> float:
        return self.displacement / self.period

    @property
    def actions(self) -> tuple[int, ...]:
        return tuple(encode(d, k, self.roc_levels) for d, k in self.moves)

    @property
    def simple(self) -> bool:
        """No shape visited twice within a period."""
        j = list(self.start)
        seen = {tuple(j)}
        for d, k in self.moves:
            j[d - 1] += k
            seen.add(tuple(j))
        return len(seen) == self.period


def _amounts(m: int, k: int) -> np.ndarray:
    """Every m-tuple of nonzero integers in -k..k summing to 0 (one DOF's moves in a closed loop)."""
    vals = [v for v in range(-k, k + 1) if v]
    if m == 0:
        return np.zeros((1, 0), np.int64)
    rows = [t for t in itertools.product(vals, repeat=m - 1) if 0 < abs(sum(t)) <= k]
    return np.array([list(t) + [-sum(t)] for t in rows], np.int64).reshape(-1, m)


@functools.lru_cache(maxsize=64)
def best_lattice_cycles(
    model: SwimmerModel, direction: int, roc_levels: int, max_len: int = 4, top: int | None = None
) -> tuple[LatticeCycle, ...]:
    """Closed strokes on the ``K``-level lattice up to ``max_len`` moves, best displacement per step first.

    Every move changes one DOF by a nonzero ``k`` without reaching past a limit, and no two
    consecutive moves (cyclically) change the same DOF: a run of moves of one DOF walks one
    segment of shape space and equals a single move (zero Reynolds number), so merging it never
    lowers the speed per step. Every start point and every such sequence is walked exactly
    ([`move_table`][jswim.judging.lattice.move_table]); one entry per loop up to cyclic shifts, shown from the shift that goes
    furthest from orientation 0 (as [`jswim.judging.gait.best_cycles`][jswim.judging.gait.best_cycles]).

    Parameters
    ----------
    model : SwimmerModel
        The swimmer.
    direction : {+1, -1}
        Target direction of the displacement.
    roc_levels : int
        ``K``.
    max_len : int
        Longest period (even, >= 4: the shortest loop that encloses area has four moves).
    top : int, optional
        Keep only this many (all by default).

    Raises
    ------
    ConfigError
        For a bad direction or length, or more than `MAX_WALKS` walks to enumerate.
    """
    k = check_roc_levels(roc_levels)
    n = model.n_dof
    check_direction(direction)
    if max_len < 4:
        raise ConfigError(
            f"--max-len must be >= 4 (the shortest closed stroke has four moves), got {max_len}"
        )
    tab = move_table(model, k)
    m_points = (k + 1) ** n
    width = 2 * k + 1
    found = []  # per (length, DOF sequence): speed per step, displacement, rotation, start, codes
    for length in range(4, max_len + 1, 2):
        dof_seqs = [
            s
            for s in itertools.product(range(n), repeat=length)
            if all(s[i] != s[(i + 1) % length] for i in range(length))
        ]
        for seq in dof_seqs:
            per_dof = [_amounts(seq.count(d), k) for d in range(n)]
            if sum(len(a) == 0 for a in per_dof if a.shape[1]):
                continue
            combos = itertools.product(*[range(len(a)) for a in per_dof])
            idx = np.array(list(combos), np.int64).reshape(-1, n)
            if idx.shape[0] * m_points > MAX_WALKS:
                raise ConfigError(
                    f"too many strokes to enumerate up to {max_len} moves at --roc-levels {k} "
                    f"({idx.shape[0] * m_points:,}); lower --max-len"
                )
            amounts = np.zeros((idx.shape[0], length), np.int64)
            for d in range(n):
                cols = [i for i, s in enumerate(seq) if s == d]
                if cols:
                    amounts[:, cols] = per_dof[d][idx[:, d]]
            codes = np.asarray(seq)[None] * width + amounts + k  # (S, L)
            codes = codes[_primitive(codes)]
            p0 = np.repeat(np.arange(m_points), codes.shape[0])
            c = np.tile(codes, (m_points, 1))
            disp, rot, ok = _walk_loops(tab, c, p0, k, n)
            found.append(
                (direction * disp[ok] / length, disp[ok] * direction, rot[ok], p0[ok], c[ok])
            )
    # One entry per loop up to cyclic shifts: the shift that goes furthest comes first.
    ranked = sorted(
        (
            (float(ps[i]), int(codes.shape[1]), float(v[i]), float(r[i]), int(p[i]), codes[i])
            for ps, v, r, p, codes in found
            for i in range(len(ps))
        ),
        key=lambda f: (-f[0], f[1]),
    )
    seen: set = set()
    out: list[LatticeCycle] = []
    for _, _, value, rot, p0, codes in ranked:
        codes = tuple(int(v) for v in codes)
        key = _loop_key(tab, p0, codes)
        if key in seen:
            continue
        seen.add(key)
        moves = tuple(decode(c, k) for c in codes)
        start = tuple(int(v) for v in point_coords(np.array(p0), n, k))
        out.append(LatticeCycle(moves, start, value, rot, k))
        if top is not None and len(out) >= top:
            break
    return tuple(out)


def _primitive(codes: np.ndarray) -> np.ndarray:
    """Sequences that are not a shorter block repeated (the square gait twice is the square gait)."""
    length = codes.shape[1]
    keep = np.ones(codes.shape[0], bool)
    for q in range(1, length):
        if length % q == 0:
            keep &= ~np.all(codes == np.roll(codes, q, axis=1), axis=1)
    return keep


def _walk_loops(tab: MoveTable, codes: np.ndarray, p0: np.ndarray, k: int, n: int):
    """Displacement along x, rotation and validity (closed, never clipped) of move sequences from ``p0``."""
    width = 2 * k + 1
    p = p0.copy()
    x = np.zeros(len(p0))
    y = np.zeros(len(p0))
    theta = np.zeros(len(p0))
    ok = np.ones(len(p0), bool)
    for t in range(codes.shape[1]):
        d, kk = codes[:, t] // width, codes[:, t] % width
        target, inc, _ = move(tab, p, d, kk - k)
        # A move that reaches past a limit is clipped: not the stroke asked for.
        want = point_coords(p, n, k)[np.arange(len(p)), d] + kk - k
        ok &= (want >= 0) & (want <= k)
        c, s = np.cos(theta), np.sin(theta)
        x, y = x + c * inc[:, 0] - s * inc[:, 1], y + s * inc[:, 0] + c * inc[:, 1]
        theta = theta + inc[:, 2]
        p = target
    ok &= p == p0
    return x, theta, ok


def _loop_key(tab: MoveTable, p0: int, codes: tuple[int, ...]) -> tuple:
    """The loop as a set of cyclic shifts: the smallest (point, code) sequence over its shifts."""
    width = 2 * tab.roc_levels + 1
    pts = [p0]
    for c in codes[:-1]:
        pts.append(int(move(tab, pts[-1], c // width, c % width - tab.roc_levels)[0]))
    pairs = list(zip(pts, codes))
    return min(tuple(pairs[i:] + pairs[:i]) for i in range(len(pairs)))


def best_per_step(model: SwimmerModel, direction: int, roc_levels: int) -> float:
    """Best displacement per step of a closed lattice stroke of four moves, the speed the judge's
    threshold is relative to (four moves: on every lattice measured so far, no longer loop goes
    faster per step; README "Continuous strokes")."""
    return best_lattice_cycles(model, direction, roc_levels, 4, 1)[0].per_step
