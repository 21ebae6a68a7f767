"""Persistent response cache (sqlite3) for deterministic requests.

Keys are SHA-256 hashes of the full request body, without the API key or the server's address;
only replies that answered are stored (``cache_if`` of [`jswim.llm.client.LLMClient.chat`][jswim.llm.client.LLMClient.chat]).
docs/servers.md (*Cache*) says why.
"""

from __future__ import annotations

import hashlib
import json
import sqlite3
import threading
import time
from pathlib import Path
from typing import Any

from jswim.errors import ConfigError

#: Bump when the stored value's layout changes (v2: reasoning stored, failed replies no longer
#: stored; v1 entries are ignored, so failures cached by older versions are never replayed).
CACHE_VERSION = "jswim-llm-cache-v2"


def request_key(payload: dict[str, Any]) -> str:
    """Hash of a request body (canonical JSON: sorted keys, no spaces)."""
    blob = json.dumps(
        [CACHE_VERSION, payload], sort_keys=True, separators=(",", ":"), ensure_ascii=False
    )
    return hashlib.sha256(blob.encode("utf-8")).hexdigest()


def check_cache(path: str | Path) -> None:
    """Open the cache at ``path`` once (creating it), so a bad ``--cache-dir`` fails in one line
    before any run: not writable, a file where a folder should be, or a file that is not a cache.

    Raises
    ------
    ConfigError
        Naming the path and the cause.
    """
    try:
        ResponseCache(path).close()
    except sqlite3.DatabaseError as exc:  # "file is not a database", a read-only database, ...
        raise ConfigError(
            f"--cache-dir {path}: not a usable jswim response cache ({exc}); "
            "give a folder, or a .sqlite file that jswim made"
        ) from None
    except OSError as exc:
        what = (
            "a file, not a folder"
            if Path(path).is_file() and Path(path).suffix not in (".sqlite", ".db")
            else (exc.strerror or type(exc).__name__)
        )
        raise ConfigError(f"--cache-dir {path}: {what}; give a writable folder") from None


class ResponseCache:
    """Key -> JSON value store in one sqlite file, safe to share between processes.

    Parameters
    ----------
    path : str or Path
        Directory (the file ``responses.sqlite`` is created in it) or a ``.sqlite`` file.
    """

    def __init__(self, path: str | Path) -> None:
        p = Path(path)
        if p.suffix not in (".sqlite", ".db"):
            p.mkdir(parents=True, exist_ok=True)
            p = p / "responses.sqlite"
        else:
            p.parent.mkdir(parents=True, exist_ok=True)
        self.path = p
        self._lock = threading.Lock()
        self._db = sqlite3.connect(p, timeout=30.0, check_same_thread=False, isolation_level=None)
        # WAL lets several study processes read while one writes.
        self._db.execute("PRAGMA journal_mode=WAL")
        self._db.execute(
            "CREATE TABLE IF NOT EXISTS responses (key TEXT PRIMARY KEY, value TEXT NOT NULL, created REAL)"
        )

    def get(self, key: str) -> dict[str, Any] | None:
        with self._lock:
            row = self._db.execute("SELECT value FROM responses WHERE key = ?", (key,)).fetchone()
        return json.loads(row[0]) if row else None

    def put(self, key: str, value: dict[str, Any]) -> None:
        blob = json.dumps(value, ensure_ascii=False)
        with self._lock:
            self._db.execute(
                "INSERT OR REPLACE INTO responses (key, value, created) VALUES (?, ?, ?)",
                (key, blob, time.time()),
            )

    def __len__(self) -> int:
        with self._lock:
            return self._db.execute("SELECT COUNT(*) FROM responses").fetchone()[0]

    def close(self) -> None:
        with self._lock:
            self._db.close()
