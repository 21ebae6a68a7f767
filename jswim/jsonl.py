"""Append-only JSON-lines files that survive tears.

A study's journals (``runs.jsonl``, ``calls.jsonl``, ``transcripts/RUN.jsonl``) are appended one
whole line at a time. A kill, a full disk or a crash can still leave the last line torn (no
final newline). Appending after it would glue the next record onto the torn one and lose both,
so every writer opens a journal through :func:`repair_tail`, which cuts the torn bytes back to
the last complete line and says how many it cut. Readers skip a line that is not JSON (only
the last can be torn), so a journal is always read as the records that were written whole.
"""

from __future__ import annotations

import os
from pathlib import Path


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
