"""Swimmer state: each DOF's place in its range and the pose of the geometric centroid."""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.env.params import EnvParams
from jswim.swimmers.models import SwimmerModel


class EnvState(NamedTuple):
    """Swimmer state: DOF values and the pose of the geometric centroid.

    Each DOF's value is held as its place in the range, ``frac = (d - lo) / (hi - lo)`` in
    [0, 1], so a step at ROC ``r`` moves ``frac`` by ``r`` (clipped to [0, 1]), the limits are
    exactly 0 and 1 in any dtype, and the paper's corner levels read straight off it
    ([`levels`][jswim.env.state.EnvState.levels]). [`dof_values`][jswim.env.state.dof_values] gives ``d`` itself.

    Every real-valued quantity is stored as a pair ``hi + lo`` of the working dtype: the value of
    X is ``x + x_lo``, and likewise ``y``, ``theta``, ``cos``, ``sin`` and ``frac`` with their
    ``*_lo`` words. ``x`` alone is the nearest number of the working dtype; [`position`][jswim.env.state.position]
    reads the full value. A float32 pair holds ~48 significant bits and every step is computed
    in float64 ([`jswim.env.advance`][jswim.env.stepping.advance]), so neither positions nor shapes drift: after 10^6
    square-gait steps in float32, X is within ~1e-10 relative of the closed form (plain float32
    accumulation was off by ~1 %). On the corners (the paper's discrete world) ``frac_lo`` stays
    0. Each component is its own field so that a batch keeps it contiguous, which vectorises
    much better than ``(B, k)`` blocks.

    Bytes per swimmer: ``8 n_dof + 44`` in float32 (60 for the two-DOF swimmers),
    ``16 n_dof + 84`` in float64.
    """

    frac: Array  # (n_dof,) (d - lo) / (hi - lo) in [0, 1], high word
    x: Array  # centroid x (X of the paper), high word
    y: Array  # centroid y (0 for the sphere swimmers), high word
    theta: Array  # orientation of the reference link (0 for the sphere swimmers), high word
    cos: Array  # cos theta and sin theta, carried so that a step needs no trigonometry
    sin: Array
    t: Array  # steps taken (int32)
    x_lo: Array  # low words
    y_lo: Array
    theta_lo: Array
    cos_lo: Array
    sin_lo: Array
    frac_lo: Array

    @property
    def rot(self) -> Array:
        """``(cos theta, sin theta)`` on a last axis of size 2 (high words)."""
        return jnp.stack([self.cos, self.sin], axis=-1)

    @property
    def levels(self) -> Array:
        """int32 ``(..., n_dof)``: the corner level of each DOF, 1 = hi, 0 = lo (exact on the
        corners, the states of the paper's discrete world; elsewhere the nearer limit)."""
        return (self.frac > 0.5).astype(jnp.int32)


class MoveInfo(NamedTuple):
    """What one step of the paper's functional environment did
    ([`step`][jswim.env.stepping.step]); a world of the protocol restates it as its
    [`StepInfo`][jswim.env.base.StepInfo]."""

    dx: Array  # x increment of the centroid (noisy when zeta > 0)
    dy: Array
    progress: Array  # direction * dx: the reward of the paper's task
    stuck: Array  # the move pushed a DOF past its limit; nothing moved
    moved: Array  # the shape changed
    x: Array  # centroid x after the step
    work: Array  # work the step's stroke did on the fluid (jswim.env.work units)


def corner_values(model: SwimmerModel, levels: Array) -> Array:
    """DOF values of the levels (0 -> lo, 1 -> hi; fractions of the range in between)."""
    return model.lo + (model.hi - model.lo) * levels


def start_orientation(model: SwimmerModel, levels: Any, xp: Any = jnp) -> Any:
    """Orientation of the reference (middle) link at the start, for start levels ``levels``.

    Purcell's swimmer (and every two-hinge swimmer) starts with its middle link along +x, the
    authors' start. Longer chains start symmetric about x: the mean link direction along +x
    (the authors' four-link start, all hinges at +2pi/9, has links at -pi/3, -pi/9, pi/9, pi/3),
    so the reference link sits at minus the mean of the link angles measured from it. Sphere
    swimmers have no orientation (0).

    Parameters
    ----------
    model : SwimmerModel
        The swimmer (static).
    levels : array (..., n_dof)
        Start levels (0 = lo, 1 = hi; fractions of the range for a shape off the corners).
    xp : module
        ``jax.numpy`` (default) or ``numpy``.

    Returns
    -------
    array (...)
        Radians.
    """
    levels = xp.asarray(levels)
    if not model.planar or model.n_dof <= 2:
        return xp.zeros(levels.shape[:-1])
    d = model.lo + (model.hi - model.lo) * levels
    zeros = xp.zeros(levels.shape[:-1] + (1,))
    cum = xp.concatenate([zeros, xp.cumsum(d, axis=-1)], axis=-1)  # link angles + const
    m = model.n_dof // 2  # the reference link, (N - 1) // 2 for N = n_dof + 1 links
    return -(xp.mean(cum, axis=-1) - cum[..., m])


