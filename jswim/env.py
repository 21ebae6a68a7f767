"""Functional, vectorisable environment for the discrete swimmers of Xu & Zhu.

Each DOF sits at one of two levels, ``lo`` or ``hi``. An action picks one DOF and a rate of change
ROC in {-1, 0, 1}; a step sweeps that DOF across its whole range at unit rate. A move past a limit
(ROC +1 at ``hi`` or -1 at ``lo``) produces no motion and is flagged ``stuck``; ROC 0 holds still.

Because every step starts and ends on a corner of the DOF cube and the body-frame motion does not
depend on the orientation, a step is exact when read from a per-model table of body-frame
increments (built once by :func:`jswim.integrate.integrate_stroke` in float64) and rotated by the
current orientation. Noise follows the paper: the step's centroid displacement becomes
``(dX, dY) (1 + zeta Y)`` with ``Y ~ U[-1, 1]`` drawn from the step's key (the rotation is not
perturbed; the paper perturbs the displacement only).

API in the gymnax style::

    params = make_params("purcell", zeta=0.5)
    state = reset(key, params)
    state, info = step(key, state, encode_action(1, -1), params)

Batch with ``jax.vmap(step, in_axes=(0, 0, 0, None))``; ``params`` is a pytree whose ``zeta``,
``direction`` and ``init`` leaves may also be batched.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
import math
from typing import Any, NamedTuple, Sequence

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.errors import ConfigError
from jswim.integrate import centroid, integrate_stroke
from jswim.swimmers.models import SwimmerModel, make_model

#: Rates of change an action may carry.
ROCS = (-1, 0, 1)

#: Chebyshev degree used to build the step table (error ~1e-15 relative, see tests).
TABLE_DEGREE = 32


@functools.partial(
    jax.tree_util.register_dataclass,
    data_fields=["zeta", "direction", "init"],
    meta_fields=["model"],
)
@dataclasses.dataclass(frozen=True)
class EnvParams:
    """Environment parameters.

    Attributes
    ----------
    model : SwimmerModel
        Static swimmer description (kind, number of DOFs, levels).
    zeta : float or Array
        Noise level, >= 0 (0 = the noiseless swimmer).
    direction : float or Array
        Target direction, +1 for +e_x, -1 for -e_x (sign of the reward ``progress``).
    init : Array, int32 (n_dof,)
        Initial DOF levels: 0 = lo, 1 = hi, -1 = drawn at random by :func:`reset`.
    """

    model: SwimmerModel
    zeta: Any = 0.0
    direction: Any = 1.0
    init: Any = None

    def replace(self, **changes: Any) -> "EnvParams":
        """A copy with some fields changed (fields may be traced arrays)."""
        return dataclasses.replace(self, **changes)

    @property
    def n_dof(self) -> int:
        return self.model.n_dof

    @property
    def n_actions(self) -> int:
        return 3 * self.model.n_dof

    @property
    def lo(self) -> float:
        return self.model.lo

    @property
    def hi(self) -> float:
        return self.model.hi


class EnvState(NamedTuple):
    """Swimmer state: DOF levels and the pose of the geometric centroid.

    The pose is stored as pairs ``hi + lo`` of the working dtype: the value of X is
    ``x + x_lo``, and likewise ``y``, ``theta``, ``cos`` and ``sin`` with their ``*_lo`` words.
    ``x`` alone is the nearest number of the working dtype; :func:`position` reads the full
    value. A float32 pair holds ~48 significant bits and every step is computed in float64
    (:func:`advance`), so positions do not drift: after 10^6 square-gait steps in float32, X is
    within ~1e-10 relative of the closed form (plain float32 accumulation was off by ~1 %).
    Each component is its own field so that a batch keeps it contiguous, which vectorises
    much better than ``(B, k)`` blocks.

    Bytes per swimmer: ``4 n_dof + 44`` in float32 (52 for the two-DOF swimmers), ``4 n_dof + 84``
    in float64.
    """

    levels: Array  # int32 (n_dof,), 0 = lo, 1 = hi
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

    @property
    def rot(self) -> Array:
        """``(cos theta, sin theta)`` on a last axis of size 2 (high words)."""
        return jnp.stack([self.cos, self.sin], axis=-1)


class StepInfo(NamedTuple):
    """What one step did."""

    dx: Array  # x increment of the centroid (noisy when zeta > 0)
    dy: Array
    progress: Array  # direction * dx: the reward of the paper's task
    stuck: Array  # the move pushed a DOF past its limit; nothing moved
    moved: Array  # the shape changed
    x: Array  # centroid x after the step


def make_params(
    swimmer: str | SwimmerModel = "purcell",
    *,
    zeta: float = 0.0,
    direction: int | str = 1,
    init: Sequence[int] | str | None = None,
    **model_kwargs: Any,
) -> EnvParams:
    """Validated environment parameters with the paper's defaults.

    Parameters
    ----------
    swimmer : str or SwimmerModel
        ``"purcell"``, ``"ng"``, ``"nlink"`` or ``"nsphere"``; model options (``d_max``,
        ``d_min``, ``n_links``, ``n_spheres``, ``xi_ratio``) go by keyword, see
        :func:`jswim.swimmers.models.make_model`.
    zeta : float
        Noise level, >= 0.
    direction : int or str
        +1 / ``"+x"`` or -1 / ``"-x"``.
    init : sequence of int or str, optional
        Initial configuration: levels per DOF as 0/1 (``(1, 1)``), as a sign string (``"+-"``:
        + = hi, - = lo), or ``"random"``. Default: every DOF at ``hi``, the (+, +) start.
    """
    model = swimmer if isinstance(swimmer, SwimmerModel) else make_model(swimmer, **model_kwargs)
    try:
        z = float(zeta)
    except (TypeError, ValueError):
        raise ConfigError(f"zeta must be a number, got {zeta!r}") from None
    if not (math.isfinite(z) and z >= 0):
        raise ConfigError(f"zeta (noise level) must be >= 0, got {zeta!r}")
    return EnvParams(
        model=model,
        zeta=z,
        direction=float(parse_direction(direction)),
        init=np.asarray(parse_init(init, model.n_dof), np.int32),
    )


def parse_direction(direction: int | str) -> int:
    """``+1`` / ``"+x"`` / ``"+"`` -> 1 and ``-1`` / ``"-x"`` / ``"-"`` -> -1."""
    table = {"+x": 1, "+": 1, "x": 1, "+1": 1, "1": 1, "-x": -1, "-": -1, "-1": -1}
    if isinstance(direction, str) and direction.strip().lower() in table:
        return table[direction.strip().lower()]
    if not isinstance(direction, (str, bool)) and direction in (1, -1):
        return int(direction)
    raise ConfigError(f"direction must be +1 ('+x') or -1 ('-x'), got {direction!r}")


def parse_init(init: Sequence[int] | str | None, n_dof: int) -> tuple[int, ...]:
    """Initial levels as a tuple of 0/1 (or -1 for random) of length ``n_dof``."""
    if init is None:
        return (1,) * n_dof
    if isinstance(init, str):
        text = init.strip().lower()
        if text == "random":
            return (-1,) * n_dof
        if text and all(ch in "+-" for ch in text):
            init = tuple(1 if ch == "+" else 0 for ch in text)
        else:
            raise ConfigError(
                f"init must be levels like (1, 0), a sign string like '+-', or 'random'; got {init!r}"
            )
    try:
        levels = tuple(int(v) for v in init)
    except (TypeError, ValueError):
        raise ConfigError(f"init must be a sequence of 0/1 levels, got {init!r}") from None
    if len(levels) != n_dof or any(v not in (0, 1, -1) for v in levels):
        raise ConfigError(
            f"init must give {n_dof} levels, each 0 (lo), 1 (hi) or -1 (random); got {init!r}"
        )
    return levels


def all_inits(n_dof: int) -> list[tuple[int, ...]]:
    """Every corner of the DOF cube, e.g. the four initial configurations of a 2-DOF swimmer."""
    return [tuple((c >> k) & 1 for k in range(n_dof)) for c in range(2**n_dof)][::-1]


def encode_action(dof: int, roc: int) -> int:
    """Action index of ``(dof, roc)``; ``dof`` is 1-based as in the prompt."""
    return (dof - 1) * 3 + (roc + 1)


def decode_action(action: int) -> tuple[int, int]:
    """``(dof, roc)`` of an action index."""
    return action // 3 + 1, action % 3 - 1


def validate_actions(actions: Any, n_dof: int) -> np.ndarray:
    """Check ``(dof, roc)`` pairs (last axis of size 2) and return their action indices."""
    arr = np.asarray(actions)
    if arr.ndim < 1 or arr.shape[-1] != 2 or not np.issubdtype(arr.dtype, np.number):
        raise ConfigError("actions must be (dof, roc) pairs, shape (steps, 2) or (batch, steps, 2)")
    if not np.all(arr == np.round(arr)):
        raise ConfigError("actions must be integers: dof in 1..n_dof, roc in {-1, 0, 1}")
    dof, roc = arr[..., 0].astype(int), arr[..., 1].astype(int)
    if np.any((dof < 1) | (dof > n_dof)):
        raise ConfigError(f"action dof must be in 1..{n_dof}, got {sorted(set(dof[(dof < 1) | (dof > n_dof)].tolist()))}")
    if np.any(np.abs(roc) > 1):
        raise ConfigError(f"action roc must be -1, 0 or 1, got {sorted(set(roc[np.abs(roc) > 1].tolist()))}")
    return ((dof - 1) * 3 + roc + 1).astype(np.int32)


def corner_values(model: SwimmerModel, levels: Array) -> Array:
    """DOF values of the levels (0 -> lo, 1 -> hi)."""
    return model.lo + (model.hi - model.lo) * levels


@functools.lru_cache(maxsize=64)
def step_table(model: SwimmerModel) -> tuple[np.ndarray, np.ndarray]:
    """Exact body-frame step increments of ``model`` (float64, built once per model).

    Returns
    -------
    increments : ndarray, shape (2**n_dof, n_dof, 3)
        For the corner with levels ``l`` (index ``sum_k l_k 2**k``) and a move of DOF ``k`` to the
        opposite level: centroid displacement ``(dx, dy)`` in the body frame at the start of the
        step, and the change of orientation.
    offsets : ndarray, shape (2**n_dof, 2)
        Centroid minus reference point, body frame, per corner.
    """
    n = model.n_dof
    corners = np.array([[(c >> k) & 1 for k in range(n)] for c in range(2**n)], np.float64)
    # Evaluate now even when first called while tracing a step (the table is a constant).
    with jax.ensure_compile_time_eval(), jax.enable_x64(True):
        lv = jnp.asarray(np.repeat(corners, n, axis=0))  # (2**n * n, n)
        dof = jnp.tile(jnp.arange(n), 2**n)
        sign = 1.0 - 2.0 * lv[jnp.arange(lv.shape[0]), dof]  # lo -> +1, hi -> -1
        rate = jax.nn.one_hot(dof, n, dtype=jnp.float64) * sign[:, None]
        d0 = corner_values(model, lv)
        d1 = d0 + rate * model.duration

        def one(a: Array, r: Array, b: Array) -> Array:
            pose = integrate_stroke(model, a, r, model.duration, n_sub=TABLE_DEGREE)
            disp = centroid(model, b, pose) - centroid(model, a, jnp.zeros(3))
            return jnp.concatenate([disp, pose[2:]])

        inc = jax.jit(jax.vmap(one))(d0, rate, d1)
        offs = jax.vmap(model.centroid_offset)(corner_values(model, jnp.asarray(corners)))
        return np.asarray(inc).reshape(2**n, n, 3), np.asarray(offs)


def _corner_index(levels: Array) -> Array:
    return jnp.sum(levels * (2 ** jnp.arange(levels.shape[-1], dtype=jnp.int32)), axis=-1, dtype=jnp.int32)


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
    levels : int array (..., n_dof)
        Start levels (0 = lo, 1 = hi).
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
    :func:`start_orientation` (0 except for chains of more than three links)."""
    n = params.model.n_dof
    init = jnp.asarray(params.init, jnp.int32)
    coin = jax.random.bernoulli(key, 0.5, (n,)).astype(jnp.int32)
    levels = jnp.where(init < 0, coin, init)
    return start_state(params.model, levels, jnp.result_type(float))


