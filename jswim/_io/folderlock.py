"""One writer per study folder: an exclusive OS lock held for a whole session.

Two processes writing one study folder would send and journal every call twice. `FolderLock`
takes an exclusive lock on ``FOLDER/.jswim.lock`` (`filelock`) before anything in the folder
is read or written and holds it until the session ends; ``FOLDER/.jswim.holder.json`` says who
holds it. Readers never lock (`holder` tells them whether a live session holds it). What
happens to a dead holder's lock is in docs/studies.md (*One writer*).
"""

from __future__ import annotations

import json
import os
import socket
import sys
import time
from pathlib import Path
from typing import Any

from jswim._io.atomic import write_json
from jswim.errors import FolderBusyError
from jswim._io.permissions import file_mode

LOCK = ".jswim.lock"
HOLDER = ".jswim.holder.json"


def holder(folder: str | os.PathLike) -> dict[str, Any] | None:
    """Who last took the folder's lock (``pid``, ``host``, ``since`` in UTC, ``command``), with
    ``alive`` (``True``/``False`` for a process on this host, ``None`` for another host); ``None``
    when no session holds it or the holder file is unreadable."""
    try:
        info = json.loads((Path(folder) / HOLDER).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if not isinstance(info, dict):
        return None
    info["alive"] = _alive(info.get("pid")) if info.get("host") == socket.gethostname() else None
    return info


def describe_holder(info: dict[str, Any] | None) -> str:
    """``pid 4242 on host node7 since 2026-12-01 19:40:03 UTC`` (or ``another process``)."""
    if not info:
        return "another process"
    return f"pid {info.get('pid')} on host {info.get('host')} since {info.get('since')}"


def _alive(pid: Any) -> bool | None:
    if not isinstance(pid, int) or pid <= 0:
        return None
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # exists, owned by someone else
        return True
    except OSError:
        return None
    return True


class FolderLock:
    """Exclusive lock on a study folder for one session (docs/studies.md).

    Parameters
    ----------
    folder : path
        An existing folder.

    Raises
    ------
    FolderBusyError
        From `acquire`, when a live process holds the lock: the message names it.
    """

    def __init__(self, folder: str | os.PathLike) -> None:
        self.folder = Path(folder)
        self._lock: Any = None

    @property
    def held(self) -> bool:
        return self._lock is not None

    def acquire(self) -> FolderLock:
        """Take the lock without waiting, and record this process as its holder."""
        import filelock  # lazy: only a session that writes a folder needs it

        lock = filelock.FileLock(self.folder / LOCK, timeout=0, mode=file_mode())
        try:
            lock.acquire(timeout=0)
        except filelock.Timeout:
            who = describe_holder(holder(self.folder))
            raise FolderBusyError(
                f"{self.folder} is in use by another jswim session ({who}); one session writes a study "
                "folder at a time: wait for it to end, or use another --out"
            ) from None
        self._lock = lock
        write_json(
            self.folder / HOLDER,
            {
                "pid": os.getpid(),
                "host": socket.gethostname(),
                "since": time.strftime("%Y-%m-%d %H:%M:%S UTC", time.gmtime()),
                # The program only: arguments may carry a --base-url with credentials in it.
                "command": os.path.basename(sys.argv[0]) if sys.argv and sys.argv[0] else "python",
            },
        )
        return self

    def release(self) -> None:
        """Drop the lock (the holder file first, so nobody reads a holder that has left)."""
        if self._lock is None:
            return
        try:
            (self.folder / HOLDER).unlink(missing_ok=True)
        except OSError:
            pass  # a read-only or vanished folder: the lock itself still goes
        self._lock.release()
        self._lock = None

    def __del__(
        self,
    ) -> None:  # a store dropped without close() (notebooks, tests) frees its folder
        try:
            self.release()
        except Exception:
            pass

    def __enter__(self) -> FolderLock:
        return self.acquire()

    def __exit__(self, *exc: object) -> None:
        self.release()
