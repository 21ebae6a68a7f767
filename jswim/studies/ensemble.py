"""Noise ensembles: one stroke or policy, many noisy swimmers, statistics of X/a per step.

A noise study asks how a fixed way of swimming fares when every step's displacement is
perturbed, ``(dX, dY)(1 + zeta Y)`` with ``Y ~ U[-1, 1]`` (the paper's noise). This module runs
``n`` independent swimmers per noise level ``zeta`` under one policy and reports, at every
``every``-th step, the mean, standard deviation, quantiles, extremes of X/a and the fraction of
swimmers that keep moving forward (``direction * (X_t - X_{t-w}) > 0`` over the last ``w``
steps, ``w`` = the stroke's period by default).

Policies: a fixed stroke repeated cyclically (`stroke_policy`; the signature gait is
``jswim.judging.gait.best_cycles(model, direction)[0]``) or the greedy policy of a Q-table
(`q_policy`, ties broken at random per swimmer).

Scale: swimmers are simulated ``chunk`` at a time (one jitted scan over all steps per chunk,
sharded over every device, `jswim.sharding`), so memory is bounded by the chunk, not by
``n``: about ``52 + 4 w + 16`` bytes per swimmer of the chunk in float32 (two-DOF swimmers:
state 52, the ring of the last ``w`` positions, noise and policy temporaries), plus per-chunk
statistics. Nothing per swimmer is kept after its chunk.

Exactness: swimmer ``i`` of noise level ``zeta`` has its noise from the counter-based
[`jswim.env.noise`][jswim.env.randomness.noise] under a key derived from ``(seed, zeta)`` and its index, so results do not
depend on ``chunk`` or on the device count, and adding a noise level does not change the others.
Mean and spread are combined in float64 from fixed blocks of `BLOCK` swimmers; quantiles
come from a histogram per reported step whose range is set by a pilot run of the first block
(``resolution`` = the bin width; a quantile that falls outside the range is NaN, the exact
``min``/``max`` are always reported).
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
from typing import Any, NamedTuple
from collections.abc import Callable, Sequence

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim import sharding
from jswim.action_codes import check_action_set
from jswim.agents import qlearning
from jswim.agents.defaults import default_rocs
from jswim.agents.qlearning import greedy_set, offered_actions, pick_uniform
from jswim.env import EnvParams, EnvState, advance, make_params, noise, seed_key, start_state
from jswim.env.swimmer_world import SwimmerWorld
from jswim.env.discretiser import corner
from jswim.errors import ConfigError, check_zeta
from jswim.judging import gait

#: Swimmers per statistics block: partial sums are formed per block on the device and combined
#: on the host in float64, in block order; chunks are multiples of it.
BLOCK = 4096

#: Default quantiles reported.
QUANTILES = (0.05, 0.25, 0.5, 0.75, 0.95)

#: Histogram bins per reported step (quantile resolution ~ 1.5 x pilot range / BINS).
BINS = 1024


@dataclasses.dataclass(frozen=True)
class Policy:
    """What the swimmers do: ``kind`` ``"stroke"`` (``actions`` repeated) or ``"q"`` (greedy on ``q``).

    Build with `stroke_policy` or `q_policy`.
    """

    kind: str
    actions: tuple[int, ...] = ()
    q: Any = None
    action_set: str = "all"
    rocs: tuple[int, ...] = (-1, 0, 1)
    label: str = ""

    @property
    def period(self) -> int:
        return len(self.actions) if self.kind == "stroke" else 4


def stroke_policy(actions: Sequence[int], label: str = "stroke") -> Policy:
    """A fixed stroke: action ``actions[t % len(actions)]`` at step ``t`` (action indices)."""
    acts = tuple(int(a) for a in actions)
    if not acts:
        raise ConfigError("a stroke needs at least one move")
    return Policy("stroke", actions=acts, label=label)


def q_policy(q: Any, params: EnvParams, action_set: str = "all", label: str = "Q-policy") -> Policy:
    """The greedy policy of a Q-table (rows: corners, columns: actions); random tie-breaks."""
    check_action_set(action_set)
    q = np.asarray(q, np.float64)
    n = params.model.n_dof
    if q.shape != (2**n, 3 * n):
        raise ConfigError(
            f"a Q-table for a {n}-DOF swimmer has shape {(2**n, 3 * n)}, got {q.shape}"
        )
    return Policy(
        "q", q=q, action_set=action_set, rocs=tuple(default_rocs(params.model)), label=label
    )


class EnsembleStats(NamedTuple):
    """Statistics of X/a for one noise level; arrays over reported steps (R,)."""

    zeta: float
    n: int
    steps: np.ndarray  # int (R,): step numbers (1-based: after that many steps)
    mean: np.ndarray
    std: np.ndarray
    quantiles: np.ndarray  # (R, len(qs)); NaN where the quantile fell outside the histogram
    qs: tuple[float, ...]
    min: np.ndarray
    max: np.ndarray
    forward: np.ndarray  # fraction with direction * (X_t - X_{t-w}) > 0
    resolution: np.ndarray  # histogram bin width (quantile resolution)


def _seed_key(seed: int, zeta: float) -> Array:
    """Key of one noise level: a hash of (seed, zeta), so other levels never shift it."""
    digest = hashlib.blake2b(
        repr(("ensemble", int(seed), float(zeta))).encode(), digest_size=8
    ).digest()
    return jax.random.PRNGKey(int.from_bytes(digest, "little") & 0x7FFFFFFF)


def _policy_action(policy: Policy, params: EnvParams, t: Array, state: EnvState, u: Array) -> Array:
    if policy.kind == "stroke":
        return jnp.asarray(policy.actions, jnp.int32)[t % len(policy.actions)]
    q = jnp.asarray(policy.q, state.x.dtype)
    row = jax.lax.dynamic_slice_in_dim(q, corner(state.levels), 1)[0]
    mask = offered_actions(state.levels, params, policy.action_set)
    return pick_uniform(greedy_set(row, mask, "random"), u)


class _Chunk(NamedTuple):
    """Per-chunk partial statistics (R reported steps, G blocks)."""

    count: Array  # (G,)
    mean: Array  # (R, G)
    m2: Array  # (R, G)
    min: Array  # (R,)
    max: Array  # (R,)
    forward: Array  # (R,) int
    hist: Array  # (R, bins + 2) int: underflow, bins, overflow


@functools.partial(
    jax.jit,
    static_argnames=("policy_static", "size", "steps", "every", "window", "bins", "devices"),
)
def _run_chunk(
    key: Array,
    start: Array,
    n: Array,
    params: EnvParams,
    q: Array,
    lo: Array,
    width: Array,
    *,
    policy_static: Policy,
    size: int,
    steps: int,
    every: int,
    window: int,
    bins: int,
    devices: int,
) -> _Chunk:
    dtype = jnp.result_type(float)
    idx = start + jnp.arange(size, dtype=jnp.int32)
    if devices > 1:  # the swimmers of the chunk are spread over the devices from here on
        idx = jax.lax.with_sharding_constraint(idx, sharding.batch_sharding())
    valid = idx < n
    policy = dataclasses.replace(policy_static, q=q)
    init = jnp.asarray(params.init, jnp.int32)
    # A random start: one fair coin per DOF and swimmer, from the same counter-based draws.
    coins = jnp.stack(
        [
            noise(jax.random.fold_in(key, 2 + k), size, start=start) > 0
            for k in range(init.shape[0])
        ],
        axis=1,
    ).astype(jnp.int32)
    levels = jnp.where(init[None, :] < 0, coins, init[None, :])
    zero = jnp.zeros((size,), dtype)
    state = jax.vmap(lambda lv: start_state(params.model, lv, dtype))(levels)
    ring = jnp.zeros((window, size), dtype)
    k_policy = jax.random.fold_in(key, 1)
    g = size // BLOCK
    vmask = valid.reshape(g, BLOCK)
    counts = jnp.sum(vmask, axis=1, dtype=jnp.int32)

    def one_step(carry, t):
        st, ring, _, _ = carry
        u = noise(k_policy, size, start=start, step=t) * 0.5 + 0.5 if policy.kind == "q" else zero
        a = jax.vmap(lambda s, uu: _policy_action(policy, params, t, s, uu))(st, u)
        y = noise(key, size, start=start, step=t).astype(dtype)
        st, _ = jax.vmap(advance, in_axes=(0, 0, 0, None))(st, a, y, params)
        x = st.x + st.x_lo
        before = ring[t % window]  # X/a `window` steps ago (0 before that)
        return (st, ring.at[t % window].set(x), x, before), None

    def report(carry, r):
        carry, _ = jax.lax.scan(one_step, carry, r * every + jnp.arange(every))
        x, prev = carry[2], carry[3]
        xb = x.reshape(g, BLOCK)
        mean = jnp.sum(jnp.where(vmask, xb, 0.0), axis=1) / jnp.maximum(counts, 1)
        m2 = jnp.sum(jnp.where(vmask, (xb - mean[:, None]) ** 2, 0.0), axis=1)
        xmin = jnp.min(jnp.where(valid, x, jnp.inf))
        xmax = jnp.max(jnp.where(valid, x, -jnp.inf))
        direction = jnp.asarray(params.direction, dtype)
        fwd = jnp.sum(valid & (direction * (x - prev) > 0), dtype=jnp.int32)
        b = jnp.floor((x - lo[r]) / width[r]).astype(jnp.int32)
        b = jnp.where(valid, jnp.clip(b, -1, bins) + 1, bins + 2)  # invalid ones fall off the end
        hist = jnp.zeros((bins + 2,), jnp.int32).at[b].add(1, mode="drop")
        return carry, (mean, m2, xmin, xmax, fwd, hist)

    n_reports = steps // every
    _, (mean, m2, xmin, xmax, fwd, hist) = jax.lax.scan(
        report, (state, ring, zero, zero), jnp.arange(n_reports)
    )
    return _Chunk(counts, mean, m2, xmin, xmax, fwd, hist)


def check_every(every: int, steps: int) -> None:
    """The one check that a report every ``every`` steps fits a run of ``steps`` (``jswim ensemble``
    makes it before it trains a policy)."""
    if every > steps:
        raise ConfigError(f"--every ({every}) must not exceed --steps ({steps})")


def run(
    policy: Policy,
    params: EnvParams,
    *,
    n: int,
    zetas: Sequence[float] = (0.0,),
    steps: int = 100,
    every: int = 1,
    window: int | None = None,
    seed: int = 0,
    chunk: int = 1 << 20,
    qs: Sequence[float] = QUANTILES,
    bins: int = BINS,
    progress: Callable[[int, int], None] | None = None,
) -> list[EnsembleStats]:
    """Run ``n`` noisy swimmers per noise level under ``policy`` and summarise X/a.

    Parameters
    ----------
    policy : Policy
        `stroke_policy` or `q_policy`.
    params : EnvParams
        Swimmer, target direction and initial configuration (``zeta`` is taken from ``zetas``).
    n : int
        Swimmers per noise level (any size: they are run ``chunk`` at a time).
    zetas : sequence of float
        Noise levels, each >= 0.
    steps : int
        Steps per swimmer.
    every : int
        Report every ``every``-th step (``steps`` is rounded down to a multiple of it).
    window : int, optional
        Steps over which "moving forward" is judged (default: the stroke's period, 4 for a
        Q-policy).
    seed : int
        Seed; each noise level's key is derived from ``(seed, zeta)``.
    chunk : int
        Swimmers simulated at once (rounded up to a multiple of `BLOCK` x devices).
    qs : sequence of float
        Quantiles in (0, 1).
    bins : int
        Histogram bins per reported step.
    progress : callable, optional
        ``progress(done, total)`` in swimmer-steps after every chunk.

    Returns
    -------
    list of EnsembleStats
        One per noise level, in the order of ``zetas``.

    Raises
    ------
    ConfigError
        On a non-positive ``n``/``steps``/``every``/``chunk``, ``every > steps``, a negative
        noise level or a quantile outside (0, 1).
    """
    zetas, window = _checked(policy, n, zetas, steps, every, window, chunk, qs, bins)
    steps = steps // every * every
    unit = BLOCK * sharding.device_count()
    size = min(-(-max(chunk, 1) // unit) * unit, -(-n // unit) * unit)
    q_arr = jnp.asarray(np.zeros((1, 1)) if policy.q is None else policy.q, jnp.result_type(float))
    static = dataclasses.replace(policy, q=None)
    kw = dict(
        policy_static=static,
        size=size,
        steps=steps,
        every=every,
        window=window,
        bins=bins,
        devices=sharding.device_count(),
    )
    n_rep = steps // every
    total, done = len(zetas) * n * steps, 0
    out = []
    for zeta in zetas:
        key = _seed_key(seed, zeta)
        p = params.replace(zeta=zeta)
        # Pilot: the first block (its own small compile) sets each reported step's histogram range.
        pilot = _run_chunk(
            key,
            jnp.int32(0),
            jnp.int32(min(n, BLOCK)),
            p,
            q_arr,
            jnp.zeros(n_rep),
            jnp.ones(n_rep),
            **{**kw, "size": BLOCK * sharding.device_count()},
        )
        pmin, pmax = np.asarray(pilot.min, np.float64), np.asarray(pilot.max, np.float64)
        span = pmax - pmin
        pad = 0.25 * span + 1e-6 * np.maximum(1.0, np.abs(pmax) + np.abs(pmin))
        lo = pmin - pad
        width = (span + 2 * pad) / bins
        parts = []
        for start in range(0, n, size):
            c = _run_chunk(
                key,
                jnp.int32(start),
                jnp.int32(n),
                p,
                q_arr,
                jnp.asarray(lo),
                jnp.asarray(width),
                **kw,
            )
            parts.append(sharding.to_host(c))
            done += min(size, n - start) * steps
            if progress is not None:
                progress(done, total)
        out.append(_combine(parts, zeta, n, every, n_rep, tuple(qs), lo, width))
    return out


def _checked(
    policy: Policy,
    n: int,
    zetas: Sequence[float],
    steps: int,
    every: int,
    window: int | None,
    chunk: int,
    qs: Sequence[float],
    bins: int,
) -> tuple[list[float], int]:
    """`run`'s arguments checked (its ``Raises``): the noise levels and the judging window."""
    if n < 1 or steps < 1 or every < 1 or chunk < 1 or bins < 1:
        raise ConfigError("n, steps, every, chunk and bins must be >= 1")
    check_every(every, steps)
    zetas = [check_zeta(z) for z in zetas]
    if not zetas:
        raise ConfigError("give at least one noise level zeta")
    if any(not 0.0 < q < 1.0 for q in qs):
        raise ConfigError(f"quantiles must lie in (0, 1), got {list(qs)}")
    window = policy.period if window is None else int(window)
    if window < 1:
        raise ConfigError(f"window must be >= 1, got {window}")
    return zetas, window