def start_state(model: SwimmerModel, levels: Array, dtype: Any = None) -> EnvState:
    """State of one swimmer at the origin with DOF ``levels`` and the start orientation
    (:func:`start_orientation`, computed in float64 and stored as a pair of ``dtype``)."""
    dtype = jnp.result_type(float) if dtype is None else dtype
    zero = jnp.zeros((), dtype)
    with jax.enable_x64(True):
        theta = jnp.asarray(start_orientation(model, levels), jnp.float64)
        (th, tl), (ch, cl), (sh, sl) = (_narrow(v, dtype) for v in (theta, jnp.cos(theta), jnp.sin(theta)))
    return EnvState(levels, zero, zero, th, ch, sh, jnp.zeros((), jnp.int32), zero, zero, tl, cl, sl)


def _narrow(v: Array, dtype: Any) -> tuple[Array, Array]:
    """A float64 value as a pair ``(hi, lo)`` of ``dtype`` (``lo = 0`` when ``dtype`` is float64)."""
    hi = v.astype(dtype)
    return hi, (v - hi.astype(jnp.float64)).astype(dtype)


def step(key: Array, state: EnvState, action: Array, params: EnvParams) -> tuple[EnvState, StepInfo]:
    """Advance one swimmer by one action (an index from :func:`encode_action`).

    The noise variable ``Y ~ U[-1, 1]`` is drawn from ``key``. Indices outside ``[0, 3 n_dof)``
    are clipped; validate user input with :func:`validate_actions` before it reaches a jitted
    loop.
    """
    return advance(state, action, jax.random.uniform(key, (), state.x.dtype, -1.0, 1.0), params)


