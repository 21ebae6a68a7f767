"""The baselines' reward of a step: progress, or progress minus a price on the work it cost.

The energy-aware reward ``progress - lambda x work`` trades distance for the energy the strokes
dissipate ([`StepInfo.work`][jswim.env.base.StepInfo]), the velocity-versus-energy trade of
energy-aware navigation rewards (Lai, Heydari, Pak & Man, arXiv:2506.00084, 2025). ``lambda`` is
in units of length per work (``a / (xi_par a^3 / tau)`` for Purcell's swimmer).
"""

from __future__ import annotations

import math
from collections.abc import Callable

from jax import Array

from jswim.env.base import StepInfo
from jswim.errors import ConfigError
from jswim.reals import is_real


def energy_reward(weight: float) -> Callable[[StepInfo], Array]:
    """The reward function of a step for energy weight ``lambda = weight``.

    ``weight == 0`` gives ``info.progress`` itself (the same array, so every number of a run
    without the option is unchanged, and a world that does not count work still trains);
    otherwise ``info.progress - weight * info.work``.

    Raises
    ------
    ValueError
        If ``weight`` is negative or not finite (a [`ConfigError`][jswim.errors.ConfigError]).
    """
    if not (is_real(weight) and math.isfinite(weight) and weight >= 0):
        raise ConfigError(f"energy_weight must be a finite number >= 0, got {weight!r}")
    if weight == 0:
        return lambda info: info.progress
    return lambda info: info.progress - weight * info.work
