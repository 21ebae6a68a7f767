"""On-disk cache of the exact tables (the corner, lattice, motion, work and flow tables).

Building a table runs the float64 integrator (seconds, mostly compilation); reading it back takes
milliseconds. Entries are keyed by the table's name, the swimmer model, its parameters (a flow
table's form, the lattice's K, degrees, cut-offs), the code version (a hash of
``jswim.__version__`` and of the source of every module a table depends on) and the file format
(`FORMAT`), so a change to the physics never reads a stale table.

Nothing on disk is trusted. Each entry records what it was built from (the table, its key, the
code version, the format, every array's shape and dtype) and a checksum of all of it with the
arrays' bytes (`_checksum`). An entry is used only if it is a regular file (checked before it is
opened, and opened without blocking: a FIFO, a device or a folder at its path is never read)
whose record matches what the caller asks for, whose arrays are exactly the recorded ones, of
the caller's shape, finite float64, and whose checksum holds. Anything else is damage: the table
is rebuilt, written atomically over the entry (a temporary file, then ``os.replace``), and one
`TableCacheWarning` line says so; a missing entry is
built silently. The folder (`cache_dir`) follows the XDG Base Directory spec;
``JSWIM_TABLE_CACHE=off`` disables the cache (docs/continuous.md, "Start-up").
"""

from __future__ import annotations

import atexit
import functools
import hashlib
import json
import os
import shutil
import stat
import tempfile
from collections.abc import Callable, Mapping
from pathlib import Path

import numpy as np

from jswim._io import xdg
from jswim._io.callsite import warn_user
from jswim.errors import JswimWarning

__all__ = ["FORMAT", "TableCacheWarning", "cache_dir", "cached", "code_version", "model_key"]

#: Version of the entry layout (the arrays plus the ``__meta__`` record); part of every key, so
#: entries of an older layout are never read (they stay as orphans in the folder).
FORMAT = 2

#: The array holding an entry's record (JSON text).
META = "__meta__"

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

#: A caller's expected shape of each array: ints, ``None`` where a size is not known in advance.
Shapes = Mapping[str, tuple[int | None, ...]]


class TableCacheWarning(JswimWarning):
    """A cached table was damaged and has been rebuilt, or the cache folder is a temporary one
    (no usable home folder). Nothing stops: the tables are always built when not read."""


#: Entries already reported in this process (each damage is said once).
_warned: set[str] = set()


def _say(message: str, once: str) -> None:
    if once not in _warned:
        _warned.add(once)
        warn_user(message, TableCacheWarning)


# --- the folder ----------------------------------------------------------------------------


