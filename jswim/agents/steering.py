"""The steering controller as an agent of a navigation world: turn with an off-centre loop until
the target's bearing is small, then swim the square gait. In a background flow it steers the
crab angle ([`crab_bearing`][jswim.agents.steering.crab_bearing]): the heading whose swimming
velocity plus the flow (averaged along the line to the target) points at the target, at the
speed it keeps while its loops cancel the flow's turn
(`Controller.speed`); and it feeds the flow's turn of
its heading forward into its choice of cycle
([`flow_rotation`][jswim.agents.steering.flow_rotation],
[`choose_cycle`][jswim.swimmers.turning.choose_cycle]). In still fluid neither acts: every
number is as without them.

The controller is kinematics written from the physics ([`jswim.swimmers.turning`][jswim.swimmers.turning]); its
cycles and their measured rotation come from the exact tables ([`jswim.env.loops.steering_plan`][jswim.env.loops.steering_plan]).
Here it reads the world's [`target_view`][jswim.env.navigation.NavigationWorld.target_view] bearing each step
and plays its cycles as the world's actions: integer codes on an even K lattice (the quarter
loops need the centre of shape space on it), else float ROC vectors of the K = 2 plan (ROC
``q / 2``: real ROCs through the integrator). It is the reference stroke of navigation, as the
square gait is for +x.

Example::

    env, params = jswim.make("purcell", roc_levels=2, target=FixedTarget(3.0, bearing=90))
    traj = steering.run(env, params, jax.random.key(0))       # budget steps
    summarise(env, params, traj)                                # reached, steps, energy, ...
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim import sharding
from jswim.env.episodes import Trajectory
from jswim.env.flows import SWIM_SPEED
from jswim.env.loops import steering_plan
from jswim.errors import ConfigError
from jswim.swimmers.turning import ControllerState, SteeringPlan, controller_start, controller_step

__all__ = [
    "COURSE_SAMPLES",
    "JEFFERY",
    "Controller",
    "controller",
    "crab_bearing",
    "flow_rotation",
    "run",
]


@dataclasses.dataclass(frozen=True)
class Controller:
    """The steering controller of one navigation world (static, hashable).

    Attributes
    ----------
    plan_k : int
        K of the lattice its plan's moves ``(dof, q)`` count in.
    world_k : int
        K of the world's integer codes; 0: the controller sends float ROC vectors.
    reverse : bool
        A target behind is reached by swimming backward (the reversed gait).
    """

    plan_k: int
    world_k: int
    reverse: bool
    plan: Any = dataclasses.field(compare=False, hash=False)

    def speed(self, rotation: Array) -> Array:
        """The swimmer's mean speed through the water (``a / tau``) while it holds a heading
        against the flow's turn ``rotation`` (rad per step): the turning loops cancel it, a share
        ``4 |rotation| / turn`` of the steps (all of them where the flow beats the loops), at
        their own speed, and the square gait swims the rest at `SWIM_SPEED`. The crab angle
        steers with it: a swimmer that spends half its steps turning is slower than the gait."""
        share = jnp.minimum(1.0, 4.0 * jnp.abs(rotation) / self.plan.turn)
        loop = 2.0 * self.plan.radius * math.sin(self.plan.turn / 2) / 4.0  # chord per step
        return SWIM_SPEED * (1.0 - share) + loop * share

    def start(self, levels: Array | None = None) -> ControllerState:
        """The memory of a controller at the start: on hub 1 where the shape starts at ``(lo,
        lo)``, else on hub 0 = ``(hi, hi)`` (``levels``: the start's corner levels, int32
        ``(2,)``; None: hub 0)."""
        memory = controller_start()
        if levels is None:
            return memory
        return memory._replace(hub=jnp.all(jnp.asarray(levels) == 0).astype(jnp.int32))

    def to_hub(self, levels: Array, n_dof: int) -> tuple[Array, Array]:
        """``(needed, action)``: from a start on neither hub, ``(hi, lo)`` or ``(lo, hi)``, the
        one step that moves the DOF at ``lo`` to ``hi``, onto hub 0; ``needed`` False on a
        hub. ``levels``: the start's corner levels, int32 ``(2,)``."""
        levels = jnp.asarray(levels)
        move = jnp.stack([jnp.argmin(levels), jnp.asarray(self.plan_k)]).astype(jnp.int32)
        return levels[0] != levels[1], self.encode(move, n_dof)

    def encode(self, move: Array, n_dof: int) -> Array:
        """The world's action for a lattice move ``(dof, q)`` (ROC ``q / plan_k``): an integer
        code on the world's K lattice, else a float ROC vector ``(n_dof,)``."""
        if self.world_k:
            return move[0] * (2 * self.world_k + 1) + move[1] + self.world_k
        roc = move[1].astype(jnp.result_type(float)) / self.plan_k
        return jnp.where(jnp.arange(n_dof) == move[0], roc, 0.0)

    def act(
        self,
        memory: ControllerState,
        bearing: Array,
        distance: Array,
        reach: Array,
        n_dof: int,
        rotation: Array | float = 0.0,
    ) -> tuple[Array, ControllerState]:
        """The world's action for the target's ``bearing`` (rad, body frame) and ``distance``
        (``a``), swimming straight when that passes within ``reach`` (``a``, half the success
        radius) of it, and the new memory; ``rotation``: the flow's turn of the body (rad per
        step, [`flow_rotation`][jswim.agents.steering.flow_rotation]), 0 in still fluid."""
        move, memory = controller_step(self.plan, memory, bearing, distance, reach, rotation)
        return self.encode(move, n_dof), memory


