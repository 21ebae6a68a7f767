"""Navigation: a planar swimmer of the paper's world sent to a target (docs/navigation.md).

[`NavigationWorld`][jswim.env.navigation.NavigationWorld] wraps a
[`SwimmerWorld`][jswim.env.swimmer_world.SwimmerWorld] (Purcell's swimmer, in the bulk or in a
plane parallel to a wall) and adds the task of [`jswim.env.targets`][jswim.env.targets]:

* state: [`NavState`][jswim.env.navigation.NavState], the swimmer's state, the episode's step
  count, the current waypoint, whether the task is done, and counters over episodes;
* observation: the swimmer's, with ``target``: a [`TargetView`][jswim.env.navigation.TargetView]
  (the current target's position, its distance and its bearing in the body frame);
* reward (``StepInfo.progress``): the decrease of the distance to the current target over the
  step, ``|T(t) - X(t)| - |T(t + 1) - X(t + 1)|`` (a moving target's own motion included); it
  sums to the start distance minus the end distance over a leg;
* success: the centroid within the radius of the last waypoint; a waypoint reached makes the
  next one current. The episode is over at success or when the budget is spent
  ([`termination`][jswim.env.navigation.NavigationWorld.termination]). Steps after that move the
  swimmer but earn nothing and change no flag; ``reset`` starts again.

The learners' step ([`learner_advance`][jswim.env.navigation.NavigationWorld.learner_advance])
restarts an episode that ended (the swimmer back at the start, gymnax's auto-reset), so the
baselines, which train on one continuing run, see many episodes; the state's counters say how
they went.

The corner world (K = 1) cannot turn: on the four corners the only closed strokes are the
square gait (either way) and back-and-forth moves, none of which rotates the swimmer, so its
heading after every cycle is its start heading. It is refused; K >= 2 and real ROCs turn.
"""

from __future__ import annotations

import dataclasses
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.env.base import Environment, Observation, Scenery, StepInfo, scaled
from jswim.env.discretiser import Cells, corner, offered_mask, positions
from jswim.env.flows import SWIM_SPEED
from jswim.env.params import EnvParams, broadcast_params
from jswim.env.state import EnvState, dof_values, turned
from jswim.env.swimmer_world import SwimmerWorld
from jswim.env.targets import (
    FixedTarget,
    MovingTarget,
    Target,
    TargetParams,
    Waypoints,
    budget_source,
    default_budget,
    target_params,
)
from jswim.errors import ConfigError

__all__ = [
    "BEARING_BINS",
    "DISTANCE_SCALE",
    "FLOW_BINS",
    "FLOW_CALM",
    "NavCells",
    "NavParams",
    "NavState",
    "NavSummary",
    "NavigationWorld",
    "TargetView",
    "energy_per_distance",
    "navigation_world",
    "summarise",
    "wrap",
]

#: Bearing bins of the tabular learners' state (45 degrees each, one centred on straight ahead):
#: measured best of 4, 6, 8 and 12 for Q-learning at 90 degrees (docs/navigation.md).
BEARING_BINS = 8

#: Bins of the local flow in the tabular learners' state, in a world with a flow: calm (slower
#: than `FLOW_CALM` of the swimming speed), then the flow's direction in the body frame in four
#: quadrants (from ahead, left, behind, right).
FLOW_BINS = 5

#: Below this fraction of the swimming speed the local flow counts as calm (`FLOW_BINS`).
FLOW_CALM = 0.1

#: Length (``a``) the distance feature is divided by (``features``): about a typical target
#: distance, so the feature is of order 1.
DISTANCE_SCALE = 4.0


def wrap(angle: Array) -> Array:
    """An angle (rad) in ``(-pi, pi]``."""
    return jnp.pi - jnp.mod(jnp.pi - angle, 2 * jnp.pi)


class TargetView(NamedTuple):
    """The current target as the swimmer sees it.

    Attributes
    ----------
    position : Array (2,)
        The target's ``(x, y)``, lab frame (``a``).
    distance : Array ()
        From the swimmer's centroid (``a``).
    bearing : Array ()
        Angle (rad, in ``(-pi, pi]``) of the direction to the target from the body frame's x
        axis (the middle link, ``Observation.orientation``), counterclockwise positive: 0 is
        ahead of the middle link, ``+-pi`` behind.
    flow : Array (2,)
        The background flow's velocity at the centroid, lab frame (``a / tau``); zeros in
        still fluid ([`jswim.env.flows`][jswim.env.flows]).
    """

    position: Array
    distance: Array
    bearing: Array
    flow: Array