@functools.lru_cache(maxsize=1)
def _temporary_dir() -> Path:
    """A private folder for this process, removed at exit, with one warning saying why."""
    folder = Path(tempfile.mkdtemp(prefix="jswim-tables-"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    _say(
        f"no usable home folder (HOME={os.environ.get('HOME', '')!r}, XDG_CACHE_HOME not an "
        f"absolute path): the tables are cached in {folder} for this process only; set "
        "XDG_CACHE_HOME or JSWIM_TABLE_CACHE to keep them (JSWIM_TABLE_CACHE=off: no cache)",
        "temporary folder",
    )
    return folder


def cache_dir() -> Path | None:
    """The table cache folder, or None when disabled (``JSWIM_TABLE_CACHE=off``).

    ``$JSWIM_TABLE_CACHE`` (a leading ``~`` or ``~user`` expanded), else
    ``$XDG_CACHE_HOME/jswim/tables`` when ``$XDG_CACHE_HOME`` is an absolute path (a relative one
    is ignored, as the XDG Base Directory spec says), else ``~/.cache/jswim/tables``. Without a
    usable home (``$HOME`` empty or relative) where one is needed, a temporary folder for this
    process, with one `TableCacheWarning`.
    """
    env = os.environ.get("JSWIM_TABLE_CACHE")
    if env is not None:
        if env.strip().lower() in ("", "off", "0", "none"):
            return None
        if env == "~" or env.startswith("~/"):
            home = xdg.home()
            return _temporary_dir() if home is None else home / env[2:]
        if env.startswith("~"):
            expanded = os.path.expanduser(env)  # ~user: the password database
            return _temporary_dir() if expanded.startswith("~") else Path(expanded)
        return Path(env)
    base = xdg.cache_home()
    return _temporary_dir() if base is None else base / "jswim" / "tables"


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


# --- an entry ------------------------------------------------------------------------------


class _Damaged(Exception):
    """Why an entry on disk cannot be used (one phrase)."""


def _record(name: str, key: str, arrays: Mapping[str, np.ndarray]) -> dict:
    """What an entry says it holds, less its checksum."""
    return {
        "format": FORMAT,
        "table": name,
        "key": key,
        "code": code_version(),
        "arrays": {
            k: {"shape": list(v.shape), "dtype": v.dtype.str} for k, v in sorted(arrays.items())
        },
    }


def _checksum(record: dict, arrays: Mapping[str, np.ndarray]) -> str:
    """blake2b of the record (JSON) and of each array's name, dtype, shape and bytes."""
    h = hashlib.blake2b(json.dumps(record, sort_keys=True).encode(), digest_size=16)
    for k in sorted(arrays):
        v = np.ascontiguousarray(arrays[k])
        h.update(f"|{k}|{v.dtype.str}|{v.shape}|".encode())
        h.update(v.tobytes())
    return h.hexdigest()


def _fits(shape: tuple[int, ...], want: tuple[int | None, ...]) -> bool:
    return len(shape) == len(want) and all(w is None or s == w for s, w in zip(shape, want))


def _layout(arrays: Mapping[str, np.ndarray], shapes: Shapes | None) -> str | None:
    """Why ``arrays`` does not have the names, dtype (float64) and ``shapes`` asked for, or None."""
    if shapes is not None and set(arrays) != set(shapes):
        return f"arrays {sorted(arrays)}, expected {sorted(shapes)}"
    for k, v in arrays.items():
        if v.dtype != np.float64:
            return f"{k!r} is {v.dtype}, not float64"
        if shapes is not None and not _fits(v.shape, shapes[k]):
            want = ", ".join("n" if w is None else str(w) for w in shapes[k])
            return f"{k!r} has shape {v.shape}, expected ({want})"
    return None


def _values(arrays: Mapping[str, np.ndarray]) -> str | None:
    """Why ``arrays`` cannot be a table (an empty or non-finite array), or None."""
    for k, v in arrays.items():
        if v.size == 0:
            return f"{k!r} is empty, shape {v.shape}"
        if not np.all(np.isfinite(v)):
            return f"{k!r} holds non-finite values"
    return None


def _kind(mode: int) -> str:
    for test, what in (
        (stat.S_ISDIR, "a folder"),
        (stat.S_ISFIFO, "a FIFO"),
        (stat.S_ISLNK, "a symbolic link"),
        (stat.S_ISCHR, "a character device"),
        (stat.S_ISBLK, "a block device"),
        (stat.S_ISSOCK, "a socket"),
    ):
        if test(mode):
            return what
    return "not a regular file"


def _read(path: Path, name: str, key: str, shapes: Shapes | None) -> dict[str, np.ndarray] | None:
    """The entry at ``path`` if it holds the table asked for; None if there is none.

    Raises
    ------
    _Damaged
        Anything else at ``path``: not a regular file, unreadable, another table, a record that
        does not match its arrays or the caller's shapes, a failed checksum.
    """
    try:
        mode = os.lstat(path).st_mode  # before opening: a FIFO's open or read would block
    except OSError:  # none there, or an unusable folder (not a folder, not searchable)
        return None
    if not stat.S_ISREG(mode):
        raise _Damaged(f"{_kind(mode)}, not a regular file")
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_NOFOLLOW", 0)
    try:
        fd = os.open(path, flags)
    except OSError as err:
        raise _Damaged(f"cannot open it: {err.strerror}") from None
    with os.fdopen(fd, "rb") as fh:
        if not stat.S_ISREG(os.fstat(fd).st_mode):  # replaced since the lstat
            raise _Damaged("not a regular file")
        try:
            with np.load(fh, allow_pickle=False) as data:
                files = list(data.files)
                if not files or META not in files:
                    raise _Damaged(f"no record of what it was built from (arrays {sorted(files)})")
                arrays = {k: np.asarray(data[k]) for k in files if k != META}
                meta = data[META]
        except _Damaged:
            raise
        except Exception as err:  # zip, npy or pickle refusal: not an entry we wrote
            raise _Damaged(f"unreadable ({type(err).__name__})") from None
    problem = _layout(arrays, shapes)
    if problem:
        raise _Damaged(problem)
    try:
        record = json.loads(str(meta[()]))
        stored = record.pop("checksum")
    except Exception:
        raise _Damaged("its record is unreadable or incomplete") from None
    expected = _record(name, key, arrays)
    for field in ("format", "table", "key", "code"):
        if record.get(field) != expected[field]:
            raise _Damaged(f"built from another {field}")
    if record.get("arrays") != expected["arrays"]:
        raise _Damaged("its arrays are not the ones it records")
    problem = _values(arrays)
    if problem:
        raise _Damaged(problem)
    if stored != _checksum(record, arrays):
        raise _Damaged("checksum mismatch")
    return arrays


def _write(path: Path, name: str, key: str, arrays: Mapping[str, np.ndarray]) -> None:
    """Write the entry atomically: a temporary file in the folder, then ``os.replace``."""
    record = _record(name, key, arrays)
    record["checksum"] = _checksum(record, arrays)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{name}-", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            np.savez(fh, **arrays, **{META: np.array(json.dumps(record, sort_keys=True))})
        os.replace(tmp, path)
    finally:
        if os.path.lexists(tmp):
            os.unlink(tmp)


def cached(
    name: str,
    key: str,
    build: Callable[[], dict[str, np.ndarray]],
    shapes: Shapes | None = None,
) -> dict[str, np.ndarray]:
    """``build()`` (a dict of float64 arrays), read from the cache when present and intact.

    Parameters
    ----------
    name : str
        The table's name (the entry's file name starts with it).
    key : str
        Everything the table is built from (model, parameters), as text.
    build : callable
        Builds the table: array name -> finite float64 array.
    shapes : mapping, optional
        Array name -> expected shape (``None`` for a size not known in advance). An entry with
        other arrays or shapes is damaged; without it, the entry's own record decides.

    Returns
    -------
    dict of ndarray
        The table; a damaged entry is never returned: it is rebuilt, written over and reported
        once (`TableCacheWarning`).

    Raises
    ------
    RuntimeError
        If ``build()`` itself returns arrays that do not match ``shapes`` (a bug in jswim).
    """
    folder = cache_dir()
    if folder is None:
        return _built(name, build, shapes)
    digest = hashlib.blake2b(
        f"{name}|{key}|{code_version()}|format={FORMAT}".encode(), digest_size=12
    ).hexdigest()
    path = folder / f"{name}-{digest}.npz"
    try:
        found = _read(path, name, key, shapes)
    except _Damaged as why:
        damage: str | None = str(why)
    except Exception as err:  # never a reason for a step to fail: build instead
        damage = f"unreadable ({type(err).__name__})"
    else:
        if found is not None:
            return found
        damage = None
    out = _built(name, build, shapes)
    replaced = _values(out)  # an empty or non-finite build is returned, never stored
    if replaced is None:
        try:
            _write(path, name, key, out)
        except Exception as err:
            replaced = getattr(err, "strerror", None) or type(err).__name__
    if damage is not None:
        if replaced is None:
            _warned.discard(str(path))  # replaced: damage found there again is news
        fate = "rebuilt" if replaced is None else f"rebuilt in memory, not stored ({replaced})"
        _say(f"cached {name} table {path} is damaged ({damage}): not used, {fate}", str(path))
    return out


def _built(
    name: str, build: Callable[[], dict[str, np.ndarray]], shapes: Shapes | None
) -> dict[str, np.ndarray]:
    out = {k: np.asarray(v) for k, v in build().items()}
    problem = _layout(out, shapes)
    if problem:
        raise RuntimeError(f"the {name} table just built is not one: {problem}")
    return out


def model_key(model: object) -> str:
    """A stable text key of a (frozen dataclass) swimmer model: its repr (floats exact)."""
    return repr(model)
