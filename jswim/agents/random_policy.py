"""Random baseline: uniformly random actions from the same allowed set the LLM is offered.

It is the floor an LLM has to beat: a model that "swims" no better than this has learned nothing.
Runs are vectorised like the Q-learner (one ``lax.scan``, ``vmap`` over learners).
"""

from __future__ import annotations

from typing import NamedTuple

import jax
import jax.numpy as jnp
from jax import Array

from jswim.agents.qlearning import offered, _pick
from jswim.env import EnvParams, advance, reset
from jswim.prompt import ALLOWED_MODES

ALLOWED = ALLOWED_MODES


class RandomRun(NamedTuple):
    """Per-run record (leading batch axis): executed actions, X after each step, start levels."""

    actions: Array
    x: Array
    levels0: Array


def _one(key: Array, params: EnvParams, steps: int, allowed: str, rocs: tuple[int, ...]) -> RandomRun:
    n = params.model.n_dof
    k_reset, k_run = jax.random.split(key)
    state0 = reset(k_reset, params)
    roc_ok = jnp.zeros(3, bool).at[jnp.asarray(rocs) + 1].set(True)
    roc_mask = jnp.tile(roc_ok, n)

    def body(state, u):
        mask = offered(state.levels, n, allowed) & roc_mask
        action = _pick(mask, u[0])
        state, _ = advance(state, action, 2.0 * u[1] - 1.0, params)
        return state, (action, state.x)

    _, (acts, xs) = jax.lax.scan(body, state0, jax.random.uniform(k_run, (steps, 2)))
    return RandomRun(acts, xs, state0.levels)


def run_batch(
    keys: Array, params: EnvParams, steps: int, allowed: str = "all", rocs: tuple[int, ...] | None = None
) -> RandomRun:
    """Run one random policy per key; ``params`` leaves may carry a leading batch axis.

    Parameters
    ----------
    keys : Array (B, 2)
        One key per run (start configuration when random, actions and noise).
    params : EnvParams
        Shared or batched (see :func:`jswim.agents.qlearning.batch_params`).
    steps : int
        Steps per run.
    allowed : {"all", "shape-changing"}
        Offered actions, as in the LLM's prompt.
    rocs : tuple of int, optional
        ROCs offered (default: the swimmer's, e.g. (-1, 0, 1)).
    """
    rocs = tuple(params.model.default_rocs if rocs is None else rocs)
    batched = jnp.ndim(params.zeta) > 0
    fn = jax.vmap(_one, in_axes=(0, 0 if batched else None, None, None, None))
    return jax.jit(fn, static_argnums=(2, 3, 4))(keys, params, steps, allowed, rocs)
