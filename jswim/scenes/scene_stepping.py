"""``scene_step``: one action moves one arm of one swimmer; every body in the scene responds.

A step moves arm ``dof`` of swimmer ``swimmer`` by ``roc x (d_max - d_min)`` at unit rate
(duration ``|roc| (d_max - d_min)``; at zero Reynolds number only the path matters), clipped to
``[d_min, d_max]`` (a non-zero ROC that cannot move the arm at all is ``stuck``). The other arms
are held fixed. Then, by medium:

* ``"bulk"``: the paper's formula ([`jswim.swimmers.ng`][jswim.swimmers.ng]): the moving swimmer advances along its
  axis by the closed-form displacement of the move; the others do not move; no contact.
* ``"free"`` / ``"wall"``: all spheres of all swimmers and the obstacles are coupled through the
  point-force mobility ([`jswim.swimmers.mobility`][jswim.swimmers.mobility]), every swimmer force- and torque-free
  ([`jswim.swimmers.forcefree`][jswim.swimmers.forcefree]; in the unbounded fluid without obstacles each swimmer is
  solved through its response, [`jswim.swimmers.bodyframe`][jswim.swimmers.bodyframe], a function of its arms alone);
  the poses ``(x, z, tilt)`` of all swimmers are integrated over the step by Gauss-Legendre
  collocation (`jswim.scenes.collocation`).

Contact: if along the step (at any collocation node or at its end) a swimmer sphere's surface
comes within ``params.contact_gap`` (0.1 a) of the wall, of an obstacle's surface or of a sphere of
another swimmer, the step is refused: the state is left as it was (shape and pose; only ``t``
advances) and ``contact`` is set. The point-force model has no lubrication or contact forces, so
motion that close is not modelled.

Noise, as in the paper and `jswim.env`: swimmer ``s``'s displacement ``(dx, dz)`` over the
step is multiplied by ``1 + zeta Y_s``, ``Y_s ~ U[-1, 1]`` drawn from the step's key (one per
swimmer: ``jax.random.uniform(key, (S,))``, for one swimmer ``uniform(key, ())`` as
[`jswim.env.step`][jswim.env.stepping.step] draws it); the tilt change is not perturbed.
"""

from __future__ import annotations

from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.scenes.scene_actions import split_action
from jswim.scenes.collocation import gauss_rule
from jswim.scenes.scene_parameters import SceneParams
from jswim.scenes.scene_state import SceneState, SceneStepInfo, add_displacement, centre_low
from jswim.swimmers import bodyframe, forcefree


def scene_step(
    params: SceneParams, state: SceneState, action: Any, key: Array
) -> tuple[SceneState, SceneStepInfo]:
    """Advance a scene by one action.

    Parameters
    ----------
    params : SceneParams
    state : SceneState
    action : (swimmer, dof, roc)
        A 3-tuple of scalars/arrays (int32, int32, float) or a float array ``(3,)``; ``swimmer``
        and ``dof`` 0-based, ``roc`` in [-1, 1] (clipped). Integer codes: decode them with
        `jswim.scenes.decode_scene_action`.
    key : PRNG key
        The step's noise key.

    Returns
    -------
    (SceneState, SceneStepInfo)
        Works under ``jit`` and ``vmap`` (batch states, actions and keys together).
    """
    dtype = state.arms.dtype
    s = params.n_swimmers
    if s == 1:
        y = jax.random.uniform(key, (), dtype, -1.0, 1.0)[None]
    else:
        y = jax.random.uniform(key, (s,), dtype, -1.0, 1.0)
    return scene_advance(params, state, action, y)