class NavParams(NamedTuple):
    """A navigation world's params: the swimmer's and the target's (each may be batched)."""

    swimmer: EnvParams
    target: TargetParams

    @property
    def direction(self) -> Any:
        """The swimmer's ``direction`` (not read by navigation; every world has one)."""
        return self.swimmer.direction


class NavState(NamedTuple):
    """A navigation world's state.

    Attributes
    ----------
    swimmer : EnvState
        The swimmer ([`jswim.env.EnvState`][jswim.env.state.EnvState]).
    t : Array () int32
        Steps taken in this episode (the moving target's clock).
    index : Array () int32
        The current waypoint (``P`` once the last is reached).
    reached : Array () bool
        The last waypoint was reached in this episode (success).
    done : Array () bool
        The episode is over: reached, or ``t`` reached the budget.
    episodes : Array () int32
        Episodes ended so far (only [`learner_advance`][jswim.env.navigation.NavigationWorld.learner_advance]
        starts new ones; 0 in a plain rollout).
    successes : Array () int32
        Of those, the ones that reached the target.
    last_steps : Array () int32
        Steps of the last ended episode (0 before one has ended).
    last_reached : Array () bool
        Whether it reached the target.
    """

    swimmer: EnvState
    t: Array
    index: Array
    reached: Array
    done: Array
    episodes: Array
    successes: Array
    last_steps: Array
    last_reached: Array


