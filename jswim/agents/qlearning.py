"""Tabular Q-learning baseline, trained online on one swimmer, thousands of learners at once.

The learner sees what the LLM sees: the state is the DOF configuration, an action a ``(DOF, ROC)``
pair of the environment's action set, the reward the step's displacement in the target direction.
There are no episodes: one learner is one swimmer that keeps swimming, like one LLM run, judged by
the same code, [`jswim.judging.gait.judge`][jswim.judging.gait.judge]. The update is Q-learning as an optax problem: the
Q-table is the parameter, the loss half the squared TD error of the visited entry,

    L(Q) = 1/2 (r + gamma max_a' Q(s', a') - Q(s, a))^2,   target under stop_gradient,

and ``optax.sgd`` with learning rate ``alpha`` turns its gradient into the textbook update
``Q(s, a) += alpha * TD error``. A whole run is one ``lax.scan``; [`train`][jswim.agents.qlearning.train] vmaps it over
keys and the world's params, so one jitted call trains e.g. 10,000 learners, in any world of the
protocol (the table's rows from the world's discretiser). On a ROC lattice the table is over
lattice points and codes (``K = 1``: the paper's learner, number for number); docs/baselines.md
("Q-learning baseline", "Any world") and docs/continuous.md say the rest.

Example::

    import jax
    import jswim
    from jswim.agents.qlearning import QConfig, train, evaluate

    env, params = jswim.make("ng", direction=-1)
    params = env.batch_params(params, 1000)[0]
    run = train(env, params, jax.random.split(jax.random.PRNGKey(0), 1000), QConfig())
    report = evaluate(run, params)   # steps to learn, success, ... per learner
"""

from __future__ import annotations

import dataclasses
import functools
from typing import Any, NamedTuple
from collections.abc import Callable

import jax
import jax.numpy as jnp
import numpy as np
import optax
from jax import Array

from jswim import sharding
from jswim.agents.rewards import energy_reward
from jswim.action_codes import check_action_set
from jswim.env import EnvParams, advance, broadcast_params, reset, uniforms
from jswim.env.base import Environment
from jswim.env.discretiser import Cells, corner, offered_mask, positions
from jswim.env.episodes import Trajectory
from jswim.errors import ConfigError
from jswim.reals import plain
from jswim.judging.gait import PAPER, Criterion, GaitReport, judge

#: Exploration rate ``0.8**t``: 1 at the start (nothing is known yet), below 1 % after 21 steps,
#: about 5 random steps in all. It has to reach 0: success means the stroke lasts to the end of
#: the run, and a learner that keeps exploring keeps breaking it.
DEFAULT_EPSILON: optax.Schedule = optax.exponential_decay(1.0, transition_steps=1, decay_rate=0.8)