def _combine(
    parts: list,
    zeta: float,
    n: int,
    every: int,
    n_rep: int,
    qs: tuple[float, ...],
    lo: np.ndarray,
    width: np.ndarray,
) -> EnsembleStats:
    """Merge per-block partial statistics (Chan et al.'s pairwise update, in float64)."""
    counts = np.concatenate([np.asarray(c.count, np.float64) for c in parts])  # (G_total,)
    means = np.concatenate([np.asarray(c.mean, np.float64) for c in parts], axis=1)  # (R, G_total)
    m2s = np.concatenate([np.asarray(c.m2, np.float64) for c in parts], axis=1)
    mean = (means * counts).sum(axis=1) / n
    m2 = m2s.sum(axis=1) + (counts * (means - mean[:, None]) ** 2).sum(axis=1)
    std = np.sqrt(np.maximum(m2, 0.0) / max(n - 1, 1))
    xmin = np.min([np.asarray(c.min, np.float64) for c in parts], axis=0)
    xmax = np.max([np.asarray(c.max, np.float64) for c in parts], axis=0)
    fwd = np.sum([np.asarray(c.forward, np.int64) for c in parts], axis=0) / n
    hist = np.sum([np.asarray(c.hist, np.int64) for c in parts], axis=0)  # (R, bins + 2)
    quant = np.full((n_rep, len(qs)), np.nan)
    bins = hist.shape[1] - 2
    for r in range(n_rep):
        cdf = np.cumsum(hist[r])
        for j, q in enumerate(qs):
            target = q * n
            k = int(np.searchsorted(cdf, target, side="left"))
            if k == 0 or k > bins:
                continue  # in the underflow or overflow bin: outside the histogram's range
            below = cdf[k - 1]
            frac = (target - below) / max(hist[r, k], 1)
            quant[r, j] = lo[r] + width[r] * (k - 1 + frac)
    steps = (np.arange(n_rep) + 1) * every
    return EnsembleStats(zeta, n, steps, mean, std, quant, qs, xmin, xmax, fwd, np.asarray(width))


