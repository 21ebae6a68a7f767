"""PPO in the structure of PureJaxRL's ``ppo.py`` (Lu et al. 2022), written for jswim's tests and
docs/rl.md: the env wrapped in gymnax's ``FlattenObservationWrapper`` and ``LogWrapper``, envs
vmapped, time scanned, the whole training run one jitted function. Plain JAX and optax (no
network library): two tanh MLPs, a categorical head for ``Discrete`` actions and a Gaussian head
(state-independent log std) for ``Box`` actions.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import optax
from gymnax.environments import spaces
from gymnax.wrappers.purerl import FlattenObservationWrapper, LogWrapper

CONFIG = {
    "LR": 3e-3,
    "NUM_ENVS": 16,
    "NUM_STEPS": 64,
    "TOTAL_TIMESTEPS": 200_000,
    "UPDATE_EPOCHS": 4,
    "NUM_MINIBATCHES": 4,
    "GAMMA": 0.99,
    "GAE_LAMBDA": 0.95,
    "CLIP_EPS": 0.2,
    "ENT_COEF": 0.0,
    "VF_COEF": 0.5,
    "MAX_GRAD_NORM": 0.5,
    "HIDDEN": 64,
}


class Transition(NamedTuple):
    done: jax.Array
    action: jax.Array
    value: jax.Array
    reward: jax.Array
    log_prob: jax.Array
    obs: jax.Array
    info: Any


def _init_mlp(key: jax.Array, sizes: list[int], last_scale: float) -> list:
    layers = []
    keys = jax.random.split(key, len(sizes) - 1)
    for i, (k, n_in, n_out) in enumerate(zip(keys, sizes[:-1], sizes[1:], strict=True)):
        scale = last_scale if i == len(sizes) - 2 else jnp.sqrt(2.0)
        w = jax.nn.initializers.orthogonal(scale)(k, (n_in, n_out), jnp.float32)
        layers.append((w, jnp.zeros(n_out, jnp.float32)))
    return layers


def _mlp(layers: list, x: jax.Array) -> jax.Array:
    for w, b in layers[:-1]:
        x = jnp.tanh(x @ w + b)
    w, b = layers[-1]
    return x @ w + b


def make_train(config: dict, env: Any, env_params: Any):
    """PureJaxRL's ``make_train``: ``train(key) -> {"runner_state", "metrics"}``; ``metrics`` is
    LogWrapper's info per update, step and env (``returned_episode_returns`` ...)."""
    config = {**CONFIG, **config}
    num_updates = config["TOTAL_TIMESTEPS"] // config["NUM_STEPS"] // config["NUM_ENVS"]
    minibatch = config["NUM_ENVS"] * config["NUM_STEPS"] // config["NUM_MINIBATCHES"]
    env = LogWrapper(FlattenObservationWrapper(env))
    action_space = env.action_space(env_params)
    continuous = isinstance(action_space, spaces.Box)
    n_obs = env.observation_space(env_params).shape[0]
    n_out = action_space.shape[0] if continuous else action_space.n
    hidden = config["HIDDEN"]

    def init(key):
        ka, kc = jax.random.split(key)
        return {
            "actor": _init_mlp(ka, [n_obs, hidden, hidden, n_out], 0.01),
            "critic": _init_mlp(kc, [n_obs, hidden, hidden, 1], 1.0),
            "log_std": jnp.zeros(n_out, jnp.float32),
        }

    def dist(net, obs):
        out = _mlp(net["actor"], obs)
        value = _mlp(net["critic"], obs)[..., 0]
        return out, value

    def log_prob(net, out, action):
        if continuous:
            std = jnp.exp(net["log_std"])
            z = (action - out) / std
            return jnp.sum(-0.5 * z**2 - net["log_std"] - 0.5 * jnp.log(2 * jnp.pi), -1)
        return jnp.take_along_axis(jax.nn.log_softmax(out), action[..., None], -1)[..., 0]

    def entropy(net, out):
        if continuous:
            return jnp.sum(net["log_std"] + 0.5 * jnp.log(2 * jnp.pi * jnp.e)) * jnp.ones(
                out.shape[:-1]
            )
        p = jax.nn.softmax(out)
        return -jnp.sum(p * jax.nn.log_softmax(out), -1)

    def sample(net, out, key):
        if continuous:
            return out + jnp.exp(net["log_std"]) * jax.random.normal(key, out.shape)
        return jax.random.categorical(key, out)

    tx = optax.chain(
        optax.clip_by_global_norm(config["MAX_GRAD_NORM"]), optax.adam(config["LR"], eps=1e-5)
    )

    def train(key):
        key, k_net, k_env = jax.random.split(key, 3)
        net = init(k_net)
        opt_state = tx.init(net)
        obs, env_state = jax.vmap(env.reset, in_axes=(0, None))(
            jax.random.split(k_env, config["NUM_ENVS"]), env_params
        )

        def update_step(runner_state, _):
            def env_step(runner_state, _):
                net, opt_state, env_state, last_obs, key = runner_state
                key, k_act, k_step = jax.random.split(key, 3)
                out, value = dist(net, last_obs)
                action = sample(net, out, k_act)
                logp = log_prob(net, out, action)
                obs, env_state, reward, _term, truncated, info = jax.vmap(
                    env.step, in_axes=(0, 0, 0, None)
                )(jax.random.split(k_step, config["NUM_ENVS"]), env_state, action, env_params)
                t = Transition(truncated, action, value, reward, logp, last_obs, info)
                return (net, opt_state, env_state, obs, key), t

            runner_state, traj = jax.lax.scan(env_step, runner_state, None, config["NUM_STEPS"])
            net, opt_state, env_state, last_obs, key = runner_state
            last_value = dist(net, last_obs)[1]

            def gae(carry, t):
                adv, next_value = carry
                # A truncated episode is cut, not ended: the reset state's value is not the
                # bootstrap, so the advantage stops there (as PureJaxRL does with done).
                delta = t.reward + config["GAMMA"] * next_value * (1 - t.done) - t.value
                adv = delta + config["GAMMA"] * config["GAE_LAMBDA"] * (1 - t.done) * adv
                return (adv, t.value), adv

            _, adv = jax.lax.scan(
                gae, (jnp.zeros_like(last_value), last_value), traj, reverse=True, unroll=16
            )
            targets = adv + traj.value

            def epoch(carry, _):
                net, opt_state, key = carry
                key, k = jax.random.split(key)
                batch = jax.tree.map(
                    lambda v: v.reshape((-1,) + v.shape[2:]),
                    (traj.obs, traj.action, traj.log_prob, adv, targets),
                )
                perm = jax.random.permutation(k, batch[0].shape[0])
                batch = jax.tree.map(
                    lambda v: v[perm].reshape((config["NUM_MINIBATCHES"], minibatch) + v.shape[1:]),
                    batch,
                )

                def minibatch_step(carry, mb):
                    net, opt_state = carry
                    obs, action, old_logp, adv, target = mb

                    def loss(net):
                        out, value = dist(net, obs)
                        logp = log_prob(net, out, action)
                        ratio = jnp.exp(logp - old_logp)
                        a = (adv - adv.mean()) / (adv.std() + 1e-8)
                        actor = -jnp.mean(
                            jnp.minimum(
                                ratio * a,
                                jnp.clip(ratio, 1 - config["CLIP_EPS"], 1 + config["CLIP_EPS"]) * a,
                            )
                        )
                        critic = 0.5 * jnp.mean((value - target) ** 2)
                        ent = jnp.mean(entropy(net, out))
                        return actor + config["VF_COEF"] * critic - config["ENT_COEF"] * ent

                    grads = jax.grad(loss)(net)
                    updates, opt_state = tx.update(grads, opt_state, net)
                    return (optax.apply_updates(net, updates), opt_state), None

                (net, opt_state), _ = jax.lax.scan(minibatch_step, (net, opt_state), batch)
                return (net, opt_state, key), None

            (net, opt_state, key), _ = jax.lax.scan(
                epoch, (net, opt_state, key), None, config["UPDATE_EPOCHS"]
            )
            return (net, opt_state, env_state, last_obs, key), traj.info

        runner_state = (net, opt_state, env_state, obs, key)
        runner_state, metrics = jax.lax.scan(update_step, runner_state, None, num_updates)
        return {"runner_state": runner_state, "metrics": metrics}

    return train


def episode_returns(metrics: dict) -> jax.Array:
    """The returns of the episodes completed in each update, mean over them ``(num_updates,)``."""
    done = metrics["returned_episode"]
    r = metrics["returned_episode_returns"]
    axes = tuple(range(1, done.ndim))
    return jnp.sum(r * done, axes) / jnp.maximum(jnp.sum(done, axes), 1)
