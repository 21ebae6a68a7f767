"""A study's output folder, written by one session at a time ([`StudyStore`][jswim.results.store.StudyStore])."""

from __future__ import annotations

import contextlib
import errno
import json
import os
import re
import warnings
from pathlib import Path
from typing import Any
from collections.abc import Callable, Iterable, Iterator, Mapping

from jswim._io.atomic import atomic_write, dumps, plain_json, write_json
from jswim._io.folderlock import HOLDER, LOCK, FolderLock
from jswim._io.jsonl import repair_tail
from jswim._io.permissions import file_mode, opener
from jswim.errors import ResultFolderError, StudyFolderError
from jswim.results.read import clean_metadata, read_metadata, read_run_rows, read_runs
from jswim.results.migrate import migrate_metadata, migrate_row
from jswim.results.schema import META, RUNS, is_failed, run_problem
from jswim.results.tables import write_tables

#: Room kept on the study's disk while a session runs, freed to record its status when the disk
#: fills up (a full disk would otherwise leave ``metadata.json`` reading "running").
RESERVE = ".jswim.reserve"
RESERVE_MIN_BYTES = 64 * 1024

#: Temporary files of `atomic_write` (``.NAME.XXXXXXXX.tmp``, as ``mkstemp`` names them).
_TEMPORARY = re.compile(r"^\..+\.[A-Za-z0-9_]{8}\.tmp$")


def _is_own_file(p: Path) -> bool:
    """What jswim itself leaves in a folder before its first record: its lock, its holder note,
    temporary files of an interrupted first write, an empty figures folder."""
    if p.name in (LOCK, HOLDER, RESERVE) or _TEMPORARY.match(p.name):
        return True
    return p.name == "figures" and p.is_dir()


def _umask() -> int:
    mask = os.umask(0o022)  # the only way to read it; set back at once (at import, single-threaded)
    os.umask(mask)
    return mask


#: Mode of new files: ``0600`` under the usual umask, what the umask says where it lets the group
#: write (`jswim._io.permissions`).
FILE_MODE = file_mode(_umask())


@contextlib.contextmanager
def writing(
    what: str | os.PathLike, hint: str = "choose a writable --out folder"
) -> Iterator[None]:
    """Turn an ``OSError`` while writing ``what`` into a one-line [`StudyFolderError`][jswim.errors.StudyFolderError]."""
    try:
        yield
    except OSError as exc:
        where = exc.filename or what
        cause = exc.strerror or type(exc).__name__
        if exc.errno in (errno.ENOSPC, errno.EDQUOT):  # the folder is fine; the disk is full
            hint = "every finished run and answered call is kept: make room and run the same command to resume"
        elif exc.errno == errno.EISDIR:  # the folder is writable: something stands in the way
            hint = "a folder stands where this file goes: move it away and run the same command to resume"
        elif exc.errno == errno.ENOTDIR:
            hint = "a file stands where a folder goes on this path: move it away, or choose another --out"
        raise StudyFolderError(f"cannot write {where}: {cause}; {hint}") from None


