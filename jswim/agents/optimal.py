"""The swimmer's own optimum: the least-time sequence of a navigation world's actions to its target.

Zermelo's steerer ([`jswim.agents.zermelo`][jswim.agents.zermelo]) is the optimum of a point
that turns instantly and feels the flow at its centre. The swimmer turns at most about 0.015 rad
a step and feels the flow averaged over its links, so its own least time is longer (a turn) or
shorter (a flow averaged to less than the centroid's). [`solve`][jswim.agents.optimal.solve]
finds it with the world's own step (its tables, flow, budget and target rule, on its K lattice):

* ``"beam"``: a breadth-first search over the world's actions, one layer a step, that merges
  states falling in the same (shape, waypoint, x, y, heading) cell and keeps the ``beam`` with
  the least estimated time to go: the still-fluid value iteration of
  [`jswim.agents.cost_to_go`][jswim.agents.cost_to_go], with the target moved by the local flow
  (and its own velocity) over that time. The first layer in which a state reaches the target is
  the answer. Known sequences stay in the beam at every layer (the ``"dp"`` method's, the
  model-predictive agent's, the steering controller's and any ``incumbents`` given; a study
  gives every run of the cell that reached the target), so the answer is never longer than
  any of them. Merging and the beam make it a search for the optimum, not a proof of it: the
  answer is an upper bound on the least time, exact where the beam never drops a state that
  lies on an optimal path, and in strong flows far from it (docs/navigation.md).
* ``"dp"``: the still-fluid value iteration's closed-loop policy (each step the action with the
  least estimated time to go), run through the world: a second, independent answer, the
  optimum of the still-fluid model where the flow is still.

Every answer is replayed with [`jswim.rollout`][jswim.env.episodes.rollout]: the returned
actions reach the target exactly at ``steps``. ``lower`` is a bound no sequence can beat: the
distance to close over the fastest step's displacement plus the flow's speed (the flow's speed
grows with the distance covered where its gradient is bounded and its speed is not).

Example::

    env, params = jswim.make("purcell", roc_levels=2, target=FixedTarget(3.0, 90.0))
    best = optimal.solve(env, params)
    best.steps, best.lower                 # e.g. 154 and 55
    jswim.rollout(env, params, 0, best.actions).state.reached[-1]   # True
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from typing import Any, NamedTuple

import jax
import jax.numpy as jnp
import numpy as np
from jax import Array

from jswim.agents.cost_to_go import lattice_moves, still_cost_to_go
from jswim.env.discretiser import corner, positions
from jswim.env.episodes import rollout
from jswim.env.navigation import NavigationWorld, wrap
from jswim.errors import ConfigError, check_choice

__all__ = [
    "BEAM",
    "BEAM_WIDTH",
    "HORIZON",
    "METHODS",
    "REPLAN",
    "OptimalResult",
    "check_whole",
    "check_world",
    "heuristic",
    "lower_bound",
    "receding",
    "search",
    "solve",
]

#: The methods of [`solve`][jswim.agents.optimal.solve].
METHODS = ("beam", "dp")

#: The merge cells of the beam: centroid (``a``) and heading (rad). A step moves the centroid
#: about 0.05 a and turns it up to about 0.015 rad: a cell holds a fraction of a step.
CELL_XY = 0.01
CELL_HEADING = 0.005


#: Where the heuristic samples the flow: along the straight line to the target.
_ALONG = jnp.linspace(0.0, 1.0, 9)


class OptimalResult(NamedTuple):
    """The least-time sequence [`solve`][jswim.agents.optimal.solve] found.

    Attributes
    ----------
    steps : int or None
        Steps to the target (``None``: not reached within the budget).
    actions : ndarray (steps,) int32
        The world's action codes; ``jswim.rollout(env, params, key, actions)`` reaches the
        target at its last step (where ``steps`` is None: the sequence that ended closest).
    lower : int or None
        Steps no sequence can beat ([`lower_bound`][jswim.agents.optimal.lower_bound]).
    method : str
        ``"beam"`` or ``"dp"``.
    """

    steps: int | None
    actions: np.ndarray
    lower: int | None
    method: str


def check_world(env: Any, params: Any) -> None:
    """Raise `ConfigError` unless ``env`` is a noiseless navigation world on a K >= 2 lattice
    with one target (what `solve` searches)."""
    if not isinstance(env, NavigationWorld):
        raise ConfigError(
            "the optimum is solved for a navigation world: jswim.make(swimmer, target=..., "
            f"roc_levels=K), not {type(env).__name__}"
        )
    if env.lattice is False and env.roc_levels < 2:
        raise ConfigError("the optimum searches a K-lattice world: make it with roc_levels >= 2")
    if np.any(np.asarray(params.swimmer.zeta) != 0):
        raise ConfigError(
            "a noisy world (zeta > 0) has no one least-time sequence: solve it at zeta = 0 "
            "(the mpc agent re-plans under noise)"
        )
    if np.ndim(params.target.budget) or np.ndim(params.target.points) > 2:
        raise ConfigError("solve one world at a time: params hold a batch of targets")


def lower_bound(env: NavigationWorld, params: Any, key: Array | int = 0) -> int:
    """Steps no action sequence can beat from the world's start (``key``).

    The centroid moves at most ``s`` a step by its stroke (the largest still-fluid step over
    every shape and action) plus the flow's speed where it is (bounded by the flow's largest
    speed, and by the speed at the start plus ``2 G`` times the distance covered, ``G`` the
    flow's largest gradient entry); the task asks it to cover the distance to the first
    waypoint (less the radius, less the target's own motion) and each further leg (less two
    radii). The first step count whose reach covers that is the bound.
    """
    moves, _ = lattice_moves(env, params)
    s = float(np.max(np.hypot(moves[..., 0], moves[..., 1])))
    start = env.reset(jax.random.PRNGKey(key) if isinstance(key, int) else key, params)
    x0 = np.asarray(env.inner.observe(start.swimmer, params.swimmer).position[0], np.float64)
    pts = np.asarray(params.target.points, np.float64).reshape(-1, 2)
    r = float(params.target.radius)
    v = float(np.hypot(*np.asarray(params.target.velocity, np.float64)))
    need = max(0.0, float(np.hypot(*(pts[0] - x0))) - r)
    need += float(np.sum(np.maximum(0.0, np.hypot(*np.diff(pts, axis=0).T) - 2 * r)))
    flow = env.flow
    u0 = 0.0 if flow is None else float(np.hypot(*np.asarray(flow.velocity(x0))))
    top = 0.0 if flow is None else float(flow.speed)
    grad = 0.0 if flow is None else 2.0 * float(flow.max_gradient)
    bounded = flow is None or flow.kind != "shear"  # shear alone has no largest speed
    covered = 0.0
    budget = int(params.target.budget)
    for t in range(1, budget + 1):
        u = u0 + grad * covered
        if bounded:
            u = min(u, top)
        covered += s + u
        if covered + v * t >= need:
            return t
    return budget


def heuristic(env: NavigationWorld, params: Any) -> Any:
    """``h(state, params)``, the estimated steps to go of a state of ``env``: the still-fluid
    time to go to the current waypoint with the target moved by its own velocity and against the
    flow (averaged along the straight line to it) over that time (two fixed-point passes), plus
    each later leg's still-fluid time to go (the first from the heading the swimmer has now)."""
    pts = np.asarray(params.target.points, np.float64).reshape(-1, 2)
    half = math.ceil(max(5.0, 1.5 * float(np.max(np.hypot(pts[:, 0], pts[:, 1])))))
    ctg = still_cost_to_go(env, params, half=half)
    # one function per world and table, so the jitted search compiles once for them
    key = (env, id(ctg))
    if key not in _HEURISTICS:
        _HEURISTICS[key] = (ctg, _heuristic(env, ctg))
    return _HEURISTICS[key][1]