@dataclasses.dataclass(frozen=True)
class QConfig:
    """Hyperparameters of a Q-learner (static: one compilation per distinct config).

    The defaults were chosen on the noiseless swimmers, the setting of the paper's comparison;
    docs/baselines.md gives each one's reason and the steps to learn measured around it.

    Attributes
    ----------
    steps : int
        Steps per run (200), past the paper's 50-step horizon, to check that a learned stroke lasts.
    learning_rate : float or optax schedule
        ``alpha`` (1.0 constant: the noiseless swimmer is deterministic). With noise (``zeta > 0``)
        pass a smaller rate, or a decaying optax schedule, so that estimates average over the noise.
    discount : float
        ``gamma`` (0.9: NG's cycle is the optimal policy only for ``gamma > 0.743``).
    epsilon : float or optax schedule
        Probability of a uniformly random action from the offered set (default
        `DEFAULT_EPSILON`, ``0.8**t``).
    q_init : float
        Initial value of every table entry (0.35): mildly optimistic, so the greedy learner tries
        each action before repeating a useless one.
    action_set : str
        ``"all"``: every ``(DOF, ROC)`` pair offered to the LLM (six for the two-DOF swimmers;
        ROC 0 is left out for more DOFs, see ``SwimmerModel.default_rocs``), holds and moves
        against a limit included. ``"shape-changing"``: only the ``n_dof`` moves that change the
        shape from the current configuration.
    tie_break : str
        ``"random"`` (uniformly among the maxima, the default) or ``"first"`` (lowest index, like
        ``argmax``: from equal values the learner repeats one useless action forever; kept to show
        that failure).
    energy_weight : float
        ``lambda`` of the energy-aware reward ``progress - lambda x work``
        ([`StepInfo.work`][jswim.env.base.StepInfo], in the world's work units per unit length
        of progress). 0.0 (the default) rewards progress alone, the paper's reward, with the
        same numbers as without the option; the world must count work (not ``nan``) when > 0.
    """

    steps: int = 200
    learning_rate: float | optax.Schedule = 1.0
    discount: float = 0.9
    epsilon: float | optax.Schedule = DEFAULT_EPSILON
    q_init: float = 0.35
    action_set: str = "all"
    tie_break: str = "random"
    energy_weight: float = 0.0

    def __post_init__(self) -> None:
        # A NumPy number (np.float32(0.1), a value read from an array) is the plain Python number
        # it holds: configs are hashed into jit's cache.
        for field in dataclasses.fields(self):
            object.__setattr__(self, field.name, plain(getattr(self, field.name)))
        energy_reward(self.energy_weight)  # raises on a bad weight
        if not isinstance(self.steps, int) or self.steps < 1:
            raise ConfigError(f"steps must be a positive integer, got {self.steps!r}")
        if not 0.0 <= self.discount < 1.0:
            raise ConfigError(
                f"discount must lie in [0, 1) (the task never ends), got {self.discount!r}"
            )
        check_action_set(self.action_set)
        if self.tie_break not in ("random", "first"):
            raise ConfigError(f"tie_break must be 'random' or 'first', got {self.tie_break!r}")
        for name in ("learning_rate", "epsilon"):
            value = getattr(self, name)
            if not callable(value) and not (isinstance(value, (int, float)) and value >= 0):
                raise ConfigError(
                    f"{name} must be a number >= 0 or an optax schedule, got {value!r}"
                )

    def replace(self, **changes: Any) -> QConfig:
        """A copy with some fields changed."""
        return dataclasses.replace(self, **changes)


class QRun(NamedTuple):
    """What training recorded, per learner (leading batch axis for a batch of keys).

    Attributes
    ----------
    actions : int8 (steps,)
        Executed action indices.
    x : float (steps,)
        Centroid x after each step (noisy when ``zeta > 0``), the X of the paper; the reward of
        step t is ``direction * (x[t] - x[t - 1])`` (with ``x[-1] = 0``).
    explored : bool (steps,)
        The step's action was drawn at random (it may coincide with the greedy one).
    q : float ((K + 1)**n_dof, n_dof (2K + 1))
        Final Q-table, rows indexed by lattice point ``sum_d j_d (K + 1)**d`` (``K = 1``: the
        corner ``sum_k level_k 2**k``), columns by action code.
    levels0 : int32 (n_dof,)
        Initial DOF levels (drawn by [`jswim.env.reset`][jswim.env.state.reset] for a random start); on a ROC
        lattice the start's lattice positions ``j`` in ``0..K`` (a corner: ``level * K``).
    y, orientation : float (steps,) or None
        Centroid y and orientation (rad, of the reference link) after each step, when asked for
        (``pose=True``; the study folders' trajectories); ``None`` otherwise, which keeps the
        training loop's memory traffic to what learning needs. In other worlds
        ``x`` is the swimmers' mean x, ``y`` and ``orientation`` swimmer 1's.
    trace : Trajectory or None
        With ``trace=True``: the world's state, observation and
        [`StepInfo`][jswim.env.base.StepInfo] after each step ([`jswim.env.episodes.Trajectory`][jswim.env.episodes.Trajectory]).
    """

    actions: Array
    x: Array
    explored: Array
    q: Array
    levels0: Array
    y: Array
    orientation: Array
    trace: Any = None


def _schedule(value: float | optax.Schedule) -> optax.Schedule:
    return value if callable(value) else optax.constant_schedule(float(value))


_corner = corner


def _row(q: Array, corner: Array) -> Array:
    return jax.lax.dynamic_slice_in_dim(q, corner, 1)[0]


def offered_actions(levels: Array, params: EnvParams, action_set: str) -> Array:
    """The mask ``(n_actions,)`` of the codes ``action_set`` offers at ``levels``, on the ROC
    lattice of ``params`` ([`offered_mask`][jswim.env.discretiser.offered_mask])."""
    return offered_mask(levels, params.model.n_dof, action_set, roc_levels=_k(params))


