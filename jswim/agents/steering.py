"""The steering controller as an agent of a navigation world: turn with an off-centre loop until
the target's bearing is small, then swim the square gait. In a background flow it steers the
crab angle ([`crab_bearing`][jswim.agents.steering.crab_bearing]): the heading whose swimming
velocity plus the local flow points at the target.

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

__all__ = ["Controller", "controller", "crab_bearing", "run"]


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

    def start(self) -> ControllerState:
        """The memory of a controller at the start, hub 0 = ``(hi, hi)``."""
        return controller_start()

    def act(
        self, memory: ControllerState, bearing: Array, distance: Array, reach: Array, n_dof: int
    ) -> tuple[Array, ControllerState]:
        """The world's action for the target's ``bearing`` (rad, body frame) and ``distance``
        (``a``), swimming straight when that passes within ``reach`` (``a``, half the success
        radius) of it, and the new memory."""
        move, memory = controller_step(self.plan, memory, bearing, distance, reach)
        if self.world_k:
            return move[0] * (2 * self.world_k + 1) + move[1] + self.world_k, memory
        roc = move[1].astype(jnp.result_type(float)) / self.plan_k
        return jnp.where(jnp.arange(n_dof) == move[0], roc, 0.0), memory


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


def _one(key: Array, params: Any, env: Any, ctrl: Controller, steps: int) -> Trajectory:
    state = env.reset(key, params)
    keys = jax.random.split(key, steps)

    def body(carry, k):
        st, memory = carry
        view = env.target_view(st, params)
        reach = 0.5 * params.target.radius
        bearing = view.bearing
        if getattr(env, "flow", None) is not None:  # steer the course, not the heading
            bearing = crab_bearing(bearing, env.body_flow(st, params).astype(bearing.dtype))
        action, memory = ctrl.act(memory, bearing, view.distance, reach, env.n_dof)
        st, info = env.step(k, st, action, params)
        return (st, memory), Trajectory(st, env.observe(st, params), info)

    return jax.lax.scan(body, (state, ctrl.start()), keys)[1]


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
        From ``jswim.make(..., target=spec)``; the swimmer must start at ``(hi, hi)`` (the
        default ``init``), the controller's hub 0.
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
        As [`controller`][jswim.agents.steering.controller]; a start other than ``(hi, hi)``.
    """
    ctrl = controller(env, reverse)
    init = np.asarray(params.swimmer.init)
    if not np.all(init == 1):
        raise ConfigError(
            f"the steering controller starts on (hi, hi) (init '++'), got init {init.tolist()}"
        )
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