def step_batch(
    key: Array, states: EnvState, actions: Array, params: EnvParams, *, start: int | Array = 0
) -> tuple[EnvState, StepInfo]:
    """Advance a batch of swimmers, drawing every swimmer's ``Y`` from the one key.

    Equivalent in law to ``jax.vmap(step)`` with one key per swimmer, but it draws all the noise
    with one counter-based hash per two swimmers instead of splitting a key per swimmer: the fast
    path for large batches. Swimmer ``i`` gets ``noise(key, n)[i]`` (see :func:`noise`), a
    function of the key and ``start + i`` only, so the numbers do not depend on how the batch is
    split into chunks or sharded over devices.

    With more than one device (``jax.devices()``) the batch axis is sharded over all of them
    (:mod:`jswim.sharding`); results are the same as on one device. Peak memory is the input and
    output states plus the infos: about ``2 (4 n_dof + 48) + 24`` bytes per swimmer in float32.

    Parameters
    ----------
    key : PRNG key
        Key of this step's noise.
    states : EnvState
        Batched states, leading axis B.
    actions : int array (B,)
        Action indices (:func:`encode_action`).
    params : EnvParams
        Shared, or with ``zeta``/``direction``/``init`` batched along B.
    start : int
        Index of the first swimmer in a larger population (even; for chunked callers).
    """
    from jswim import sharding

    n = states.x.shape[0]
    if is_batched(params):
        return sharding.apply_batched(_step_batch_jit, (key, start), (states, actions, broadcast_params(params, n)), n)
    return sharding.apply_batched(
        lambda k, s0, p, st, a: _step_batch_jit(k, s0, st, a, p), (key, start, params), (states, actions), n
    )