@dataclasses.dataclass(frozen=True)
class NavigationWorld(Environment):
    """A planar swimmer of the paper's world sent to a target (module docs); ``params`` is a
    [`NavParams`][jswim.env.navigation.NavParams]. Build one with
    ``jswim.make(swimmer, target=..., roc_levels=K)``.

    Attributes
    ----------
    inner : SwimmerWorld
        The swimmer's world (static).
    n_points : int
        Waypoints of the target (static: the shape of ``params.target.points``).
    bearing_bins : int
        Bearing bins of the tabular learners' state ([`NavCells`][jswim.env.navigation.NavCells]).
    lattice : bool
        Float ROC vectors are rounded to the K lattice (ROC ``k / K``, what the integer codes
        move) before the step: a continuous learner then acts on K levels. False: real ROCs.
    target : Target
        The spec ``make`` was given (it builds ``default_params``). Not part of the world's
        identity: worlds that differ only in it share their compilations (every number a step
        reads is in ``params``).
    flow : Flow or None
        The swimmer's background flow (static; its params' ``flow``,
        [`jswim.env.flows`][jswim.env.flows]): what the observation's ``target.flow``, the
        features and the cells read. ``None``: still fluid.
    """

    inner: SwimmerWorld
    n_points: int = 1
    bearing_bins: int = BEARING_BINS
    lattice: bool = False
    target: Any = dataclasses.field(default=None, compare=False)
    flow: Any = None

    # -- sizes and names: the swimmer's ---------------------------------------------------

    @property
    def model(self) -> Any:
        return self.inner.model

    @property
    def n_dof(self) -> int:
        return self.inner.n_dof

    @property
    def roc_levels(self) -> int:
        return self.inner.roc_levels

    @property
    def dof_range(self) -> tuple[float, float]:
        return self.inner.dof_range

    def scenery(self) -> Scenery:
        return self.inner.scenery()

    @property
    def default_params(self) -> NavParams:
        if self.target is None:
            raise ConfigError("this navigation world was built without a target spec")
        swimmer = self.inner.default_params
        tp = target_params(self.target, self.model, self.roc_levels, flow=self.flow)
        return NavParams(swimmer, tp)

    def __repr__(self) -> str:
        # the fields, then the target's budget and the rule that gave it (a target in a flow
        # has a flow budget: jswim.env.targets.flow_budget)
        fields = ", ".join(
            f"{f.name}={getattr(self, f.name)!r}" for f in dataclasses.fields(self) if f.repr
        )
        text = f"{type(self).__name__}({fields}"
        if self.target is not None:
            try:
                n = default_budget(self.target, self.model, self.roc_levels, self.flow)
                why = budget_source(self.target, self.model, self.roc_levels, self.flow)
                text += f", budget={n} steps ({why})"
            except ConfigError:  # a spec without a budget the world cannot measure
                pass
        return text + ")"

    def dtype(self, state: NavState) -> Any:
        return state.swimmer.x.dtype

    # -- the task ----------------------------------------------------------------------------

    def _start(self, key: Array, params: NavParams) -> EnvState:
        # the swimmer's start, turned to the target spec's start heading (0: as it is)
        return turned(self.inner.reset(key, params.swimmer), params.target.heading)

    def reset(self, key: Array, params: NavParams) -> NavState:
        zero = jnp.zeros((), jnp.int32)
        false = jnp.zeros((), bool)
        return NavState(self._start(key, params), zero, zero, false, false, zero, zero, zero, false)

    def target_position(self, t: Array, index: Array, params: NavParams) -> Array:
        """The target at episode step ``t`` while waypoint ``index`` is current (the last one
        once all are reached), ``(2,)``, lab frame."""
        tp = params.target
        i = jnp.clip(index, 0, tp.points.shape[-2] - 1)
        return tp.points[i] + tp.velocity * t.astype(tp.points.dtype)

    def target_view(self, state: NavState, params: NavParams) -> TargetView:
        """The current target: position, distance and bearing in the body frame
        ([`TargetView`][jswim.env.navigation.TargetView])."""
        obs = self.inner.observe(state.swimmer, params.swimmer)
        return self._view(state, obs, params)

    def _view(self, state: NavState, obs: Observation, params: NavParams) -> TargetView:
        target = self.target_position(state.t, state.index, params).astype(obs.position.dtype)
        rel = target - obs.position[0]
        bearing = wrap(jnp.arctan2(rel[1], rel[0]) - obs.orientation[0])
        if self.flow is None:
            flow = jnp.zeros_like(rel)
        else:
            flow = self.flow.velocity(obs.position[0]).astype(rel.dtype)
        return TargetView(target, jnp.hypot(rel[0], rel[1]), bearing, flow)

    def body_flow(self, state: NavState, params: NavParams) -> Array:
        """The local flow in the body frame (``a / tau``, ``(2,)``: along the middle link, then
        to its left); zeros in still fluid."""
        obs = self.inner.observe(state.swimmer, params.swimmer)
        u = self._view(state, obs, params).flow
        c, s = jnp.cos(obs.orientation[0]), jnp.sin(obs.orientation[0])
        return jnp.stack([c * u[0] + s * u[1], -s * u[0] + c * u[1]])

    def termination(self, state: NavState, params: NavParams) -> tuple[Array, Array]:
        """``(terminated, truncated)``: the target reached; the budget spent without reaching it."""
        return state.reached, state.done & ~state.reached

    def _action(self, action: Array, params: NavParams) -> Array:
        action = jnp.asarray(action)
        if self.lattice and jnp.issubdtype(action.dtype, jnp.floating):
            k = self.roc_levels
            return jnp.round(jnp.clip(action, -1.0, 1.0) * k) / k
        return action

    def _task(
        self, state: NavState, new_swimmer: EnvState, info: StepInfo, params: NavParams
    ) -> tuple[NavState, StepInfo]:
        """The task's bookkeeping of one swimmer step: reward, waypoint, flags."""
        before = self.target_view(state, params).distance
        t = state.t + 1
        pos = self.inner.observe(new_swimmer, params.swimmer).position[0]
        target = self.target_position(t, state.index, params).astype(pos.dtype)
        after = jnp.hypot(target[0] - pos[0], target[1] - pos[1])
        live = ~state.done
        hit = live & (after < params.target.radius)
        index = state.index + hit.astype(jnp.int32)
        reached = state.reached | (hit & (index >= params.target.points.shape[-2]))
        done = state.done | reached | (t >= params.target.budget)
        new = state._replace(
            swimmer=new_swimmer,
            t=jnp.where(live, t, state.t),
            index=index,
            reached=reached,
            done=done,
        )
        progress = jnp.where(live, before - after, 0.0).astype(info.progress.dtype)
        return new, info._replace(progress=progress)

    def advance(
        self, state: NavState, action: Array, noise: Array, params: NavParams
    ) -> tuple[NavState, StepInfo]:
        """The swimmer's step ([`SwimmerWorld.advance`][jswim.env.swimmer_world.SwimmerWorld.advance]) and the task's bookkeeping."""
        swimmer, info = self.inner.advance(
            state.swimmer, self._action(action, params), noise, params.swimmer
        )
        return self._task(state, swimmer, info, params)

    def learner_advance(
        self, state: NavState, action: Array, noise: Array, params: NavParams
    ) -> tuple[NavState, StepInfo]:
        """The step, then a fresh episode if this one ended (the swimmer back at its start; a
        random start drawn from the episode count): the baselines' continuing run."""
        swimmer, info = self.inner.learner_advance(
            state.swimmer, self._action(action, params), noise, params.swimmer
        )
        new, info = self._task(state, swimmer, info, params)
        fresh = self._start(jax.random.fold_in(jax.random.PRNGKey(0), new.episodes + 1), params)
        ended = new.done
        restarted = NavState(
            fresh,
            jnp.zeros_like(new.t),
            jnp.zeros_like(new.index),
            jnp.zeros_like(new.reached),
            jnp.zeros_like(new.done),
            new.episodes + 1,
            new.successes + new.reached.astype(jnp.int32),
            new.t,
            new.reached,
        )
        return jax.tree.map(lambda a, b: jnp.where(ended, a, b), restarted, new), info

    # -- what agents see ---------------------------------------------------------------------

    def observe(self, state: NavState, params: NavParams) -> Observation:
        obs = self.inner.observe(state.swimmer, params.swimmer)
        return obs._replace(target=self._view(state, obs, params))

    def features(self, state: NavState, params: NavParams) -> Array:
        """The DOFs scaled to [-1, 1], then the target's ``cos(bearing)``, ``sin(bearing)`` and
        ``distance / DISTANCE_SCALE`` (what PPO reads); in a flow, then the local flow in the
        body frame over the swimming speed (`body_flow` / `jswim.env.flows.SWIM_SPEED`)."""
        view = self.target_view(state, params)
        dofs = scaled(dof_values(state.swimmer, params.swimmer), self.model.lo, self.model.hi)
        extra = [jnp.cos(view.bearing), jnp.sin(view.bearing), view.distance / DISTANCE_SCALE]
        if self.flow is not None:
            u = self.body_flow(state, params) / SWIM_SPEED
            extra += [u[0], u[1]]
        return jnp.concatenate([dofs, jnp.stack(extra).astype(dofs.dtype)])

    @property
    def n_features(self) -> int:
        return self.n_dof + 3 + (2 if self.flow is not None else 0)

    def cells(self) -> NavCells:
        """The lattice point crossed with the target's bearing bin ([`NavCells`][jswim.env.navigation.NavCells])."""
        return NavCells(self)

    def pose(self, state: NavState, params: NavParams) -> tuple[Array, Array, Array]:
        return self.inner.pose(state.swimmer, params.swimmer)

    def judge_view(self, params: NavParams) -> None:
        """``None``: the gait criterion (a stroke toward +-x) does not judge navigation."""
        return None

    def batch_params(self, params: NavParams, n: int) -> tuple[NavParams, NavParams]:
        """The swimmer's leaves broadcast to ``n`` runs (as the swimmer world's); a target leaf
        with a leading axis more than the default's is per run."""
        swimmer = broadcast_params(params.swimmer, n)
        ref = (2, 1, 0, 0, 0)
        axes = TargetParams(
            *(0 if jnp.ndim(v) > r else None for v, r in zip(params.target, ref, strict=True))
        )
        return NavParams(swimmer, params.target), NavParams(0, axes)


