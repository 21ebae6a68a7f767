"""Rollouts of ``(dof, roc)`` moves for one swimmer or a batch, always in float64.

A shortcut of the protocol's one rollout ([`jswim.env.episodes.rollout`][jswim.env.episodes.rollout]): the moves
become action codes (or ROC vectors), the paper's world
([`SwimmerWorld`][jswim.env.swimmer_world.SwimmerWorld]) runs them, and each step keeps the
fields of a [`Rollout`][jswim.env.rollouts.Rollout].
"""

from __future__ import annotations

from typing import Any, NamedTuple
from collections.abc import Sequence

from jax import Array

from jswim.env.base import Environment, StepInfo
from jswim.env.params import EnvParams, make_params
from jswim.env.randomness import seed32, seed_key  # noqa: F401  (re-exported: their old place)
from jswim.env.state import EnvState
from jswim.env.swimmer_world import moves_rollout
from jswim.errors import ConfigError
from jswim import reprs
from jswim.swimmers.models import SwimmerModel


class Rollout(NamedTuple):
    """Per-step record of a rollout (state after each step); leading axes (batch, steps).

    ``x``, ``y`` and ``orientation`` are the full values (``hi + lo``) rounded to the working
    dtype (float64 in [`rollout_moves`][jswim.env.rollouts.rollout_moves])."""

    x: Array
    y: Array
    orientation: Array
    dofs: Array
    stuck: Array
    progress: Array

    __repr__ = reprs.trajectory_text
    _repr_html_ = reprs.trajectory_html


def _record(env: Environment, params: EnvParams, state: EnvState, info: StepInfo) -> Rollout:
    """A `Rollout`'s entry of one step: the full (``hi + lo``) pose after it."""
    obs = env.observe(state, params)
    return Rollout(
        obs.position[0, 0],
        obs.position[0, 1],
        obs.orientation[0],
        obs.dofs,
        info.stuck,
        info.progress,
    )


def rollout_moves(
    swimmer: str | SwimmerModel,
    actions: Any,
    *,
    key: Array | int = 0,
    zeta: float = 0.0,
    direction: int | str = 1,
    init: Sequence[int] | str | None = None,
    scene: Any = None,
    **model_kwargs: Any,
) -> Any:
    """Run a given action sequence for one swimmer or a batch.

    The shortcut for a named swimmer and ``(dof, roc)`` moves, always in float64; any world of
    [`jswim.make`][jswim.env.registry.make] runs through the protocol's one rollout,
    [`jswim.rollout`][jswim.env.episodes.rollout] ``(env, params, key, actions)``.

    Parameters
    ----------
    swimmer : str
        ``"purcell"`` or ``"ng"`` (or ``"nlink"``, ``"nsphere"``).
    actions : array-like, shape (steps, 2) or (batch, steps, 2)
        ``(dof, roc)`` pairs: dof in 1..n_dof (as in the prompt), roc a real number in [-1, 1]
        (the fraction of the DOF's range moved in one step; {-1, 0, 1} is the paper's discrete
        world, stepped on the corner table; any other ROC goes through the integrator).
    key : jax key or int
        Seed of the noise (only used when ``zeta > 0`` or ``init="random"``); batch members get
        independent keys split from it.
    zeta, direction, init, **model_kwargs
        As in [`jswim.env.make_params`][jswim.env.params.make_params] (``d_max``, ``d_min``, ...).
    scene : jswim.scenes.Scene, optional
        Swim in a scene (``"ng"`` only): a wall, obstacles, two swimmers
        ([`jswim.env.scene_rollout`][jswim.env.scene_rollouts.scene_rollout], which returns a
        [`jswim.env.SceneRollout`][jswim.env.scene_rollouts.SceneRollout]; ``actions`` may then be ``(swimmer, dof, roc)``
        triples). ``None``, or one untilted swimmer in the ``"bulk"`` medium, is exactly this
        function without a scene.

    Returns
    -------
    Rollout
        ``x``, ``y`` (centroid), ``orientation``, ``dofs``, ``stuck``, ``progress``: one entry per
        step, the state after the step; NumPy arrays, float64 whatever ``jax_enable_x64`` says
        (the rollout runs under ``jax.enable_x64(True)``: ~1e-16 relative per cycle). A batch is
        sharded over every device; it holds ``8 (4 + n_dof) + 2`` bytes per swimmer and step.

    Raises
    ------
    ConfigError
        Actions that are not ``(dof, roc)`` pairs with ``dof`` in ``1..n_dof`` and ``|roc| <= 1``.

    Examples
    --------
    >>> r = rollout_moves("purcell", [(1, -1), (2, -1), (1, 1), (2, 1)])
    >>> r.x.shape
    (4,)
    >>> rollout_moves("purcell", [(1, -0.5), (2, -0.5)]).dofs[-1].round(4).tolist()
    [0.0, 0.0]
    """
    if scene is not None and not _is_plain_bulk(scene):
        from jswim.env.scene_rollouts import scene_rollout  # lazy: start-up (the scene physics)

        if direction not in (1, "+x", "+", "x", "+1", "1"):
            raise ConfigError(
                "direction is not a scene option: scene rollouts record x, z and tilt"
            )
        return scene_rollout(swimmer, actions, scene, key=key, zeta=zeta, init=init, **model_kwargs)
    params = make_params(swimmer, zeta=zeta, direction=direction, init=init, **model_kwargs)
    return moves_rollout(params, actions, key, _record)


def _is_plain_bulk(scene: Any) -> bool:
    """Whether ``scene`` is today's environment: one untilted swimmer in the bulk medium."""
    from jswim.env.registry import is_plain_bulk  # lazy: start-up (the scene modules)

    return is_plain_bulk(scene)
