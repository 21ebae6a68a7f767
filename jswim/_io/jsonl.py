"""Append-only JSON-lines files that survive tears.

A kill, a full disk or a crash can leave a journal's last line torn; every writer opens it through
`repair_tail`, which cuts the torn bytes back to the last complete line (appending after them
would glue the next record on and lose both), and readers (`read_records`) skip a line that
is not a record. docs/studies.md (*Torn files*) says what a session does with both.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any
from collections.abc import Callable, Iterator

from jswim.errors import JswimWarning


def repair_tail(path: str | os.PathLike) -> int:
    """Cut a torn last line (bytes after the last newline) off ``path``; returns the bytes cut.

    A missing or empty file, or one that ends with a newline, is left as it is (0).

    Raises
    ------
    OSError
        The file cannot be read or truncated.
    """
    path = Path(path)
    try:
        size = path.stat().st_size
    except FileNotFoundError:
        return 0
    if size == 0:
        return 0
    with open(path, "rb+") as fh:
        fh.seek(-1, os.SEEK_END)
        if fh.read(1) == b"\n":
            return 0
        # Scan back in blocks for the last newline (a journal line is short; a file may be large).
        end, block = size, 1 << 16
        keep = 0
        while end > 0:
            start = max(0, end - block)
            fh.seek(start)
            chunk = fh.read(end - start)
            i = chunk.rfind(b"\n")
            if i >= 0:
                keep = start + i + 1
                break
            end = start
        fh.truncate(keep)
        fh.flush()
        os.fsync(fh.fileno())
    return size - keep


class SkippedRecord(JswimWarning):
    """A line of a study's JSON-lines file that is not a readable record (not UTF-8, not JSON, not
    an object, or fields of the wrong type: a hand edit or damage), skipped as a torn line is."""


_warned: set[tuple[str, int, bytes]] = (
    set()
)  # each bad line is said once (per command: forget_warnings)


def forget_warnings() -> None:
    """Say every bad line again from now on (a new command in the same process)."""
    _warned.clear()


def read_records(
    path: str | os.PathLike,
    check: Callable[[dict[str, Any]], str | None] | None = None,
    convert: Callable[[dict[str, Any]], dict[str, Any]] | None = None,
) -> Iterator[tuple[int, dict[str, Any]]]:
    """``(line number, record)`` for every readable record of the JSON-lines file ``path``
    (through ``convert`` where given: an earlier version's record in today's form; ``check``
    sees the record as the file holds it, so its message names the file's fields).

    A torn last line (no final newline, from a kill) is skipped silently. Any other line that is
    not UTF-8, not JSON, not a JSON object, or that ``check`` finds fault with (``check`` returns
    why, or ``None``) is skipped with one `SkippedRecord` warning naming the file and the
    line. A missing or unreadable file has no records.
    """
    import json
    import warnings

    try:
        data = Path(path).read_bytes()
    except OSError:
        return
    lines = data.split(b"\n")
    torn = lines[-1] != b""  # bytes after the last newline
    if not torn:
        lines.pop()
    for n, raw in enumerate(lines, 1):
        if not raw.strip():
            continue
        why = None
        rec: Any = None
        try:
            rec = json.loads(raw.decode("utf-8"))
        except UnicodeDecodeError as exc:
            why = f"not UTF-8 text (byte 0x{raw[exc.start]:02x} at column {exc.start + 1})"
        except ValueError:
            if torn and n == len(lines):
                continue  # a torn last line: the record was never written whole
            why = "not JSON"
        if why is None and not isinstance(rec, dict):
            why = f"a JSON {type(rec).__name__}, not a record"
        if why is None and check is not None:
            why = check(rec)
        if why is None:
            yield n, (convert(rec) if convert is not None else rec)
            continue
        key = (str(Path(path).resolve()), n, raw[:64])
        if key not in _warned:
            _warned.add(key)
            warnings.warn(
                SkippedRecord(
                    f"{path}, line {n}: {why}; that record is skipped, as a torn line is"
                ),
                stacklevel=3,
            )