_HEURISTICS: dict[tuple[Any, int], tuple[Any, Any]] = {}


def _heuristic(env: NavigationWorld, ctg: Any) -> Any:
    k = env.roc_levels

    def h(state: Any, params: Any) -> Array:
        obs = env.inner.observe(state.swimmer, params.swimmer)
        x = obs.position[0].astype(jnp.float32)
        th = obs.orientation[0].astype(jnp.float32)
        shape = corner(positions(state.swimmer, k), k)
        target = env.target_position(state.t, state.index, params).astype(jnp.float32)
        if env.flow is None:
            u = jnp.zeros(2, jnp.float32)
        else:  # the flow along the way, not where the swimmer is: it may change on the way
            along = x + _ALONG[:, None] * (target - x)
            u = jnp.mean(env.flow.velocity(along).astype(jnp.float32), axis=0)
        drift = params.target.velocity.astype(jnp.float32) - u
        c, s = jnp.cos(th), jnp.sin(th)

        def body(p_lab: Array) -> Array:
            return jnp.stack([c * p_lab[0] + s * p_lab[1], -s * p_lab[0] + c * p_lab[1]])

        t_go = ctg(shape, body(target - x))
        for _ in range(2):
            t_go = ctg(shape, body(target + drift * t_go - x))
        # the legs after the current waypoint: each from the still-fluid time to go, the
        # first with the heading the swimmer has now (a turn at the waypoint costs steps), the
        # later ones with the previous leg's direction
        pts = params.target.points.astype(jnp.float32)
        rest = jnp.zeros((), jnp.float32)
        heading = th
        for i in range(pts.shape[0] - 1):
            leg = pts[i + 1] - pts[i]
            ci, si = jnp.cos(heading), jnp.sin(heading)
            p_leg = jnp.stack([ci * leg[0] + si * leg[1], -si * leg[0] + ci * leg[1]])
            rest = rest + jnp.where(i >= state.index, ctg(shape, p_leg), 0.0)
            heading = jnp.where(i >= state.index, jnp.arctan2(leg[1], leg[0]), heading)
        return jnp.where(state.reached, 0.0, t_go + rest)

    return h