def identity_differences(
    folder: Mapping[str, Any], now: Mapping[str, Any], prefix: str = ""
) -> list[str]:
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
            out.append(f"{name}: {b!r} now, not set in the folder")
        elif b is _MISSING:
            out.append(f"{name}: not set now, {a!r} in the folder")
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
        (``identity``, compared in today's form: [`migrate_metadata`][jswim.results.migrate.migrate_metadata]), otherwise
        [`ResultFolderError`][jswim.errors.ResultFolderError] says what differs.
    study : str
        Study name, e.g. ``"noise"``.
    identity : mapping
        Everything that defines the study's runs (grid, seed, backend, model, prompt template).
        Stored in ``metadata.json`` and compared on resume.
    extra : mapping or callable, optional
        More metadata that may change between sessions (versions, host); not compared. A
        callable is given the folder's metadata as it was before this session (``None`` for a
        new folder) and returns the mapping: what a session records of the folder may depend on
        what the folder already held (a resume never narrows its grid).
    """

    def __init__(
        self,
        folder: str | os.PathLike,
        study: str,
        identity: Mapping[str, Any],
        extra: Mapping[str, Any]
        | Callable[[dict[str, Any] | None], Mapping[str, Any]]
        | None = None,
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
            raise ResultFolderError(
                f"--out {self.folder} is a file, not a folder; choose another path"
            )
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
            if (
                isinstance(exc, KeyboardInterrupt)
                and getattr(self, "meta", {}).get("status") == "running"
            ):
                with contextlib.suppress(OSError, ResultFolderError):
                    self.set_status("interrupted")
            self.close()
            raise

    def _open(self, study: str, meta_path: Path, extra: Any) -> None:
        for name in (
            "transcripts",
            "figures",
        ):  # a file in the way is no full disk: said so, nothing written
            p = self.folder / name
            if (p.exists() or p.is_symlink()) and not p.is_dir():
                raise ResultFolderError(
                    f"{p} is a file where jswim keeps a folder; move it away and run the "
                    "same command (the study folder is left as it is)"
                )
        with writing(self.folder):
            self._clean_temporary_files()
        if meta_path.exists():
            if not meta_path.is_file():  # a FIFO would hang the read, a device never end it
                raise ResultFolderError(
                    f"{meta_path} is not a regular file (a FIFO, a device or a folder); move it "
                    "away or use a new --out folder"
                )
            try:
                meta = json.loads(meta_path.read_text())
            except (OSError, ValueError) as exc:
                raise ResultFolderError(
                    f"{meta_path} is unreadable ({exc}); use a new --out folder"
                ) from None
            if not isinstance(meta, dict):
                raise ResultFolderError(
                    f"{meta_path} is not a study's metadata; use a new --out folder"
                )
            if not isinstance(
                meta.get("identity"), dict
            ):  # nothing to compare today's settings with
                raise ResultFolderError(
                    f"{meta_path}: 'identity' is {meta.get('identity')!r:.40}, not the study's "
                    "settings (an object); the folder is left as it is: use a new --out folder"
                )
            # The study and its settings as the file holds them (a hand edit of either, a field
            # of the wrong type included, is a difference named in one line), then the derived
            # fields, of which those of the wrong type are dropped with a warning and rewritten.
            if meta.get("study") != study:
                raise ResultFolderError(
                    f"{self.folder} holds a '{meta.get('study')}' study, not '{study}'; "
                    "use a new --out folder"
                )
            old = migrate_metadata(meta)["identity"]
            if old != self.identity:
                diff = identity_differences(old, self.identity)
                raise ResultFolderError(
                    f"{self.folder} holds a '{study}' study with different settings: {'; '.join(diff[:4])}"
                    f"{'; ...' if len(diff) > 4 else ''}. Use a new --out folder, or the folder's settings to resume"
                )
            self.meta = migrate_metadata(clean_metadata(meta, meta_path))
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
        #: [`restore_status`][jswim.results.store.StudyStore.restore_status] when the session stops on an error before changing anything.
        self.status_before = self.meta.get("status") if meta_path.exists() else None
        #: Whether this session changed the study (a run recorded, a call journaled).
        self.changed = False
        if callable(extra):  # what the folder held before decides what this session records
            extra = extra(dict(self.meta) if meta_path.exists() else None)
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
                    self.repairs.append(
                        f"removed {p.name}, a temporary file left by an interrupted write"
                    )

    def _repair_journals(self) -> None:
        """Cut the torn last line of every append-only file (see `jswim._io.jsonl`)."""
        paths = [self.folder / RUNS, self.folder / "calls.jsonl", self.folder / "requests.jsonl"]
        if (self.folder / "transcripts").is_dir():
            paths += sorted((self.folder / "transcripts").glob("*.jsonl"))
        for path in paths:
            # A FIFO or a device would hang the first read or append: refused before either.
            if path.exists() and not (path.is_file() or path.is_dir()):
                raise StudyFolderError(
                    f"{path} is not a regular file (a FIFO or a device); move it away and run "
                    "the same command to resume"
                )
        done: set[str] | None = None
        for path in paths:
            cut = repair_tail(path)
            if not cut:
                continue
            rel = path.relative_to(self.folder)
            what = f"{rel}: cut a torn last line ({cut} bytes, from an interrupted write)"
            if path.parent.name == "transcripts":
                done = (
                    {r.run_id for r in read_run_rows(self.folder) if not is_failed(r)}
                    if done is None
                    else done
                )
                if (
                    path.stem in done
                ):  # a finished run is not run again: say what its transcript lost
                    self.repairs.append(
                        f"{what}; the run is finished and is not redone, so the transcript lacks "
                        "that last record (its end or last step); runs.jsonl keeps the run's "
                        "result and calls.jsonl every answered call"
                    )
                    continue
            self.repairs.append(f"{what}; what it held is redone, no answered call is lost")

    def close(self) -> None:
        """Release the folder's lock (the session is over; [`set_status`][jswim.results.store.StudyStore.set_status] first)."""
        if self._reserved:
            self._free_reserve()
        if self._lock is not None:
            self._lock.release()
            self._lock = None

    def __enter__(self) -> StudyStore:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- runs -------------------------------------------------------------------------------

    def load_runs(self) -> list[dict[str, Any]]:
        """Finished runs, first record per ``run_id``; a torn last line (a kill) is dropped."""
        return read_runs(self.folder)

    def done_ids(self) -> set[str]:
        """Run ids already finished (failed runs are not: a resume runs them again)."""
        return {r.run_id for r in read_run_rows(self.folder) if not is_failed(r)}

    def add_runs(self, rows: Iterable[Mapping[str, Any]]) -> None:
        """Append finished runs durably (one write and fsync for the batch).

        Raises
        ------
        ValueError
            For a row its readers would skip (`run_problem`): a bug in the row's builder, caught
            before the line is written rather than skipped silently when the folder is read.
        """
        rows = [dict(r) for r in rows]
        for r in rows:
            problem = run_problem(r)
            if problem is not None:
                raise ValueError(f"jswim built an unreadable run record: {problem}")
        lines = "".join(dumps(r, sort_keys=True) + "\n" for r in rows)
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


