"""The baselines' side of a scene (walls, obstacles, pairs; issue 19): joint action codes and
batched steps for the scene baselines and the scene studies (the LLM driver steps any world
through the world protocol instead: :mod:`jswim.agents.step_batcher`).

An agent steers every swimmer of a scene through one set of **joint DOFs**: swimmer ``s``
(0-based) owns DOFs ``2s + 1`` and ``2s + 2`` (its two arms, 1-based as in the prompt), so the
paper's reply ``[changed DOF, ROC]`` names the swimmer through its DOF (``[3, 1]`` lengthens swimmer
2's first arm). A joint action code is the paper's lattice code over the joint DOFs,
``(dof - 1)(2K + 1) + k + K`` (:func:`jswim.judging.lattice.encode`), so one swimmer's codes are the
bulk swimmer's codes unchanged.

The environment is :mod:`jswim.scenes` (the hydrodynamics, part A of issue 19).
"""

from __future__ import annotations

import json
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jswim.scenes import Scene, decode_scene_action, scene_advance, scene_params, scene_reset, scene_step

#: Arms (DOFs) of one NG swimmer.
ARMS = 2


def canonical(scene: Any) -> str:
    """A scene as canonical JSON (``Scene.to_dict()``, sorted keys): the form plans and run ids
    carry; ``""`` is no scene (the paper's bulk swimmer through :mod:`jswim.env`)."""
    if scene is None or scene == "":
        return ""
    if isinstance(scene, str):
        scene = from_json(scene)
    return json.dumps(scene.to_dict(), sort_keys=True)


def from_json(text: str) -> Any:
    """The :class:`Scene` of :func:`canonical`'s text (validated)."""
    return Scene.from_dict(json.loads(text))


def start_levels(init: Any) -> tuple[int, ...] | None:
    """The ``init`` of :func:`scene_params` (every swimmer's arm levels) from a plan's or spec's
    start: corner levels as given, ``None`` (the scene's default) for anything else."""
    if isinstance(init, (tuple, list)) and all(v in (0, 1) for v in init):
        return tuple(int(v) for v in init)
    return None


def has_wall(scene: Any) -> bool:
    return scene.medium == "wall"


def decode(codes: jax.Array, roc_levels: int = 1) -> tuple[jax.Array, jax.Array, jax.Array]:
    """Joint action codes -> ``(swimmer, dof, roc)`` of :func:`jswim.scenes.scene_step`: the
    swimmer and its arm 0-based (int32), the ROC ``k / K`` as a float (the joint codes are
    :func:`jswim.scenes.encode_scene_action`'s)."""
    return decode_scene_action(codes, roc_levels)


class Observation(NamedTuple):
    """What the agents read after a step, per scene in a batch (leading axis ``B``).

    ``x`` is the swimmers' mean position (:func:`centroid_x`) (the quantity whose progress is rewarded), ``xs``,
    ``z`` (the middle sphere's height above the wall, in a) and ``tilt`` (rad) per swimmer
    ``(B, S)``, ``dofs`` the joint arm lengths ``(B, 2S)``, ``stuck`` whether a non-zero ROC could
    not move its arm, ``contact`` whether any sphere touched the wall or another body.
    """

    x: jax.Array
    xs: jax.Array
    z: jax.Array
    tilt: jax.Array
    dofs: jax.Array
    stuck: jax.Array
    contact: jax.Array


def centroid_x(state: Any, medium: str) -> jax.Array:
    """Each swimmer's position along x ``(S,)``: the centroid of its three spheres (the middle
    sphere's x plus ``(d2 - d1) cos(tilt) / 3``), the point whose velocity the paper's formula gives.
    The middle sphere itself jumps by more than 1 a at every move while the swimmer nets 0.17 a per
    cycle; the centroid moves by about a tenth of that per move, as the bulk swimmer's X does. In the
    ``"bulk"`` medium the state's x already is the paper's X."""
    x = state.centre[..., 0]
    if medium == "bulk":
        return x
    return x + (state.arms[..., 1] - state.arms[..., 0]) * jnp.cos(state.tilt) / 3.0


def observe(state: Any, stuck: Any = False, contact: Any = False, medium: str = "bulk") -> Observation:
    """The :class:`Observation` of one (unbatched) scene state (positions: :func:`centroid_x`;
    heights: the middle sphere's)."""
    xs = centroid_x(state, medium)
    return Observation(jnp.mean(xs, axis=-1), xs, state.centre[..., 1], state.tilt,
                       state.arms.reshape(state.arms.shape[:-2] + (-1,)), jnp.asarray(stuck, bool).reshape(()),
                       jnp.any(jnp.asarray(contact, bool)))


def start(params: Any, batch: int) -> tuple[Any, Observation]:
    """``batch`` copies of the scene's start state and their observation."""
    s0 = scene_reset(params)
    states = jax.tree.map(lambda a: jnp.broadcast_to(a, (batch,) + jnp.shape(a)), s0)
    return states, jax.vmap(lambda st: observe(st, medium=params.scene.medium))(states)


def step(params: Any, state: Any, code: jax.Array, key: jax.Array, roc_levels: int = 1) -> tuple[Any, Observation]:
    """One joint action on one scene state (vmap it for batches)."""
    sw, dof, roc = decode(code, roc_levels)
    new, info = scene_step(params, state, (sw, dof, roc), key)
    return new, observe(new, jnp.any(jnp.asarray(info.stuck)), info.contact, params.scene.medium)


def advance(params: Any, state: Any, action: Any, y_noise: jax.Array) -> tuple[Any, Observation]:
    """One ``(swimmer, arm, real ROC)`` action on one scene state with given noise variables
    ``(S,)`` in [-1, 1] (the PPO baseline's step, :mod:`jswim.agents.ppo_envs`): the new state and
    its :class:`Observation`."""
    new, info = scene_advance(params, state, action, y_noise)
    return new, observe(new, jnp.any(jnp.asarray(info.stuck)), info.contact, params.scene.medium)


def as_numpy(obs: Observation) -> dict[str, np.ndarray]:
    """An observation's arrays on the host, float64 where real."""
    out = jax.device_get(obs._asdict())
    return {k: np.asarray(v, np.float64 if k not in ("stuck", "contact") else bool) for k, v in out.items()}
