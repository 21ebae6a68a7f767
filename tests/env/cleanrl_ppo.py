"""PPO in the structure of CleanRL's single-file ``ppo.py`` (Huang et al. 2022), written for
jswim's tests and docs/rl.md: ``gym.make_vec`` environments stepped from a Python loop, rollouts
stored in NumPy buffers, GAE, then minibatch epochs of the clipped objective. The networks are
JAX and optax (CleanRL's JAX variants) so that it runs where torch is not installed.

Gymnasium 1.x vector envs autoreset on the *next* step: the step after an episode ends returns
the reset observation with reward 0 and ignores the action. Those steps are masked out of the
loss and cut the advantage, as CleanRL does with ``next_done``.
"""

from __future__ import annotations

import time

import gymnasium as gym
import jax
import jax.numpy as jnp
import numpy as np
import optax

import jswim.gym  # noqa: F401  (registers the ids)


def _init(key, sizes, last):
    out = []
    for i, k in enumerate(jax.random.split(key, len(sizes) - 1)):
        scale = last if i == len(sizes) - 2 else np.sqrt(2)
        w = jax.nn.initializers.orthogonal(scale)(k, (sizes[i], sizes[i + 1]), jnp.float32)
        out.append((w, jnp.zeros(sizes[i + 1], jnp.float32)))
    return out


def _mlp(layers, x):
    for w, b in layers[:-1]:
        x = jnp.tanh(x @ w + b)
    w, b = layers[-1]
    return x @ w + b


def train(
    env_id: str = "jswim/Purcell-v0",
    num_envs: int = 16,
    num_steps: int = 64,
    total_timesteps: int = 100_000,
    lr: float = 3e-3,
    gamma: float = 0.99,
    gae_lambda: float = 0.95,
    epochs: int = 4,
    minibatches: int = 4,
    clip: float = 0.2,
    seed: int = 0,
) -> list[tuple[int, float]]:
    """Train; returns ``(global_step, episode_return)`` of every episode that ended."""
    envs = gym.make_vec(env_id, num_envs=num_envs)
    n_obs = envs.single_observation_space.shape[0]
    n_act = envs.single_action_space.n
    key = jax.random.PRNGKey(seed)
    key, ka, kc = jax.random.split(key, 3)
    net = {
        "actor": _init(ka, [n_obs, 64, 64, n_act], 0.01),
        "critic": _init(kc, [n_obs, 64, 64, 1], 1.0),
    }
    tx = optax.chain(optax.clip_by_global_norm(0.5), optax.adam(lr, eps=1e-5))
    opt = tx.init(net)

    @jax.jit
    def act(net, obs, key):
        logits = _mlp(net["actor"], obs)
        a = jax.random.categorical(key, logits)
        logp = jnp.take_along_axis(jax.nn.log_softmax(logits), a[:, None], 1)[:, 0]
        return a, logp, _mlp(net["critic"], obs)[:, 0]

    @jax.jit
    def update(net, opt, obs, actions, logp_old, adv, ret, mask):
        def loss(net):
            logits = _mlp(net["actor"], obs)
            logp = jnp.take_along_axis(jax.nn.log_softmax(logits), actions[:, None], 1)[:, 0]
            ratio = jnp.exp(logp - logp_old)
            a = (adv - adv.mean()) / (adv.std() + 1e-8)
            pg = -jnp.minimum(ratio * a, jnp.clip(ratio, 1 - clip, 1 + clip) * a)
            v = 0.5 * (_mlp(net["critic"], obs)[:, 0] - ret) ** 2
            return jnp.sum((pg + 0.5 * v) * mask) / jnp.maximum(mask.sum(), 1)

        grads = jax.grad(loss)(net)
        updates, opt = tx.update(grads, opt, net)
        return optax.apply_updates(net, updates), opt

    shape = (num_steps, num_envs)
    obs_buf = np.zeros(shape + (n_obs,), np.float32)
    act_buf, logp_buf, val_buf, rew_buf, done_buf, mask_buf = (
        np.zeros(shape, t)
        for t in (np.int32, np.float32, np.float32, np.float32, np.float32, np.float32)
    )
    next_obs, _ = envs.reset(seed=seed)
    next_done = np.zeros(num_envs, bool)  # this step is an autoreset step
    episode = np.zeros(num_envs)
    returns: list[tuple[int, float]] = []
    global_step = 0
    for _ in range(total_timesteps // (num_envs * num_steps)):
        for t in range(num_steps):
            key, k = jax.random.split(key)
            a, logp, v = act(net, next_obs, k)
            obs_buf[t], mask_buf[t] = next_obs, ~next_done
            act_buf[t], logp_buf[t], val_buf[t] = np.asarray(a), np.asarray(logp), np.asarray(v)
            next_obs, r, term, trunc, _ = envs.step(np.asarray(a))
            global_step += num_envs
            rew_buf[t] = r
            episode += r
            next_done = term | trunc
            done_buf[t] = next_done
            for i in np.flatnonzero(next_done):
                returns.append((global_step, float(episode[i])))
                episode[i] = 0.0
        # GAE, cut at every episode end (truncation: no bootstrap from the reset state)
        last_v = np.asarray(act(net, next_obs, key)[2])
        adv = np.zeros(shape, np.float32)
        gae = np.zeros(num_envs, np.float32)
        for t in reversed(range(num_steps)):
            nv = last_v if t == num_steps - 1 else val_buf[t + 1]
            live = 1.0 - done_buf[t]
            delta = rew_buf[t] + gamma * nv * live - val_buf[t]
            gae = delta + gamma * gae_lambda * live * gae
            adv[t] = gae
        ret = adv + val_buf
        flat = [
            x.reshape((-1,) + x.shape[2:]) for x in (obs_buf, act_buf, logp_buf, adv, ret, mask_buf)
        ]
        n = flat[0].shape[0]
        rng = np.random.default_rng(global_step)
        for _ in range(epochs):
            perm = rng.permutation(n)
            for mb in np.array_split(perm, minibatches):
                net, opt = update(net, opt, *(jnp.asarray(x[mb]) for x in flat))
    envs.close()
    return returns


if __name__ == "__main__":
    t = time.perf_counter()
    out = train()
    print(
        f"{len(out)} episodes in {time.perf_counter() - t:.1f} s; last returns",
        [round(r, 3) for _, r in out[-5:]],
    )
