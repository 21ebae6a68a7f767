"""Baselines on scenes (issue 19): a fixed stroke, the random policy and tabular Q-learning on
the joint state, each vectorised over runs (one ``lax.scan`` over steps, vmapped over runs).

The same task as the LLM's: the reward of a step is the progress of the swimmers' mean x in the
target direction; actions are joint codes (:mod:`jswim.agents.scene_env`) on the paper's ROCs
-1, 0, 1 (``K = 1``).

Q-learning's state is the **joint corner**: every arm of every swimmer short or long
(``2^(2S)`` shapes: 4 alone, 16 for a pair) and, with a wall, a coarse **height bin** of swimmer 1
(:data:`HEIGHT_EDGES`, in sphere radii: about doubling, so the bins are as fine near the wall as
the wall's effect is strong). The hyperparameters are the bulk learner's
(:class:`jswim.agents.qlearning.QConfig` defaults: alpha 1, gamma 0.9, epsilon 0.8^t, optimistic
start 0.35).
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np

from jswim.agents import scene_env
from jswim.agents.qlearning import QConfig

#: Height-bin edges of the Q-learner's wall state (a of the middle sphere above the wall).
HEIGHT_EDGES = (2.0, 3.5, 6.0, 10.0, 17.0, 30.0)


class SceneRun(NamedTuple):
    """Per-step record of a batch of scene runs (``B`` runs, ``T`` steps, ``S`` swimmers)."""

    actions: np.ndarray  # (B, T) joint codes
    x: np.ndarray  # (B, T) mean x after each step
    xs: np.ndarray  # (B, T, S)
    z: np.ndarray  # (B, T, S)
    tilt: np.ndarray  # (B, T, S)
    dofs: np.ndarray  # (B, T, 2S)
    stuck: np.ndarray  # (B, T)
    contact: np.ndarray  # (B, T)


def _n_actions(n_swimmers: int) -> int:
    return scene_env.ARMS * n_swimmers * 3


def offered(dofs: jax.Array, lo: float, hi: float, action_set: str) -> jax.Array:
    """Boolean mask over joint codes (K = 1): every code (``"all"``), or only the moves that change
    the shape (``"shape-changing"``)."""
    n = dofs.shape[-1]
    if action_set == "all":
        return jnp.ones((n * 3,), bool)
    mid = 0.5 * (lo + hi)
    long = dofs > mid
    m = jnp.stack([long, jnp.zeros_like(long), ~long], axis=-1)  # ROC -1 from long, +1 from short
    return m.reshape(-1)


def corner_state(dofs: jax.Array, z0: jax.Array, lo: float, hi: float, wall: bool) -> jax.Array:
    """The Q-table row: joint corner index (bit i = arm i long) times height bins when ``wall``."""
    bits = (dofs > 0.5 * (lo + hi)).astype(jnp.int32)
    corner = jnp.sum(bits * (2 ** jnp.arange(dofs.shape[-1])), axis=-1)
    if not wall:
        return corner
    hbin = jnp.searchsorted(jnp.asarray(HEIGHT_EDGES), z0).astype(jnp.int32)
    return corner * (len(HEIGHT_EDGES) + 1) + hbin


def n_states(n_swimmers: int, wall: bool) -> int:
    """Rows of the Q-table."""
    return 2 ** (scene_env.ARMS * n_swimmers) * ((len(HEIGHT_EDGES) + 1) if wall else 1)


def _pack(obs_seq: scene_env.Observation, actions: jax.Array) -> SceneRun:
    o = jax.device_get(obs_seq)
    return SceneRun(np.asarray(actions), np.asarray(o.x, np.float64), np.asarray(o.xs, np.float64),
                    np.asarray(o.z, np.float64), np.asarray(o.tilt, np.float64), np.asarray(o.dofs, np.float64),
                    np.asarray(o.stuck), np.asarray(o.contact))


def stroke(params: Any, codes: np.ndarray, keys: jax.Array) -> SceneRun:
    """Fixed joint action sequences ``codes`` ``(B, T)`` played from the scene's start."""
    codes = jnp.asarray(codes, jnp.int32)
    states, _ = scene_env.start(params, codes.shape[0])

    def one(state, seq, key):
        def body(st, inp):
            t, c = inp
            st, obs = scene_env.step(params, st, c, jax.random.fold_in(key, t))
            return st, obs
        return jax.lax.scan(body, state, (jnp.arange(seq.shape[0]), seq))[1]

    return _pack(jax.jit(jax.vmap(one))(states, codes, keys), codes)


