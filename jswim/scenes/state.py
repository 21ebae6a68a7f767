"""``SceneState`` and ``SceneStepInfo``: what a scene holds between steps and what a step did."""

from __future__ import annotations

from typing import NamedTuple

import jax.numpy as jnp
from jax import Array

from jswim.scenes.params import SceneParams


class SceneState(NamedTuple):
    """State of every swimmer in a scene (a pytree; batch it with a leading axis).

    ``S`` is the number of swimmers. Positions are in sphere radii ``a``, in the working dtype.
    """

    arms: Array  # (S, 2) arm lengths d1, d2 of each swimmer
    centre: Array  # (S, 2) (x, z) of each swimmer's middle sphere ("bulk": x is the paper's X)
    tilt: Array  # (S,) axis angle from the wall plane, rad, positive nose (sphere 3) up
    t: Array  # int32 steps taken


class SceneStepInfo(NamedTuple):
    """What one :func:`jswim.scenes.scene_step` did (``S`` swimmers)."""

    dx: Array  # (S,) displacement of each middle sphere along x (noisy when zeta > 0)
    dz: Array  # (S,) along z
    dtilt: Array  # (S,) tilt change, rad (never noisy)
    stuck: Array  # bool: a non-zero ROC pushed the arm past its limit; nothing moved
    moved: Array  # bool: the shape changed
    contact: Array  # bool: the move would bring a surface within contact_gap; it was refused
    gap: Array  # smallest surface gap (wall, obstacles, other swimmer) along the accepted or
    # refused path, units of a (inf in the bulk medium)


def scene_reset(params: SceneParams) -> SceneState:
    """The start state of ``params`` (deterministic: scenes have no random start)."""
    arms = jnp.asarray(params.arms0)
    return SceneState(arms, jnp.asarray(params.centre0, arms.dtype), jnp.asarray(params.tilt0, arms.dtype),
                      jnp.zeros((), jnp.int32))
