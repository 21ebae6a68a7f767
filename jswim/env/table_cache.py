"""On-disk cache of the exact tables (the corner, lattice, motion and work tables).

Building a table runs the float64 integrator (seconds, mostly compilation); reading it back takes
milliseconds. Entries are keyed by the table's name, the swimmer model, its parameters and the
code version (a hash of ``jswim.__version__`` and of the source of every module a table depends
on), so a change to the physics never reads a stale table. Any problem falls back to building;
the folder and ``JSWIM_TABLE_CACHE=off``: docs/continuous.md, "Start-up".
"""

from __future__ import annotations

import functools
import hashlib
import os
import tempfile
from pathlib import Path
from collections.abc import Callable

import numpy as np

#: Modules whose source decides a table's numbers.
_SOURCES = (
    "jswim.integrate",
    "jswim.swimmers.models",
    "jswim.swimmers.purcell",
    "jswim.swimmers.nlink",
    "jswim.swimmers.ng",
    "jswim.swimmers.nsphere",
    "jswim.swimmers.wall_rft",
    "jswim.swimmers.purcell_beads",
    "jswim.swimmers.mobility",
    "jswim.env.step_tables",
    "jswim.env.motion",
    "jswim.env.state",
    "jswim.env.work",
    "jswim.swimmers.dissipation",
)


def cache_dir() -> Path | None:
    """The table cache folder, or None when disabled (``JSWIM_TABLE_CACHE=off``)."""
    env = os.environ.get("JSWIM_TABLE_CACHE")
    if env is not None:
        return None if env.strip().lower() in ("", "off", "0", "none") else Path(env)
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "jswim" / "tables"


@functools.lru_cache(maxsize=1)
def code_version() -> str:
    """Hash of ``jswim.__version__`` and the source of the modules in `_SOURCES`."""
    import importlib.util

    import jswim  # lazy: the package's __init__ imports this module, so only a call can read its version

    h = hashlib.blake2b(jswim.__version__.encode(), digest_size=10)
    for name in _SOURCES:
        spec = importlib.util.find_spec(name)
        origin = getattr(spec, "origin", None)
        try:
            h.update(Path(origin).read_bytes() if origin else name.encode())
        except OSError:
            h.update(name.encode())
    return h.hexdigest()


def cached(
    name: str, key: str, build: Callable[[], dict[str, np.ndarray]]
) -> dict[str, np.ndarray]:
    """``build()`` (a dict of float64 arrays), read from the cache when present and valid."""
    folder = cache_dir()
    if folder is None:
        return build()
    digest = hashlib.blake2b(f"{name}|{key}|{code_version()}".encode(), digest_size=12).hexdigest()
    path = folder / f"{name}-{digest}.npz"
    try:
        with np.load(path, allow_pickle=False) as data:
            out = {k: np.asarray(data[k]) for k in data.files}
        if out and all(v.dtype == np.float64 and np.all(np.isfinite(v)) for v in out.values()):
            return out
    except Exception:
        pass
    out = build()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{name}-", suffix=".tmp", dir=folder)
        try:
            with os.fdopen(fd, "wb") as fh:
                np.savez(fh, **out)
            os.replace(tmp, path)
        finally:
            if os.path.exists(tmp):
                os.unlink(tmp)
    except Exception:
        pass
    return out


def model_key(model: object) -> str:
    """A stable text key of a (frozen dataclass) swimmer model: its repr (floats exact)."""
    return repr(model)