def random_runs(params: Any, keys: jax.Array, steps: int, action_set: str = "all") -> SceneRun:
    """The random policy: a uniform choice among the offered joint codes at every step."""
    lo, hi = float(params.lo), float(params.hi)
    states, obs0 = scene_env.start(params, keys.shape[0])

    def one(state, dofs0, key):
        def body(carry, t):
            st, dofs = carry
            k_act, k_env = jax.random.split(jax.random.fold_in(key, t))
            mask = offered(dofs, lo, hi, action_set)
            code = jax.random.choice(k_act, mask.shape[0], p=mask / mask.sum())
            st, obs = scene_env.step(params, st, code, k_env)
            return (st, obs.dofs), (obs, code)
        return jax.lax.scan(body, (state, dofs0), jnp.arange(steps))[1]

    obs, codes = jax.jit(jax.vmap(one))(states, obs0.dofs, keys)
    return _pack(obs, codes)


def qlearning_runs(params: Any, keys: jax.Array, steps: int, direction: np.ndarray, *, wall: bool,
                   action_set: str = "all", config: QConfig = QConfig()) -> SceneRun:
    """Tabular Q-learning on the joint state (module docs), one learner per key, learning online
    for ``steps`` steps (the paper's protocol: the run's X is the learner's own trajectory).

    ``direction`` ``(B,)``: +1 or -1, the target direction of each run.
    """
    lo, hi = float(params.lo), float(params.hi)
    n_sw = int(params.scene.swimmers) if hasattr(params, "scene") else 1
    b = keys.shape[0]
    states, obs0 = scene_env.start(params, b)
    n_act = obs0.dofs.shape[-1] * 3
    rows = n_states(n_sw, wall)
    alpha = float(config.learning_rate) if not callable(config.learning_rate) else None
    gamma = float(config.discount)
    eps_fn = config.epsilon if callable(config.epsilon) else (lambda t, e=float(config.epsilon): e)
    q0 = jnp.full((rows, n_act), float(config.q_init))
    lr_fn = config.learning_rate if callable(config.learning_rate) else (lambda t: alpha)

    def one(state, obs, key, d):
        def body(carry, t):
            st, dofs, z0, x, q = carry
            s = corner_state(dofs, z0, lo, hi, wall)
            mask = offered(dofs, lo, hi, action_set)
            k_eps, k_rand, k_tie, k_env = jax.random.split(jax.random.fold_in(key, t), 4)
            row = jnp.where(mask, q[s], -jnp.inf)
            best = row >= row.max()
            greedy = jax.random.choice(k_tie, n_act, p=best / best.sum())
            rand = jax.random.choice(k_rand, n_act, p=mask / mask.sum())
            code = jnp.where(jax.random.uniform(k_eps) < eps_fn(t), rand, greedy)
            st, ob = scene_env.step(params, st, code, k_env)
            reward = d * (ob.x - x)
            s2 = corner_state(ob.dofs, ob.z[0], lo, hi, wall)
            mask2 = offered(ob.dofs, lo, hi, action_set)
            target = reward + gamma * jnp.max(jnp.where(mask2, q[s2], -jnp.inf))
            q = q.at[s, code].add(lr_fn(t) * (target - q[s, code]))
            return (st, ob.dofs, ob.z[0], ob.x, q), (ob, code)
        carry = (state, obs.dofs, obs.z[0], obs.x, q0)
        return jax.lax.scan(body, carry, jnp.arange(steps))[1]

    obs, codes = jax.jit(jax.vmap(one))(states, obs0, keys, jnp.asarray(direction, q0.dtype))
    return _pack(obs, codes)