def scene_advance(
    params: SceneParams, state: SceneState, action: Any, y_noise: Array
) -> tuple[SceneState, SceneStepInfo]:
    """[`scene_step`][jswim.scenes.scene_stepping.scene_step] with given noise variables ``y_noise`` ``(S,)`` in [-1, 1]."""
    sw, dof, roc = split_action(action)
    arms = state.arms
    dtype = arms.dtype
    s = params.n_swimmers
    span = params.hi - params.lo
    roc = jnp.clip(jnp.asarray(roc, dtype), -1.0, 1.0)
    onehot = (jnp.arange(s)[:, None] == sw) & (jnp.arange(2)[None, :] == dof)  # (S, 2)
    d0 = jnp.sum(jnp.where(onehot, arms, 0.0))
    target = jnp.clip(d0 + roc * span, params.lo, params.hi)
    delta = target - d0
    stuck = (roc != 0) & (delta == 0)
    moved = delta != 0
    new_arms = jnp.where(onehot, target, arms)
    if params.scene.medium == "bulk":
        disp = _bulk_displacement(arms, sw, dof, delta)  # along the moving swimmer's axis
        mine = jnp.arange(s) == sw
        step_x = jnp.where(mine, disp * jnp.cos(state.tilt), 0.0)
        step_z = jnp.where(mine, disp * jnp.sin(state.tilt), 0.0)
        step_t = jnp.zeros_like(state.tilt)
        gap = jnp.asarray(jnp.inf, dtype)
    else:
        rates = jnp.where(onehot, jnp.sign(delta), 0.0).astype(dtype)
        pose0 = jnp.concatenate([state.centre, state.tilt[:, None]], -1)
        inc, gap = pose_change(params, pose0, arms, rates, jnp.abs(delta), centre_low(state))
        step_x, step_z, step_t = inc.T
    contact = ~(
        gap >= params.contact_gap
    )  # NaN (a solve that broke down at contact) counts as contact
    factor = 1.0 + jnp.asarray(params.zeta, dtype) * jnp.asarray(y_noise, dtype)
    dx = jnp.where(contact, 0.0, step_x * factor)
    dz = jnp.where(contact, 0.0, step_z * factor)
    dtilt = jnp.where(contact, 0.0, step_t)
    centre, centre_lo = add_displacement(state, jnp.stack([dx, dz], -1))
    new = SceneState(
        arms=jnp.where(contact, arms, new_arms),
        centre=centre,
        tilt=state.tilt + dtilt,
        t=state.t + 1,
        centre_lo=centre_lo,
    )
    return new, SceneStepInfo(dx, dz, dtilt, stuck, moved & ~contact, contact, gap)


def scene_step_joint(
    params: SceneParams, state: SceneState, dofs: Any, rocs: Any, key: Array
) -> tuple[SceneState, SceneStepInfo]:
    """Every swimmer moves one arm at once: swimmer ``s`` moves arm ``dofs[s]`` by
    ``rocs[s] x (d_max - d_min)`` (clipped), all along one straight path in the joint shape space
    (each arm at rate ``delta_s / T``, ``T`` the longest move). For simultaneous strokes of two
    swimmers (a phase offset between their cycles); ``"free"`` and ``"wall"`` media. Noise, contact
    and the info as in [`scene_step`][jswim.scenes.scene_stepping.scene_step] (``stuck``: every non-zero ROC was stuck)."""
    if params.scene.medium == "bulk":
        raise ValueError("scene_step_joint needs medium 'free' or 'wall'")
    arms = state.arms
    dtype = arms.dtype
    s = params.n_swimmers
    span = params.hi - params.lo
    rocs = jnp.clip(jnp.asarray(rocs, dtype).reshape(s), -1.0, 1.0)
    onehot = jnp.arange(2)[None, :] == jnp.asarray(dofs, jnp.int32).reshape(s, 1)  # (S, 2)
    d0 = jnp.sum(jnp.where(onehot, arms, 0.0), -1)
    target = jnp.clip(d0 + rocs * span, params.lo, params.hi)
    delta = target - d0
    duration = jnp.max(jnp.abs(delta))
    rates = jnp.where(onehot, (delta / jnp.where(duration > 0, duration, 1.0))[:, None], 0.0)
    pose0 = jnp.concatenate([state.centre, state.tilt[:, None]], -1)
    inc, gap = pose_change(params, pose0, arms, rates, duration, centre_low(state))
    y = jax.random.uniform(key, (s,), dtype, -1.0, 1.0)
    contact = ~(gap >= params.contact_gap)
    factor = 1.0 + jnp.asarray(params.zeta, dtype) * y
    step_x, step_z, step_t = inc.T
    dx = jnp.where(contact, 0.0, step_x * factor)
    dz = jnp.where(contact, 0.0, step_z * factor)
    dtilt = jnp.where(contact, 0.0, step_t)
    centre, centre_lo = add_displacement(state, jnp.stack([dx, dz], -1))
    new = SceneState(
        jnp.where(contact, arms, jnp.where(onehot, target[:, None], arms)),
        centre,
        state.tilt + dtilt,
        state.t + 1,
        centre_lo,
    )
    stuck = jnp.any(rocs != 0) & jnp.all((rocs == 0) | (delta == 0))
    moved = jnp.any(delta != 0)
    return new, SceneStepInfo(dx, dz, dtilt, stuck, moved & ~contact, contact, gap)