def controller(env: Any, reverse: bool = True) -> Controller:
    """The controller of navigation world ``env`` (its swimmer's measured plan).

    Raises
    ------
    ConfigError
        A world without a target view (not a navigation world) or a swimmer the controller
        cannot steer (not a two-DOF planar swimmer).
    """
    if not hasattr(env, "target_view"):
        raise ConfigError(
            "the steering controller drives a navigation world (jswim.make(..., target=))"
        )
    model = env.model
    if not (model.planar and model.n_dof == 2):
        raise ConfigError(
            f"the steering controller steers two-DOF planar swimmers, not {model.label}"
        )
    even = env.roc_levels % 2 == 0
    plan_k = env.roc_levels if even else 2
    plan: SteeringPlan = steering_plan(model, plan_k, reverse=reverse)
    return Controller(plan_k, env.roc_levels if even else 0, bool(reverse), plan)


def crab_bearing(bearing: Array, flow: Array, speed: float = SWIM_SPEED) -> Array:
    """The heading (rad, body frame, as ``bearing``) that makes a swimmer of speed ``speed``
    move straight at a target at ``bearing`` through the local flow ``flow`` (``(2,)``, body
    frame, ``a / tau``): the crab angle of Zermelo's problem in a locally uniform flow.

    The ground velocity ``speed e + u`` points along ``d = (cos bearing, sin bearing)`` when
    ``e = (s d - u) / speed`` with ``s = u.d + sqrt(speed^2 - (d x u)^2)`` (the larger ground
    speed). Where no heading holds the course (``|d x u| > speed`` or ``s <= 0``: a cross or
    head flow faster than the swimmer), it aims at ``speed d - u`` (upstream of the target, to
    lose the least ground). In still fluid it returns ``bearing``.
    """
    d = jnp.stack([jnp.cos(bearing), jnp.sin(bearing)])
    along = d[0] * flow[0] + d[1] * flow[1]
    cross = d[0] * flow[1] - d[1] * flow[0]
    disc = speed**2 - cross**2
    s = along + jnp.sqrt(jnp.maximum(disc, 0.0))
    holds = (disc >= 0) & (s > 0)
    aim = jnp.where(holds, s, speed) * d - flow
    return jnp.arctan2(aim[1], aim[0])


#: Jeffery's shape factor the feed-forward uses: the square gait's, averaged over its stroke
#: (docs/physics.md, Poiseuille: upstream swinging).
JEFFERY = 0.83753


def flow_rotation(gradient: Array, heading: Array, shape: float = JEFFERY) -> Array:
    """The rate (rad per step, counterclockwise) at which a flow with velocity gradient
    ``gradient`` (``(2, 2)``, ``[i, j] = du_i / dx_j``, ``1 / tau``) turns a body headed at
    ``heading`` (rad, lab frame): half the vorticity plus ``shape`` times the strain's turn of
    the heading, Jeffery's ``omega / 2 + B p_perp . E p`` (one step lasts one ``tau``). ``shape
    = 0``: half the vorticity alone. Zero in a uniform stream and in still fluid."""
    g = jnp.asarray(gradient)
    spin = 0.5 * (g[1, 0] - g[0, 1])
    c, s = jnp.cos(heading), jnp.sin(heading)
    strain = (g[1, 1] - g[0, 0]) * s * c + 0.5 * (g[0, 1] + g[1, 0]) * (c * c - s * s)
    return spin + shape * strain


#: Points along the line to the target whose mean flow the crab angle steers against.
COURSE_SAMPLES = 8