@dataclasses.dataclass(frozen=True)
class NavCells(Cells):
    """The tabular learners' state in a navigation world: the lattice point times the bearing
    bin (``bearing_bins`` bins, bin 0 centred on straight ahead, counterclockwise), times, in a
    flow, the local flow's bin (`flow_bin`); the codes offered are the swimmer's
    ([`offered_mask`][jswim.env.discretiser.offered_mask])."""

    @property
    def flow_bins(self) -> int:
        return FLOW_BINS if self.env.flow is not None else 1

    @property
    def n_cells(self) -> int:
        return super().n_cells * self.env.bearing_bins * self.flow_bins

    def positions(self, state: NavState, params: NavParams) -> Array:
        return positions(state.swimmer, self.env.roc_levels)

    def bearing_bin(self, state: NavState, params: NavParams) -> Array:
        """The bin of the target's bearing, int32 in ``0 .. bearing_bins - 1``."""
        n = self.env.bearing_bins
        b = self.env.target_view(state, params).bearing
        return (jnp.round(b * (n / (2 * jnp.pi))).astype(jnp.int32)) % n

    def flow_bin(self, state: NavState, params: NavParams) -> Array:
        """The bin of the local flow, int32 in ``0 .. FLOW_BINS - 1``: 0 calm (slower than
        `FLOW_CALM` of the swimming speed), 1-4 its direction in the body frame (from ahead,
        left, behind, right: quadrants centred on those); 0 always in still fluid."""
        if self.env.flow is None:
            return jnp.zeros((), jnp.int32)
        u = self.env.body_flow(state, params)
        quadrant = jnp.round(jnp.arctan2(u[1], u[0]) * (2 / jnp.pi)).astype(jnp.int32) % 4
        calm = jnp.hypot(u[0], u[1]) < FLOW_CALM * SWIM_SPEED
        return jnp.where(calm, 0, 1 + quadrant)

    def cell(self, state: NavState, j: Array, params: NavParams) -> Array:
        place = corner(j, self.env.roc_levels) * self.env.bearing_bins + self.bearing_bin(
            state, params
        )
        return place * self.flow_bins + self.flow_bin(state, params)

    def mask(
        self, j: Array, params: NavParams, action_set: str, rocs: tuple[int, ...] | None = None
    ) -> Array:
        return offered_mask(j, self.env.n_dof, action_set, rocs, self.env.roc_levels)


