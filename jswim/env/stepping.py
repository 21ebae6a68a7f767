"""Stepping: one action moves one DOF at a rate of change ROC in [-1, 1] for one step.

A step moves the DOF by ``ROC x (hi - lo)``, stopping at a limit: a push past a limit moves only
up to it (at its ROC, then the shape holds for the rest of the step, which a flow still acts on
and the work does not count), and a move that cannot change the shape at all (ROC +1 at ``hi``, -1 at ``lo``) is
flagged ``stuck``; ROC 0 holds still. At zero Reynolds number the motion depends on the path in
shape space only, not on the rate, and the body-frame motion does not depend on the
orientation. So:

* the paper's discrete world (integer codes with K = 1: every step from corner to corner) reads
  each step from the corner table (`jswim.env.step_table`) and rotates it by the current
  orientation;
* any other step (integer codes on the K lattice, float ROC vectors) integrates its path with
  the spectral integrator ([`jswim.integrate.integrate_stroke`][jswim.integrate.integrate_stroke], float64); a diagonal stroke
  whose DOFs reach their limits at different times is integrated piece by piece along its bent
  path.

Noise follows the paper: the step's centroid displacement becomes ``(dX, dY) (1 + zeta Y)`` with
``Y ~ U[-1, 1]`` drawn from the step's key (the rotation is not perturbed; the paper perturbs the
displacement only).

In a background flow (``params.flow``) a `Uniform` stream adds ``u`` to the table step (exact);
any other flow adds what [`jswim.env.flow_tables`][jswim.env.flow_tables] reads for the step's
table row ([`jswim.env.flow_steps`][jswim.env.flow_steps]: one flow evaluation, second order
in the flow), and steps off the tables, or in an
[`Integrated`][jswim.env.flow_steps.Integrated] flow, are integrated through it
([`flow_step`][jswim.env.stepping.flow_step], RK4: the reference the tables are measured
against).
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
from jax import Array

from jswim.action_codes import decode_action
from jswim.env.params import EnvParams, broadcast_params, is_batched, param_axes
from jswim.env import motion
from jswim.env.randomness import noise
from jswim.env.state import EnvState, MoveInfo, corner_values, narrow, wide
from jswim.env.step_tables import (
    MAX_LATTICE_ROWS,
    corner_index,
    step_rows,
    still_row,
    lattice_rows,
    lattice_table,
)
from jswim.env.work import corner_work_table, lattice_work_table, step_work
from jswim.env.flows import Uniform
from jswim.env.flow_steps import Integrated, flow_increment, tabulated
from jswim.env.flow_tables import corner_flow_row, flow_table, gather_row, lattice_flow_row
from jswim.integrate import centroid, integrate_stroke
from jswim.swimmers.flow_response import flow_velocity
from jswim import sharding

#: How one-DOF moves off the corner table are computed: ``"table"`` (the motion table, for
#: two-DOF swimmers) or ``"integrator"``.
STEP_METHOD = "table"

#: Chebyshev degree of the integrator path for steps off the corner table (~1e-15 relative).
INTEGRATOR_DEGREE = 24

#: RK4 pieces of a step integrated through a non-uniform flow (`flow_step`, the reference).
FLOW_SUBSTEPS = 16


def step(
    key: Array, state: EnvState, action: Array, params: EnvParams
) -> tuple[EnvState, MoveInfo]:
    """Advance one swimmer by one action.

    ``action`` is an integer code ([`jswim.env.encode_action`][jswim.action_codes.encode_action], ROC ``k / K`` with
    ``K = params.roc_levels``) or a float ROC vector of shape ``(n_dof,)`` with entries in
    [-1, 1] (see [`jswim.env.action_input`][jswim.env.action_input]). The noise variable ``Y ~ U[-1, 1]`` is drawn from
    ``key``. Codes outside ``[0, n_actions)`` are clipped and ROCs clipped to [-1, 1]; validate
    user input with [`jswim.env.validate_actions`][jswim.env.action_input.validate_actions] / [`jswim.env.validate_moves`][jswim.env.action_input.validate_moves] before it
    reaches a jitted loop.
    """
    return advance(state, action, jax.random.uniform(key, (), state.x.dtype, -1.0, 1.0), params)


def step_batch(
    key: Array, states: EnvState, actions: Array, params: EnvParams, *, start: int | Array = 0
) -> tuple[EnvState, MoveInfo]:
    """Advance a batch of swimmers, drawing every swimmer's ``Y`` from the one key.

    Equivalent in law to ``jax.vmap(step)`` with one key per swimmer, but it draws all the noise
    with one counter-based hash per two swimmers instead of splitting a key per swimmer: the fast
    path for large batches. Swimmer ``i`` gets ``noise(key, n)[i]`` (see
    [`jswim.env.noise`][jswim.env.randomness.noise]), a function of the key and ``start + i`` only, so the numbers do not
    depend on how the batch is split into chunks or sharded over devices.

    With more than one device (``jax.devices()``) the batch axis is sharded over all of them
    (`jswim.sharding`); results are the same as on one device. Peak memory is the input and
    output states plus the infos: about ``2 (8 n_dof + 48) + 24`` bytes per swimmer in float32.

    Parameters
    ----------
    key : PRNG key
        Key of this step's noise.
    states : EnvState
        Batched states, leading axis B.
    actions : int array (B,) or float array (B, n_dof)
        Integer codes ([`jswim.env.encode_action`][jswim.action_codes.encode_action]) or float ROC vectors.
    params : EnvParams
        Shared, or with ``zeta``/``direction``/``init`` batched along B.
    start : int
        Index of the first swimmer in a larger population (even; for chunked callers).
    """
    n = states.x.shape[0]
    if is_batched(params):
        return sharding.apply_batched(
            _step_batch_jit, (key, start), (states, actions, broadcast_params(params, n)), n
        )
    return sharding.apply_batched(
        lambda k, s0, p, st, a: _step_batch_jit(k, s0, st, a, p),
        (key, start, params),
        (states, actions),
        n,
    )


@jax.jit
def _step_batch_jit(key: Array, start: Array, states: EnvState, actions: Array, params: EnvParams):
    y = noise(key, actions.shape[0], start=start).astype(states.x.dtype)
    return jax.vmap(advance, in_axes=(0, 0, 0, param_axes(params)))(states, actions, y, params)


def advance(
    state: EnvState, action: Array, y_noise: Array, params: EnvParams, *, exact: bool = True
) -> tuple[EnvState, MoveInfo]:
    """One step with a given noise variable ``y_noise`` in [-1, 1] (the core of [`step`][jswim.env.stepping.step]).

    ``action`` is an integer code or a float ROC vector ``(n_dof,)``; the choice of path is
    static (by dtype and ``params.roc_levels``). Integer codes with K = 1 (the paper's world)
    assume the state is on a corner of the DOF cube, and codes with K > 1 that it is on the K
    lattice (``frac`` a multiple of 1/K): true of every state reached from a corner start by such
    codes. Use float ROC vectors for anything else.

    With ``exact`` (the default, and what every environment entry point uses) the pose is
    stored as pairs ``hi + lo`` of the working dtype; the step itself is computed in float64
    (under ``jax.enable_x64``, whatever the global setting) from the float64 table or the
    integrator, and the new pose is split back into pairs. In float32 a pair holds ~48 bits, so
    positions, orientation, the carried rotation and the shape neither drift nor lose the
    table's accuracy.

    ``exact=False`` steps the paper's world (integer codes, K = 1) in plain working-dtype
    arithmetic (about 2.3 x less CPU time per step in float32) and leaves the low words of the
    position as they are: for short runs where only the step's reward matters, e.g. the
    baselines' 200-step training runs (drift there stays below ~1e-5 a). Other actions ignore
    it. ``MoveInfo`` reports values rounded to the working dtype.
    """
    action = jnp.asarray(action)
    if jnp.issubdtype(action.dtype, jnp.integer) or jnp.issubdtype(action.dtype, jnp.bool_):
        if action.ndim != 0:
            raise ValueError(f"an integer action code is a scalar, got shape {action.shape}")
        if params.roc_levels == 1:
            return _advance_corner(state, action, y_noise, params, exact)
        return _advance_lattice(state, action, y_noise, params)
    if action.shape != (params.model.n_dof,):
        raise ValueError(
            f"a float action is a ROC vector of shape ({params.model.n_dof},), got {action.shape}"
        )
    return _advance_rocs(state, action, y_noise, params)


def _advance_corner(
    state: EnvState, action: Array, y_noise: Array, params: EnvParams, exact: bool
) -> tuple[EnvState, MoveInfo]:
    """The paper's discrete step: corner to corner, read from the corner table."""
    model = params.model
    n = model.n_dof
    action = jnp.clip(action.astype(jnp.int32), 0, 3 * n - 1)
    dof, roc = decode_action(action)
    dof = dof - 1
    # Integer one-hot arithmetic on the corner levels (exactly 0/1 on the corners) instead of
    # gather/scatter: much cheaper under vmap, and as fast as the int32 levels it replaced.
    onehot = (jnp.arange(n, dtype=jnp.int32) == dof).astype(jnp.int32)
    levels = state.frac.astype(jnp.int32)
    level = jnp.sum(levels * onehot, dtype=jnp.int32)
    stuck = ((roc == 1) & (level == 1)) | ((roc == -1) & (level == 0))
    moved = (roc != 0) & ~stuck
    # One gather per step; the table's last row is the identity step (nothing moved).
    row = jnp.where(moved, corner_index(levels) * n + dof, still_row(model))
    frac = (levels + onehot * moved.astype(jnp.int32) * (1 - 2 * level)).astype(state.frac.dtype)
    if not exact and not _moving_fluid(params):  # a non-uniform flow: the float64 path
        work = jnp.asarray(corner_work_table(model), state.x.dtype)[row]
        return _advance_plain(state, frac, row, y_noise, params, stuck, moved, work)
    flow_index = corner_flow_row(corner_index(levels), dof, moved, n)
    with jax.enable_x64(True):
        entry = jnp.asarray(step_rows(model), jnp.float64)[row]
        work = jnp.asarray(corner_work_table(model), jnp.float64)[row]
        flow_row = _flow_row(params, None, flow_index)
    return _apply(state, entry, y_noise, params, stuck, moved, frac, state.frac_lo, work, flow_row)


def _advance_lattice(
    state: EnvState, action: Array, y_noise: Array, params: EnvParams
) -> tuple[EnvState, MoveInfo]:
    """An integer code on the K lattice: ROC ``k / K``; the new shape is the lattice point
    ``round(K frac) + k`` (clipped to ``0..K``) over K, computed afresh so it never drifts. The
    step is read from the lattice table (`jswim.env.step_tables.lattice_table`, one gather like
    the corner table) when it is small enough, else integrated."""
    model = params.model
    n, big_k = model.n_dof, params.roc_levels
    width = 2 * big_k + 1
    action = jnp.clip(action.astype(jnp.int32), 0, width * n - 1)
    dof, k = action // width, action % width - big_k
    onehot = (jnp.arange(n, dtype=jnp.int32) == dof).astype(jnp.int32)
    j0 = jnp.round(state.frac * big_k).astype(jnp.int32)
    j1 = j0 + onehot * (jnp.clip(jnp.sum(j0 * onehot) + k, 0, big_k) - jnp.sum(j0 * onehot))
    moved = jnp.any(j1 != j0)
    stuck = (k != 0) & ~moved
    if lattice_rows(model, big_k) <= MAX_LATTICE_ROWS:
        shape = jnp.sum(j0 * (big_k + 1) ** jnp.arange(n, dtype=jnp.int32), dtype=jnp.int32)
        row = (shape * n + dof) * (big_k + 1) + jnp.sum(j1 * onehot)
        # A push clipped at a limit moves |j1 - j0| lattice units at ROC k / K, then holds: it
        # costs |k| / |j1 - j0| times the row's work (the row holds the move at the ROC that
        # lands on j1), and in a flow it has its own row (the held part feels the flow too).
        step = jnp.abs(jnp.sum((j1 - j0) * onehot))
        count = jnp.maximum(step, 1)
        flow_index = lattice_flow_row(shape, dof, k, n, big_k)
        with jax.enable_x64(True):
            entry = jnp.asarray(lattice_table(model, big_k), jnp.float64)[row]
            fh, fl = narrow(j1.astype(jnp.float64) / big_k, state.frac.dtype)
            table = jnp.asarray(lattice_work_table(model, big_k), jnp.float64)
            scale = jnp.abs(k).astype(jnp.float64) / count.astype(jnp.float64)
            work = jnp.where(step > 0, table[row] * scale, 0.0)
            flow_row = _flow_row(params, big_k, flow_index)
            duration = jnp.where(step > 0, 1.0 / jnp.where(step > 0, scale, 1.0), 1.0)
        return _apply(state, entry, y_noise, params, stuck, moved, fh, fl, work, flow_row, duration)
    with jax.enable_x64(True):
        s0, s1 = j0.astype(jnp.float64) / big_k, j1.astype(jnp.float64) / big_k
        rocs = onehot.astype(jnp.float64) * k.astype(jnp.float64) / big_k
        return _advance_path(
            state,
            s0,
            s1,
            y_noise,
            params,
            requested=k != 0,
            dof=dof,
            work=step_work(model, s0, rocs),
            duration=_move_time(s0, s1, rocs),
        )


def _advance_rocs(
    state: EnvState, rocs: Array, y_noise: Array, params: EnvParams
) -> tuple[EnvState, MoveInfo]:
    """A float ROC vector: each moving DOF at its ROC, stopping at its limit."""
    n = params.model.n_dof
    # Integer work outside the float64 block (its index types would not match the caller's).
    first = jnp.argmax(rocs != 0).astype(jnp.int32)
    keep = (jnp.arange(n, dtype=jnp.int32) == first) | params.diagonal
    with jax.enable_x64(True):
        r = jnp.where(keep, jnp.clip(rocs.astype(jnp.float64), -1.0, 1.0), 0.0)  # one DOF at a time
        s0 = wide(state.frac, state.frac_lo)
        s1 = jnp.clip(s0 + r, 0.0, 1.0)
        requested = jnp.any(r != 0)
        return _advance_path(
            state,
            s0,
            s1,
            y_noise,
            params,
            requested=requested,
            rocs=r,
            dof=None if params.diagonal else first,
            work=step_work(params.model, s0, r),
            duration=None if params.diagonal else _move_time(s0, s1, r),
        )


def _move_time(s0: Array, s1: Array, rocs: Array) -> Array:
    """The part of the step (``tau``) a one-DOF move ``s0 -> s1`` at ROCs ``rocs`` takes: 1, or
    less for a push past a limit, which moves at its ROC until the limit and then holds (float64;
    1 for a step that moves nothing)."""
    moved = jnp.sum(jnp.abs(s1 - s0))
    rate = jnp.sum(jnp.abs(rocs))
    return jnp.where(moved > 0, jnp.minimum(moved / jnp.where(moved > 0, rate, 1.0), 1.0), 1.0)


def _advance_path(
    state: EnvState,
    s0: Array,
    s1: Array,
    y_noise: Array,
    params: EnvParams,
    *,
    requested: Array,
    rocs: Array | None = None,
    dof: Array | None = None,
    method: str | None = None,
    work: Array,
    duration: Array | None = None,
) -> tuple[EnvState, MoveInfo]:
    """Move the shape from ``s0`` to ``s1`` (float64 fractions of the range), integrating the path;
    ``work`` is the step's work (float64, [`jswim.env.work`][jswim.env.work]); ``duration``
    the part of the step a one-DOF move takes before it holds (`flow_step`; None: all of it).

    With ``rocs`` and ``params.diagonal`` the path is the one the motors follow:
    ``clip(s0 + rocs t, 0, 1)`` for ``t`` in [0, 1], straight until a DOF reaches its limit.
    """
    model = params.model
    with jax.enable_x64(True):
        moved = jnp.any(s1 != s0)
        stuck = requested & ~moved
        method = method or STEP_METHOD
        if rocs is not None and params.diagonal:
            entry = _path_increment(model, s0, rocs)
        elif dof is not None and method == "table" and motion.supported(model):
            entry = motion.move_increment(model, s0, s1, dof)
        else:
            entry = _segment_increment(model, s0, s1)
        fh, fl = narrow(s1, state.frac.dtype)
    return _apply(state, entry, y_noise, params, stuck, moved, fh, fl, work, None, duration)


def _segment_increment(model: Any, s0: Array, s1: Array) -> Array:
    """Body-frame step row ``(dx, dy, dtheta, cos, sin)`` of the straight move ``s0 -> s1``."""
    span = model.hi - model.lo
    d0, d1 = corner_values(model, s0), corner_values(model, s1)
    pose = integrate_stroke(model, d0, (s1 - s0) * span, 1.0, n_sub=INTEGRATOR_DEGREE, dotless=True)
    disp = centroid(model, d1, pose) - centroid(model, d0, jnp.zeros(3, jnp.float64))
    return jnp.stack([disp[0], disp[1], pose[2], jnp.cos(pose[2]), jnp.sin(pose[2])])


def _path_increment(model: Any, s0: Array, rocs: Array) -> Array:
    """Step row of the bent path ``clip(s0 + rocs t, 0, 1)``, ``t`` in [0, 1]: one straight
    piece between consecutive times at which a DOF reaches its limit."""
    span = model.hi - model.lo
    room = jnp.where(rocs > 0, 1.0 - s0, s0)
    hit = jnp.where(
        rocs != 0, jnp.clip(room / jnp.where(rocs != 0, jnp.abs(rocs), 1.0), 0.0, 1.0), 1.0
    )
    times = jnp.concatenate([jnp.zeros(1), jnp.sort(hit)])
    pose = jnp.zeros(3, jnp.float64)
    for i in range(model.n_dof):  # n_dof pieces (static), some of length 0
        ta, tb = times[i], times[i + 1]
        rate = jnp.where(hit >= tb, rocs, 0.0) * span
        start = jnp.clip(s0 + rocs * ta, 0.0, 1.0)
        pose = integrate_stroke(
            model,
            corner_values(model, start),
            rate,
            tb - ta,
            pose,
            n_sub=INTEGRATOR_DEGREE,
            dotless=True,
        )
    d0, d1 = corner_values(model, s0), corner_values(model, jnp.clip(s0 + rocs, 0.0, 1.0))
    disp = centroid(model, d1, pose) - centroid(model, d0, jnp.zeros(3, jnp.float64))
    return jnp.stack([disp[0], disp[1], pose[2], jnp.cos(pose[2]), jnp.sin(pose[2])])


def _apply(
    state: EnvState,
    entry: Array,
    y_noise: Array,
    params: EnvParams,
    stuck: Array,
    moved: Array,
    frac: Array,
    frac_lo: Array,
    work: Array,
    flow_row: tuple[Array, ...] | None = None,
    duration: Array | float | None = None,
) -> tuple[EnvState, MoveInfo]:
    """Apply a body-frame step row ``(dx, dy, dtheta, cos dtheta, sin dtheta)`` (float64) to the
    pose, with the paper's noise on the displacement, in float64; store the result as pairs.
    ``work`` (float64; the noise does not touch it) is reported in the working dtype. In a
    non-uniform flow ``flow_row`` (float64, `jswim.env.flow_tables.flow_table`) is the step's row,
    or None to integrate the step (`flow_step`, the move taking the first ``duration`` of the
    step, then held; None: the whole step)."""
    model = params.model
    dtype = state.x.dtype
    with jax.enable_x64(True):
        f64 = jnp.float64
        entry = entry.astype(f64)
        factor = 1.0 + jnp.asarray(params.zeta, f64) * jnp.asarray(y_noise, f64)
        x, y, theta = (
            wide(state.x, state.x_lo),
            wide(state.y, state.y_lo),
            wide(state.theta, state.theta_lo),
        )
        c0, s0 = wide(state.cos, state.cos_lo), wide(state.sin, state.sin_lo)
        if model.planar:
            dx0, dy0 = c0 * entry[0] - s0 * entry[1], s0 * entry[0] + c0 * entry[1]
            # Compose rotations as unit complex numbers: no sin/cos per step.
            c, s = c0 * entry[3] - s0 * entry[4], s0 * entry[3] + c0 * entry[4]
        else:
            c, s = c0, s0
            dx0, dy0 = entry[0], jnp.zeros((), f64)
        dx, dy = dx0 * factor, dy0 * factor
        turn = entry[2]
        # In a moving fluid the paper's noise stays on the stroke's own (still-fluid)
        # displacement: dX (1 + zeta Y) there, as without a flow, plus what the flow adds.
        if _moving_fluid(params) and flow_row is not None:
            fx, fy, extra, ce, se = flow_increment(params.flow, flow_row, entry[:2], x, y, c0, s0)
            dx, dy = dx + c0 * fx - s0 * fy, dy + s0 * fx + c0 * fy
            turn = turn + extra
            c, s = c * ce - s * se, s * ce + c * se
        elif _moving_fluid(params):  # integrated through the flow: the reference
            flow, n_sub = params.flow, None
            if isinstance(flow, Integrated):
                flow, n_sub = flow.flow, flow.substeps
            a, b = wide(state.frac, state.frac_lo), wide(frac, frac_lo).astype(f64)
            pose = jnp.stack([x, y, theta])
            fx, fy, turn = flow_step(model, flow, a, b, pose, n_sub, duration=duration)
            dx, dy = fx + (factor - 1.0) * dx0, fy + (factor - 1.0) * dy0
            c, s = jnp.cos(theta + turn), jnp.sin(theta + turn)
        elif params.flow is not None:  # a uniform stream carries the body one u per step (tau = 1)
            dx = dx + jnp.asarray(params.flow.u[0], f64)
            dy = dy + jnp.asarray(params.flow.u[1], f64)
        x, y, theta = x + dx, y + dy, theta + turn

        (xh, xl), (yh, yl), (th, tl), (ch, cl), (sh, sl) = (
            narrow(v, dtype) for v in (x, y, theta, c, s)
        )
        dxh, dyh = dx.astype(dtype), dy.astype(dtype)
        progress = (jnp.asarray(params.direction, f64) * dx).astype(dtype)
        work = jnp.asarray(work, f64).astype(dtype)
    new = EnvState(
        frac.astype(dtype),
        xh,
        yh,
        th,
        ch,
        sh,
        state.t + 1,
        xl,
        yl,
        tl,
        cl,
        sl,
        frac_lo.astype(dtype),
    )
    return new, MoveInfo(dxh, dyh, progress, stuck, moved, new.x, work)


def _moving_fluid(params: EnvParams) -> bool:
    """Whether the step goes through a non-uniform flow (any flow but a uniform one)."""
    return params.flow is not None and not isinstance(params.flow, Uniform)


def _flow_row(params: EnvParams, roc_levels: int | None, index: Array) -> tuple[Array, ...] | None:
    """The step's `jswim.env.flow_tables.flow_table` row (float64; the corner world's with
    ``roc_levels=None``), or None: still fluid, a uniform flow, or a flow the tables do not model
    (an `Integrated` one, a flow without a ``hessian``), whose steps are integrated."""
    if not _moving_fluid(params) or not tabulated(params.flow):
        return None
    return gather_row(flow_table(params.model, params.flow, roc_levels), index)


def flow_step(
    model: Any,
    flow: Any,
    s0: Array,
    s1: Array,
    pose: Array,
    substeps: int | None = None,
    *,
    duration: Array | float | None = None,
) -> Array:
    """Lab-frame change ``(dx, dy, dtheta)`` of the centroid's place and the orientation over one
    step (one ``tau``) in which the shape moves straight from ``s0`` to ``s1`` (fractions of the
    range, float64) through ``flow``, from the centroid pose ``pose`` (x, y, theta).

    The move takes the whole step (``duration`` None), or its first ``duration`` (``tau``, in
    (0, 1]) after which the shape holds ``s1``: a one-DOF push past a limit moves at its ROC until
    the limit, then holds (the motors' path, whose work `jswim.env.work` charges).

    The pose obeys ``d/dt (x_ref, theta) = R(theta) u_body(d, d_dot) + U_flow(d, x_ref, theta)``:
    the still-fluid velocity plus the flow's rigid response
    (`jswim.swimmers.flow_response.flow_velocity`), integrated by classical RK4 in
    ``substeps`` pieces (default `FLOW_SUBSTEPS`; tested against a finer integration), as many
    again for the held part when ``duration`` is given (the kink in the shape's path falls on a
    piece's end, so RK4 keeps its order). The reference the flow tables
    (`jswim.env.flow_steps`) are measured against; worlds use it for steps off the tables and for
    `jswim.env.flow_steps.Integrated` flows."""
    span = model.hi - model.lo
    d_move = (s1 - s0) * span
    d0 = corner_values(model, s0)
    n = FLOW_SUBSTEPS if substeps is None else substeps
    off0 = model.centroid_offset(d0)
    c0, s_0 = jnp.cos(pose[2]), jnp.sin(pose[2])
    ref = pose - jnp.stack([c0 * off0[0] - s_0 * off0[1], s_0 * off0[0] + c0 * off0[1], 0.0])
    if duration is None:
        ref = _rk4_piece(model, flow, d0, d_move, 1.0, ref, n)
    else:
        t_move = jnp.asarray(duration, s0.dtype)
        ref = _rk4_piece(model, flow, d0, d_move / t_move, t_move, ref, n)
        ref = _rk4_piece(model, flow, d0 + d_move, None, 1.0 - t_move, ref, n)
    end = centroid(model, d0 + d_move, ref)
    return jnp.stack([end[0] - pose[0], end[1] - pose[1], ref[2] - pose[2]])


def _rk4_piece(
    model: Any,
    flow: Any,
    d0: Array,
    d_dot: Array | None,
    length: Array | float,
    ref: Array,
    n: int,
) -> Array:
    """The reference pose ``ref`` (x, y, theta) after ``length`` (``tau``) of the straight shape
    path ``d0 + d_dot t`` (``d_dot`` None: the shape held at ``d0``) through ``flow``: classical
    RK4 in ``n`` equal pieces (`flow_step`)."""
    h = length / n
    # The still-fluid body-frame velocity depends on the shape alone: one evaluation at each of
    # the 2n + 1 times the RK stages visit (t = j h / 2), shared by the stages that meet there.
    times = jnp.arange(2 * n + 1, dtype=d0.dtype) * (h / 2)
    if d_dot is not None:
        body = jax.vmap(lambda t: model.body_velocity(d0 + d_dot * t, d_dot))(times)  # (2n+1, 3)

    def rate(j: int, ref: Array) -> Array:
        if d_dot is None:  # a held shape moves only with the fluid
            return flow_velocity(d0, ref, flow.velocity, model.xi_ratio)
        u, v, omega = body[j]
        c, s = jnp.cos(ref[2]), jnp.sin(ref[2])
        still = jnp.stack([c * u - s * v, s * u + c * v, omega])
        return still + flow_velocity(d0 + d_dot * times[j], ref, flow.velocity, model.xi_ratio)

    for i in range(n):  # static: unrolled, inside the jitted step
        k1 = rate(2 * i, ref)
        k2 = rate(2 * i + 1, ref + h / 2 * k1)
        k3 = rate(2 * i + 1, ref + h / 2 * k2)
        k4 = rate(2 * i + 2, ref + h * k3)
        ref = ref + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return ref


def _advance_plain(
    state: EnvState,
    frac: Array,
    row: Array,
    y_noise: Array,
    params: EnvParams,
    stuck: Array,
    moved: Array,
    work: Array,
) -> tuple[EnvState, MoveInfo]:
    """[`advance`][jswim.env.stepping.advance] with ``exact=False``: the same step in working-dtype arithmetic."""
    dtype = state.x.dtype
    entry = jnp.asarray(step_rows(params.model), dtype)[row]
    factor = 1.0 + jnp.asarray(params.zeta, dtype) * jnp.asarray(y_noise, dtype)
    c, s = state.cos, state.sin
    if params.model.planar:
        dx = (c * entry[0] - s * entry[1]) * factor
        dy = (s * entry[0] + c * entry[1]) * factor
        c, s = c * entry[3] - s * entry[4], s * entry[3] + c * entry[4]
    else:
        dx, dy = entry[0] * factor, jnp.zeros((), dtype)
    if params.flow is not None:
        dx, dy = (
            dx + jnp.asarray(params.flow.u[0], dtype),
            dy + jnp.asarray(params.flow.u[1], dtype),
        )
    zero = jnp.zeros((), dtype)
    new = state._replace(
        frac=frac,
        x=state.x + dx,
        y=state.y + dy,
        theta=state.theta + entry[2],
        cos=c,
        sin=s,
        t=state.t + 1,
        cos_lo=zero,
        sin_lo=zero,
    )
    progress = jnp.asarray(params.direction, dtype) * dx
    return new, MoveInfo(dx, dy, progress, stuck, moved, new.x, work)