def signature_policy(params: EnvParams) -> tuple[Policy, tuple[int, ...]]:
    """The best closed cycle in the target direction and its start levels."""
    direction = int(np.sign(float(np.asarray(params.direction))))
    best = gait.best_cycles(params.model, direction)[0]
    return stroke_policy(best.actions, label="signature gait"), tuple(best.start)


def learned_policy(params: EnvParams, *, seed: int = 0, action_set: str = "all") -> Policy:
    """Train one Q-learner (default [`QConfig`][jswim.agents.qlearning.QConfig], no noise) and
    return its greedy policy."""
    config = qlearning.QConfig(action_set=action_set)
    world = SwimmerWorld(params.model, params.roc_levels, params.diagonal)
    run_ = qlearning.train(world, params.replace(zeta=0.0), seed_key(seed), config)
    return q_policy(
        np.asarray(run_.q), params, action_set, label=f"Q-policy (seed {seed}, {action_set})"
    )


def format_table(stats: Sequence[EnsembleStats], max_rows: int = 12) -> str:
    """Plain-text table: per noise level, up to ``max_rows`` reported steps at a round stride
    (`regular_rows`: every 5th of 50 steps, say) and the last step."""
    if not stats:
        return ""
    qs = stats[0].qs
    head = (
        f"{'zeta':>5} {'step':>8} {'mean X/a':>11} {'std':>9} "
        + " ".join(f"{'q' + format(100 * q, 'g'):>9}" for q in qs)
        + f" {'min':>10} {'max':>10} {'forward':>8}"
    )
    lines = [head, "-" * len(head)]
    for s in stats:
        for r in regular_rows(s.steps, max_rows):
            qtxt = " ".join(f"{v:9.4f}" if np.isfinite(v) else f"{'-':>9}" for v in s.quantiles[r])
            lines.append(
                f"{s.zeta:5g} {s.steps[r]:8d} {s.mean[r]:11.5f} {s.std[r]:9.5f} {qtxt} "
                f"{s.min[r]:10.4f} {s.max[r]:10.4f} {s.forward[r]:8.4f}"
            )
    return "\n".join(lines)