def navigation_world(
    world: Environment,
    params: Any,
    target: Target,
    *,
    bearing_bins: int = BEARING_BINS,
    lattice: bool = False,
) -> tuple[NavigationWorld, NavParams]:
    """``world`` (from [`jswim.make`][jswim.env.registry.make]) with the task of reaching ``target``.

    Raises
    ------
    ConfigError
        A world whose swimmer cannot turn in its plane: the sphere swimmers (they move on a
        line), scenes (their swimmers are NG's; the obstacles are there), registered worlds,
        the corner world (K = 1, module docs); a target that is not a spec; bad options.
    """
    if not isinstance(target, (FixedTarget, Waypoints, MovingTarget)):
        raise ConfigError(
            f"target must be a FixedTarget, Waypoints or MovingTarget (jswim.env.targets), "
            f"got {type(target).__name__}"
        )
    if not isinstance(world, SwimmerWorld) or not world.model.planar:
        model = world.scenery().model
        what = "a scene's NG swimmers" if not isinstance(world, SwimmerWorld) else model.label
        raise ConfigError(
            f"navigation needs a swimmer that turns in its plane (Purcell's, in the bulk or in a "
            f"plane parallel to a wall), not {what}: sphere swimmers move on a line"
        )
    if world.roc_levels == 1:
        raise ConfigError(
            "the corner world (roc_levels=1) cannot turn: its only closed strokes (the square "
            "gait, back-and-forth moves) do not rotate the swimmer; use roc_levels >= 2"
        )
    if world.diagonal:
        raise ConfigError("navigation moves one DOF per step: leave diagonal off")
    if (
        isinstance(bearing_bins, bool)
        or not isinstance(bearing_bins, (int, np.integer))
        or bearing_bins < 1
    ):
        raise ConfigError(f"bearing_bins must be a whole number >= 1, got {bearing_bins!r}")
    env = NavigationWorld(
        world, len(target.points()), int(bearing_bins), bool(lattice), target, params.flow
    )
    tp = target_params(target, world.model, world.roc_levels, flow=params.flow)
    return env, NavParams(params, tp)