def _k(params: EnvParams) -> int:
    """``K`` of the environment's ROC lattice (1 before environments had one)."""
    return int(getattr(params, "roc_levels", 1))


#: Largest action count `pick_uniform` serves from a bit-mask table (2**A rows); beyond, a scan.
_TABLE_ACTIONS = 12


@functools.lru_cache(maxsize=8)
def _kth_true_table(n_actions: int) -> np.ndarray:
    """``table[m * n_actions + k]``: index of the k-th set bit of the bit mask ``m``."""
    table = np.zeros((2**n_actions, n_actions), np.int32)
    for m in range(2**n_actions):
        bits = [a for a in range(n_actions) if m >> a & 1]
        table[m, : len(bits)] = bits
    return table.reshape(-1)


def pick_uniform(mask: Array, u: Array) -> Array:
    """Index of a uniformly chosen True entry of ``mask`` (``u`` uniform in [0, 1)).

    A lookup of the k-th set bit of the mask read as an integer: on CPU a cumulative sum and an
    argmax over a handful of actions cost more than the whole lookup (20 % of a training step).
    """
    a = mask.shape[0]
    count = jnp.sum(mask, dtype=jnp.int32)
    k = jnp.clip(jnp.floor(u * count).astype(jnp.int32), 0, jnp.maximum(count - 1, 0))
    if (
        a > _TABLE_ACTIONS
    ):  # ROC lattices: 2**A rows would not fit; the k-th set entry by a running count
        return jnp.argmax(jnp.cumsum(mask, dtype=jnp.int32) > k).astype(jnp.int32)
    bits = jnp.sum(mask.astype(jnp.int32) << jnp.arange(a, dtype=jnp.int32), dtype=jnp.int32)
    return jnp.asarray(_kth_true_table(a))[bits * a + k]


def greedy_set(q_row: Array, mask: Array, tie_break: str) -> Array:
    """Offered actions whose value equals the best offered value (or the first of them)."""
    best = jnp.max(jnp.where(mask, q_row, -jnp.inf))
    ties = mask & (q_row == best)
    if tie_break == "first":
        ties = jnp.arange(q_row.shape[0]) == jnp.argmax(ties)
    return ties


def _act(
    q_row: Array, mask: Array, epsilon: Array, u: Array, tie_break: str
) -> tuple[Array, Array]:
    """Epsilon-greedy choice from one uniform ``u``: explore when ``u < epsilon``.

    Conditioned on the coin, ``u / epsilon`` and ``(u - epsilon) / (1 - epsilon)`` are again
    uniform on [0, 1), so one random number per step picks both the branch and the action.
    """
    explore = u < epsilon
    v = jnp.where(
        explore, u / jnp.maximum(epsilon, 1e-30), (u - epsilon) / jnp.maximum(1.0 - epsilon, 1e-30)
    )
    candidates = jnp.where(explore, mask, greedy_set(q_row, mask, tie_break))
    return pick_uniform(candidates, v), explore


@jax.custom_vjp
def _entry(q: Array, corner: Array, action: Array) -> Array:
    """``q[corner, action]`` (0 for corner -1); its gradient is a one-hot table.

    Under vmap a plain index would be a gather whose gradient is a scatter, and a one-hot sum a
    reduction over the whole table; this reads one entry and writes the gradient densely.
    """
    return jnp.where(corner >= 0, _row(q, jnp.maximum(corner, 0))[action], 0.0)


def _entry_fwd(q: Array, corner: Array, action: Array) -> tuple[Array, tuple[Array, Array, Array]]:
    return _entry(q, corner, action), (corner, action, jnp.zeros_like(q))


def _entry_bwd(res: tuple[Array, Array, Array], g: Array) -> tuple[Array, None, None]:
    corner, action, zeros = res
    s, a = zeros.shape
    hit = (jnp.arange(s)[:, None] == corner) & (jnp.arange(a)[None, :] == action)
    return jnp.where(hit, g, zeros), None, None


_entry.defvjp(_entry_fwd, _entry_bwd)


class _Pending(NamedTuple):
    """A step's TD update, waiting to be applied: ``Q(s, a)`` towards ``target``."""

    corner: Array
    action: Array
    target: Array  # r + gamma max_a' Q(s', a'), from the table the step acted on