def regular_rows(steps: np.ndarray, most: int) -> np.ndarray:
    """Indices of ``steps`` at a round stride (1, 2, 5, 10, 20, 25, 50, ... times 10^k) giving at
    most ``most`` rows, the last step always included: the table's rows at regular steps."""
    steps = np.asarray(steps)
    if steps.size <= most:
        return np.arange(steps.size)
    span = int(steps[-1])
    stride = 1
    for scale in (10**k for k in range(12)):
        for m in (1, 2, 2.5, 5):
            stride = int(m * scale)
            if m * scale == stride and span // stride + 1 <= most:
                break
        else:
            continue
        break
    pick = [i for i, s in enumerate(steps) if int(s) % stride == 0]
    if not pick or pick[-1] != steps.size - 1:
        pick.append(steps.size - 1)
    if len(pick) > most:  # the last step pushed it over: drop the one before it
        pick.pop(-2)
    return np.asarray(pick)


def to_rows(stats: Sequence[EnsembleStats]) -> list[dict[str, Any]]:
    """One dict per (noise level, reported step), e.g. for a CSV file."""
    rows = []
    for s in stats:
        for r in range(len(s.steps)):
            row = {
                "zeta": s.zeta,
                "n": s.n,
                "step": int(s.steps[r]),
                "mean": float(s.mean[r]),
                "std": float(s.std[r]),
                "min": float(s.min[r]),
                "max": float(s.max[r]),
                "forward": float(s.forward[r]),
                "resolution": float(s.resolution[r]),
            }
            row.update({f"q{format(100 * q, 'g')}": float(v) for q, v in zip(s.qs, s.quantiles[r])})
            rows.append(row)
    return rows


__all__ = [
    "EnsembleStats",
    "Policy",
    "format_table",
    "learned_policy",
    "make_params",
    "q_policy",
    "regular_rows",
    "run",
    "signature_policy",
    "stroke_policy",
    "to_rows",
]
