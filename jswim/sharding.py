"""Spread a swimmer/learner batch axis over every device, and cut it into bounded chunks.

One mesh over ``jax.devices()`` with a single axis, ``"batch"``; a batched array is placed with
``NamedSharding(mesh, P("batch"))`` (contiguous blocks, one per device) and jitted code follows the
data without communication. The numbers are the same on any device count (noise is counter-based,
[`jswim.env.noise`][jswim.env.randomness.noise]). Memory is bounded by chunks (`chunks`), multiples of
`granule` so that they split evenly and keep swimmer pairs (which share one noise hash)
together. One CPU, forced host devices, GPUs, several hosts (results gathered by
`to_host`): docs/performance.md, "Scaling out".
"""

from __future__ import annotations

import contextlib
import functools
from typing import Any
from collections.abc import Callable, Iterator, Sequence

import jax
import jax.numpy as jnp
import numpy as np
from jax.sharding import Mesh, NamedSharding, PartitionSpec

__all__ = [
    "AXIS",
    "apply_batched",
    "apply_runs",
    "batch_sharding",
    "chunks",
    "device_count",
    "devices",
    "granule",
    "leaf_axes",
    "limit",
    "mesh",
    "pad",
    "padded_size",
    "shard",
    "to_host",
]

#: Name of the mesh axis that carries swimmers or learners.
AXIS = "batch"


@functools.lru_cache(maxsize=4)
def _mesh(devices: tuple[Any, ...]) -> Mesh:
    return Mesh(np.asarray(devices), (AXIS,))


_LIMIT: list[int | None] = [None]


def devices() -> list[Any]:
    """The devices batches are spread over: ``jax.devices()``, or its first ``n`` inside
    `limit`."""
    devs = jax.devices()
    return devs if _LIMIT[0] is None else devs[: _LIMIT[0]]


@contextlib.contextmanager
def limit(n: int | None) -> Iterator[None]:
    """Spread batches over only the first ``n`` devices inside this block (benchmarks, tests)."""
    if n is not None and not 1 <= n <= len(jax.devices()):
        raise ValueError(f"limit must lie in 1..{len(jax.devices())}, got {n}")
    old, _LIMIT[0] = _LIMIT[0], n
    try:
        yield
    finally:
        _LIMIT[0] = old


def mesh() -> Mesh:
    """A one-axis mesh over every device of every process (``jax.devices()``)."""
    return _mesh(tuple(devices()))


def device_count() -> int:
    return len(devices())


def granule() -> int:
    """Batch sizes that are multiples of this split evenly (two swimmers per device at least)."""
    return 2 * device_count()


def batch_sharding() -> NamedSharding:
    """Leading axis split over the mesh, other axes whole."""
    return NamedSharding(mesh(), PartitionSpec(AXIS))


def padded_size(n: int) -> int:
    """``n`` rounded up to a multiple of `granule`."""
    g = granule()
    return -(-n // g) * g


def pad(tree: Any, n: int, size: int) -> Any:
    """Pad every leaf's leading axis from ``n`` to ``size`` by repeating its last entry."""
    if size == n:
        return tree
    return jax.tree_util.tree_map(
        lambda a: jnp.concatenate([a, jnp.repeat(a[-1:], size - n, axis=0)]), tree
    )


def shard(tree: Any) -> Any:
    """Place every leaf with its leading axis split over the mesh (a no-op on one device)."""
    if device_count() == 1:
        return tree
    sh = batch_sharding()
    return jax.tree_util.tree_map(lambda a: jax.device_put(a, sh), tree)


def apply_batched(
    fn: Callable[..., Any], shared: Sequence[Any], batched: Sequence[Any], n: int
) -> Any:
    """``fn(*shared, *batched)`` with the batch axis (size ``n``) sharded over every device.

    Every array leaf of ``batched`` must have leading axis ``n``; ``shared`` leaves are
    replicated. On one device this is a plain call. Otherwise the batch is padded to a multiple
    of `granule`, sharded, and the outputs (leading axis ``n`` again) are cut back.
    """
    if device_count() == 1:
        return fn(*shared, *batched)
    size = padded_size(n)
    args = shard(pad(tuple(batched), n, size))
    out = fn(*shared, *args)
    if size == n:
        return out
    return jax.tree_util.tree_map(lambda a: a[:n], out)


def leaf_axes(tree: Any, axes: Any) -> Any:
    """``axes`` (a ``vmap`` ``in_axes`` prefix of ``tree``: 0, None or a tree of them) spelled out
    for every leaf of ``tree``."""
    return jax.tree_util.tree_map(
        lambda ax, sub: jax.tree_util.tree_map(lambda _: ax, sub),
        axes,
        tree,
        is_leaf=lambda a: a is None,
    )


def apply_runs(fn: Callable[[Any, Any], Any], keys: Any, params: Any, axes: Any, n: int) -> Any:
    """``fn(keys, params)`` for ``n`` runs, the runs sharded over every device.

    ``keys`` has leading axis ``n``; ``params``' leaves carry it where ``axes`` (a ``vmap``
    ``in_axes`` prefix of ``params``) says 0, and are replicated where it says None. On one device
    this is a plain call; otherwise as `apply_batched`.
    """
    if device_count() == 1:
        return fn(keys, params)
    size = padded_size(n)
    per_leaf = leaf_axes(params, axes)
    leaves, treedef = jax.tree_util.tree_flatten(params)
    ax = treedef.flatten_up_to(per_leaf)
    run_leaves = [leaf for leaf, a in zip(leaves, ax) if a == 0]
    keys, run_leaves = shard(pad((keys, tuple(run_leaves)), n, size))
    it = iter(run_leaves)
    params = treedef.unflatten([next(it) if a == 0 else leaf for leaf, a in zip(leaves, ax)])
    out = fn(keys, params)
    if size == n:
        return out
    return jax.tree_util.tree_map(lambda a: a[:n], out)


def chunks(n: int, chunk: int) -> Iterator[tuple[int, int]]:
    """``(start, stop)`` ranges covering ``0 .. n``; every start is a multiple of the chunk,
    which is rounded up to a multiple of `granule`."""
    size = padded_size(max(1, chunk))
    for start in range(0, n, size):
        yield start, min(n, start + size)


def to_host(tree: Any) -> Any:
    """Fetch arrays as NumPy, gathering the other processes' blocks in a multi-host run."""
    if jax.process_count() > 1:
        from jax.experimental import multihost_utils

        return multihost_utils.process_allgather(tree, tiled=True)
    return jax.tree_util.tree_map(np.asarray, jax.device_get(tree))
