"""Who may read what jswim writes: the owner alone, unless the umask shares with a group on purpose.

Under the usual umask ``022``, or any umask that does not let the group write, jswim creates
folders ``0700`` and files ``0600``; a umask that lets the group write (``002``, ``007``, ``000``)
is honoured as it is. Why: docs/studies.md.
"""

from __future__ import annotations

import contextlib
import os
from collections.abc import Iterator


def current_umask() -> int:
    """The process's umask (read by setting it and setting it back)."""
    mask = os.umask(0o077)
    os.umask(mask)
    return mask


def effective_umask(mask: int) -> int:
    """The umask jswim writes under: ``mask`` if it lets the group write, else owner only (``077``)."""
    return mask if not mask & 0o020 else mask | 0o077


def file_mode(mask: int | None = None) -> int:
    """Mode of a new file under ``mask`` (default: the current umask): ``0600`` under ``022``."""
    return 0o666 & ~effective_umask(current_umask() if mask is None else mask)


@contextlib.contextmanager
def private_files() -> Iterator[None]:
    """Create files and folders under `effective_umask` inside the block (process-wide)."""
    old = os.umask(0o077)
    os.umask(effective_umask(old))
    try:
        yield
    finally:
        os.umask(old)


def opener(path: str, flags: int) -> int:
    """``open(..., opener=opener)``: a new file gets `file_mode` whatever the block it is in."""
    return os.open(path, flags, file_mode())
