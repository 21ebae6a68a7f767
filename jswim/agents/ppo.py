"""Continuous-action RL baseline: PPO on one swimmer, thousands of learners at once.

The learner sees what the Q-learner and the LLM see: the shape (each DOF's value, scaled to
[-1, 1]). An action is a DOF and a real ROC in [-1, 1], the environment's continuous action
(`jswim.env`): a one-hot ROC vector of shape ``(n_dof,)``. The reward of a step is its
progress in the target direction (``StepInfo.progress``, noisy when ``zeta > 0``). As for the
Q-learner there are no episodes: one learner is one swimmer that keeps swimming for
``config.steps`` steps, and every step it takes is part of its record, so "steps to learn" is
read from the training run itself, as for the other agents.

Algorithm (proximal policy optimisation, Schulman et al. 2017, in the PureJaxRL style: the whole
run is one jitted ``lax.scan``, vmapped over learners)::

    repeat steps / rollout times:
        act `rollout` steps with the current policy (one swimmer, no reset)
        advantages by GAE(lambda), bootstrapped from V(last shape) (a continuing task)
        `epochs` full-batch Adam steps on the clipped surrogate + value loss

Policy (plain JAX, no framework): two small tanh MLPs on the scaled shape. The actor gives
``n_dof`` DOF logits (a categorical choice of the DOF to move) and ``n_dof`` ROC means; the ROC is
``clip(u, -1, 1)`` with ``u ~ N(mean[dof], std[dof])`` (the log-probability is that of ``u``,
the usual treatment of bounded actions in PPO: the clip is part of the environment's reading of
the action, so a policy can reach a limit exactly and return to the same shape, which a squashed
distribution never quite does). ``log std`` is a learned vector per DOF. The critic gives V.
With ``PPOConfig(policy="categorical")`` the actor instead gives one logit per integer action
code of the world (``env.n_actions``) and acts with the code (a discrete PPO, opt-in).

Exploration must end for a learner to keep a stroke to the end of its run (the success
criterion); the policy's own std and logits sharpen as it learns, and a temperature ``tau(t)``
(default: 1 until ``anneal_start`` then down to ``anneal_end`` by the last step, see
[`PPOConfig`][jswim.agents.ppo.PPOConfig]) divides the logits and multiplies the std of the distribution that acts.
The temperature is part of the behaviour policy, and the PPO ratio uses the same tempered
distribution for old and new parameters, so the surrogate stays on-policy.

Example::

    import jax
    import jswim
    from jswim.agents.ppo import PPOConfig, train, evaluate

    env, params = jswim.make("purcell")
    run = train(env, params, jax.random.split(jax.random.PRNGKey(0), 1000), PPOConfig())
    report = evaluate(run, env.batch_params(params, 1000)[0])   # steps to learn, success, ...

The same learner runs in any world of the protocol (a wall or a pair of `jswim.scenes`, a
registered world), judged by [`evaluate`][jswim.agents.ppo_judge.evaluate]; every world is
stepped as the other baselines step it
([`Environment.learner_advance`][jswim.env.base.Environment.learner_advance]).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from typing import Any, NamedTuple
from collections.abc import Callable

import jax
import jax.numpy as jnp
import optax
from jax import Array

from jswim import env as _env
from jswim import sharding
from jswim.agents.rewards import energy_reward
from jswim.agents.qlearning import training_compiler_options
from jswim.env.base import Environment
from jswim.env.episodes import Trajectory
from jswim.agents.ppo_judge import evaluate, evaluate_swimmers, exact_x  # noqa: F401  (the judge, next to the learner)
from jswim.errors import ConfigError, check_choice
from jswim.reals import plain

#: The actor heads of `PPOConfig.policy`.
POLICIES = ("gaussian", "categorical")


@dataclasses.dataclass(frozen=True)
class PPOConfig:
    """Hyperparameters of a PPO learner (static: one compilation per distinct config).

    Chosen on Purcell's noiseless swimmer from the paper's start, 16-64 seeds per setting and
    direction (a small sweep: the shared 2-core machine allowed about a dozen settings); the
    README's "Continuous strokes" section lists what was tried and the 1,000-seed results.

    Attributes
    ----------
    steps : int
        Environment steps per run (200, the Q-learner's budget).
    rollout : int
        Steps per policy update (4): short, because 200 steps allow only ``steps / rollout``
        updates (50 here; 8 steps per update learned less).
    epochs : int
        Full-batch Adam steps per rollout (8).
    learning_rate : float
        Adam's step size (3e-3; 1e-2 learned less, 6e-3 no better).
    discount : float
        ``gamma`` (0.9, as the Q-learner: NG's cycle needs ``gamma > 0.743``, see
        [`jswim.agents.qlearning.QConfig`][jswim.agents.qlearning.QConfig]).
    gae_lambda : float
        GAE's ``lambda`` (0.5; 0.9 learned less at 200 steps).
    clip : float
        PPO's ratio clip ``epsilon`` (0.2).
    value_coef : float
        Weight of the value loss (0.5).
    entropy_coef : float
        Weight of the entropy bonus (0.03; it keeps exploring after the first rewards).
    max_grad_norm : float
        Global-norm gradient clip (0.5).
    hidden : int
        Width of the two hidden layers of each MLP (32).
    init_std : float
        Initial std of the ROC's Gaussian before the clip (2.0: about 60 % of the first pushes
        reach a limit, i.e. sweep the whole remaining range).
    anneal_start : float
        Fraction of the run after which the temperature starts to fall (0.5; from the start
        (0) or a quarter in, the policy froze before it had found a stroke).
    anneal_end : float
        Temperature at the last step (0.05).
    normalize_advantages : bool
        Standardise advantages per rollout (False: with 4 samples the standardised values are
        noise when the rewards are all 0, and drove the policy to push against a limit).
    reward_norm : bool
        Divide rewards by their running RMS over the learner's run so far (True).
    energy_weight : float
        ``lambda`` of the energy-aware reward ``progress - lambda x work``
        ([`StepInfo.work`][jswim.env.base.StepInfo], in the world's work units per unit length
        of progress). 0.0 (the default) rewards progress alone, the paper's reward, with the
        same numbers as without the option; the world must count work (not ``nan``) when > 0.
    max_std : float or None
        Upper bound on the ROC's std before the clip (static; None, the default: unbounded).
        The entropy bonus is the Gaussian's before the clip, so an unbounded std can grow
        while every push lands on a limit (a deterministic, often stuck, action); on K >= 2
        levels, where the half moves matter, that froze navigation learners
        (docs/navigation.md).
    envs : int
        Swimmers per learner (static; 1, the default: one swimmer, the paper's learner). Each
        update pools ``envs x rollout`` steps under one policy; the run's record (and
        ``trace``) is the first swimmer's. With one swimmer a rollout's advantages on a task
        whose random moves earn about nothing are mostly noise, and navigation learners drifted
        into doing nothing (docs/navigation.md).
    policy : str
        The actor's head (static). ``"gaussian"`` (the default, the paper's continuous learner):
        a categorical DOF and a Gaussian ROC clipped to [-1, 1], as above. ``"categorical"``:
        one categorical over the world's integer action codes (``env.n_actions``, the
        Q-learner's actions: every DOF and ROC ``k / K``), tempered by ``tau(t)`` as the DOF's
        logits are; ``init_std``, ``max_std`` are then unused. On K levels a Gaussian rounded
        to the lattice pushed navigation learners against their limits; the categorical
        reaches the 90-degree target (docs/navigation.md).
    """

    steps: int = 200
    rollout: int = 4
    epochs: int = 8
    learning_rate: float = 3e-3
    discount: float = 0.9
    gae_lambda: float = 0.5
    clip: float = 0.2
    value_coef: float = 0.5
    entropy_coef: float = 0.03
    max_grad_norm: float = 0.5
    hidden: int = 32
    init_std: float = 2.0
    anneal_start: float = 0.5
    anneal_end: float = 0.05
    normalize_advantages: bool = False
    reward_norm: bool = True
    energy_weight: float = 0.0
    max_std: float | None = None
    envs: int = 1
    policy: str = "gaussian"

    def __post_init__(self) -> None:
        # A NumPy number (np.float32(0.1), a value read from an array) is the plain Python number
        # it holds: configs are hashed into jit's cache.
        for field in dataclasses.fields(self):
            object.__setattr__(self, field.name, plain(getattr(self, field.name)))
        energy_reward(self.energy_weight)  # raises on a bad weight
        check_choice(self.policy, POLICIES, "PPO policy")
        for name in ("steps", "rollout", "epochs", "hidden", "envs"):
            value = getattr(self, name)
            if not isinstance(value, int) or isinstance(value, bool) or value < 1:
                raise ConfigError(f"{name} must be a positive integer, got {value!r}")
        if not 0.0 <= self.discount < 1.0:
            raise ConfigError(
                f"discount must lie in [0, 1) (the task never ends), got {self.discount!r}"
            )
        if not 0.0 <= self.gae_lambda <= 1.0:
            raise ConfigError(f"gae_lambda must lie in [0, 1], got {self.gae_lambda!r}")
        if not 0.0 <= self.anneal_start <= 1.0:
            raise ConfigError(f"anneal_start must lie in [0, 1], got {self.anneal_start!r}")
        for name in ("learning_rate", "clip", "init_std", "anneal_end", "max_grad_norm"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ConfigError(f"{name} must be a positive number, got {value!r}")
        if self.max_std is not None and not (
            isinstance(self.max_std, (int, float))
            and math.isfinite(self.max_std)
            and self.max_std > 0
        ):
            raise ConfigError(f"max_std must be None or a positive number, got {self.max_std!r}")
        for name in ("value_coef", "entropy_coef"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ConfigError(f"{name} must be a number >= 0, got {value!r}")

    def replace(self, **changes: Any) -> PPOConfig:
        """A copy with some fields changed."""
        return dataclasses.replace(self, **changes)

    def temperature(self, t: Array) -> Array:
        """``tau(t)`` of step ``t`` (0-based): 1, then geometric down to ``anneal_end``."""
        return _temperature(t, self.steps, self.anneal_start, self.anneal_end)


#: The numeric hyperparameters: traced, not static, so one compilation serves every value (and
#: a sweep can vmap over them).
NUMERIC = (
    "learning_rate",
    "discount",
    "gae_lambda",
    "clip",
    "value_coef",
    "entropy_coef",
    "max_grad_norm",
    "init_std",
    "anneal_start",
    "anneal_end",
)


def _numbers(config: PPOConfig) -> dict[str, Array]:
    dtype = jnp.result_type(float)
    return {name: jnp.asarray(getattr(config, name), dtype) for name in NUMERIC}


def _structure(config: PPOConfig) -> PPOConfig:
    """``config`` with its numeric fields at their defaults: the static part (jit cache key)."""
    return dataclasses.replace(config, **{name: getattr(PPOConfig, name) for name in NUMERIC})


def _temperature(t: Array, steps: int, start: Array, end: Array) -> Array:
    t0 = start * (steps - 1)
    frac = jnp.clip((t - t0) / jnp.maximum(steps - 1 - t0, 1e-9), 0.0, 1.0)
    return jnp.asarray(end, jnp.result_type(float)) ** frac


class PPORun(NamedTuple):
    """What training recorded, per learner (leading batch axis for a batch of keys).

    Attributes
    ----------
    actions : float (steps, n_dof)
        Executed continuous actions: the ROC vector (one non-zero entry, in [-1, 1]) the
        environment got.
    dof : int8 (steps,)
        The DOF chosen, 1-based as in the prompt.
    x : float (steps,)
        Centroid x after each step (noisy when ``zeta > 0``), the X of the paper.
    progress : float (steps,)
        Reward of each step, ``direction * dx``.
    dofs : float (steps, n_dof)
        DOF values after each step.
    dofs0 : float (n_dof,)
        DOF values at the start.
    y, orientation : float (steps,)
        Centroid y and orientation (rad, of the reference link) after each step.
    trace : Trajectory or None
        With ``trace=True`` ([`train`][jswim.agents.ppo.train]): the world's state, observation and
        [`StepInfo`][jswim.env.base.StepInfo] after each step ([`jswim.env.episodes.Trajectory`][jswim.env.episodes.Trajectory];
        what the scene studies' rows read: every swimmer's position, height, tilt, stuck, contact).
    """

    actions: Array
    dof: Array
    x: Array
    progress: Array
    dofs: Array
    dofs0: Array
    y: Array
    orientation: Array
    trace: Any = None


# ----------------------------------------------------------------------------- policy


def _dense(key: Array, n_in: int, n_out: int, scale: float, dtype: Any) -> tuple[Array, Array]:
    # Gaussian weights of variance scale^2 / fan_in. Not orthogonal (PureJaxRL's choice): a
    # vmapped orthogonal init is a batched LAPACK QR, which hung XLA:CPU at 384+ learners.
    w = jax.random.normal(key, (n_in, n_out), dtype) * (scale / math.sqrt(n_in))
    return w, jnp.zeros((n_out,), dtype)


def init_policy(
    key: Array,
    n_dof: int,
    hidden: int = 32,
    init_std: float | Array = 1.0,
    n_obs: int | None = None,
    n_logits: int | None = None,
) -> dict[str, Any]:
    """Initial network parameters: Gaussian weights of std ``gain / sqrt(fan_in)``, gains as in
    PureJaxRL (sqrt 2 for hidden layers, 0.01 for the actor's head so the first policy is near
    uniform over DOFs with ROC mean ~0, 1 for the critic's head), zero biases. ``n_obs`` is the
    observation's length (default ``n_dof``: the shape alone). ``n_logits``: the actor's
    outputs (default ``2 n_dof``: DOF logits and ROC means; a categorical policy's action count).

    Returns
    -------
    dict
        ``actor`` and ``critic``: lists of ``(W, b)``; ``log_std``: float (n_dof,).
    """
    dtype = jnp.result_type(float)
    h = hidden
    n_in = n_dof if n_obs is None else n_obs
    ka, kc = jax.random.split(key)
    ka = jax.random.split(ka, 3)
    kc = jax.random.split(kc, 3)
    root2 = math.sqrt(2.0)
    actor = [
        _dense(ka[0], n_in, h, root2, dtype),
        _dense(ka[1], h, h, root2, dtype),
        _dense(ka[2], h, 2 * n_dof if n_logits is None else n_logits, 0.01, dtype),
    ]
    critic = [
        _dense(kc[0], n_in, h, root2, dtype),
        _dense(kc[1], h, h, root2, dtype),
        _dense(kc[2], h, 1, 1.0, dtype),
    ]
    log_std = jnp.full((n_dof,), jnp.log(init_std), dtype)
    return {"actor": actor, "critic": critic, "log_std": log_std}


def _mlp(layers: list[tuple[Array, Array]], x: Array) -> Array:
    for w, b in layers[:-1]:
        x = jnp.tanh(x @ w + b)
    w, b = layers[-1]
    return x @ w + b


def policy(
    net: dict[str, Any], obs: Array, max_std: float | None = None
) -> tuple[Array, Array, Array, Array]:
    """``(dof logits, ROC means, ROC log-stds, value)`` for observations ``obs`` (..., n_obs)."""
    out = _mlp(net["actor"], obs)
    n = out.shape[-1] // 2
    value = _mlp(net["critic"], obs)[..., 0]
    log_std = net["log_std"]
    if max_std is not None:
        log_std = jnp.minimum(log_std, math.log(max_std))
    return out[..., :n], out[..., n:], jnp.broadcast_to(log_std, out[..., n:].shape), value


def _log_prob(
    logits: Array, mean: Array, log_std: Array, dof: Array, u: Array, tau: Array
) -> Array:
    """Log-density of (dof, u) under the tempered policy (logits / tau, std * tau)."""
    logp_dof = jnp.take_along_axis(jax.nn.log_softmax(logits / tau[..., None]), dof[..., None], -1)[
        ..., 0
    ]
    m = jnp.take_along_axis(mean, dof[..., None], -1)[..., 0]
    ls = jnp.take_along_axis(log_std, dof[..., None], -1)[..., 0] + jnp.log(tau)
    z = (u - m) * jnp.exp(-ls)
    return logp_dof - 0.5 * z * z - ls - 0.5 * math.log(2 * math.pi)


def _entropy(logits: Array, log_std: Array, tau: Array) -> Array:
    """Entropy of the tempered policy: the categorical's plus the expected Gaussian's."""
    logp = jax.nn.log_softmax(logits / tau[..., None])
    p = jnp.exp(logp)
    gauss = log_std + jnp.log(tau)[..., None] + 0.5 * (1.0 + math.log(2 * math.pi))
    return -jnp.sum(p * logp, -1) + jnp.sum(p * gauss, -1)


def _sample(
    logits: Array, mean: Array, log_std: Array, tau: Array, u_dof: Array, z: Array
) -> tuple[Array, Array]:
    """A DOF (inverse CDF of the tempered categorical at ``u_dof``) and ``u = mean + std z``."""
    cdf = jnp.cumsum(jax.nn.softmax(logits / tau), -1)
    dof = jnp.minimum(jnp.sum(cdf < u_dof, dtype=jnp.int32), logits.shape[-1] - 1)
    onehot = jnp.arange(logits.shape[-1]) == dof
    m = jnp.sum(jnp.where(onehot, mean, 0.0))
    ls = jnp.sum(jnp.where(onehot, log_std, 0.0))
    return dof, m + jnp.exp(ls) * tau * z


def _code_log_prob(logits: Array, code: Array, tau: Array) -> Array:
    """Log-probability of action code ``code`` under the tempered categorical ``logits / tau``."""
    logp = jax.nn.log_softmax(logits / tau[..., None])
    return jnp.take_along_axis(logp, code[..., None], -1)[..., 0]


def _code_entropy(logits: Array, tau: Array) -> Array:
    logp = jax.nn.log_softmax(logits / tau[..., None])
    return -jnp.sum(jnp.exp(logp) * logp, -1)


def _sample_code(logits: Array, tau: Array, u: Array) -> Array:
    """An action code: the inverse CDF of the tempered categorical at the uniform ``u``."""
    cdf = jnp.cumsum(jax.nn.softmax(logits / tau), -1)
    return jnp.minimum(jnp.sum(cdf < u, dtype=jnp.int32), logits.shape[-1] - 1)


# ----------------------------------------------------------------------------- training


class _Batch(NamedTuple):
    """One rollout, time-major (rollout,)."""

    obs: Array
    dof: Array  # the DOF (gaussian) or the action code (categorical)
    u: Array
    logp: Array
    value: Array
    reward: Array
    tau: Array


def _gae(reward: Array, value: Array, last_value: Array, gamma: float, lam: float) -> Array:
    """Generalised advantage estimates of a continuing task (no episode ends)."""

    def back(carry, inp):
        adv, next_v = carry
        r, v = inp
        delta = r + gamma * next_v - v
        adv = delta + gamma * lam * adv
        return (adv, v), adv

    _, adv = jax.lax.scan(
        back, (jnp.zeros_like(last_value), last_value), (reward, value), reverse=True
    )
    return adv


def _loss(
    net: dict[str, Any], batch: _Batch, adv: Array, target: Array, config: PPOConfig, hp: dict
) -> Array:
    if config.policy == "categorical":
        logits = _mlp(net["actor"], batch.obs)
        value = _mlp(net["critic"], batch.obs)[..., 0]
        logp = _code_log_prob(logits, batch.dof, batch.tau)
        entropy = jnp.mean(_code_entropy(logits, batch.tau))
    else:
        logits, mean, log_std, value = policy(net, batch.obs, config.max_std)
        logp = _log_prob(logits, mean, log_std, batch.dof, batch.u, batch.tau)
        entropy = jnp.mean(_entropy(logits, log_std, batch.tau))
    ratio = jnp.exp(logp - batch.logp)
    a = (adv - adv.mean()) / (adv.std() + 1e-8) if config.normalize_advantages else adv
    surrogate = jnp.minimum(ratio * a, jnp.clip(ratio, 1.0 - hp["clip"], 1.0 + hp["clip"]) * a)
    value_loss = 0.5 * jnp.mean((value - target) ** 2)
    return -jnp.mean(surrogate) + hp["value_coef"] * value_loss - hp["entropy_coef"] * entropy


def _optimizer(hp: dict) -> optax.GradientTransformation:
    return optax.chain(
        optax.clip_by_global_norm(hp["max_grad_norm"]), optax.adam(hp["learning_rate"], eps=1e-5)
    )


def _draws(keys: Array, config: PPOConfig, world: Environment, dtype: Any) -> tuple:
    """Every random number of a run, drawn up front: one draw per learner (``keys`` (B, 2)) for
    the whole run, the DOF's uniform, the ROC's normal and the noise Y, laid out as the scans
    read them: ``(t, u_dof, z_roc, y)``, each (n_updates, rollout, B, [E,] ...)."""
    b, e = keys.shape[0], config.envs
    n_updates = -(-config.steps // config.rollout)
    total = n_updates * config.rollout
    width = 2 + world.n_swimmers
    shape = (total, width) if e == 1 else (total, e, width)
    u = jax.vmap(lambda k: _env.uniforms(k, shape, dtype))(keys)  # (B, total, [E,] width)
    u = jnp.moveaxis(u, 0, 1).reshape((n_updates, config.rollout, b) + shape[1:])
    z = jax.scipy.special.ndtri(jnp.clip(u[..., 1], 1e-7, 1.0 - 1e-7))
    return (
        jnp.arange(total).reshape(n_updates, config.rollout),
        u[..., 0],
        z,
        2.0 * u[..., 2:] - 1.0,
    )


def _act_one(world: Environment, config: PPOConfig, trace: bool, dtype: Any) -> Callable:
    """One swimmer's step under its learner's policy: ``(state, net, p, tau, u_dof, z_roc, y) ->
    (state, _Batch, record)``, the record being what `PPORun` keeps of the step."""
    n = world.n_dof
    categorical = config.policy == "categorical"

    def act_one(state, net, p, tau, u_dof, z_roc, y):
        obs = world.features(state, p)
        if categorical:
            # One categorical over the integer codes; the record is the code's ROC vector.
            logits = _mlp(net["actor"], obs)
            value = _mlp(net["critic"], obs)[..., 0]
            code = _sample_code(logits, tau, u_dof)
            logp = _code_log_prob(logits, code, tau)
            state, info = world.learner_advance(state, code, y, p)
            k = world.roc_levels
            dof, u_roc = code // (2 * k + 1), jnp.zeros((), dtype)
            roc = (code % (2 * k + 1) - k).astype(dtype) / k
            action = jnp.where(jnp.arange(n) == dof, roc, 0.0).astype(dtype)
            batch_act = code
        else:
            logits, mean, log_std, value = policy(net, obs, config.max_std)
            dof, u_roc = _sample(logits, mean, log_std, tau, u_dof, z_roc)
            roc = jnp.clip(u_roc, -1.0, 1.0)
            action = jnp.where(jnp.arange(n) == dof, roc, 0.0).astype(dtype)
            logp = _log_prob(logits, mean, log_std, dof, u_roc, tau)
            state, info = world.learner_advance(state, action, y, p)
            batch_act = dof
        reward = energy_reward(config.energy_weight)(info).astype(dtype)
        x, y_pos, theta = world.pose(state, p)
        record = (
            action,
            (dof + 1).astype(jnp.int8),
            x,
            info.progress.astype(dtype),
            world.observe(state, p).dofs,
            y_pos,
            theta,
            Trajectory(state, world.observe(state, p), info) if trace else None,
        )
        return state, _Batch(obs, batch_act, u_roc, logp, value, reward, tau), record

    return act_one


def _learn_one(config: PPOConfig, hp: dict, opt: Any) -> Callable:
    """One learner's update from its rollout: ``(net, opt_state, r2, batch, last_obs, t_end) ->
    (net, opt_state, r2)`` (GAE, then ``epochs`` full-batch gradient steps; ``r2`` the running
    sum of squared rewards when ``reward_norm``)."""
    e = config.envs

    def learn_one(net, opt_state, r2, batch, last_obs, t_end):
        if config.reward_norm:
            # Rewards in units of their running RMS (this learner's, so far): one set of
            # hyperparameters for swimmers whose steps differ in size.
            r2 = r2 + jnp.sum(batch.reward**2)
            count = t_end if e == 1 else t_end * e
            batch = batch._replace(reward=batch.reward / (jnp.sqrt(r2 / count) + 1e-8))
        last_value = _mlp(net["critic"], last_obs)[..., 0]
        adv = _gae(batch.reward, batch.value, last_value, hp["discount"], hp["gae_lambda"])
        target = adv + batch.value

        def epoch(c, _):
            net, opt_state = c
            grads = jax.grad(_loss)(net, batch, adv, target, config, hp)
            updates, opt_state = opt.update(grads, opt_state, net)
            return (optax.apply_updates(net, updates), opt_state), None

        (net, opt_state), _ = jax.lax.scan(epoch, (net, opt_state), None, length=config.epochs)
        return net, opt_state, r2

    return learn_one


def _train(
    keys: Array,
    params: Any,
    config: PPOConfig,
    hp: dict,
    world: Environment,
    axes: Any = 0,
    trace: bool = False,
) -> PPORun:
    """Train ``B`` learners (``keys`` (B, 2), ``params`` batched along B as ``axes`` says, a
    ``vmap`` prefix) in the world ``world`` (default: the paper's world of ``params``): time
    outermost. The world's step is [`Environment.learner_advance`][jswim.env.base.Environment.learner_advance], its observation
    ``features``, its reward ``StepInfo.progress`` (minus ``energy_weight x StepInfo.work``).

    The scans run over time and every step is vmapped over learners inside them (as in
    PureJaxRL), which keeps the environment's float64 step blocks inside a plain ``vmap``.
    """
    n = world.n_dof
    b = keys.shape[0]
    e = config.envs
    dtype = jnp.result_type(float)
    split = jax.vmap(lambda k: jax.random.split(k, 3))(keys)
    # With several swimmers per learner (envs > 1) every per-swimmer function is vmapped once
    # more over them (axis 1 after the learners'); the learner's net and params are shared.
    per_env = (lambda f, *a: f) if e == 1 else (lambda f, axes: jax.vmap(f, in_axes=axes))
    split_e = jax.vmap(lambda k: jax.random.split(k, e))
    reset_keys = split[:, 0] if e == 1 else split_e(split[:, 0])
    reset = per_env(world.reset, (0, None))
    states = jax.vmap(reset, in_axes=(0, axes))(reset_keys, params)
    first = states if e == 1 else jax.tree.map(lambda v: v[:, 0], states)
    dofs0 = jax.vmap(lambda st, p: world.observe(st, p).dofs, in_axes=(0, axes))(first, params)
    n_logits = world.n_actions if config.policy == "categorical" else None
    nets = jax.vmap(
        lambda k: init_policy(k, n, config.hidden, hp["init_std"], world.n_features, n_logits)
    )(split[:, 1])
    opt = _optimizer(hp)
    inputs = _draws(split[:, 2], config, world, dtype)
    total = inputs[0].size
    act_one = _act_one(world, config, trace, dtype)
    learn_one = _learn_one(config, hp, opt)

    def act_learner(state, net, p, tau, u_dof, z_roc, y):
        state, batch, record = per_env(act_one, (0, None, None, None, 0, 0, 0))(
            state, net, p, tau, u_dof, z_roc, y
        )
        # The record is the learner's first swimmer's (its run, as with one swimmer).
        return state, batch, record if e == 1 else jax.tree.map(lambda v: v[0], record)

    def act(carry, inp):
        states, nets = carry
        t, u_dof, z_roc, y = inp
        tau = _temperature(t, config.steps, hp["anneal_start"], hp["anneal_end"])
        states, batch, record = jax.vmap(act_learner, in_axes=(0, 0, axes, None, 0, 0, 0))(
            states, nets, params, tau, u_dof, z_roc, y
        )
        return (states, nets), (batch, record)

    def update(carry, inp):
        states, nets, opt_states, r2 = carry
        (states, _), (batch, record) = jax.lax.scan(act, (states, nets), inp)
        features = per_env(world.features, (0, None))
        last_obs = jax.vmap(features, in_axes=(0, axes))(states, params)
        t_end = (inp[0][-1] + 1).astype(dtype)
        nets, opt_states, r2 = jax.vmap(learn_one, in_axes=(0, 0, 0, 1, 0, None))(
            nets, opt_states, r2, batch, last_obs, t_end
        )
        return (states, nets, opt_states, r2), record

    carry = (states, nets, jax.vmap(opt.init)(nets), jnp.zeros((b,), dtype))
    _, record = jax.lax.scan(update, carry, inputs)
    # (n_updates, rollout, B, ...) -> (B, steps, ...)
    record = jax.tree.map(
        lambda v: jnp.moveaxis(v.reshape((total,) + v.shape[2:]), 0, 1)[:, : config.steps], record
    )
    return PPORun(*record[:5], dofs0, *record[5:])


def train(
    env: Environment,
    params: Any,
    key: Array,
    config: PPOConfig = PPOConfig(),
    *,
    trace: bool = False,
) -> PPORun:
    """Train PPO learners online for ``config.steps`` steps in any world ([`jswim.make`][jswim.env.registry.make]).

    The learner sees the world's ``features``, is rewarded with ``StepInfo.progress`` (minus ``config.energy_weight x StepInfo.work``), and acts
    with float ROC vectors (one non-zero entry).

    Parameters
    ----------
    env : Environment
        The world (static).
    params : pytree
        Its params, shared by the learners or with a value per learner in the leaves the world
        batches ([`Environment.batch_params`][jswim.env.base.Environment.batch_params]).
    key : PRNG key ``(2,)``, or keys ``(B, 2)``
        All randomness of a run: initial shape (if random), network init, actions and the
        world's noise. A batch trains ``B`` independent learners in one jitted, vmapped call,
        sharded over every device.
    config : PPOConfig
        Hyperparameters (static).
    trace : bool
        Also record the world's state, observation and step info after each step.

    Returns
    -------
    PPORun
        Per-step actions, X (the swimmers' mean x), progress and DOF values; ``y`` and
        ``orientation`` swimmer 1's (leading axis B for a batch of keys). Memory:
        ``(4 (2 n_dof + 5) + 1) steps`` bytes per learner in float32 (7.2 kB at 200 steps for two
        DOFs), plus the networks while training.

    Raises
    ------
    ConfigError
        From `PPOConfig` when it is built: a bad policy, count, rate or weight.
    """
    key = jnp.asarray(key)
    if key.ndim == 1:
        return jax.tree.map(lambda v: v[0], train(env, params, key[None], config, trace=trace))
    n = key.shape[0]
    params, axes = env.batch_params(params, n)
    fn = functools.partial(
        _jitted(),
        config=_structure(config),
        hp=_numbers(config),
        world=env,
        axes=axes,
        trace=trace,
    )
    return sharding.apply_runs(fn, key, params, axes, n)


@functools.lru_cache(maxsize=1)
def _jitted() -> Callable[..., PPORun]:
    return jax.jit(
        _train,
        static_argnames=("config", "world", "axes", "trace"),
        compiler_options=training_compiler_options(),
    )
