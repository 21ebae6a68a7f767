"""The paper's world through the protocol: one swimmer alone in the fluid (`jswim.env`).

States, actions, noise and numbers are `jswim.env`'s own: `SwimmerWorld.step` is
[`jswim.env.step`][jswim.env.stepping.step] (the same draw from the key, the same state, bit for bit), its info
restated as the protocol's [`StepInfo`][jswim.env.base.StepInfo].
"""

from __future__ import annotations

import dataclasses
from typing import Any

import jax.numpy as jnp
from jax import Array

from jswim.env.base import Environment, Observation, StepInfo, scaled
from jswim.env.params import EnvParams, make_params
from jswim.env.state import EnvState, dof_values, reset
from jswim.env.stepping import advance
from jswim.swimmers.models import SwimmerModel


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
        )

    def observe(self, state: EnvState, params: EnvParams) -> Observation:
        position = jnp.stack([state.x + state.x_lo, state.y + state.y_lo])[None]
        return Observation(
            dof_values(state, params), position, (state.theta + state.theta_lo)[None]
        )

    def features(self, state: EnvState, params: EnvParams) -> Array:
        """The DOFs scaled to [-1, 1] (what the PPO baseline reads)."""
        return scaled(dof_values(state, params), self.model.lo, self.model.hi)