def _course_flow(flow: Any, position: Array, target: Array, heading: Array) -> Array:
    """The flow averaged over the straight line from ``position`` to ``target`` (midpoints of
    `COURSE_SAMPLES` pieces), in the body frame of ``heading``: what the swimmer will cross, so
    that it turns upstream early rather than when it is already in the strong flow (its turns
    are slow, about 0.015 rad per step)."""
    frac = (jnp.arange(COURSE_SAMPLES) + 0.5) / COURSE_SAMPLES
    u = jnp.mean(flow.velocity(position + frac[:, None] * (target - position)), axis=0)
    c, s = jnp.cos(heading), jnp.sin(heading)
    return jnp.stack([c * u[0] + s * u[1], -s * u[0] + c * u[1]])


def _one(key: Array, params: Any, env: Any, ctrl: Controller, steps: int) -> Trajectory:
    state = env.reset(key, params)
    keys = jax.random.split(key, steps)
    levels = state.swimmer.levels
    off_hub, first = ctrl.to_hub(levels, env.n_dof)  # a start on neither hub: one step onto hub 0

    def body(carry, k):
        st, memory = carry
        view = env.target_view(st, params)
        reach = 0.5 * params.target.radius
        bearing = view.bearing
        rotation = 0.0  # still fluid: no feed-forward, every number as before
        if getattr(env, "flow", None) is not None:  # steer the course, not the heading
            obs = env.inner.observe(st.swimmer, params.swimmer)
            rotation = flow_rotation(env.flow.gradient(obs.position[0]), obs.orientation[0]).astype(
                bearing.dtype
            )
            flow = _course_flow(env.flow, obs.position[0], view.position, obs.orientation[0])
            bearing = crab_bearing(bearing, flow.astype(bearing.dtype), ctrl.speed(rotation))
        action, chosen = ctrl.act(memory, bearing, view.distance, reach, env.n_dof, rotation)
        prelude = off_hub & (st.t == 0)
        action = jnp.where(prelude, first, action)
        memory = jax.tree.map(lambda a, b: jnp.where(prelude, a, b), memory, chosen)
        st, info = env.step(k, st, action, params)
        return (st, memory), Trajectory(st, env.observe(st, params), info)

    return jax.lax.scan(body, (state, ctrl.start(levels)), keys)[1]


@functools.partial(jax.jit, static_argnames=("env", "ctrl", "steps", "axes"))
def _batch(
    keys: Array, params: Any, env: Any, ctrl: Controller, steps: int, axes: Any
) -> Trajectory:
    return jax.vmap(lambda k, p: _one(k, p, env, ctrl, steps), in_axes=(0, axes))(keys, params)


def run(
    env: Any,
    params: Any,
    key: Array | int,
    steps: int | None = None,
    *,
    reverse: bool = True,
) -> Trajectory:
    """The steering controller in navigation world ``env``, one run or a batch.

    Parameters
    ----------
    env : NavigationWorld
        From ``jswim.make(..., target=spec)``; the swimmer may start on any corner of its
        shape square (``init``): on ``(hi, hi)`` or ``(lo, lo)`` the controller starts on that
        hub, from ``(hi, lo)`` or ``(lo, hi)`` its first step moves onto ``(hi, hi)``.
    params : NavParams
        Shared, or with a value per run where the world batches them (e.g. one target per run).
    key : PRNG key or int, or keys ``(B, 2)``
        Run ``i`` resets with ``keys[i]``; a step's noise is drawn from ``split(run_key, T)``
        (as [`jswim.rollout`][jswim.env.episodes.rollout]).
    steps : int, optional
        Steps per run; default the largest budget in ``params``. Steps after the episode ended
        move the swimmer but earn nothing ([`summarise`][jswim.env.navigation.summarise] cuts
        them).
    reverse : bool
        Reach a target behind by swimming backward (else turn round).

    Returns
    -------
    Trajectory
        The world's state, observation and step info after each step (after the batch axis).

    Raises
    ------
    ConfigError
        As [`controller`][jswim.agents.steering.controller].
    """
    ctrl = controller(env, reverse)
    steps = int(np.max(np.asarray(params.target.budget))) if steps is None else int(steps)
    keys = jnp.asarray(jax.random.key_data(key) if _typed(key) else key)
    if keys.ndim == 0:
        keys = jax.random.PRNGKey(int(keys))
    if keys.ndim == 1:
        return jax.tree.map(lambda v: v[0], run(env, params, keys[None], steps, reverse=reverse))
    n = keys.shape[0]
    params, axes = env.batch_params(params, n)
    fn = functools.partial(_batch, env=env, ctrl=ctrl, steps=steps, axes=axes)
    return sharding.apply_runs(fn, keys, params, axes, n)


def _typed(key: Any) -> bool:
    return isinstance(key, jax.Array) and jnp.issubdtype(key.dtype, jax.dtypes.prng_key)