def reset(key: Array, params: EnvParams) -> EnvState:
    """Start state: centroid at the origin, DOFs at ``params.init``, orientation
    [`start_orientation`][jswim.env.state.start_orientation] (0 except for chains of more than three links)."""
    n = params.model.n_dof
    init = jnp.asarray(params.init, jnp.int32)
    coin = jax.random.bernoulli(key, 0.5, (n,)).astype(jnp.int32)
    levels = jnp.where(init < 0, coin, init)
    return start_state(params.model, levels, jnp.result_type(float))


def start_state(model: SwimmerModel, levels: Array, dtype: Any = None) -> EnvState:
    """State of one swimmer at the origin with DOF ``levels`` and the start orientation
    ([`start_orientation`][jswim.env.state.start_orientation], computed in float64 and stored as a pair of ``dtype``).

    ``levels`` are corner levels (0 = lo, 1 = hi) or, for a shape off the corners, each DOF's
    fraction of its range in [0, 1] (``frac`` of [`EnvState`][jswim.env.state.EnvState]).
    """
    dtype = jnp.result_type(float) if dtype is None else dtype
    zero = jnp.zeros((), dtype)
    with jax.enable_x64(True):
        frac64 = jnp.asarray(levels, jnp.float64)
        theta = jnp.asarray(start_orientation(model, frac64), jnp.float64)
        (th, tl), (ch, cl), (sh, sl) = (
            narrow(v, dtype) for v in (theta, jnp.cos(theta), jnp.sin(theta))
        )
        fh, fl = narrow(frac64, dtype)
    return EnvState(
        fh, zero, zero, th, ch, sh, jnp.zeros((), jnp.int32), zero, zero, tl, cl, sl, fl
    )


def turned(state: EnvState, angle: Array | float) -> EnvState:
    """``state`` turned about its centroid by ``angle`` (rad, counterclockwise; the shape and
    the centroid unchanged), its orientation and its cosine and sine recomputed in float64 and
    stored as pairs of the state's dtype. ``angle = 0`` returns ``state`` as it is, bit for bit."""
    dtype = state.x.dtype
    with jax.enable_x64(True):
        theta = wide(state.theta, state.theta_lo) + jnp.asarray(angle, jnp.float64)
        (th, tl), (ch, cl), (sh, sl) = (
            narrow(v, dtype) for v in (theta, jnp.cos(theta), jnp.sin(theta))
        )
    new = state._replace(theta=th, theta_lo=tl, cos=ch, cos_lo=cl, sin=sh, sin_lo=sl)
    same = jnp.asarray(angle) == 0
    return jax.tree.map(lambda a, b: jnp.where(same, a, b), state, new)


def narrow(v: Array, dtype: Any) -> tuple[Array, Array]:
    """A float64 value as a pair ``(hi, lo)`` of ``dtype`` (``lo = 0`` when ``dtype`` is float64)."""
    hi = v.astype(dtype)
    return hi, (v - hi.astype(jnp.float64)).astype(dtype)


def wide(hi: Array, lo: Array) -> Array:
    """The float64 value ``hi + lo`` of a pair (call under ``jax.enable_x64``)."""
    return hi.astype(jnp.float64) + lo.astype(jnp.float64)


def position(state: EnvState) -> tuple[np.ndarray, np.ndarray]:
    """Full-precision centroid ``(X, Y)`` of a state or batch of states, as NumPy float64."""

    def full(hi: Array, lo: Array) -> np.ndarray:
        return np.asarray(hi, np.float64) + np.asarray(lo, np.float64)

    return full(state.x, state.x_lo), full(state.y, state.y_lo)


def fractions(state: EnvState) -> np.ndarray:
    """Full-precision ``frac`` (each DOF's place in its range) of a state or batch, NumPy float64."""
    return np.asarray(state.frac, np.float64) + np.asarray(state.frac_lo, np.float64)


def dof_values(state: EnvState, params: EnvParams) -> Array:
    """Current DOF values (hinge angles or arm lengths), working dtype, shape ``(n_dof,)``."""
    frac = state.frac + state.frac_lo
    return corner_values(params.model, frac.astype(jnp.result_type(float)))


def reference_point(state: EnvState, params: EnvParams) -> Array:
    """Lab position of the reference point: the middle link's centre for link swimmers."""
    model = params.model
    dtype = state.x.dtype
    with jax.enable_x64(True):
        d = corner_values(model, wide(state.frac, state.frac_lo))
        off = model.centroid_offset(d).astype(dtype)
    c, s = jnp.cos(state.theta), jnp.sin(state.theta)
    return jnp.stack([state.x - (c * off[0] - s * off[1]), state.y - (s * off[0] + c * off[1])])
