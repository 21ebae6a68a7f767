"""Study results on disk: one folder per study, resumable, written atomically.

Layout of a study folder::

    metadata.json        study name, parameters, seed, backend, prompt template, versions, status
    runs.jsonl           one line per finished run (the durable record, appended and fsynced)
    runs.parquet         tidy table of runs (rebuilt from runs.jsonl; also runs.csv)
    trajectories.parquet per-step rows: run_id, step, x, y, orientation, action, progress, stuck
    transcripts/RUN.jsonl  the LLM transcript of each LLM run
    usage.json           tokens and cost per run and in total
    figures/             PNG and PDF figures

A run is "done" once its line is in ``runs.jsonl``. Running a study again on the same folder skips
the done runs; a run that was interrupted is started again from scratch (its transcript is
rewritten), so no row is lost or duplicated. Every other file is derived from ``runs.jsonl`` and
rewritten whole through a temporary file and ``os.replace``, so a kill never leaves half a file.

:func:`load` reads a folder (finished or not, read-only) into pandas DataFrames.

Files are plain: JSON without ``NaN``/``Infinity`` (non-finite numbers are written as ``null``,
so any language's parser reads them) and the same permissions for every file (owner only, ``0600``,
unless the umask lets the group write: :mod:`jswim._io.permissions`; a rewritten file keeps its mode). A folder that cannot
be written (read-only, full disk) is a :class:`StudyFolderError` naming the folder and the cause.
"""

from __future__ import annotations

import contextlib
import csv
import errno
import io
import json
import os
import re
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Iterable, Iterator, Mapping

from jswim.errors import ResultFolderError, StudyFolderError  # noqa: F401  (also read from here)
from jswim._io.permissions import file_mode, opener
from jswim._io.folderlock import HOLDER, LOCK, FolderLock
from jswim._io.jsonl import SkippedRecord, read_records, repair_tail
from jswim._io.atomic import _jsonable, atomic_write, dumps, plain_json, write_json  # noqa: F401  (their old place)

if TYPE_CHECKING:
    import pandas as pd

RUNS = "runs.jsonl"
META = "metadata.json"
#: Room kept on the study's disk while a session runs, freed to record its status when the disk
#: fills up (a full disk would otherwise leave ``metadata.json`` reading "running").
RESERVE = ".jswim.reserve"
RESERVE_MIN_BYTES = 64 * 1024

#: Temporary files of :func:`atomic_write` (``.NAME.XXXXXXXX.tmp``, as ``mkstemp`` names them).
_TEMPORARY = re.compile(r"^\..+\.[A-Za-z0-9_]{8}\.tmp$")


def _is_own_file(p: Path) -> bool:
    """What jswim itself leaves in a folder before its first record: its lock, its holder note,
    temporary files of an interrupted first write, an empty figures folder."""
    if p.name in (LOCK, HOLDER, RESERVE) or _TEMPORARY.match(p.name):
        return True
    return p.name == "figures" and p.is_dir()

#: Statuses of runs that did not finish (the server failed them): recorded with their error, not
#: done. A resume runs them again, and a later record of the same run replaces them.
FAILED_STATUSES = frozenset({"llm_error", "aborted"})


def is_failed(row: Mapping[str, Any]) -> bool:
    """Whether a run record is a failed run (:data:`FAILED_STATUSES`), not a finished one."""
    return row.get("status") in FAILED_STATUSES

#: Fields renamed since folders were first written: old name -> new name. Folders keep what they
#: were written with; readers translate (:func:`upgrade_names`), so an old folder still resumes,
#: summarises and plots.
RENAMED = {"allowed": "action_set"}