@functools.partial(jax.jit, static_argnames=("env", "n_actions"))
def _expand(env: NavigationWorld, params: Any, states: Any, noise: Array, n_actions: int) -> Any:
    def one(st: Any) -> Any:
        return jax.vmap(lambda a: env.advance(st, a, noise, params)[0])(
            jnp.arange(n_actions, dtype=jnp.int32)
        )

    return jax.vmap(one)(states)


@functools.partial(jax.jit, static_argnames=("env", "h"))
def _score(env: NavigationWorld, h: Any, params: Any, states: Any) -> tuple[Array, ...]:
    """Per state: estimated steps to go, reached, and the merge cell's coordinates."""
    k = env.roc_levels

    def one(st: Any) -> tuple[Array, ...]:
        obs = env.inner.observe(st.swimmer, params.swimmer)
        x = obs.position[0]
        th = wrap(obs.orientation[0])
        shape = corner(positions(st.swimmer, k), k)
        cell = jnp.stack(
            [
                jnp.floor(x[0] / CELL_XY).astype(jnp.int32),
                jnp.floor(x[1] / CELL_XY).astype(jnp.int32),
                jnp.floor(th / CELL_HEADING).astype(jnp.int32),
                shape * 64 + st.index,
            ]
        )
        return h(st, params), st.reached, cell

    return jax.vmap(jax.vmap(one))(states)


def _merge_keys(cell: np.ndarray) -> np.ndarray:
    c = cell.astype(np.int64)
    return (((c[..., 3] << 21) + (c[..., 0] + (1 << 20))) << 21 | (c[..., 1] + (1 << 20))) << 12 | (
        c[..., 2] + 2048
    )


@jax.jit
def _select(cand: Any, idx: Array) -> Any:
    """The kept candidates ``idx`` (flat row-major indices of ``(width, n_actions)``) as the
    next frontier: one compiled gather (leaf by leaf outside ``jit`` it was most of a solve)."""
    return jax.tree.map(lambda v: v.reshape((-1,) + v.shape[2:])[idx], cand)


def _take(tree: Any, idx: Array) -> Any:
    return jax.tree.map(lambda v: v[idx], tree)