def _train_one(
    key: Array,
    params: Any,
    config: QConfig,
    pose: bool,
    cells: Cells,
    trace: bool = False,
) -> QRun:
    env = cells.env
    dtype = jnp.result_type(float)
    k_reset, k_run = jax.random.split(key)
    state = env.reset(k_reset, params)
    q = jnp.full((cells.n_cells, env.n_actions), config.q_init, dtype)
    alpha = _schedule(config.learning_rate)
    # Update k of the optimizer is step k - 1's (update 0 is a no-op, see below), so the
    # learning-rate schedule is read one count back: step t learns at rate alpha(t).
    opt = optax.sgd(lambda count: alpha(count - 1))
    epsilon = _schedule(config.epsilon)
    gamma = config.discount
    reward = energy_reward(config.energy_weight)

    def act(state, q, t, u):
        """Choose, step the world, and form the TD target from the current table."""
        j = cells.positions(state, params)
        s = cells.cell(state, j, params)
        mask = cells.mask(j, params, config.action_set)
        action, explore = _act(_row(q, s), mask, epsilon(t), u[0], config.tie_break)
        new, info = env.learner_advance(state, action, 2.0 * u[1:] - 1.0, params)
        j2 = cells.positions(new, params)
        mask2 = cells.mask(j2, params, config.action_set)
        future = jnp.max(jnp.where(mask2, _row(q, cells.cell(new, j2, params)), -jnp.inf))
        x, y, theta = env.pose(new, params)
        out = (action.astype(jnp.int8), x, explore) + ((y, theta) if pose else (None, None))
        out += (Trajectory(new, env.observe(new, params), info) if trace else None,)
        return new, _Pending(s, action, reward(info) + gamma * future), out

    def learn(q, opt_state, pending):
        """One optax step on the squared TD error, the target held fixed (semi-gradient)."""

        def td_loss(q: Array) -> Array:
            return (
                0.5
                * (
                    jax.lax.stop_gradient(pending.target)
                    - _entry(q, pending.corner, pending.action)
                )
                ** 2
            )

        updates, opt_state = opt.update(jax.grad(td_loss)(q), opt_state, q)
        return optax.apply_updates(q, updates), opt_state

    # Step t's update is applied at the top of step t + 1, before anything reads the table
    # again: the same algorithm, but the target reaches the update as a loop-carried value, so
    # XLA computes it once per learner instead of once per table entry. Step 0 finds a no-op
    # update pending (corner -1 matches no row).
    def body(carry, inp):
        state, q, opt_state, pending = carry
        q, opt_state = learn(q, opt_state, pending)
        state, pending, out = act(state, q, *inp)
        return (state, q, opt_state, pending), out

    steps = config.steps
    # One draw for the whole run: column 0 drives the agent, the others are the world's noise
    # Y, one per swimmer.
    inputs = (jnp.arange(steps), uniforms(k_run, (steps, 1 + env.n_swimmers), dtype))
    nothing = _Pending(jnp.int32(-1), jnp.int32(0), jnp.zeros((), dtype))
    carry = (state, q, opt.init(q), nothing)
    (_, q, opt_state, pending), (acts, x, explored, y, theta, tr) = jax.lax.scan(
        body, carry, inputs
    )
    q, _ = learn(q, opt_state, pending)
    return QRun(acts, x, explored, q, cells.positions(state, params), y, theta, tr)


@functools.lru_cache(maxsize=1)
def training_compiler_options() -> dict[str, str] | None:
    """XLA options for the training kernels, where this XLA accepts them.

    XLA:CPU's experimental YNNPACK fusions turn the tiny per-learner reductions (over 4 corners
    or 6 actions) into library calls that cost more than the arithmetic; switched off here, a
    batch of 10,000 learners trains about twice as fast. Other backends ignore the question.
    """
    if jax.default_backend() != "cpu":
        return None
    options = {"xla_cpu_experimental_ynn_fusion_type": ""}
    try:
        jax.jit(lambda x: x + 1, compiler_options=options).lower(1.0).compile()
    except Exception:  # an XLA without this option: keep its defaults
        return None
    return options