def _bulk_displacement(arms: Array, sw: Array, dof: Array, delta: Array) -> Array:
    """The paper's displacement of one arm move (closed form of [`jswim.swimmers.ng.arm_move_displacement`][jswim.swimmers.ng.arm_move_displacement])."""
    d1, d2 = arms[sw, 0], arms[sw, 1]
    move_1 = (-jnp.log1p(delta / (d1 + d2)) + 2.0 * delta / d2) / 6.0
    move_2 = (jnp.log1p(delta / (d1 + d2)) - 2.0 * delta / d1) / 6.0
    return jnp.where(dof == 0, move_1, move_2)


def integrate_move(
    params: SceneParams, pose0: Array, arms: Array, rates: Array, duration: Array
) -> tuple[Array, Array]:
    """Poses after moving the arms at ``rates`` for ``duration``, and the smallest surface gap:
    ``pose0`` plus [`pose_change`][jswim.scenes.scene_stepping.pose_change]."""
    inc, gap = pose_change(params, pose0, arms, rates, duration)
    return pose0 + inc, gap


def pose_change(
    params: SceneParams,
    pose0: Array,
    arms: Array,
    rates: Array,
    duration: Array,
    centre_lo: Array | None = None,
) -> tuple[Array, Array]:
    """Change of every swimmer's pose over a move of the arms at ``rates`` for ``duration``, and
    the smallest surface gap.

    Parameters
    ----------
    pose0 : Array (S, 3)
        ``(x, z, tilt)`` of every swimmer at the start.
    arms, rates : Array (S, 2)
        Start arms and their (constant) rates.
    duration : scalar
        Time of the move.
    centre_lo : Array (S, 2), optional
        Low words of the positions ([`jswim.scenes.SceneState`][jswim.scenes.scene_state.SceneState]): the positions are
        ``pose0[:, :2] + centre_lo``.

    Returns
    -------
    (Array (S, 3), scalar)
        Pose changes ``(dx, dz, dtilt)``; the smallest surface gap over the nodes and the end.
        The solve runs in coordinates whose x origin is swimmer 1's start (the physics is
        invariant under translations along the wall), so in float32 the result does not lose
        precision as the swimmers travel far from x = 0; with ``centre_lo`` the swimmers' offsets
        from it are formed from both words, so they are exact to the dtype's rounding of the offset.
    """
    nodes, y_run, y_end = (jnp.asarray(v, pose0.dtype) for v in gauss_rule(params.nodes))
    t = nodes * duration
    arms_t = arms[None] + t[:, None, None] * rates[None]  # (n, S, 2)
    pose0, obstacles = _solve_frame(params, pose0, centre_lo)
    body_rates, state = _node_solver(params, pose0, arms_t, rates, obstacles)
    sweep = _picard_sweep(body_rates, pose0, duration, y_run)
    it = (jnp.zeros((params.nodes, pose0.shape[0], 3), pose0.dtype), state)
    if params.sweeps is None:
        it, lab, omega = _sweep_until_converged(sweep, it, picard_tolerance(pose0.dtype))
    else:
        if params.sweeps > 1:  # a loop, not unrolled: the solve is large straight-line code
            it = jax.lax.fori_loop(0, params.sweeps - 1, lambda _, p: sweep(p)[0], it)
        it, lab, omega = sweep(it)
    inc = it[0]
    poses = pose0 + inc
    step = duration * jnp.concatenate(
        [jnp.einsum("j,jsk->sk", y_end, lab), (y_end @ omega)[:, None]], -1
    )
    arms_end = arms + duration * rates
    gaps = jax.vmap(lambda p, a: surface_gap(p, a, obstacles, params.wall))(poses, arms_t)
    return step, jnp.minimum(
        jnp.min(gaps), surface_gap(pose0 + step, arms_end, obstacles, params.wall)
    )


