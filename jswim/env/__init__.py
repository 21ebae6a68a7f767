"""Functional, vectorisable environment for the swimmers of Xu & Zhu, discrete and continuous.

Each DOF takes any value in ``[lo, hi]``. An action picks one DOF and a rate of change ROC in
[-1, 1]; a step moves that DOF by ``ROC x (hi - lo)``, stopping at a limit (a push that cannot
move it at all is flagged ``stuck``; ROC 0 holds still). The paper's discrete world is ROC in
{-1, 0, 1} from a corner of the DOF cube: every step there sweeps a DOF across its whole range
and is read from an exact per-model table; other steps are integrated exactly (float64). Noise
follows the paper: ``(dX, dY) (1 + zeta Y)``, ``Y ~ U[-1, 1]``.

API in the gymnax style::

    params = make_params("purcell", zeta=0.5)
    state = reset(key, params)
    state, info = step(key, state, encode_action(1, -1), params)      # DOF 1 at ROC -1
    state, info = step(key, state, jnp.array([0.0, 0.3]), params)     # DOF 2 at ROC 0.3

Batch with ``jax.vmap(step, in_axes=(0, 0, 0, None))``; ``params`` is a pytree whose ``zeta``,
``direction`` and ``init`` leaves may also be batched.

The world protocol (one interface for this world and the scenes', [`base`][jswim.env.base]) and
the module of each concern: docs/design.md (module map, *The world protocol*)::

    env, params = make("ng", Scene(medium="wall", height=5.0), direction="-x")
    state = env.reset(key, params)
    state, info = env.step(key, state, env.action_space(params).sample(key), params)
"""

from jswim._exports import lazy_exports
from jswim.env.action_input import (
    ROCS,
    decode_action,
    encode_action,
    roc_vector,
    validate_actions,
    validate_moves,
)
from jswim.env.params import (
    EnvParams,
    broadcast_params,
    check_roc_levels,
    is_batched,
    make_params,
    param_axes,
    parse_direction,
)
from jswim.env.randomness import noise, uniforms
from jswim.start_levels import all_inits, parse_init
from jswim.env.rollouts import Rollout, rollout_moves, seed32, seed_key
from jswim.env.state import (
    EnvState,
    MoveInfo,
    corner_values,
    dof_values,
    fractions,
    position,
    reference_point,
    reset,
    start_orientation,
    start_state,
)
from jswim.env.stepping import advance, step, step_batch
from jswim.env.base import Box, Discrete, Environment, Observation, Scenery, StepInfo
from jswim.env.swimmer_world import SwimmerWorld
from jswim.env.step_tables import TABLE_DEGREE, step_table

#: The protocol's names that reach the scene physics, loaded on first use (PEP 562) so that
#: ``import jswim.env`` does not import `jswim.scenes`.
_LAZY = {
    "make": "jswim.env.registry",
    "SceneWorld": "jswim.env.scene_world",
    "SceneTask": "jswim.env.scene_world",
    "Trajectory": "jswim.env.episodes",
    "SceneRollout": "jswim.env.scene_rollouts",
    "parse_scene_moves": "jswim.env.scene_rollouts",
    "scene_rollout": "jswim.env.scene_rollouts",
    "scene_rollout_batch": "jswim.env.scene_rollouts",
}

__getattr__, __dir__ = lazy_exports(__name__, _LAZY)


__all__ = [
    "Box",
    "Discrete",
    "Environment",
    "Observation",
    "Scenery",
    "SwimmerWorld",
    *_LAZY,
    "ROCS",
    "TABLE_DEGREE",
    "EnvParams",
    "EnvState",
    "MoveInfo",
    "Rollout",
    "StepInfo",
    "advance",
    "all_inits",
    "broadcast_params",
    "check_roc_levels",
    "corner_values",
    "decode_action",
    "dof_values",
    "encode_action",
    "fractions",
    "is_batched",
    "make_params",
    "noise",
    "param_axes",
    "parse_direction",
    "parse_init",
    "position",
    "reference_point",
    "reset",
    "roc_vector",
    "rollout_moves",
    "seed32",
    "seed_key",
    "start_orientation",
    "start_state",
    "step",
    "step_batch",
    "step_table",
    "uniforms",
    "validate_actions",
    "validate_moves",
]
