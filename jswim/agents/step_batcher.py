"""The LLM driver's one step group: the runs of one world in one batched state, stepped together.

Each LLM run is its own pipeline and hands its action over when its reply lands. Runs of the same
static [`jswim.env.base.Environment`][jswim.env.base.Environment] (with params of one structure) share one batched state:
[`StepGroup`][jswim.agents.step_batcher.StepGroup] takes the actions handed in since its last step in one jitted call, vmapped over
the runs, at the next turn of the event loop (``call_soon``), so replies that land together step
together and nobody waits for a reply that has not landed; members with no action take the no-op,
masked out. Any world serves: the group reads the protocol alone (``reset``, ``step``, ``observe``).
Run ``i`` draws its start and noise from ``PRNGKey(seed_i)`` alone (each step's key folded in from
its own step count), so its physics does not depend on who shares its batch.
"""

from __future__ import annotations

import asyncio
import functools
from typing import Any
from collections.abc import Callable, Sequence

import jax
import jax.numpy as jnp
import numpy as np

from jswim.env.base import Environment
from jswim.env.randomness import seed32


def _wide(tree: Any) -> Any:
    """Every float leaf as float64 (call under ``jax.enable_x64``)."""
    return jax.tree.map(
        lambda a: a.astype(jnp.float64) if jnp.issubdtype(a.dtype, jnp.floating) else a, tree
    )


def _seen(env: Environment, states: Any, params: Any) -> tuple[Any, jax.Array]:
    """The observation of a batch in the world's dtype, and the positions ``(B, S, 2)`` of the
    same observation of the states widened to float64: a world that keeps positions as
    ``hi + lo`` pairs gives their exact sum (the prompt encodes X to 1e-3 after any number of steps)."""
    obs = jax.vmap(env.observe)(states, params)
    with jax.enable_x64(True):
        position = jax.vmap(lambda s, p: env.observe(_wide(s), p).position.astype(jnp.float64))(
            states, params
        )
    return obs, position


@functools.partial(jax.jit, static_argnums=0)
def _start(env: Environment, seeds: jax.Array, params: Any):
    # One program for the whole start (keys, split, reset): every separate JAX call is one more
    # trace and compile-cache lookup each session pays before its first request.
    split = jax.vmap(jax.random.split)(
        jax.vmap(jax.random.PRNGKey)(seeds)
    )  # = env.seed_key per run
    states = jax.vmap(env.reset)(split[:, 0], params)
    return (split[:, 1], states) + _seen(env, states, params)


@functools.partial(jax.jit, static_argnums=0)
def _advance(
    env: Environment,
    base_keys: jax.Array,
    t: jax.Array,
    states: Any,
    actions: jax.Array,
    params: Any,
    mask: jax.Array,
):
    # Every member is stepped (one compiled shape per group) and only the masked ones keep it:
    # each run's step key is folded from its own step count, so who else steps changes nothing.
    keys = jax.vmap(jax.random.fold_in)(base_keys, t)
    new, info = jax.vmap(env.step)(keys, states, actions, params)
    new = jax.tree.map(
        lambda a, b: jnp.where(mask.reshape(mask.shape + (1,) * (a.ndim - 1)), a, b), new, states
    )
    obs, position = _seen(env, new, params)
    return (
        new,
        info.progress,
        jnp.any(info.stuck.reshape(mask.shape + (-1,)), -1),
        jnp.any(info.contact.reshape(mask.shape + (-1,)), -1),
        obs,
        position,
        _ended(env, new, params),
    )


def _ended(env: Environment, states: Any, params: Any) -> tuple[jax.Array, jax.Array]:
    """``(reached, ended)`` per run: the world's task succeeded (a navigation target reached),
    and it is over (reached or its budget spent; ``env.termination``); all False in a world
    whose task has no end (the paper's)."""
    terminated, truncated = jax.vmap(env.termination)(states, params)
    return terminated, terminated | truncated


def stack_params(params: Sequence[Any]) -> Any:
    """The params of several runs of one world as one batch (each leaf stacked on a new leading
    axis; a Python number takes JAX's default float, as the world would read it)."""
    dtype = np.dtype(jnp.result_type(float))

    return jax.tree.map(
        lambda *vs: np.stack([np.asarray(v, dtype if isinstance(v, float) else None) for v in vs]),
        *params,
    )


def group_key(env: Environment, params: Any) -> tuple[Any, ...]:
    """Runs with equal keys can share one [`StepGroup`][jswim.agents.step_batcher.StepGroup] (one world, one params structure)."""
    leaves, tree = jax.tree.flatten(params)
    return (env, tree, tuple(np.shape(v) for v in leaves))


