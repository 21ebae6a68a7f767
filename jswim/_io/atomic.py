"""Atomic file writes and strict JSON: what every folder writer uses (JAX-free, no pyarrow).

It sits below [`jswim.results`][jswim.results] so that `jswim._io.folderlock` writes its holder file
without importing the results layer (which would make an import cycle).
"""

from __future__ import annotations

import json
import math
import os
import tempfile
from pathlib import Path
from typing import Any
from collections.abc import Mapping

import numpy as np

from jswim._io.permissions import file_mode


def plain_json(obj: Any) -> Any:
    """``obj`` with only JSON types: NumPy values unwrapped, sets/tuples as lists, and
    non-finite floats (NaN, +-inf) as ``None``, so the output is strict JSON."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, (str, int, bool)) or obj is None:
        return obj
    if isinstance(obj, Mapping):
        return {str(k) if not isinstance(k, str) else k: plain_json(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple, set, frozenset)):
        items = sorted(obj, key=repr) if isinstance(obj, (set, frozenset)) else obj
        return [plain_json(v) for v in items]
    return plain_json(_jsonable(obj))


def dumps(obj: Any, **kw: Any) -> str:
    """Strict JSON text of ``obj`` (see `plain_json`); ``kw`` go to `json.dumps`."""
    return json.dumps(plain_json(obj), allow_nan=False, **kw)


def atomic_write(path: str | os.PathLike, data: bytes | str) -> None:
    """Write ``data`` to ``path`` so that readers see the old or the new file, never a part.

    The file gets `jswim._io.permissions.file_mode`, or the mode of the file it replaces.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    raw = data.encode() if isinstance(data, str) else data
    try:
        mode = path.stat().st_mode & 0o7777
    except OSError:
        mode = file_mode()  # the umask now (FILE_MODE is the one at import)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        os.fchmod(fd, mode)
        with os.fdopen(fd, "wb") as fh:
            fh.write(raw)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def write_json(path: str | os.PathLike, obj: Any) -> None:
    """Atomically write ``obj`` as indented strict JSON (no NaN; see `plain_json`)."""
    atomic_write(path, dumps(obj, indent=2, sort_keys=True) + "\n")


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, np.generic):
        return obj.item()
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, os.PathLike):
        return os.fspath(obj)
    raise TypeError(f"not JSON serialisable: {type(obj).__name__}")