class NavSummary(NamedTuple):
    """One episode of a navigation run (plain Python numbers).

    Attributes
    ----------
    reached : bool
        The target was reached (the last waypoint).
    steps : int
        Steps of the episode: to the target when reached, else until the budget or the end of
        the record.
    straight : float
        The straight path (``a``): from the start through the waypoints in order; for a moving
        target, from the start to where the target was when the episode ended.
    path : float
        Length of the centroid's path over the episode (``a``, the sum of step displacements).
    path_ratio : float
        ``path / straight``.
    closed : float
        The distance closed on the target: the episode's summed reward (``a``).
    energy : float
        Work done on the fluid over the episode (the world's work units, ``xi_par a^3 / tau``
        for Purcell's swimmer); ``nan`` where not counted.
    energy_per_distance : float
        ``energy / closed`` (work per ``a`` closed on the target); ``nan`` when nothing was
        closed.
    """

    reached: bool
    steps: int
    straight: float
    path: float
    path_ratio: float
    closed: float
    energy: float
    energy_per_distance: float


def energy_per_distance(work: Any, progress: Any) -> float:
    """Work per unit of distance closed on the target: ``sum(work) / sum(progress)`` over the
    steps given (``nan`` when the summed progress is not positive).

    For a straight swim toward +x the progress is the displacement, and this is the study rows'
    ``energy / |X|``.
    """
    closed = float(np.sum(np.asarray(progress, np.float64)))
    energy = float(np.sum(np.asarray(work, np.float64)))
    return energy / closed if closed > 0 else float("nan")


def _straight(params: NavParams, steps: int, start: np.ndarray) -> float:
    pts = np.asarray(params.target.points, np.float64).reshape(-1, 2)
    v = np.asarray(params.target.velocity, np.float64).reshape(2)
    first = pts[0] + v * steps
    legs = np.hypot(*np.diff(pts, axis=0).T).sum() if len(pts) > 1 else 0.0
    return float(np.hypot(*(first - start)) + legs)


def summarise(env: NavigationWorld, params: NavParams, trajectory: Any) -> list[NavSummary]:
    """The episodes of one run's trajectory (no batch axis; [`jswim.env.episodes.Trajectory`][jswim.env.episodes.Trajectory],
    e.g. of [`jswim.rollout`][jswim.env.episodes.rollout], `jswim.agents.steering.run`, or a learner's
    ``trace``).

    A plain rollout holds one episode: to the step that ended it (the target reached or the
    budget spent), or to the end of the record; later steps are left out. A learner's record
    (its step restarts ended episodes) holds many, each ended where the state's ``episodes``
    count rises; a last, unfinished one is included (``reached`` False, ``steps`` so far).

    Returns
    -------
    list of NavSummary
        In order.
    """
    st = trajectory.state
    done = np.asarray(st.done)
    episodes = np.asarray(st.episodes)
    info = trajectory.info
    disp = np.asarray(info.displacement, np.float64).reshape(len(done), -1, 2)[:, 0]
    work = np.asarray(info.work, np.float64) * np.ones(len(done))
    progress = np.asarray(info.progress, np.float64)
    rises = np.flatnonzero(np.diff(np.concatenate([[0], episodes])) > 0)
    if len(rises):
        ends = list(rises)
        reached = [bool(np.asarray(st.last_reached)[i]) for i in ends]
        if ends[-1] < len(done) - 1:
            ends.append(len(done) - 1)
            reached.append(False)
    else:
        first = np.flatnonzero(done)
        ends = [int(first[0]) if len(first) else len(done) - 1]
        reached = [bool(np.asarray(st.reached)[ends[0]])]
    out, begin = [], 0
    origin = np.zeros(2)  # every episode starts at the swimmer's start, the origin
    for end, ok in zip(ends, reached, strict=True):
        sl = slice(begin, end + 1)
        steps = end + 1 - begin
        path = float(np.hypot(*disp[sl].T).sum())
        straight = _straight(params, steps, origin)
        closed = float(progress[sl].sum())
        energy = float(work[sl].sum())
        out.append(
            NavSummary(
                ok,
                steps,
                straight,
                path,
                path / straight if straight > 0 else float("nan"),
                closed,
                energy,
                energy_per_distance(work[sl], progress[sl]),
            )
        )
        begin = end + 1
    return out
