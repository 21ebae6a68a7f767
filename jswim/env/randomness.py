"""Counter-based noise: the paper's ``Y ~ U[-1, 1]`` for any slice of a population."""

from __future__ import annotations

import hashlib
from typing import Any

import jax
import jax.numpy as jnp
from jax import Array


def noise(key: Array, n: int, *, start: int | Array = 0, step: int | Array = 0) -> Array:
    """The noise variables ``Y ~ U[-1, 1)`` of swimmers ``start .. start + n - 1`` (float32).

    Counter-based: swimmers ``2j`` and ``2j + 1`` share one Threefry-2x32 hash of the counter
    block ``(step, j)`` under ``key`` (one word each), so any slice of a population can be drawn
    on its own, on any device, and gives the numbers the whole draw would. ``start`` must be
    even. 23 random bits per variable (the float32 mantissa), also in float64 mode: the noise
    is the same in both precisions.
    """
    import jax.extend.random as jer

    m = (n + 1) // 2
    kd = jax.random.key_data(key) if jnp.issubdtype(key.dtype, jax.dtypes.prng_key) else key
    kd = jnp.asarray(kd, jnp.uint32).reshape(2)
    j = (jnp.asarray(start, jnp.uint32) // 2) + jnp.arange(m, dtype=jnp.uint32)
    t = jnp.broadcast_to(jnp.asarray(step, jnp.uint32), (m,))
    w0, w1 = jer.threefry2x32_p.bind(kd[0], kd[1], t, j)
    bits = jnp.stack([w0, w1], axis=-1).reshape(-1)[:n]
    u = jax.lax.bitcast_convert_type((bits >> 9) | jnp.uint32(0x3F800000), jnp.float32) - 1.0
    return 2.0 * u - 1.0


def uniforms(
    key: Array, shape: tuple[int, ...], dtype: Any, minval: float = 0.0, maxval: float = 1.0
) -> Array:
    """``jax.random.uniform`` under the non-partitionable threefry.

    It uses both words of each hash, so it costs about half as much on CPU, and gives the same
    numbers whether or not it is vmapped (the Q-learner draws its run's uniforms with it).
    """
    with jax.threefry_partitionable(False):
        return jax.random.uniform(key, shape, dtype, minval, maxval)


def seed32(seed: int) -> int:
    """A seed `jax.random.PRNGKey` takes, from any integer: ``seed`` itself in
    ``[0, 2**32)`` (so existing seeds keep their streams), else a 32-bit BLAKE2b hash of it
    (negative or huge seeds: ``--seed -1``, ``--seed 2**70``)."""
    seed = int(seed)
    if 0 <= seed < 2**32:
        return seed
    return int.from_bytes(hashlib.blake2b(str(seed).encode(), digest_size=4).digest(), "little")


def seed_key(seed: int) -> Array:
    """``jax.random.PRNGKey(seed32(seed))``: a key from any integer seed."""
    return jax.random.PRNGKey(seed32(seed))