@jax.jit
def _step_batch_jit(key: Array, start: Array, states: EnvState, actions: Array, params: EnvParams):
    y = noise(key, actions.shape[0], start=start).astype(states.x.dtype)
    return jax.vmap(advance, in_axes=(0, 0, 0, param_axes(params)))(states, actions, y, params)


def is_batched(params: EnvParams) -> bool:
    """Whether any data leaf of ``params`` carries a batch axis."""
    return jnp.ndim(params.zeta) > 0 or jnp.ndim(params.direction) > 0 or jnp.ndim(params.init) > 1


def param_axes(params: EnvParams) -> EnvParams:
    """``vmap`` axes of ``params``: 0 for batched leaves, None for shared ones."""
    return params.replace(
        zeta=0 if jnp.ndim(params.zeta) > 0 else None,
        direction=0 if jnp.ndim(params.direction) > 0 else None,
        init=0 if jnp.ndim(params.init) > 1 else None,
    )


def broadcast_params(params: EnvParams, size: int, **changes: Any) -> EnvParams:
    """Broadcast the data leaves of ``params`` (after ``changes``) to a leading axis of ``size``.

    ``changes`` may give per-swimmer values, e.g. ``zeta=np.linspace(0, 3, size)``.
    """
    n = params.model.n_dof
    fields = {"zeta": params.zeta, "direction": params.direction, "init": params.init, **changes}
    dtype = jnp.result_type(float)
    return params.replace(
        zeta=jnp.broadcast_to(jnp.asarray(fields["zeta"], dtype), (size,)),
        direction=jnp.broadcast_to(jnp.asarray(fields["direction"], dtype), (size,)),
        init=jnp.broadcast_to(jnp.asarray(fields["init"], jnp.int32), (size, n)),
    )