def train(
    env: Environment,
    params: Any,
    key: Array,
    config: QConfig = QConfig(),
    *,
    pose: bool = False,
    trace: bool = False,
    cells: Cells | None = None,
) -> QRun:
    """Train Q-learners online for ``config.steps`` steps in any world ([`jswim.make`][jswim.env.registry.make]).

    One key trains one learner; a batch of keys ``(B, 2)`` trains ``B`` independent learners in
    one jitted call vmapped over learners and sharded over every device (`jswim.sharding`;
    the numbers do not depend on the device count).

    Parameters
    ----------
    env : Environment
        The world (static); its discretiser ([`Environment.cells`][jswim.env.base.Environment.cells])
        gives the table's rows and the codes offered in each.
    params : pytree
        The world's params: shared by the learners, or with one value per learner in the leaves
        the world batches ([`Environment.batch_params`][jswim.env.base.Environment.batch_params]:
        the paper's ``zeta``, ``direction``, ``init``; a scene's direction).
    key : PRNG key ``(2,)``, or keys ``(B, 2)``
        All randomness of a run: initial configuration (if random), exploration, tie-breaks and
        the world's noise.
    config : QConfig
        Hyperparameters (static); ``action_set`` "shape-changing" offers the moves that change
        the shape from the current lattice point.
    pose, trace : bool
        Also record swimmer 1's y and orientation after each step; the world's state,
        observation and step info ([`QRun.trace`][jswim.agents.qlearning.QRun]).
    cells : Cells, optional
        A discretiser other than the world's.

    Returns
    -------
    QRun
        Per-step actions, X and exploration flags; final Q-table; initial lattice positions
        (leading axis B for a batch of keys). Memory: ``6 steps + 4 (2**n_dof)(3 n_dof) +
        4 n_dof`` bytes per learner in float32 (1,304 at 200 steps for the two-DOF swimmers);
        bound it for large populations by training in chunks, as
        ``jswim.studies.qlearn.study`` does.

    Raises
    ------
    ConfigError
        From `QConfig` when it is built: a bad step count, rates, action set or tie-break.
    """
    cells = env.cells() if cells is None else cells
    key = jnp.asarray(key)
    if key.ndim == 1:
        return _jitted("one")(key, params, config, pose, cells, trace)
    n = key.shape[0]
    params, axes = env.batch_params(params, n)
    fn = functools.partial(
        _jitted("batch"), config=config, pose=pose, cells=cells, trace=trace, axes=axes
    )
    return sharding.apply_runs(fn, key, params, axes, n)


def _batch(
    keys: Array,
    params: Any,
    config: QConfig,
    pose: bool = False,
    cells: Cells | None = None,
    trace: bool = False,
    axes: Any = 0,
) -> QRun:
    return jax.vmap(lambda k, p: _train_one(k, p, config, pose, cells, trace), in_axes=(0, axes))(
        keys, params
    )


@functools.lru_cache(maxsize=2)
def _jitted(kind: str) -> Callable[..., QRun]:
    fn = _train_one if kind == "one" else _batch
    static = ("config", "pose", "cells", "trace") + (() if kind == "one" else ("axes",))
    return jax.jit(fn, static_argnames=static, compiler_options=training_compiler_options())


# Per-learner parameters are per-swimmer parameters: one broadcasting rule (env owns it).
batch_params = broadcast_params


def evaluate(run: QRun, params: EnvParams, *, criterion: Criterion = PAPER) -> GaitReport:
    """Judge training runs with the shared success criterion, [`jswim.judging.gait.judge`][jswim.judging.gait.judge]."""
    return judge(
        np.asarray(run.actions),
        params,
        levels0=np.asarray(run.levels0),
        criterion=criterion,
        roc_levels=_k(params),
    )


@functools.partial(jax.jit, static_argnames=("steps", "action_set"))
def greedy_rollout(
    q: Array, params: EnvParams, steps: int, action_set: str = "all", key: Array | None = None
) -> Array:
    """Actions of the greedy policy of a Q-table, run on a fresh swimmer without learning.

    Ties are broken at random from ``key`` (default ``PRNGKey(0)``). Returns action indices,
    shape ``(steps,)``; vmap it over tables and params for a batch.
    """
    key = jax.random.PRNGKey(0) if key is None else key
    k_reset, k_run = jax.random.split(key)
    big_k = _k(params)

    def body(state, u):
        j = positions(state, big_k)
        mask = offered_actions(j, params, action_set)
        action = pick_uniform(greedy_set(_row(q, _corner(j, big_k)), mask, "random"), u[0])
        state, _ = advance(state, action, 2.0 * u[1] - 1.0, params, exact=False)
        return state, action

    return jax.lax.scan(body, reset(k_reset, params), jax.random.uniform(k_run, (steps, 2)))[1]
