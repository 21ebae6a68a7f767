"""The paper's world through the protocol: one swimmer alone in the fluid (`jswim.env`).

States, actions, noise and numbers are `jswim.env`'s own: `SwimmerWorld.step` is
[`jswim.env.step`][jswim.env.stepping.step] (the same draw from the key, the same state, bit for bit), its info
restated as the protocol's [`StepInfo`][jswim.env.base.StepInfo].
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.env.action_input import validate_actions, validate_moves
from jswim.env.base import Environment, Observation, Scenery, StepInfo, scaled
from jswim.env.discretiser import PaperCells
from jswim.env.episodes import Record, rollout
from jswim.env.params import EnvParams, broadcast_params, make_params
from jswim.env.state import EnvState, dof_values, reset
from jswim.env.stepping import advance
from jswim.errors import ConfigError
from jswim.swimmers.models import SwimmerModel


def _levels(init: Any) -> Any:
    """A start of [`EnvParams`][jswim.env.params.EnvParams] as ``make_params`` takes it (a random one stays random)."""
    init = np.asarray(init)
    levels = tuple(int(v) for v in (init[0] if init.ndim > 1 else init))
    return "random" if any(v < 0 for v in levels) else levels


@dataclasses.dataclass(frozen=True)
class SwimmerWorld(Environment):
    """The paper's swimmer (Purcell, NG, longer chains); ``params`` is an [`EnvParams`][jswim.env.params.EnvParams].

    Attributes
    ----------
    model : SwimmerModel
        The swimmer (static; ``params.model`` is the same).
    k : int
        ROC levels K of the integer codes (``params.roc_levels``).
    diagonal : bool
        Whether a ROC vector may move several DOFs at once (``params.diagonal``).
    """

    model: SwimmerModel
    k: int = 1
    diagonal: bool = False

    @property
    def n_dof(self) -> int:
        return self.model.n_dof

    @property
    def roc_levels(self) -> int:
        return self.k

    @property
    def dof_range(self) -> tuple[float, float]:
        return (float(self.model.lo), float(self.model.hi))

    def scenery(self) -> Scenery:
        """The swimmer by its outline; above a wall, its plane's height (seen from above)."""
        height = getattr(self.model, "height", None)
        return Scenery(model=self.model, plane_height=None if height is None else float(height))

    @property
    def default_params(self) -> EnvParams:
        return make_params(self.model, roc_levels=self.k, diagonal=self.diagonal)

    def reset(self, key: Array, params: EnvParams) -> EnvState:
        return reset(key, params)

    def dtype(self, state: EnvState) -> Any:
        return state.x.dtype

    def advance(
        self, state: EnvState, action: Array, noise: Array, params: EnvParams
    ) -> tuple[EnvState, StepInfo]:
        """[`jswim.env.advance`][jswim.env.stepping.advance] with the noise variable ``noise[0]``."""
        new, info = advance(state, action, jnp.reshape(noise, (-1,))[0], params)
        dtype = new.x.dtype
        return new, StepInfo(
            displacement=jnp.stack([info.dx, info.dy])[None],
            progress=info.progress,
            stuck=info.stuck,
            moved=info.moved,
            contact=jnp.zeros((), bool),
            gap=jnp.asarray(jnp.inf, dtype),
            work=info.work,
        )

    def observe(self, state: EnvState, params: EnvParams) -> Observation:
        """One swimmer's DOFs, centroid and orientation; its height is its ``y`` in its plane
        (seen from above: the observation has no other)."""
        position = jnp.stack([state.x + state.x_lo, state.y + state.y_lo])[None]
        return Observation(
            dof_values(state, params),
            position,
            (state.theta + state.theta_lo)[None],
            position[:, 1],
        )

    def features(self, state: EnvState, params: EnvParams) -> Array:
        """The DOFs scaled to [-1, 1] (what the PPO baseline reads)."""
        return scaled(dof_values(state, params), self.model.lo, self.model.hi)

    def cells(self) -> PaperCells:
        """The corner (or lattice point) of the state, the swimmer's offered ROCs."""
        return PaperCells(self)

    def learner_advance(
        self, state: EnvState, action: Array, noise: Array, params: EnvParams
    ) -> tuple[EnvState, StepInfo]:
        """[`advance`][jswim.env.swimmer_world.SwimmerWorld.advance] in plain working-dtype arithmetic ([`jswim.env.advance`][jswim.env.stepping.advance] with
        ``exact=False``): the baselines' training step since they were written, so their numbers
        stay the paper's."""
        new, i = advance(state, action, noise[0], params, exact=False)
        return new, StepInfo(
            jnp.stack([i.dx, i.dy])[None],
            i.progress,
            i.stuck,
            i.moved,
            jnp.zeros((), bool),
            jnp.asarray(jnp.inf, i.dx.dtype),
            i.work,
        )

    def pose(self, state: EnvState, params: EnvParams) -> tuple[Array, Array, Array]:
        """The state's own centroid x, y and orientation (their float32 high parts)."""
        return state.x, state.y, state.theta

    def judge_view(self, params: EnvParams) -> tuple[EnvParams]:
        """The paper's swimmer in the bulk fluid from this run's start: this world's own model, or
        for a swimmer whose drag a wall corrects, the paper's swimmer of its kind."""
        model = self.model if math.isinf(getattr(self.model, "height", math.inf)) else None
        bulk = make_params(model or self.model.kind, init=_levels(params.init))
        return (bulk,)

    def batch_params(self, params: EnvParams, n: int) -> tuple[EnvParams, int]:
        """Every per-run leaf (``zeta``, ``direction``, ``init``) broadcast to ``n`` runs
        ([`jswim.env.broadcast_params`][jswim.env.params.broadcast_params])."""
        return broadcast_params(params, n), 0


def moves_rollout(params: EnvParams, actions: Any, key: Array | int, record: Record) -> Any:
    """``(dof, roc)`` moves run by the protocol's one rollout in the paper's world, float64.

    Parameters
    ----------
    params : EnvParams
        The world's params (their swimmer, noise, direction and start).
    actions : array-like, shape (steps, 2) or (batch, steps, 2)
        ``(dof, roc)`` pairs (as [`rollout_moves`][jswim.env.rollouts.rollout_moves]): ROCs all in
        {-1, 0, 1} become K = 1 action codes, any other ROC vectors.
    key : PRNG key or int
        Seed; a batch's runs reset with ``split(key, batch)``.
    record : callable
        What each step keeps ([`jswim.env.episodes.rollout`][jswim.env.episodes.rollout]): a
        [`Rollout`][jswim.env.rollouts.Rollout]'s fields for
        [`rollout_moves`][jswim.env.rollouts.rollout_moves].

    Returns
    -------
    NamedTuple
        ``record``'s fields as NumPy arrays (float64 floats), leading axes (batch, steps).
    """
    moves = validate_moves(actions, params.n_dof)
    idx = validate_actions(actions, params.n_dof) if moves is None else moves
    batch_ndim = idx.ndim - (0 if moves is None else 1)
    if batch_ndim not in (1, 2):
        raise ConfigError("actions must have shape (steps, 2) or (batch, steps, 2)")
    # float64 whatever the global setting: this is the path physicists check numbers with.
    with jax.enable_x64(True):
        world = SwimmerWorld(params.model, params.roc_levels, params.diagonal)
        out = rollout(world, params, key, jnp.asarray(idx), record=record)
        return type(out)(*(np.asarray(v) for v in out))