def _solve_frame(params: SceneParams, pose0: Array, centre_lo: Array | None) -> tuple[Array, Array]:
    """``pose0`` and the obstacles in the solve's coordinates: x from swimmer 1's start (the
    physics is invariant under translations along the wall), the low words of the positions
    (``centre_lo``) added in: offsets from swimmer 1, heights (rounded to the dtype)."""
    shift = pose0[0, 0]
    obstacles = jnp.asarray(params.obstacles, pose0.dtype)
    obstacles = obstacles.at[:, 0].add(-shift)
    pose0 = pose0.at[:, 0].add(-shift)
    if centre_lo is not None:
        lo = jnp.asarray(centre_lo, pose0.dtype)
        pose0 = pose0.at[:, 0].add(lo[:, 0] - lo[0, 0]).at[:, 1].add(lo[:, 1])
        obstacles = obstacles.at[:, 0].add(-lo[0, 0])
    return pose0, obstacles


def _node_solver(
    params: SceneParams, pose0: Array, arms_t: Array, rates: Array, obstacles: Array
) -> tuple[Any, Array]:
    """``body_rates(poses, state) -> (rates (n, S, 3), state)`` at the collocation nodes, and the
    ``state`` the first sweep starts from.

    How each node's force-free solve is done (all agree to rounding; tests check it):

    * unbounded fluid, no obstacles: each swimmer through its response to the flow at its
      spheres, a function of the arms alone, built once per node (`jswim.swimmers.bodyframe`);
    * above the wall, two swimmers: each swimmer solved afresh at its pose in the other's flow;
    * otherwise (one swimmer above the wall, obstacles): one solve of all spheres.

    With two swimmers the solves go by block Gauss-Seidel, one sweep per Picard sweep, the
    forces carried from sweep to sweep (the ``state``). The rates are body-frame: along the
    axis, normal to it, and the rotation rate.
    """
    n_nodes, n_sw, n_sph = params.nodes, pose0.shape[0], arms_t.shape[2] + 1
    mob, selfm = params.scene.mobility, params.scene.self_mobility
    if obstacles.shape[0] == 0 and not params.wall:
        path, state = "response", jnp.zeros((n_nodes, n_sw, n_sph, 2), pose0.dtype)
        resp = jax.vmap(lambda a: bodyframe.response(a, mob))(arms_t)
    elif obstacles.shape[0] == 0 and n_sw >= 2:
        path, state = "by_swimmer", jnp.zeros((n_nodes, n_sw * n_sph, 2), pose0.dtype)
    else:
        path, state = "coupled", jnp.zeros((n_nodes,), pose0.dtype)

    def body_rates(poses: Array, state: Array) -> tuple[Array, Array]:
        if path == "response":
            solve = lambda pose, a, r, f: bodyframe.sweep(
                pose[:, :2], pose[:, 2], a, rates, r, f, mob
            )
            state, xi = jax.vmap(solve)(poses, arms_t, resp, state)
            return xi, state

        def one(pose: Array, arms_k: Array, forces: Array) -> tuple[Array, Array]:
            if path == "by_swimmer":
                r = forcefree.solve_by_swimmer(
                    pose[:, :2], pose[:, 2], arms_k, rates, params.wall, forces, mob, selfm
                )
                forces = r.forces.astype(forces.dtype)
            else:
                r = forcefree.rigid_motion(
                    pose[:, :2], pose[:, 2], arms_k, rates, obstacles, params.wall, mob, selfm
                )
            c, s = jnp.cos(pose[:, 2]), jnp.sin(pose[:, 2])
            u, w = r.velocity[:, 0], r.velocity[:, 1]
            return jnp.stack([c * u + s * w, -s * u + c * w, r.omega], -1), forces

        return jax.vmap(one)(poses, arms_t, state)

    return body_rates, state


def _picard_sweep(body_rates: Any, pose0: Array, duration: Array, y_run: Array) -> Any:
    """One Picard sweep ``(inc, state) -> ((inc, state), lab, omega)``: the body-frame rates at
    the current node poses, then tilt first and position with the new tilt, so that the strong
    dependence (the rotation of the swimming direction) is exact within a sweep and only the
    weak one (wall and neighbours) is iterated. The sweeps carry the poses' increments from
    ``pose0``, not the poses: in float32 far from the origin the absolute x could not resolve
    the small differences between sweeps that the stopping rule reads."""

    def sweep(it: tuple[Array, Array]) -> tuple[tuple[Array, Array], Array, Array]:
        inc, state = it
        b, state = body_rates(pose0 + inc, state)
        b = b.astype(inc.dtype)
        dtilt = duration * (y_run @ b[..., 2])  # (n, S)
        tilt = pose0[:, 2] + dtilt
        c, s = jnp.cos(tilt), jnp.sin(tilt)
        lab = jnp.stack(
            [c * b[..., 0] - s * b[..., 1], s * b[..., 0] + c * b[..., 1]], -1
        )  # (n, S, 2)
        dxz = duration * jnp.einsum("ij,jsk->isk", y_run, lab)
        new = jnp.concatenate([dxz, dtilt[..., None]], -1).astype(inc.dtype)
        return (new, state), lab, b[..., 2]

    return sweep


