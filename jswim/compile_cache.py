"""JAX's persistent compilation cache for the ``jswim`` command.

Every ``jswim`` process compiles the same jitted paths (the environment step, the baselines'
training loops, the judge); compiled once, they are kept on disk in the user's cache folder
(``$XDG_CACHE_HOME/jswim/jax`` when that is an absolute path, else ``~/.cache/jswim/jax``; with
``$HOME`` empty or relative, nowhere: `jswim._io.xdg`) and loaded by later processes in
milliseconds. JAX keys each entry by the computation, its shapes, the JAX version and the
device, so a stale entry is never used. A folder that cannot be made or written leaves the
cache off (compilation as before, nothing else changes); ``JSWIM_COMPILATION_CACHE=0`` turns
it off, and a ``JAX_COMPILATION_CACHE_DIR`` the user set is left as it is.
"""

from __future__ import annotations

import os
from pathlib import Path

from jswim._io import xdg

__all__ = ["MIN_COMPILE_S", "cache_folder", "enable"]

#: Compilations shorter than this (seconds) are not worth a disk entry.
MIN_COMPILE_S = 0.05


def cache_folder() -> Path | None:
    """Where the compiled programs go: ``$XDG_CACHE_HOME/jswim/jax`` (an absolute one) or
    ``~/.cache/jswim/jax``; None without a usable home (``$HOME`` empty or relative)."""
    root = xdg.cache_home()
    return None if root is None else root / "jswim" / "jax"


def enable() -> Path | None:
    """Turn the persistent compilation cache on; returns its folder, or ``None`` when it stays off."""
    if os.environ.get("JSWIM_COMPILATION_CACHE", "1").strip() in ("0", "false", "no", "off"):
        return None
    if os.environ.get("JAX_COMPILATION_CACHE_DIR"):
        return Path(os.environ["JAX_COMPILATION_CACHE_DIR"])  # the user's own; JAX reads it itself
    where = cache_folder()
    if where is None:  # no home to keep it in: compile as before (never /.cache)
        return None
    try:
        where.mkdir(parents=True, exist_ok=True)
    except OSError:
        return None
    if not os.access(where, os.W_OK | os.X_OK):
        return None
    import jax

    try:
        jax.config.update("jax_compilation_cache_dir", str(where))
        jax.config.update("jax_persistent_cache_min_compile_time_secs", MIN_COMPILE_S)
    except (AttributeError, ValueError):  # a JAX without these options: compile as before
        return None
    return where
