"""The user's cache folder per the XDG Base Directory spec (JAX-free; the table cache,
`jswim.env.table_cache`, and the compilation cache, `jswim.compile_cache`, live under it).

``$XDG_CACHE_HOME`` counts only as an absolute path (the spec: a relative one is invalid and is
ignored), else ``$HOME/.cache``. A home that is set but empty or relative is no home: Python's
``expanduser`` would turn ``~`` into the root folder (``HOME=""``: ``/.cache``) or a folder
under the working one, so both helpers answer None and each caller says what it does instead.
"""

from __future__ import annotations

import os
from pathlib import Path

__all__ = ["cache_home", "home"]


def home() -> Path | None:
    """``$HOME`` when it is an absolute path (unset: the password database's, as ``expanduser``
    reads it); None when it is empty or relative."""
    text = os.environ["HOME"] if "HOME" in os.environ else os.path.expanduser("~")
    return Path(text) if os.path.isabs(text) else None


def cache_home() -> Path | None:
    """``$XDG_CACHE_HOME`` when absolute, else ``home()/.cache``; None without a usable home."""
    xdg = os.environ.get("XDG_CACHE_HOME", "")
    if os.path.isabs(xdg):
        return Path(xdg)
    base = home()
    return None if base is None else base / ".cache"
