"""The fixed-stroke player: a given stroke (a cycle of action codes, or a whole sequence) played
in any world, one run or a batch, through the one rollout ([`rollout`][jswim.env.episodes.rollout]).

It is the baseline of no learning at all: the paper's square gait, its time reverse, or any
sequence a user writes down, played open-loop whatever the world does.
"""

from __future__ import annotations

from typing import Any

import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.env.base import Environment
from jswim.env.episodes import Trajectory, rollout


def play(
    env: Environment, params: Any, key: Array | int, stroke: Any, steps: int | None = None
) -> Trajectory:
    """Play ``stroke`` for ``steps`` steps in ``env``.

    Parameters
    ----------
    env : Environment
        The world ([`make`][jswim.env.registry.make]).
    params : pytree
        Its params (for a batch: shared, or with a value per run where the world batches them).
    key : PRNG key or int, or keys ``(B, 2)``
        As for [`rollout`][jswim.env.episodes.rollout]: run ``i`` resets with ``keys[i]``.
    stroke : array (L,) or (B, L) int
        Action codes: one stroke, or one per run; repeated cyclically to ``steps``.
    steps : int, optional
        Steps per run (default ``L``: the stroke once).

    Returns
    -------
    Trajectory
        One entry per step (after the batch axis).
    """
    codes = np.asarray(stroke)
    if codes.ndim not in (1, 2) or codes.shape[-1] == 0:
        raise ValueError(f"a stroke is (L,) or (B, L) action codes, got shape {codes.shape}")
    steps = codes.shape[-1] if steps is None else int(steps)
    idx = np.arange(steps) % codes.shape[-1]
    return rollout(env, params, key, jnp.asarray(codes[..., idx]))