def upgrade_names(obj: Any) -> Any:
    """``obj`` (rows, metadata, an identity; nested dicts and lists) with old field names renamed
    to new ones (:data:`RENAMED`)."""
    if isinstance(obj, dict):
        return {RENAMED.get(k, k): upgrade_names(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [upgrade_names(v) for v in obj]
    return obj


def legacy_names(obj: Any) -> Any:
    """The inverse of :func:`upgrade_names` (for hashes that must stay what they were)."""
    back = {new: old for old, new in RENAMED.items()}
    if isinstance(obj, dict):
        return {back.get(k, k): legacy_names(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [legacy_names(v) for v in obj]
    return obj


def _umask() -> int:
    mask = os.umask(0o022)  # the only way to read it; set back at once (at import, single-threaded)
    os.umask(mask)
    return mask


#: Mode of new files: ``0600`` under the usual umask, what the umask says where it lets the group
#: write (:mod:`jswim._io.permissions`).
FILE_MODE = file_mode(_umask())


@contextlib.contextmanager
def writing(what: str | os.PathLike, hint: str = "choose a writable --out folder") -> Iterator[None]:
    """Turn an ``OSError`` while writing ``what`` into a one-line :class:`StudyFolderError`."""
    try:
        yield
    except OSError as exc:
        where = exc.filename or what
        cause = exc.strerror or type(exc).__name__
        if exc.errno in (errno.ENOSPC, errno.EDQUOT):  # the folder is fine; the disk is full
            hint = ("every finished run and answered call is kept: make room and run the same command to resume")
        raise StudyFolderError(f"cannot write {where}: {cause}; {hint}") from None


def identity_differences(folder: Mapping[str, Any], now: Mapping[str, Any], prefix: str = "") -> list[str]:
    """Which settings differ between a folder's identity and today's, with both values.

    Nested settings are named by their path (``backend.model``); e.g.
    ``["backend.model: 'gpt-4o-mini' now, 'gpt-4o' in the folder"]``.
    """
    out = []
    for key in sorted(set(folder) | set(now)):
        name = f"{prefix}{key}"
        a, b = folder.get(key, _MISSING), now.get(key, _MISSING)
        if a == b:
            continue
        if isinstance(a, Mapping) and isinstance(b, Mapping):
            out += identity_differences(a, b, name + ".")
        elif a is _MISSING:
            out.append(f"{name}: {b!r} now, not set in the folder (made by another jswim version)")
        elif b is _MISSING:
            out.append(f"{name}: not set now, {a!r} in the folder (made by another jswim version)")
        else:
            out.append(f"{name}: {b!r} now, {a!r} in the folder")
    return out


_MISSING = object()


class StudyStore:
    """A study's output folder.

    Parameters
    ----------
    folder : path
        Created if missing. An existing folder must hold the same study with the same parameters
        (``identity``, compared after :func:`upgrade_names`), otherwise
        :class:`~jswim.errors.ResultFolderError` says what differs.
    study : str
        Study name, e.g. ``"noise"``.
    identity : mapping
        Everything that defines the study's runs (grid, seed, backend, model, prompt template).
        Stored in ``metadata.json`` and compared on resume.
    extra : mapping, optional
        More metadata that may change between sessions (versions, host); not compared.
    """

    def __init__(
        self,
        folder: str | os.PathLike,
        study: str,
        identity: Mapping[str, Any],
        extra: Mapping[str, Any] | None = None,
        lock: bool = True,
    ) -> None:
        self.folder = Path(folder)
        self.study = study
        self.identity = plain_json(dict(identity))
        #: What opening the folder repaired (torn journal lines, leftover temporary files), one
        #: sentence each, for the caller to report.
        self.repairs: list[str] = []
        self._lock: FolderLock | None = None
        self._reserved = False  # RESERVE is ours to free
        meta_path = self.folder / META
        if self.folder.exists() and not self.folder.is_dir():
            raise ResultFolderError(f"--out {self.folder} is a file, not a folder; choose another path")
        with writing(self.folder):
            self.folder.mkdir(parents=True, exist_ok=True)
        try:
            if lock:  # before anything is read: the folder is ours until close()
                with writing(self.folder):
                    self._lock = FolderLock(self.folder).acquire()
            self._open(study, meta_path, extra)
        except BaseException as exc:
            # A signal right after "running" was written: the caller holds no store yet to mark
            # it, so the folder would read "running" with nobody running it.
            if isinstance(exc, KeyboardInterrupt) and getattr(self, "meta", {}).get("status") == "running":
                with contextlib.suppress(OSError, ResultFolderError):
                    self.set_status("interrupted")
            self.close()
            raise

    def _open(self, study: str, meta_path: Path, extra: Mapping[str, Any] | None) -> None:
        for name in ("transcripts", "figures"):  # a file in the way is no full disk: said so, nothing written
            p = self.folder / name
            if (p.exists() or p.is_symlink()) and not p.is_dir():
                raise ResultFolderError(f"{p} is a file where jswim keeps a folder; move it away and run the "
                                        "same command (the study folder is left as it is)")
        with writing(self.folder):
            self._clean_temporary_files()
        if meta_path.exists():
            try:
                meta = json.loads(meta_path.read_text())
            except (OSError, ValueError) as exc:
                raise ResultFolderError(f"{meta_path} is unreadable ({exc}); use a new --out folder") from None
            if not isinstance(meta, dict):
                raise ResultFolderError(f"{meta_path} is not a study's metadata; use a new --out folder")
            if not isinstance(meta.get("identity"), dict):  # nothing to compare today's settings with
                raise ResultFolderError(f"{meta_path}: 'identity' is {meta.get('identity')!r:.40}, not the study's "
                                        "settings (an object); the folder is left as it is: use a new --out folder")
            meta = clean_metadata(meta, meta_path)  # derived fields of the wrong type are rewritten
            if meta.get("study") != study:
                raise ResultFolderError(
                    f"{self.folder} holds a '{meta.get('study')}' study, not '{study}'; "
                    "use a new --out folder"
                )
            old = upgrade_names(meta.get("identity", {}))
            if old != self.identity:
                diff = identity_differences(old, self.identity)
                raise ResultFolderError(
                    f"{self.folder} holds a '{study}' study with different settings: {'; '.join(diff[:4])}"
                    f"{'; ...' if len(diff) > 4 else ''}. Use a new --out folder, or the folder's settings to resume"
                )
            self.meta = meta
            self.meta["identity"] = self.identity  # rewritten under today's names
            with writing(self.folder):
                self._repair_journals()
        elif any(not _is_own_file(p) for p in self.folder.iterdir()):
            raise ResultFolderError(
                f"{self.folder} is not empty and is not a jswim study folder; choose another --out"
            )
        else:  # new, or holding nothing but what jswim itself leaves (a kill during the first write)
            self.meta = {"study": study, "identity": self.identity, "status": "running"}
        #: The status the folder had before this session (``None``: a new folder), restored by
        #: :meth:`restore_status` when the session stops on an error before changing anything.
        self.status_before = self.meta.get("status") if meta_path.exists() else None
        #: Whether this session changed the study (a run recorded, a call journaled).
        self.changed = False
        self.meta.update(dict(extra or {}))
        self.meta["status"] = "running"
        # The room to record how the session ends exists before "running" is written: a disk too
        # full for it is one line now, and the folder keeps the status it had.
        self._keep_reserve(2 * len(dumps(self.meta)))
        try:
            with writing(self.folder):
                write_json(meta_path, self.meta)
        except BaseException:
            self._free_reserve()
            raise

    def _keep_reserve(self, meta_bytes: int) -> None:
        """Hold back room for two rewrites of ``metadata.json``.

        Raises
        ------
        StudyFolderError
            The disk has no room for it (nothing else was written).
        """
        path = self.folder / RESERVE
        try:
            with writing(self.folder):
                self._write_reserve(path, max(RESERVE_MIN_BYTES, 2 * meta_bytes))
        except StudyFolderError:
            with contextlib.suppress(OSError):
                path.unlink()
            raise
        self._reserved = True

    @staticmethod
    def _write_reserve(path: Path, size: int) -> None:
        with open(path, "wb", opener=opener) as f:
            # Written, not only sized: a sparse file would hold no blocks back.
            f.write(bytes(size))
            f.flush()
            os.fsync(f.fileno())

    def restore_status(self) -> bool:
        """Put back the status the folder had before this session, when the session changed
        nothing (it stopped on an error before any run or call); ``False`` otherwise."""
        if self.changed or self.status_before is None:
            return False
        self.meta["status"] = self.status_before
        try:
            self.set_status(self.status_before)
        except (OSError, StudyFolderError):
            return False
        return True

    def _free_reserve(self) -> bool:
        """Give the reserved room back to the disk; ``False`` when there was none."""
        if not self._reserved:
            return False
        self._reserved = False
        try:
            (self.folder / RESERVE).unlink()
        except OSError:
            return False
        return True

    def _clean_temporary_files(self) -> None:
        """Remove the temporary files of atomic writes that a kill left behind (ours alone hold
        the lock, so no other writer is half way through one)."""
        for where in (self.folder, self.folder / "figures"):
            if not where.is_dir():
                continue
            for p in where.iterdir():
                if _TEMPORARY.match(p.name) and p.is_file():
                    p.unlink()
                    self.repairs.append(f"removed {p.name}, a temporary file left by an interrupted write")

    def _repair_journals(self) -> None:
        """Cut the torn last line of every append-only file (see :mod:`jswim._io.jsonl`)."""
        paths = [self.folder / RUNS, self.folder / "calls.jsonl"]
        if (self.folder / "transcripts").is_dir():
            paths += sorted((self.folder / "transcripts").glob("*.jsonl"))
        done: set[str] | None = None
        for path in paths:
            cut = repair_tail(path)
            if not cut:
                continue
            rel = path.relative_to(self.folder)
            what = f"{rel}: cut a torn last line ({cut} bytes, from an interrupted write)"
            if path.parent.name == "transcripts":
                done = {r["run_id"] for r in read_runs(self.folder) if not is_failed(r)} if done is None else done
                if path.stem in done:  # a finished run is not run again: say what its transcript lost
                    self.repairs.append(f"{what}; the run is finished and is not redone, so the transcript lacks "
                                        "that last record (its end or last step); runs.jsonl keeps the run's "
                                        "result and calls.jsonl every answered call")
                    continue
            self.repairs.append(f"{what}; what it held is redone, no answered call is lost")

    def close(self) -> None:
        """Release the folder's lock (the session is over; :meth:`set_status` first)."""
        if self._reserved:
            self._free_reserve()
        if self._lock is not None:
            self._lock.release()
            self._lock = None

    def __enter__(self) -> "StudyStore":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- runs -------------------------------------------------------------------------------

    def load_runs(self) -> list[dict[str, Any]]:
        """Finished runs, first record per ``run_id``; a torn last line (a kill) is dropped."""
        return read_runs(self.folder)

    def done_ids(self) -> set[str]:
        """Run ids already finished (failed runs are not: a resume runs them again)."""
        return {r["run_id"] for r in self.load_runs() if not is_failed(r)}

    def add_runs(self, rows: Iterable[Mapping[str, Any]]) -> None:
        """Append finished runs durably (one write and fsync for the batch)."""
        lines = "".join(dumps(dict(r), sort_keys=True) + "\n" for r in rows)
        if not lines:
            return
        path = self.folder / RUNS
        self.changed = True
        with writing(path):
            repair_tail(path)  # never glue a record onto a torn line
            with open(path, "a", encoding="utf-8", opener=opener) as fh:
                fh.write(lines)
                fh.flush()
                os.fsync(fh.fileno())

    def transcript_path(self, run_id: str) -> Path:
        """Where the LLM transcript of ``run_id`` goes."""
        path = self.folder / "transcripts" / f"{run_id}.jsonl"
        with writing(path.parent):
            path.parent.mkdir(parents=True, exist_ok=True)
        return path

    # -- derived files ----------------------------------------------------------------------

    def finalize(self, status: str = "complete", summary: Mapping[str, Any] | None = None) -> None:
        """Rewrite the derived tables from ``runs.jsonl`` and record the status."""
        runs = self.load_runs()
        with writing(self.folder):
            write_tables(self.folder, runs)
        self.meta["n_runs"] = len(runs)
        self.meta.pop("error", None)  # of an earlier session that stopped
        if summary is not None:
            self.meta["summary"] = dict(summary)
        self.set_status(status)

    def set_status(self, status: str, **fields: Any) -> None:
        """Record ``status`` (``"running"``, ``"complete"``, ``"interrupted"``, ``"failed"``...)
        and ``fields`` in ``metadata.json`` (only that file is rewritten: safe in a handler)."""
        self.meta["status"] = status
        self.meta.update(fields)
        try:
            with writing(self.folder):
                write_json(self.folder / META, self.meta)
        except StudyFolderError:  # a full disk: the room held back since the open takes this write
            if not self._free_reserve():
                raise
            with writing(self.folder):
                write_json(self.folder / META, self.meta)


#: The fields of a run record that readers compute with, by kind: a record where one of them has
#: another type (a hand edit) is skipped with a warning (:func:`run_problem`).
_RUN_TEXT = ("run_id", "agent")  # run_id required
_RUN_NUMBERS = ("final_x", "signed_final_x", "zeta", "cost_usd", "temperature", "direction", "steps", "calls",
                "billed_calls", "cache_hits", "prompt_tokens", "completion_tokens", "cached_tokens",
                "reasoning_tokens", "parse_retries", "http_retries", "failed_steps", "n_clears", "tokens_seen",
                "seed", "period", "n_ht", "steps_to_learn", "truncated", "cut_thinking", "roc_levels", "max_tokens")
_RUN_FLAGS = ("success", "learned")
_RUN_STRINGS = ("swimmer", "group", "status", "variant", "action_set", "error", "constraint")
_RUN_SERIES = ("x", "y", "orientation", "progress")


def _number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def run_problem(row: Mapping[str, Any]) -> str | None:
    """What makes ``row`` no run record readers can use (a field of the wrong type), or ``None``."""
    row = upgrade_names(dict(row))
    for k in _RUN_TEXT:
        if k == "run_id" and "run_id" not in row:
            return "no 'run_id'"
        if k in row and (not isinstance(row[k], str) or not row[k]):
            return f"{k!r} is {row[k]!r}, not a name"
    for k in _RUN_NUMBERS:
        if row.get(k) is not None and not _number(row[k]):
            return f"{k!r} is {row[k]!r}, not a number"
    for k in _RUN_FLAGS:
        if row.get(k) is not None and not isinstance(row[k], bool):
            return f"{k!r} is {row[k]!r}, not true or false"
    for k in _RUN_STRINGS:
        if row.get(k) is not None and not isinstance(row[k], str):
            return f"{k!r} is {row[k]!r}, not text"
    for k in _RUN_SERIES:
        v = row.get(k)
        if v is not None and not (isinstance(v, list) and all(e is None or _number(e) for e in v)):
            return f"{k!r} is not a list of numbers"
    acts = row.get("actions")
    if acts is not None and not isinstance(acts, list):
        return "'actions' is not a list"
    return None


def read_runs(folder: str | os.PathLike) -> list[dict[str, Any]]:
    """Runs of a study folder (see :class:`StudyStore`), one record per ``run_id`` in first-seen
    order, fields under today's names (:func:`upgrade_names`).

    The first record of a run wins, except that a failed run (:func:`is_failed`) is replaced by
    any later record of it: the one from the resume that ran it again. A line that is no run
    record (not UTF-8, not JSON, a field of the wrong type: :func:`run_problem`) is skipped with
    a warning naming the file and the line (:func:`jswim._io.jsonl.read_records`); that run counts as
    not done, as a torn line's does.
    """
    path = Path(folder) / RUNS
    by_id: dict[str, dict[str, Any]] = {}
    for _, row in read_records(path, run_problem):
        rid = row.get("run_id")
        if rid not in by_id or is_failed(by_id[rid]):
            by_id[rid] = upgrade_names(row)
    return list(by_id.values())


#: Fields of ``metadata.json`` by the JSON type readers expect of them.
_META_TYPES: dict[str, tuple[type, ...]] = {
    "study": (str,), "status": (str,), "identity": (dict,), "summary": (dict,), "llm_totals": (dict,),
    "llm_server": (dict,), "grid": (dict,), "prompt_template": (dict,), "n_planned": (int,), "n_runs": (int,),
    "horizon": (int,), "group_order": (list,), "llm_variants": (list,), "roc_levels": (list,),
    "fidelity_deviations": (list,), "server": (str, type(None)), "prices_as_of": (str,), "error": (str, type(None)),
}
_JSON_NAMES = {dict: "an object", list: "a list", str: "text", int: "a whole number", type(None): "null"}


def clean_metadata(meta: dict[str, Any], path: str | os.PathLike) -> dict[str, Any]:
    """``meta`` without the fields of the wrong type (a hand edit: ``"summary": 5``), each dropped
    with one :class:`~jswim._io.jsonl.SkippedRecord` warning naming the file and the field; the
    fields left are what a reader may compute with. ``summary.groups`` must be a list of objects."""
    import warnings


    out = dict(meta)
    for k, types in _META_TYPES.items():
        v = out.get(k)
        if k in out and not (isinstance(v, types) and not isinstance(v, bool)):
            want = " or ".join(_JSON_NAMES[t] for t in types)
            warnings.warn(SkippedRecord(f"{path}: {k!r} is {v!r:.40}, not {want}; that field is ignored"), stacklevel=3)
            out.pop(k)
    groups = (out.get("summary") or {}).get("groups")
    if groups is not None and not (isinstance(groups, list) and all(isinstance(g, dict) for g in groups)):
        warnings.warn(SkippedRecord(f"{path}: 'summary.groups' is not a list of objects; the summary is ignored"),
                      stacklevel=3)
        out.pop("summary")
    return out


def read_metadata(folder: str | os.PathLike) -> dict[str, Any]:
    """The study's ``metadata.json`` (fields under today's names); :class:`ResultFolderError` if
    the folder is not a study. A field of the wrong type is dropped with a warning
    (:func:`clean_metadata`)."""
    path = Path(folder) / META
    if not path.exists():
        raise ResultFolderError(f"{folder} is not a jswim study folder (no {META})")
    try:
        meta = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:  # ValueError: bad JSON or bad UTF-8
        raise ResultFolderError(f"{path} is unreadable ({exc})") from None
    if not isinstance(meta, dict):
        raise ResultFolderError(f"{path} is not a study's metadata (a JSON {type(meta).__name__}, not an object)")
    return upgrade_names(clean_metadata(meta, path))


def unfinished_note(status: str | None, done: int, planned: int | None) -> str | None:
    """The red line of a figure whose study has not finished (``None`` when it has)."""
    if status == "complete" and (planned is None or done >= planned):
        return None
    of = f" of {planned}" if planned else ""
    return f"UNFINISHED STUDY: {done}{of} runs done ({status or 'status unknown'})"


SCALAR_TYPES = (str, int, float, bool, type(None))


def write_tables(folder: str | os.PathLike, runs: list[dict[str, Any]]) -> None:
    """Write ``runs.parquet``/``runs.csv`` (scalar columns) and ``trajectories.parquet``.

    Per-step lists in a run row (keys ``x``, ``y``, ``orientation``, ``actions``, ``progress``,
    ``stuck``) become the long trajectory table; every other scalar key is a column of the runs
    table.
    """
    folder = Path(folder)
    cols: list[str] = []
    for r in runs:
        for k, v in r.items():
            if isinstance(v, SCALAR_TYPES) and k not in cols:
                cols.append(k)
    lead = [k for k in ("run_id", "agent", "swimmer", "direction", "group") if k in cols]
    cols = lead + [k for k in cols if k not in lead]
    table_rows = [{k: r.get(k) for k in cols} for r in runs]
    buf = io.StringIO()
    writer = csv.DictWriter(buf, fieldnames=cols)
    writer.writeheader()
    writer.writerows(table_rows)
    atomic_write(folder / "runs.csv", buf.getvalue())
    traj = []
    for r in runs:
        xs = r.get("x") or []
        for i, x in enumerate(xs):
            traj.append({
                "run_id": r["run_id"], "step": i + 1, "x": x,
                "y": _at(r.get("y"), i), "orientation": _at(r.get("orientation"), i),
                "action": _at(r.get("actions"), i), "progress": _at(r.get("progress"), i),
                "stuck": _at(r.get("stuck"), i),
            })
    import pyarrow as pa  # lazy: ~0.3 s of import that only the tables at a session's end need
    import pyarrow.parquet as pq

    for name, rows in (("runs.parquet", table_rows), ("trajectories.parquet", traj)):
        sink = pa.BufferOutputStream()
        pq.write_table(arrow_table(rows), sink)
        atomic_write(folder / name, sink.getvalue().to_pybytes())


def _arrow_type(values: Iterable[Any]) -> Any:
    """The Arrow type ``pyarrow.Table.from_pylist`` infers for a column of these Python scalars
    (``None`` where it is not one of the plain cases: bool, int, int and float, str, all null)."""
    import pyarrow as pa

    kinds = {next((t for t in (bool, int, float, str) if isinstance(v, t)), type(v)) for v in values if v is not None}
    if not kinds:
        return pa.null()
    if kinds == {bool}:
        return pa.bool_()
    if kinds == {int}:
        return pa.int64() if all(-2**63 <= v < 2**63 for v in values if v is not None) else None
    if kinds <= {int, float}:
        return pa.float64()
    return pa.string() if kinds == {str} else None


def arrow_table(rows: list[dict[str, Any]]) -> Any:
    """``rows`` (dicts of scalars, keys in column order) as a ``pyarrow.Table``, typed as
    ``Table.from_pylist`` would type them.

    Built through Arrow's JSON reader with an explicit schema rather than ``from_pylist``: any
    conversion from Python objects makes pyarrow import pandas (~0.4 s at every session's end),
    the JSON reader does not. Columns of other kinds fall back to ``from_pylist``."""
    import pyarrow as pa
    import pyarrow.json as pj

    cols: list[str] = []
    for r in rows:
        cols += [k for k in r if k not in cols]
    if not rows:
        return pa.schema([]).empty_table()
    types = [_arrow_type([r.get(c) for r in rows]) for c in cols]
    if any(t is None for t in types):
        return pa.Table.from_pylist(rows)
    schema = pa.schema(list(zip(cols, types)))
    data = "".join(dumps(r) + "\n" for r in rows).encode("utf-8")
    # One block: a line longer than the reader's block would not parse.
    return pj.read_json(io.BytesIO(data), read_options=pj.ReadOptions(block_size=max(1 << 20, len(data) + 1)),
                        parse_options=pj.ParseOptions(explicit_schema=schema))


def _at(seq: Any, i: int) -> Any:
    if isinstance(seq, list) and i < len(seq):
        v = seq[i]
        return json.dumps(v) if isinstance(v, (list, dict)) else v
    return None


# -- reading a study into pandas ----------------------------------------------------------------

#: Run columns repeated on every trajectory row, so one table answers "X/a of the LLM runs toward -x".
TRAJECTORY_KEYS = ("run_id", "agent", "swimmer", "direction", "group", "zeta", "n_ht", "init", "variant")


@dataclass
class Study:
    """A study folder read into pandas (see :func:`load`).

    Attributes
    ----------
    folder : Path
    metadata : dict
        ``metadata.json``: study name, identity (settings), status, versions, summary.
    runs : pandas.DataFrame
        One row per finished run: every scalar field of its ``runs.jsonl`` record (``agent``,
        ``swimmer``, ``direction``, ``group``, ``zeta``, ``success``, ``steps_to_learn``,
        ``signed_final_x``, tokens, cost, ...).
    trajectories : pandas.DataFrame
        One row per run and step ``n = 1 .. steps`` (the state after the step; X = 0 at n = 0):
        the run's keys (:data:`TRAJECTORY_KEYS`), ``x`` and ``y`` (centroid, in ``a``),
        ``orientation`` (rad; NaN in folders written before it was recorded), ``target_x``
        (``direction * x``: displacement in the target direction), ``dof`` and ``roc`` (the
        action), ``progress`` (that step's target-direction displacement) and ``stuck``.
    """

    folder: Path
    metadata: dict[str, Any]
    runs: "pd.DataFrame"
    trajectories: "pd.DataFrame"

    @property
    def name(self) -> str:
        """The study's name (``noise``, ``swim``, ...)."""
        return str(self.metadata.get("study", ""))

    @property
    def status(self) -> str:
        """``complete``, ``running`` (or interrupted), as recorded in ``metadata.json``."""
        return str(self.metadata.get("status", "unknown"))

    def transcript(self, run_id: str) -> "pd.DataFrame":
        """The LLM transcript of ``run_id`` (``transcripts/RUN.jsonl``), one row per step.

        Columns: ``step`` (from 1), ``prompt`` (the exact text sent), ``reply`` (the last reply
        text), ``action`` (the action played, ``[DOF, ROC]``), ``failed`` (no valid action: the
        hold was played), ``attempts`` (replies asked for, the first plus parse retries),
        ``http_retries``, ``prompt_tokens``/``completion_tokens``/``cost_usd``/``latency_s``
        (summed over the attempts), ``cache_hit``, ``x_before``, ``x_after``, ``progress``,
        ``stuck``, ``cleared`` (the history was erased after this step), ``n_clears``,
        ``dofs_after``, and ``replies`` (every attempt's record). Empty for a run without a
        transcript (baselines, or an LLM run not started yet).
        """
        import pandas as pd  # lazy, as in load()

        return pd.DataFrame(transcript_steps(read_transcript(self.folder, run_id)), columns=TRANSCRIPT_COLUMNS)

    @property
    def calls(self) -> "pd.DataFrame":
        """Every answered LLM call (``calls.jsonl``), one row per call, in the order answered.

        Columns: ``run`` (run id), ``n`` (the call's index in its run), ``key`` (hash of the
        request), ``text`` (the answer), ``raw`` (the reply as sent, reasoning included),
        ``prompt_tokens``, ``completion_tokens``, ``cached_tokens``, ``cost_usd``, ``cache_hit``,
        ``shared``, ``constraint``, ``finish_reason``. A torn last line (a kill) is skipped.
        """
        import pandas as pd

        return pd.DataFrame(read_calls(self.folder), columns=CALL_COLUMNS)


def load(folder: str | os.PathLike) -> Study:
    """Read a study folder into pandas DataFrames, without writing anything to it.

    Works on finished, interrupted and read-only folders: the runs come from ``runs.jsonl``, the
    durable record, not from the derived tables.

    Parameters
    ----------
    folder : path
        A folder written by ``jswim swim`` / ``jswim study`` / :func:`jswim.studies.run_study`.

    Returns
    -------
    Study
        ``.runs`` (one row per run), ``.trajectories`` (one row per run and step, with ``x``,
        ``y``, ``orientation``), ``.metadata``.

    Raises
    ------
    ResultFolderError
        ``folder`` is not a study folder, or its metadata is unreadable.

    Examples
    --------
    >>> s = jswim.load("jswim-out/noise-1a2b3c4d")                    # doctest: +SKIP
    >>> s.runs.groupby(["swimmer", "agent", "zeta"]).success.mean()  # doctest: +SKIP
    """
    import pandas as pd  # lazy: ~0.4 s of import that only load() needs, not every study run

    folder = Path(folder)
    meta = read_metadata(folder)
    rows = read_runs(folder)
    scalar = [{k: v for k, v in r.items() if isinstance(v, SCALAR_TYPES)} for r in rows]
    runs = pd.DataFrame(scalar)
    lead = [k for k in ("run_id", "agent", "swimmer", "direction", "group") if k in runs.columns]
    runs = runs[lead + [c for c in runs.columns if c not in lead]] if len(runs.columns) else runs
    traj: dict[str, list[Any]] = {k: [] for k in (*TRAJECTORY_KEYS, "step", "x", "y", "orientation", "target_x",
                                                  "dof", "roc", "progress", "stuck")}
    nan = float("nan")
    for r in rows:
        xs = r.get("x") or []
        n = len(xs)
        direction = r.get("direction", 1) or 1
        for k in TRAJECTORY_KEYS:
            traj[k] += [r.get(k)] * n
        traj["step"] += list(range(1, n + 1))
        traj["x"] += [float(v) for v in xs]
        traj["target_x"] += [direction * float(v) for v in xs]
        for k in ("y", "orientation", "progress"):
            vals = r.get(k)
            traj[k] += [float(vals[i]) if isinstance(vals, list) and i < len(vals) and vals[i] is not None else nan
                        for i in range(n)]
        acts = r.get("actions") or []
        traj["dof"] += [int(acts[i][0]) if i < len(acts) else None for i in range(n)]
        traj["roc"] += [acts[i][1] if i < len(acts) else None for i in range(n)]  # real for the continuous agent
        stuck = r.get("stuck")
        traj["stuck"] += [bool(stuck[i]) if isinstance(stuck, list) and i < len(stuck) else None for i in range(n)]
    trajectories = pd.DataFrame(traj)
    # Nullable dtypes: "not recorded" stays missing instead of turning a column into objects.
    real_roc = any(v is not None and v == v and float(v) != int(v) for v in traj["roc"])
    for table, cols in ((trajectories, ("dof", "n_ht") + (() if real_roc else ("roc",))),
                        (runs, ("n_ht", "steps_to_learn"))):
        for k in cols:
            if k in table.columns:
                table[k] = pd.array([None if v is None or v != v else int(v) for v in table[k]], dtype="Int64")
    if real_roc:  # real-valued ROCs (the continuous study's RL baseline): a float column
        trajectories["roc"] = pd.array([None if v is None or v != v else float(v) for v in trajectories["roc"]],
                                       dtype="Float64")
    trajectories["stuck"] = trajectories["stuck"].astype("boolean")
    return Study(folder, meta, runs, trajectories)


# -- transcripts and the call journal ------------------------------------------------------------

TRANSCRIPT_COLUMNS = ("step", "prompt", "reply", "action", "failed", "attempts", "http_retries", "prompt_tokens",
                      "completion_tokens", "cost_usd", "latency_s", "cache_hit", "x_before", "x_after", "progress",
                      "stuck", "cleared", "n_clears", "dofs_after", "replies")
CALL_COLUMNS = ("run", "n", "key", "text", "raw", "prompt_tokens", "completion_tokens", "cached_tokens", "cost_usd",
                "cache_hit", "shared", "constraint", "finish_reason")


def _jsonl(path: Path) -> list[dict[str, Any]]:
    """The JSON objects of a JSON-lines file; torn or foreign lines are skipped, a missing file is empty."""
    return [rec for _, rec in read_records(path)]


def read_transcript(folder: str | os.PathLike, run_id: str) -> list[dict[str, Any]]:
    """The records of ``transcripts/RUN.jsonl`` (``meta``, one ``step`` per step, ``end``); ``[]`` if none.

    A run id that is not a plain file name (a path, ``..``) reads nothing."""
    name = f"{run_id}.jsonl"
    if Path(name).name != name or run_id in ("", ".", ".."):
        return []
    return _jsonl(Path(folder) / "transcripts" / name)


def transcript_steps(records: Iterable[Mapping[str, Any]]) -> list[dict[str, Any]]:
    """One flat dict per ``step`` record of a transcript (see :meth:`Study.transcript` for the keys)."""
    out = []
    for r in records:
        if r.get("type") != "step":
            continue
        att = [a for a in (r.get("attempts") or []) if isinstance(a, dict)]

        def total(key: str) -> float:
            return sum(float(a.get(key) or 0) for a in att)

        out.append({
            "step": r.get("step"), "prompt": r.get("prompt"), "reply": att[-1].get("text") if att else None,
            "action": r.get("action"), "failed": bool(r.get("failed")), "attempts": len(att),
            "http_retries": int(total("retries")), "prompt_tokens": int(total("prompt_tokens")),
            "completion_tokens": int(total("completion_tokens")), "cost_usd": total("cost_usd"),
            "latency_s": total("latency_s"), "cache_hit": any(bool(a.get("cache_hit")) for a in att),
            "x_before": r.get("x_before"), "x_after": r.get("x_after"), "progress": r.get("progress"),
            "stuck": r.get("stuck"), "cleared": bool(r.get("cleared")), "n_clears": r.get("n_clears"),
            "dofs_after": r.get("dofs_after"), "replies": att,
        })
    return out


def read_calls(folder: str | os.PathLike) -> list[dict[str, Any]]:
    """The answered calls of ``calls.jsonl``, flat (``usage`` split into its three token counts)."""
    out = []
    from jswim.llm.journal import call_problem  # lazy: the journal's rule, without httpx for other readers

    for _, c in read_records(Path(folder) / "calls.jsonl", call_problem):
        usage = c.get("usage") if isinstance(c.get("usage"), list) else []
        usage = (list(usage) + [None, None, None])[:3]
        row = {k: c.get(k) for k in CALL_COLUMNS}
        row.update(prompt_tokens=usage[0], completion_tokens=usage[1], cached_tokens=usage[2])
        out.append(row)
    return out