def noise(key: Array, n: int, *, start: int | Array = 0, step: int | Array = 0) -> Array:
    """The noise variables ``Y ~ U[-1, 1)`` of swimmers ``start .. start + n - 1`` (float32).

    Counter-based: swimmers ``2j`` and ``2j + 1`` share one Threefry-2x32 hash of the counter
    block ``(step, j)`` under ``key`` (one word each), so any slice of a population can be drawn
    on its own, on any device, and gives the numbers the whole draw would. ``start`` must be
    even. 23 random bits per variable (the float32 mantissa), also in float64 mode: the noise
    is the same in both precisions.
    """
    import jax.extend.random as jer

    m = (n + 1) // 2
    kd = jax.random.key_data(key) if jnp.issubdtype(key.dtype, jax.dtypes.prng_key) else key
    kd = jnp.asarray(kd, jnp.uint32).reshape(2)
    j = (jnp.asarray(start, jnp.uint32) // 2) + jnp.arange(m, dtype=jnp.uint32)
    t = jnp.broadcast_to(jnp.asarray(step, jnp.uint32), (m,))
    w0, w1 = jer.threefry2x32_p.bind(kd[0], kd[1], t, j)
    bits = jnp.stack([w0, w1], axis=-1).reshape(-1)[:n]
    u = jax.lax.bitcast_convert_type((bits >> 9) | jnp.uint32(0x3F800000), jnp.float32) - 1.0
    return 2.0 * u - 1.0


def uniforms(key: Array, shape: tuple[int, ...], dtype: Any, minval: float = 0.0, maxval: float = 1.0) -> Array:
    """``jax.random.uniform`` under the non-partitionable threefry.

    It uses both words of each hash, so it costs about half as much on CPU, and gives the same
    numbers whether or not it is vmapped (the Q-learner draws its run's uniforms with it).
    """
    with jax.threefry_partitionable(False):
        return jax.random.uniform(key, shape, dtype, minval, maxval)


def advance(
    state: EnvState, action: Array, y_noise: Array, params: EnvParams, *, exact: bool = True
) -> tuple[EnvState, StepInfo]:
    """One step with a given noise variable ``y_noise`` in [-1, 1] (the core of :func:`step`).

    With ``exact`` (the default, and what every environment entry point uses) the pose is
    stored as pairs ``hi + lo`` of the working dtype; the step itself is computed in float64
    (under ``jax.enable_x64``, whatever the global setting) from the float64 table, and the new
    pose is split back into pairs. In float32 a pair holds ~48 bits, so positions, orientation
    and the carried rotation neither drift nor lose the table's accuracy.

    ``exact=False`` steps in plain working-dtype arithmetic (about 2.3 x less CPU time per step
    in float32) and leaves the low words of the position as they are: for short runs where
    only the step's reward matters, e.g. the baselines' 200-step training runs (drift there
    stays below ~1e-5 a). ``StepInfo`` reports values rounded to the working dtype.
    """
    model = params.model
    n = model.n_dof
    dtype = state.x.dtype
    action = jnp.clip(jnp.asarray(action, jnp.int32), 0, 3 * n - 1)
    dof, roc = action // 3, action % 3 - 1
    # One-hot arithmetic instead of gather/scatter on the levels: much cheaper under vmap.
    onehot = (jnp.arange(n, dtype=jnp.int32) == dof).astype(jnp.int32)
    level = jnp.sum(state.levels * onehot, dtype=jnp.int32)
    stuck = ((roc == 1) & (level == 1)) | ((roc == -1) & (level == 0))
    moved = (roc != 0) & ~stuck
    # One gather per step; the table's last row is the identity step (nothing moved).
    row = jnp.where(moved, _corner_index(state.levels) * n + dof, _still_row(model))
    levels = state.levels + onehot * moved.astype(jnp.int32) * (1 - 2 * level)
    if not exact:
        return _advance_plain(state, levels, row, y_noise, params, stuck, moved)
    with jax.enable_x64(True):
        f64 = jnp.float64

        def wide(hi: Array, lo: Array) -> Array:
            return hi.astype(f64) + lo.astype(f64)

        entry = jnp.asarray(_step_rows(model), f64)[row]
        factor = 1.0 + jnp.asarray(params.zeta, f64) * jnp.asarray(y_noise, f64)
        x, y, theta = wide(state.x, state.x_lo), wide(state.y, state.y_lo), wide(state.theta, state.theta_lo)
        c, s = wide(state.cos, state.cos_lo), wide(state.sin, state.sin_lo)
        if model.planar:
            dx = (c * entry[0] - s * entry[1]) * factor
            dy = (s * entry[0] + c * entry[1]) * factor
            # Compose rotations as unit complex numbers: no sin/cos per step.
            c, s = c * entry[3] - s * entry[4], s * entry[3] + c * entry[4]
        else:
            dx, dy = entry[0] * factor, jnp.zeros((), f64)
        x, y, theta = x + dx, y + dy, theta + entry[2]

        (xh, xl), (yh, yl), (th, tl), (ch, cl), (sh, sl) = (_narrow(v, dtype) for v in (x, y, theta, c, s))
        dxh, dyh = dx.astype(dtype), dy.astype(dtype)
        progress = (jnp.asarray(params.direction, f64) * dx).astype(dtype)
    new = EnvState(levels, xh, yh, th, ch, sh, state.t + 1, xl, yl, tl, cl, sl)
    return new, StepInfo(dxh, dyh, progress, stuck, moved, new.x)


def _advance_plain(state: EnvState, levels: Array, row: Array, y_noise: Array, params: EnvParams,
                   stuck: Array, moved: Array) -> tuple[EnvState, StepInfo]:
    """:func:`advance` with ``exact=False``: the same step in working-dtype arithmetic."""
    dtype = state.x.dtype
    entry = jnp.asarray(_step_rows(params.model), dtype)[row]
    factor = 1.0 + jnp.asarray(params.zeta, dtype) * jnp.asarray(y_noise, dtype)
    c, s = state.cos, state.sin
    if params.model.planar:
        dx = (c * entry[0] - s * entry[1]) * factor
        dy = (s * entry[0] + c * entry[1]) * factor
        c, s = c * entry[3] - s * entry[4], s * entry[3] + c * entry[4]
    else:
        dx, dy = entry[0] * factor, jnp.zeros((), dtype)
    zero = jnp.zeros((), dtype)
    new = state._replace(levels=levels, x=state.x + dx, y=state.y + dy, theta=state.theta + entry[2], cos=c, sin=s,
                         t=state.t + 1, cos_lo=zero, sin_lo=zero)
    progress = jnp.asarray(params.direction, dtype) * dx
    return new, StepInfo(dx, dy, progress, stuck, moved, new.x)


@functools.lru_cache(maxsize=64)
def _flat_table(model: SwimmerModel) -> np.ndarray:
    """Step table as rows ``(dx, dy, dtheta, cos dtheta, sin dtheta)`` indexed by corner*n + dof."""
    inc = step_table(model)[0].reshape(-1, 3)
    return np.concatenate([inc, np.cos(inc[:, 2:]), np.sin(inc[:, 2:])], axis=1)


@functools.lru_cache(maxsize=64)
def _step_rows(model: SwimmerModel) -> np.ndarray:
    """:func:`_flat_table` (float64) plus a last row for a step that moves nothing."""
    return np.concatenate([_flat_table(model), [[0.0, 0.0, 0.0, 1.0, 0.0]]])


def _still_row(model: SwimmerModel) -> int:
    return 2**model.n_dof * model.n_dof


def position(state: EnvState) -> tuple[np.ndarray, np.ndarray]:
    """Full-precision centroid ``(X, Y)`` of a state or batch of states, as NumPy float64."""

    def full(hi: Array, lo: Array) -> np.ndarray:
        return np.asarray(hi, np.float64) + np.asarray(lo, np.float64)

    return full(state.x, state.x_lo), full(state.y, state.y_lo)


def dof_values(state: EnvState, params: EnvParams) -> Array:
    """Current DOF values (hinge angles or arm lengths)."""
    return corner_values(params.model, state.levels.astype(jnp.result_type(float)))


def reference_point(state: EnvState, params: EnvParams) -> Array:
    """Lab position of the reference point: the middle link's centre for link swimmers."""
    _, offsets = step_table(params.model)
    off = jnp.asarray(offsets, jnp.result_type(float))[_corner_index(state.levels)]
    c, s = jnp.cos(state.theta), jnp.sin(state.theta)
    return jnp.stack([state.x - (c * off[0] - s * off[1]), state.y - (s * off[0] + c * off[1])])


class Rollout(NamedTuple):
    """Per-step record of a rollout (state after each step); leading axes (batch, steps).

    ``x``, ``y`` and ``orientation`` are the full values (``hi + lo``) rounded to the working
    dtype (float64 in :func:`rollout`)."""

    x: Array
    y: Array
    orientation: Array
    dofs: Array
    stuck: Array
    progress: Array


@functools.partial(jax.jit, static_argnames=())
def _scan(key: Array, actions: Array, params: EnvParams) -> Rollout:
    state = reset(key, params)
    keys = jax.random.split(key, actions.shape[0])

    def body(st: EnvState, inp: tuple[Array, Array]) -> tuple[EnvState, Rollout]:
        k, a = inp
        st, info = step(k, st, a, params)
        return st, Rollout(st.x + st.x_lo, st.y + st.y_lo, st.theta + st.theta_lo, dof_values(st, params),
                           info.stuck, info.progress)

    _, out = jax.lax.scan(body, state, (keys, actions))
    return out


def seed32(seed: int) -> int:
    """A seed :func:`jax.random.PRNGKey` takes, from any integer: ``seed`` itself in
    ``[0, 2**32)`` (so existing seeds keep their streams), else a 32-bit BLAKE2b hash of it
    (negative or huge seeds: ``--seed -1``, ``--seed 2**70``)."""
    seed = int(seed)
    if 0 <= seed < 2**32:
        return seed
    return int.from_bytes(hashlib.blake2b(str(seed).encode(), digest_size=4).digest(), "little")


def seed_key(seed: int) -> Array:
    """``jax.random.PRNGKey(seed32(seed))``: a key from any integer seed."""
    return jax.random.PRNGKey(seed32(seed))


def rollout(
    swimmer: str | SwimmerModel,
    actions: Any,
    *,
    key: Array | int = 0,
    zeta: float = 0.0,
    direction: int | str = 1,
    init: Sequence[int] | str | None = None,
    **model_kwargs: Any,
) -> Rollout:
    """Run a given action sequence for one swimmer or a batch.

    Parameters
    ----------
    swimmer : str
        ``"purcell"`` or ``"ng"`` (or ``"nlink"``, ``"nsphere"``).
    actions : array-like of int, shape (steps, 2) or (batch, steps, 2)
        ``(dof, roc)`` pairs: dof in 1..n_dof, roc in {-1, 0, 1}.
    key : jax key or int
        Seed of the noise (only used when ``zeta > 0`` or ``init="random"``); batch members get
        independent keys split from it.
    zeta, direction, init, **model_kwargs
        As in :func:`make_params` (``d_max``, ``d_min``, ...).

    Returns
    -------
    Rollout
        ``x``, ``y`` (centroid), ``orientation``, ``dofs``, ``stuck``, ``progress``: one entry per
        step, the state after the step; NumPy arrays, float64 whatever ``jax_enable_x64`` says
        (the rollout runs under ``jax.enable_x64(True)``: ~1e-16 relative per cycle). A batch is
        sharded over every device; it holds ``8 (4 + n_dof) + 2`` bytes per swimmer and step.

    Examples
    --------
    >>> r = rollout("purcell", [(1, -1), (2, -1), (1, 1), (2, 1)])
    >>> r.x.shape
    (4,)
    """
    from jswim import sharding

    params = make_params(swimmer, zeta=zeta, direction=direction, init=init, **model_kwargs)
    idx = validate_actions(actions, params.n_dof)
    if idx.ndim not in (1, 2):
        raise ConfigError("actions must have shape (steps, 2) or (batch, steps, 2)")
    # float64 whatever the global setting: this is the path physicists check numbers with.
    with jax.enable_x64(True):
        if isinstance(key, int):
            key = seed_key(key)
        if idx.ndim == 1:
            out = _scan(key, jnp.asarray(idx), params)
        else:
            keys = jax.random.split(key, idx.shape[0])
            out = sharding.apply_batched(_scan_batch, (params,), (keys, jnp.asarray(idx)), idx.shape[0])
        return Rollout(*(np.asarray(v) for v in out))


@jax.jit
def _scan_batch(params: EnvParams, keys: Array, actions: Array) -> Rollout:
    return jax.vmap(_scan, in_axes=(0, 0, None))(keys, actions, params)
