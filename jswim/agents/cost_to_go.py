"""The still-fluid time to go of a lattice swimmer: least steps from (shape, target in the body
frame) to the target, by value iteration.

In still fluid a step of the K-lattice world moves the swimmer by a rigid displacement that
depends only on its shape and the action (in its own frame: Purcell's swimmer is invariant under
translation and rotation), so the least number of steps to a fixed target depends only on the
shape ``s`` and the target's position ``p`` in the body frame. Value iteration on a grid of ``p``
(semi-Lagrangian, bilinear interpolation) gives it:

    V(s, p) = 1 + min_a V(s'_a, R(-dtheta_a) (p - dX_a)),   V = 0 where |p| < radius.

It is the heuristic of [`jswim.agents.optimal`][jswim.agents.optimal] (ranking a beam, with a
flow correction) and the closed-loop policy of its ``"dp"`` method. Interpolation makes it an
estimate, not a bound: [`optimal.solve`][jswim.agents.optimal.solve] replays every answer
through the world, so nothing rests on its accuracy but the search's speed.
"""

from __future__ import annotations

import functools
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.env.flows import SWIM_SPEED
from jswim.env.state import start_state

__all__ = ["CostToGo", "lattice_moves", "still_cost_to_go"]

#: Value beyond every reachable one: marks "not yet reached" in the iteration.
_FAR = 1.0e6


class CostToGo(NamedTuple):
    """A still-fluid time to go on a grid (the module's ``V``).

    Attributes
    ----------
    values : Array (S, N, N) float32
        Steps to go from shape ``s`` (lattice index, ``sum_d j_d (K + 1)**d``) with the target at
        body-frame ``(x_i, y_j)``, ``x_i = -half + i * cell``.
    half : float
        Half width of the grid (``a``).
    cell : float
        Grid spacing (``a``).
    speed : float
        The square gait's mean speed (``a`` per step): the slope used outside the grid.

    Calling it, ``ctg(shape, p)``, gives the steps to go from lattice shape ``shape`` (int,
    ``(...)``) with the target at body-frame ``p`` (``(..., 2)``, ``a``): bilinear inside the
    grid, beyond it the edge's value plus the distance past it at ``speed``.
    """

    values: Array
    half: float
    cell: float
    speed: float

    def __call__(self, shape: Array, p: Array) -> Array:
        # the class docs' call: bilinear inside the grid, the edge's value plus the distance
        # past it at `speed` outside
        n = self.values.shape[-1]
        g = (p + self.half) / self.cell
        gc = jnp.clip(g, 0.0, n - 1.000001)
        i0 = jnp.floor(gc).astype(jnp.int32)
        w = gc - i0
        i, j = i0[..., 0], i0[..., 1]
        wx, wy = w[..., 0], w[..., 1]
        v = self.values
        inside = (
            (1 - wx) * (1 - wy) * v[shape, i, j]
            + wx * (1 - wy) * v[shape, i + 1, j]
            + (1 - wx) * wy * v[shape, i, j + 1]
            + wx * wy * v[shape, i + 1, j + 1]
        )
        past = jnp.hypot(*jnp.moveaxis((g - gc) * self.cell, -1, 0))
        return inside + past / self.speed


@functools.partial(jax.jit, static_argnames=("inner", "n_actions"))
def _steps(inner: Any, n_actions: int, still: Any, shapes: Array) -> tuple[Array, Array]:
    """Every action's step from every lattice shape (rows of ``shapes``: per-DOF positions),
    from the origin at heading 0; compiled once per world (``lattice_moves`` is called by both
    the time to go and the lower bound of each solve)."""
    k = inner.roc_levels

    def one(levels: Array) -> tuple[Array, Array]:
        st = start_state(inner.model, levels / k)
        st = st._replace(theta=jnp.zeros_like(st.theta), cos=jnp.ones_like(st.cos))
        st = st._replace(sin=jnp.zeros_like(st.sin), theta_lo=jnp.zeros_like(st.theta_lo))
        st = st._replace(cos_lo=jnp.zeros_like(st.cos_lo), sin_lo=jnp.zeros_like(st.sin_lo))
        noise = jnp.zeros((), st.x.dtype)

        def act(a: Array) -> tuple[Array, Array]:
            new, _ = inner.advance(st, a, noise, still)
            d = jnp.stack([new.x + new.x_lo, new.y + new.y_lo, new.theta + new.theta_lo])
            return d, jnp.round((new.frac + new.frac_lo) * k).astype(jnp.int32)

        return jax.vmap(act)(jnp.arange(n_actions))

    return jax.vmap(one)(shapes)