def _beam(
    env: NavigationWorld,
    params: Any,
    start: Any,
    h: Any,
    width: int,
    steps: int,
    incumbents: list[np.ndarray],
) -> tuple[list[tuple[np.ndarray, np.ndarray]], list[tuple[int, int]], Any, int]:
    """The layered search (module docs). Returns each layer's (parent row, action) of the kept
    states, the reached (row, action) pairs of the last layer, that layer's candidates' scores
    and its index (``steps`` when none reached)."""
    n_act = env.n_actions
    frontier = jax.tree.map(lambda v: jnp.broadcast_to(v, (width,) + v.shape), start)
    alive = np.zeros(width, bool)
    alive[0] = True
    noise = jnp.zeros_like(env.noise(jax.random.PRNGKey(0), start))
    layers: list[tuple[np.ndarray, np.ndarray]] = []
    score = None
    for t in range(steps):
        cand = _expand(env, params, frontier, noise, n_act)
        score, reached, cell = (np.asarray(v) for v in _score(env, h, params, cand))
        live = alive[:, None] & np.ones((1, n_act), bool)
        hit = np.argwhere(reached & live)
        if len(hit):
            return layers, [(int(r), int(a)) for r, a in hit], score, t
        flat_h = np.where(live, score, np.inf).reshape(-1)
        keys = _merge_keys(cell).reshape(-1)
        order = np.lexsort((flat_h, keys))
        first = np.ones(len(order), bool)
        first[1:] = keys[order][1:] != keys[order][:-1]
        kept = order[first & np.isfinite(flat_h[order])]
        kept = kept[np.argsort(flat_h[kept], kind="stable")][:width]
        if incumbents:  # given sequences stay in the beam, incumbent j in row j
            forced = [j * n_act + int(q[t]) if t < len(q) else -1 for j, q in enumerate(incumbents)]
            rest = kept[~np.isin(kept, forced)]
            fill = iter(rest)
            head = [f if f >= 0 else next(fill, -1) for f in forced]
            used = {f for f in head if f >= 0}
            tail = [f for f in rest if f not in used]
            kept = np.asarray([f for f in head if f >= 0] + tail, np.int64)[:width]
        n = len(kept)
        idx = np.zeros(width, np.int64)
        idx[:n] = kept
        frontier = _select(cand, jnp.asarray(idx))
        alive = np.arange(width) < n
        layers.append((idx // n_act, idx % n_act))
    return layers, [], score, steps


def _path(layers: list[tuple[np.ndarray, np.ndarray]], row: int, action: int) -> np.ndarray:
    out = [action]
    for parents, actions in reversed(layers):
        out.append(int(actions[row]))
        row = int(parents[row])
    return np.asarray(out[::-1], np.int32)


def _verified(env: Any, params: Any, key: Array, actions: np.ndarray, length: int) -> bool:
    """Whether the actions reach the target exactly at their last step, replayed.

    The replay is padded with no-moves to ``length`` steps (the search's), so every replay of a
    solve, the model-predictive seed's included, runs one compiled rollout (compiling one per
    sequence length was a tenth of a solve)."""
    n = len(actions)
    if n == 0 or n > length:
        return False
    padded = np.full(length, env.roc_levels, np.int32)  # (DOF 1, ROC 0): no move
    padded[:n] = actions
    reached = np.asarray(rollout(env, params, key, jnp.asarray(padded)).state.reached)
    return bool(reached[n - 1]) and not (n > 1 and bool(reached[n - 2]))


def _controller(env: NavigationWorld, params: Any, key: Array, steps: int) -> list[np.ndarray]:
    """The steering controller's codes where it steers this world (its start, an even K), cut
    where it reached the target; none elsewhere."""
    from jswim.agents import steering  # lazy: only the optimum's seed reads the controller

    if env.roc_levels % 2:
        return []
    trace = steering.run(env, params, key, steps)
    reached = np.asarray(trace.state.reached)
    if not reached.any():
        return []
    end = int(np.argmax(reached)) + 1
    # its codes, from the lattice points it passed (a seed: an exact copy is not needed)
    k = env.roc_levels
    start = env.reset(key, params).swimmer
    frac = np.vstack(
        [
            np.asarray(start.frac + start.frac_lo, np.float64)[None],
            np.asarray(trace.state.swimmer.frac + trace.state.swimmer.frac_lo, np.float64),
        ]
    )
    j = np.rint(frac * k).astype(np.int64)[: end + 1]
    move = np.diff(j, axis=0)
    dof = np.argmax(np.abs(move), axis=1)
    roc = move[np.arange(len(move)), dof]
    return [dof * (2 * k + 1) + roc + k]


@functools.partial(jax.jit, static_argnames="env")
def _step(env: NavigationWorld, key: Array, state: Any, action: Array, params: Any) -> Any:
    return env.step(key, state, action, params)[0]


def receding(
    env: NavigationWorld,
    params: Any,
    key: Array,
    steps: int | None,
    *,
    horizon: int,
    replan: int,
    beam: int,
) -> np.ndarray:
    """The receding-horizon loop of [`jswim.agents.mpc`][jswim.agents.mpc] (its docs): every
    ``replan`` steps a `search` of ``horizon`` steps with ``beam`` states from the state the
    world (noise included) has reached, warm-started with the rest of the previous plan; the
    codes played, ``(steps,)`` int32 (no moves once the episode ended)."""
    model = params._replace(swimmer=params.swimmer.replace(zeta=0.0))
    key = jax.random.PRNGKey(key) if isinstance(key, (int, np.integer)) else key
    budget = int(params.target.budget)
    steps = budget if steps is None else int(steps)
    keys = jax.random.split(key, steps)
    idle = env.roc_levels  # code of (DOF 1, ROC 0): no move
    h = heuristic(env, model)
    state = env.reset(key, params)
    played: list[int] = []
    plan = np.zeros(0, np.int64)
    for t in range(steps):
        if bool(state.done):
            played.extend([idle] * (steps - t))
            break
        if t % replan == 0 or not len(plan):
            ahead = max(1, min(horizon, budget - int(state.t)))
            found = search(env, model, state, h, beam=beam, steps=ahead, incumbents=[plan])
            plan = np.asarray(found[0][0], np.int64)
            if not len(plan):
                plan = np.asarray([idle], np.int64)
        a, plan = int(plan[0]), plan[1:]
        state = _step(env, keys[t], state, jnp.int32(a), params)
        played.append(a)
    return np.asarray(played, np.int32)


#: The model-predictive agent's settings (`jswim.agents.mpc`): steps looked ahead (six
#: square-gait cycles), steps played between plans (two cycles), states kept per layer.
#: Measured (K = 2, target 3 a at 90 degrees, still fluid and the four flows at 0.5 v): 24
#: ahead, 8 played, 128 kept reach in 80, 105, 222, 127 and 115 steps in 15 s; 48, 4 and 256
#: in 105, 105, 215, 126 and 113 in 73 s.
HORIZON, REPLAN, BEAM = 24, 8, 128

#: States the optimum's beam keeps a layer (`solve`'s default ``beam``). 2,048 was too narrow in
#: a strong stream carrying the swimmer to its target (uniform 0.9 v, 90 degrees: 58 steps, which
#: PPO and Q-learning beat with 57); 8,192 finds 56 there and 210 for 215 in Taylor-Green at
#: 0.5 v, at about the same wall time (the compilations and the seeds dominate a solve).
BEAM_WIDTH = 8192


def _closed_loop(env: NavigationWorld, params: Any, key: Array, steps: int) -> np.ndarray:
    """The model-predictive agent's codes ([`jswim.agents.mpc`][jswim.agents.mpc]), cut where it
    reached the target: its short horizon finds what the long beam's estimate misses (in a
    stream along the target's line, drifting beats turning: 80 steps where the beam alone found
    107)."""
    codes = receding(env, params, key, steps, horizon=HORIZON, replan=REPLAN, beam=BEAM)
    codes = codes.astype(np.int64)
    # int32 and the search's length: the same compiled rollout as `_verified`'s
    reached = np.asarray(rollout(env, params, key, jnp.asarray(codes, jnp.int32)).state.reached)
    return codes[: int(np.argmax(reached)) + 1] if reached.any() else codes[:0]


@functools.partial(jax.jit, static_argnames=("env", "h"))
def _greedy(env: NavigationWorld, h: Any, params: Any, noise: Array, st: Any) -> tuple[Any, Array]:
    """One step of the time to go's closed-loop policy: the action whose next state has the
    least estimate (a reached one first). Compiled once per world and time to go."""
    nxt = jax.vmap(lambda a: env.advance(st, a, noise, params)[0])(jnp.arange(env.n_actions))
    est = jax.vmap(lambda s: h(s, params))(nxt)
    best = jnp.argmin(jnp.where(nxt.reached, -1.0, est))
    return _take(nxt, best), best


def _dp(env: NavigationWorld, params: Any, key: Array, h: Any, steps: int) -> np.ndarray:
    """The closed-loop policy of the time to go, ``steps`` steps (fewer: the target reached)."""
    state = env.reset(key, params)
    noise = jnp.zeros_like(env.noise(jax.random.PRNGKey(0), state))
    actions = []
    for _ in range(steps):
        state, a = _greedy(env, h, params, noise, state)
        actions.append(int(a))
        if bool(state.reached):
            break
    return np.asarray(actions, np.int32)


def _codes(sequence: Any, n_actions: int) -> np.ndarray:
    """An incumbent as the world's action codes, ``(T,)`` int64.

    Raises
    ------
    ConfigError
        Not a sequence of whole numbers in ``0 .. n_actions - 1``.
    """
    q = np.asarray(sequence)
    if q.ndim != 1 or (q.size and (not np.issubdtype(q.dtype, np.integer))):
        raise ConfigError(
            f"an incumbent is a sequence of whole action codes, got a {q.dtype} array of "
            f"shape {q.shape}"
        )
    if q.size and (q.min() < 0 or q.max() >= n_actions):
        raise ConfigError(f"an incumbent's codes must lie in 0..{n_actions - 1}")
    return q.astype(np.int64)


def check_whole(value: Any, what: str) -> int:
    """``value`` as an int if it is a whole number ``>= 1`` (a beam, horizon or step count).

    Raises
    ------
    ConfigError
        Anything else (a bool, a float, zero, a negative number), in one line naming ``what``.
    """
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
        raise ConfigError(f"{what} must be a whole number >= 1, got {value!r}")
    return int(value)


def solve(
    env: NavigationWorld,
    params: Any,
    *,
    key: Array | int = 0,
    method: str = "beam",
    beam: int = BEAM_WIDTH,
    max_steps: int | None = None,
    incumbents: Sequence[Any] = (),
) -> OptimalResult:
    """The least-time action sequence from the world's start to its target (module docs).

    Parameters
    ----------
    env : NavigationWorld
        From ``jswim.make(swimmer, target=..., roc_levels=K)`` (K >= 2, integer codes), zeta 0.
    params : NavParams
        Its params (one target).
    key : PRNG key or int
        The start, as ``env.reset(key, params)`` draws it (and ``jswim.rollout`` replays it).
    method : {"beam", "dp"}
        The search (module docs).
    beam : int
        States kept per layer (``"beam"``): more is slower and closer to the optimum.
    max_steps : int, optional
        Steps searched; default the target's budget.
    incumbents : sequence of array (T,) int
        Sequences kept in the beam at every layer they cover (``"beam"``), beside its own
        seeds (the ``"dp"`` method's sequence, the model-predictive agent's
        ([`jswim.agents.mpc`][jswim.agents.mpc]) and, where it steers the world and reaches
        the target, the steering controller's): the answer is never longer than any of them
        that reaches the target, and the beam branches off them. A study passes every run of
        the cell that reached the target (`jswim.studies.kinds.navigate.optimal_path`).

    Returns
    -------
    OptimalResult

    Raises
    ------
    ConfigError
        Not a navigation world on a K >= 2 lattice, a noisy world, a batch of targets, an
        unknown method, a beam below 1, or an incumbent that is not a sequence of the world's
        action codes.
    """
    check_world(env, params)
    check_choice(method, METHODS, "method")
    check_whole(beam, "beam")
    given = [_codes(q, env.n_actions) for q in incumbents]
    key = jax.random.PRNGKey(key) if isinstance(key, (int, np.integer)) else key
    budget = int(params.target.budget)
    steps = budget if max_steps is None else min(int(max_steps), budget)
    h = heuristic(env, params)
    low = lower_bound(env, params, key)
    if method == "dp":
        actions = _dp(env, params, key, h, steps)
        ok = _verified(env, params, key, actions, steps)
        return OptimalResult(len(actions) if ok else None, actions, low, method)
    start = env.reset(key, params)
    # known good sequences seed the beam: it is never worse than them
    seeds = [q[:steps] for q in given]
    seeds += [
        _dp(env, params, key, h, steps),
        *_controller(env, params, key, steps),
        _closed_loop(env, params, key, steps),
    ]
    plans = search(env, params, start, h, beam=int(beam), steps=steps, incumbents=seeds)
    # the world's rollout decides: a state a hair inside the radius in the batched step may be
    # a hair outside in the scan (float32); the first of the layer's hits that replays is kept
    for actions, reached in plans:
        if reached and _verified(env, params, key, actions, steps):
            return OptimalResult(len(actions), actions, low, method)
    return OptimalResult(None, plans[-1][0], low, method)


def search(
    env: NavigationWorld,
    params: Any,
    start: Any,
    h: Any,
    *,
    beam: int,
    steps: int,
    incumbents: list[np.ndarray] | None = None,
) -> list[tuple[np.ndarray, bool]]:
    """The layered beam search (module docs) from state ``start`` for at most ``steps`` steps.

    Returns
    -------
    list of (actions, reached)
        The sequences of the first layer in which a state reached the target, best estimate
        first (each with ``True``); when none did within ``steps``, one sequence ending at the
        last layer's state of least estimated time to go (``False``).
    """
    seeds = [np.asarray(q, np.int64).reshape(-1) for q in incumbents or [] if len(q)]
    layers, hits, score, _ = _beam(env, params, start, h, beam, steps, seeds[:beam])
    if hits:
        ranked = sorted(hits, key=lambda ra: score[ra[0], ra[1]])
        return [(_path(layers, row, a), True) for row, a in ranked]
    if score is None:
        return [(np.zeros(0, np.int32), False)]
    row, a = np.unravel_index(np.argmin(score), score.shape)
    return [(_path(layers, int(row), int(a)), False)]