class StepGroup:
    """Runs of one world: one batched state (module docs).

    A run hands its action to [`submit`][jswim.agents.step_batcher.StepGroup.submit] and awaits what it sees after the step: ``xs`` (each
    swimmer's x displacement from its start ``x0``, float64 ``(S,)``) and their mean ``x``,
    ``heights`` (the observation's ``height``, else each position's y) and ``tilts`` (each
    orientation), ``dofs`` (float64), ``y`` and ``orientation`` (swimmer 1's height and orientation,
    the world's dtype), ``progress`` (the reward), ``stuck``, ``contact``, ``reached`` and ``ended`` (the
    world's task succeeded, and it is over: ``env.termination``, a navigation target reached or its budget spent;
    always False in the paper's world); a navigation world's also ``target`` (the current
    target's ``(x, y)``) and ``distance``. ``start`` holds the same (but the step's) before the first step, with a batch
    axis; ``levels0`` each start as corner levels of ``[lo, hi]``; ``n_steps`` the env calls made
    (for benchmarks: steps per call = the batching achieved).
    """

    def __init__(
        self,
        members: list[int],
        env: Environment,
        params: Sequence[Any],
        seeds: Sequence[int],
        noop: int,
        lo: Any,
        hi: Any,
    ) -> None:
        self.members = members
        self.env = env
        self.params = stack_params(params)
        self._noop = noop
        seeds32 = np.array([seed32(s) for s in seeds], np.uint32)
        self.step_keys, self.states, obs, position = _start(env, seeds32, self.params)
        self.x0 = np.asarray(position, np.float64)[..., 0]
        self.start = self._outputs(obs, position, None)
        self.start["x"] = np.zeros(len(members))
        self.levels0 = np.rint(
            (self.start["dofs"] - np.asarray(lo, np.float64))
            / (np.asarray(hi, np.float64) - np.asarray(lo, np.float64))
        ).astype(np.int64)
        self.t = np.zeros(len(members), np.int32)
        self._pending: dict[int, tuple[int, asyncio.Future]] = {}
        self.n_steps = 0

    def _outputs(self, obs: Any, position: Any, rest: Any) -> dict[str, np.ndarray]:
        obs, position = jax.device_get((obs, position))
        xs = np.asarray(position, np.float64)[..., 0] - self.x0
        height = obs.height  # a scene's: the middle sphere's; seen from above: the plane's y
        out = {
            "xs": xs,
            "x": xs.mean(-1),
            "heights": np.asarray(height, np.float64),
            "tilts": np.asarray(obs.orientation, np.float64),
            "dofs": np.asarray(obs.dofs, np.float64),
            "y": np.asarray(height[:, 0]),
            "orientation": np.asarray(obs.orientation[:, 0]),
        }
        target = getattr(obs, "target", None)
        if target is not None:  # a navigation task: the current target, lab frame
            out["target"] = np.asarray(target.position, np.float64)
            out["distance"] = np.asarray(target.distance, np.float64)
            out["flow"] = np.asarray(target.flow, np.float64)  # the local flow, lab frame
        if rest is not None:
            progress, stuck, contact, (reached, ended) = jax.device_get(rest)
            out.update(
                progress=np.asarray(progress),
                stuck=np.asarray(stuck),
                contact=np.asarray(contact),
                reached=np.asarray(reached),
                ended=np.asarray(ended),
            )
        return out

    def submit(self, pos: int, action: int) -> asyncio.Future:
        """Step member ``pos`` with env action ``action`` soon; the future gets its step's outputs."""
        loop = asyncio.get_running_loop()
        fut = loop.create_future()
        if not self._pending:
            loop.call_soon(self._flush)
        self._pending[pos] = (action, fut)
        return fut

    def _step(self, codes: np.ndarray, mask: np.ndarray) -> Callable[[int], dict[str, Any]]:
        """Advance the members in ``mask`` by ``codes`` (int32 ``(n,)``); each member's outputs by position."""
        self.states, progress, stuck, contact, obs, position, ended = _advance(
            self.env, self.step_keys, self.t, self.states, codes, self.params, mask
        )
        self.t = self.t + mask.astype(np.int32)
        out = self._outputs(obs, position, (progress, stuck, contact, ended))
        return lambda pos: {k: v[pos] for k, v in out.items()}

    def _flush(self) -> None:
        pending, self._pending = self._pending, {}
        codes = np.full(len(self.members), self._noop, np.int32)
        mask = np.zeros(len(self.members), bool)
        for pos, (a, _) in pending.items():
            codes[pos], mask[pos] = a, True
        try:
            outputs = self._step(codes, mask)
        except BaseException as exc:  # pragma: no cover - an env failure reaches every waiting run
            for _, fut in pending.values():
                if not fut.done():
                    fut.set_exception(exc)
            return
        self.n_steps += 1
        for pos, (_, fut) in pending.items():
            if not fut.done():  # a cancelled run (Ctrl-C) no longer waits
                fut.set_result(outputs(pos))


#: The name of the base before the groups became one (its subclasses were the bulk and scene groups).
StepBatcher = StepGroup