def lattice_moves(env: Any, params: Any) -> tuple[np.ndarray, np.ndarray]:
    """Each (lattice shape, action code)'s still-fluid step, from the world's own step.

    Returns
    -------
    moves : ndarray (S, A, 3) float64
        ``(dx, dy, dtheta)`` in the body frame at the step's start (``a``, rad).
    after : ndarray (S, A) int
        The lattice shape after the step.
    """
    k = env.roc_levels
    n = env.n_dof
    shapes = np.stack(np.meshgrid(*[np.arange(k + 1)] * n, indexing="ij"), -1).reshape(-1, n)
    index = (shapes * (k + 1) ** np.arange(n)).sum(-1)
    order = np.argsort(index)
    shapes = shapes[order]
    still = params.swimmer.replace(flow=None, zeta=0.0)
    d, j = _steps(env.inner, env.n_actions, still, jnp.asarray(shapes, jnp.result_type(float)))
    after = (np.asarray(j) * (k + 1) ** np.arange(n)).sum(-1)
    return np.asarray(d, np.float64), after


@functools.partial(jax.jit, static_argnames=("half", "cell", "speed"))
def _sweeps(
    v: Array,
    hit: Array,
    nxt: Array,
    q: Array,
    inside: Array,
    half: float,
    cell: float,
    speed: float,
) -> Array:
    """Twenty sweeps of the value iteration (the grids are arguments, not constants: XLA folded
    them for seconds when they were closed over)."""

    def sweep(_: int, v: Array) -> Array:
        model = CostToGo(v, half, cell, speed)
        cand = jnp.where(hit, 1.0, 1.0 + model(nxt, q))  # (S, A, N, N)
        return jnp.where(inside[None], 0.0, jnp.minimum(v, jnp.min(cand, axis=1)))

    return jax.lax.fori_loop(0, 20, sweep, v)


@functools.lru_cache(maxsize=16)
def _solve(
    moves_key: bytes, after_key: bytes, shape: tuple[int, int], radius: float, half: float
) -> CostToGo:
    moves = np.frombuffer(moves_key, np.float64).reshape(*shape, 3)
    after = np.frombuffer(after_key, np.int64).reshape(shape)
    cell = 0.1
    n = round(2 * half / cell) + 1
    axis = -half + cell * np.arange(n)
    px, py = np.meshgrid(axis, axis, indexing="ij")
    p = jnp.asarray(np.stack([px, py], -1), jnp.float32)  # (N, N, 2)
    d = jnp.asarray(moves, jnp.float32)
    # where each move sends the target, in the new body frame: R(-dtheta) (p - dX)
    c, s = jnp.cos(d[..., 2]), jnp.sin(d[..., 2])
    q = p[None, None] - d[:, :, None, None, :2]  # (S, A, N, N, 2)
    qx = c[..., None, None] * q[..., 0] + s[..., None, None] * q[..., 1]
    qy = -s[..., None, None] * q[..., 0] + c[..., None, None] * q[..., 1]
    q = jnp.stack([qx, qy], -1)
    hit = jnp.hypot(qx, qy) < radius
    nxt = jnp.asarray(after)[..., None, None] * jnp.ones(q.shape[:-1], jnp.int32)
    speed = SWIM_SPEED  # beyond the grid: the square gait's mean speed
    inside = jnp.hypot(p[..., 0], p[..., 1]) < radius

    v = jnp.full((shape[0], n, n), _FAR, jnp.float32)
    # each sweep carries the values one step further out; the slowest way to any grid point
    # (turning while crossing it) takes a few hundred steps: sweep until a block changes nothing
    for _ in range(100):
        new = _sweeps(v, hit, nxt, q, inside, half=half, cell=cell, speed=speed)
        done = bool(jnp.max(jnp.abs(new - v)) < 1e-3)
        v = new
        if done:
            break
    v = jnp.minimum(v, _FAR)
    return CostToGo(v, half, cell, speed)


def still_cost_to_go(env: Any, params: Any, half: float = 5.0) -> CostToGo:
    """The still-fluid time to go of navigation world ``env`` (module docs), computed once per
    swimmer, lattice and success radius in a process.

    Parameters
    ----------
    env : NavigationWorld
        On a K lattice (integer codes).
    params : NavParams
        Its params (the success radius is read from them).
    half : float
        Half width of the grid of body-frame target positions (``a``); beyond it the time to go
        grows at the fastest stroke's speed.

    Returns
    -------
    CostToGo
    """
    moves, after = lattice_moves(env, params)
    radius = float(np.max(np.asarray(params.target.radius)))
    return _solve(
        moves.tobytes(),
        after.astype(np.int64).tobytes(),
        after.shape,
        radius,
        float(half),
    )