def migrate_folder(folder: str | os.PathLike) -> list[str]:
    """Rewrite a study folder an earlier jswim wrote in today's form (``jswim migrate FOLDER``).

    Under the folder's lock, ``metadata.json`` and the records of ``runs.jsonl`` are rewritten
    through [`jswim.results.migrate`][jswim.results.migrate], each file atomically; the folder
    reads the same before and after (readers migrate as they read). A line readers skip (damaged,
    hand-edited) and a torn last line are kept as they are; the call journal, the money ledger
    and the transcripts are not touched, so every paid call still answers a resume.

    Parameters
    ----------
    folder : path
        A study folder.

    Returns
    -------
    list of str
        One sentence per file rewritten (empty: the folder is already in today's form).

    Raises
    ------
    ResultFolderError
        Not a study folder, or its metadata or runs cannot be read.
    FolderBusyError
        A live session holds the folder.
    StudyFolderError
        The folder cannot be written.
    """
    folder = Path(folder)
    meta = read_metadata(folder, as_written=True)
    done = []
    with writing(folder), FolderLock(folder):
        new = migrate_metadata(meta)
        if new.get("grids") != meta.get("grids"):  # derived as a reader does: from the kept grid
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")  # the readers say what they drop, not this
                kept = migrate_metadata(clean_metadata(meta, folder / META)).get("grids")
            if kept is None:
                new.pop("grids", None)
            else:
                new["grids"] = kept
        if new != meta:
            write_json(folder / META, new)
            done.append(f"{META}: rewritten in today's form")
        path = folder / RUNS
        if path.exists() and not path.is_file():  # a FIFO would hang the read
            raise ResultFolderError(f"{path} is not a regular file; move it away to migrate")
        try:
            lines = path.read_bytes().split(b"\n") if path.exists() else [b""]
        except OSError as exc:
            raise ResultFolderError(f"{path} is unreadable ({exc.strerror or exc})") from None
        tail, n = lines.pop(), 0  # tail: b"" after the last newline, else a torn line, kept
        for i, raw in enumerate(lines):
            try:
                rec = json.loads(raw)
            except ValueError:
                continue
            if isinstance(rec, dict) and run_problem(rec) is None and migrate_row(rec) != rec:
                # In the migrated key order: the rows read back as they were read before.
                lines[i], n = dumps(migrate_row(rec)).encode(), n + 1
        if n:
            atomic_write(path, b"\n".join([*lines, tail]))
            done.append(f"{RUNS}: {n} run record{'s' * (n != 1)} rewritten in today's form")
    return done