#: Most Picard sweeps of an adaptive step (`_sweep_until_converged`); 3 at least.
MAX_SWEEPS = 16
MIN_SWEEPS = 3


def picard_tolerance(dtype: Any) -> float:
    """Error per step, relative to the step's largest displacement, at which adaptive sweeps stop:
    below the working dtype's own rounding of a step (float32 ~1e-7, float64 1e-13)."""
    return 1e-7 if jnp.dtype(dtype).itemsize <= 4 else 1e-13


def _sweep_until_converged(
    sweep: Any, it: tuple[Array, Array], tol: float
) -> tuple[tuple[Array, Array], Array, Array]:
    """Picard sweeps until the error estimate of the increments falls below ``tol`` times the
    largest displacement of the step, at least `MIN_SWEEPS` and at most `MAX_SWEEPS`.

    ``it`` is ``(increments, forces)``: the poses' increments at the nodes and the sphere forces
    the solves by swimmer carry from sweep to sweep. The iteration converges linearly: with ``c_k`` the largest change made by sweep ``k``
    the error left is about ``c_k rho``, ``rho = c_k / c_(k-1)``; the first change is the whole
    step, so the rule is read from sweep 3 on. Under ``vmap`` the loop runs until every member of
    the batch has converged (the others keep their values: a swimmer's result does not depend on
    its batch). Returns the iterate and the last sweep's lab-frame velocities and rotation rates.
    """

    def step(carry: tuple) -> tuple:
        k, it, _, _, change, _ = carry
        new, lab, omega = sweep(it)
        return k + 1, new, lab, omega, jnp.max(jnp.abs(new[0] - it[0])), change

    def more(carry: tuple) -> Array:
        k, it, _, _, change, prev = carry
        scale = jnp.max(jnp.abs(it[0][..., :2]))
        estimate = change * jnp.minimum(1.0, change / jnp.where(prev > 0, prev, 1.0))
        return (k < MIN_SWEEPS) | ((k < MAX_SWEEPS) & (estimate > tol * scale))

    first, lab, omega = sweep(it)
    big = jnp.asarray(jnp.inf, it[0].dtype)
    carry = (jnp.asarray(1, jnp.int32), first, lab, omega, jnp.max(jnp.abs(first[0])), big)
    _, it, lab, omega, _, _ = jax.lax.while_loop(more, step, carry)
    return it, lab, omega


def surface_gap(pose: Array, arms: Array, obstacles: Array, wall: bool) -> Array:
    """Smallest surface gap between a swimmer sphere and the wall, an obstacle or another
    swimmer's sphere (units of a); ``inf`` when there is nothing to touch."""
    pos = forcefree.sphere_centres(pose[:, :2], pose[:, 2], arms)  # (S, n, 2)
    s, n = pos.shape[:2]
    flat = pos.reshape(s * n, 2)
    out = jnp.asarray(jnp.inf, pose.dtype)
    if wall:
        out = jnp.minimum(out, jnp.min(flat[:, 1]) - 1.0)
    if obstacles.shape[0]:
        d = flat[:, None, :] - obstacles[None, :, :2]
        out = jnp.minimum(out, jnp.min(jnp.sqrt(jnp.sum(d * d, -1)) - 1.0 - obstacles[None, :, 2]))
    if s > 1:  # each pair of swimmers once (a swimmer's own spheres are held apart by its arms)
        a, b = np.tril_indices(s, -1)
        d = pos[a][:, :, None, :] - pos[b][:, None, :, :]  # (pairs, n, n, 2)
        out = jnp.minimum(out, jnp.min(jnp.sqrt(jnp.sum(d * d, -1))) - 2.0)
    return out
