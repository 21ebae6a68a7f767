"""Prompt files known by their content: a hash of each file's bytes, recorded with its name.

A ``--prompt-files`` sweep names its runs and rows by each file's name (``p-short``,
``prompt=short``), so the name alone cannot tell an edited file, or another file of the same
name, from the one a folder's runs were made with. Each study folder records, per label, the
file's name and the SHA-256 of its bytes (``metadata.json``: ``prompt_files``; the single
``--prompt-file`` under ``prompt_file``). A later session whose file of the same label has other
bytes is refused in one line (exit 2) before anything is written or sent: the folder's runs of
that label were made with the other text, and mixing them would pool two prompts into one row.
Renaming the file makes it a new setting (its own runs and row) in the same folder. A folder made
before these records resumes as before (the name is all it knew) and records the hashes then.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any
from collections.abc import Mapping

from jswim.errors import ConfigError
from jswim.studies.options import StudyOptions, prompt_label


def file_record(path: str | Path) -> dict[str, str]:
    """``{"file": name, "sha256": 16 hex digits of the bytes' SHA-256}`` of one prompt file.

    Raises
    ------
    ConfigError
        When the file cannot be read.
    """
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise ConfigError(f"prompt file {path}: cannot read it ({exc.strerror or exc})") from None
    return {"file": Path(path).name, "sha256": hashlib.sha256(data).hexdigest()[:16]}


def records(o: StudyOptions) -> dict[str, Any]:
    """What a study with options ``o`` records: ``{"prompt_files": {label: record}}`` for a sweep,
    ``{"prompt_file": record}`` for a single ``--prompt-file``; empty without either."""
    out: dict[str, Any] = {}
    if o.prompt_files:
        out["prompt_files"] = {prompt_label(f): file_record(f) for f in o.prompt_files}
    if o.prompt_file:
        out["prompt_file"] = file_record(o.prompt_file)
    return out


def check(folder: str | Path, o: StudyOptions) -> dict[str, Any]:
    """Refuse a prompt file whose label the folder knows with other bytes; return what to record
    (the folder's earlier records with this session's added).

    Reads ``metadata.json`` without the folder's lock (as readers do): a folder another session
    holds is refused by the lock right after.

    Raises
    ------
    ConfigError
        One line naming the file, the label and both hashes, and the two ways on.
    """
    new = records(o)
    path = Path(folder) / "metadata.json"
    try:  # a FIFO or a device is never read here (the store refuses it in one line)
        meta = json.loads(path.read_text(encoding="utf-8")) if path.is_file() else {}
    except (OSError, ValueError):
        meta = {}
    old = meta.get("prompt_files") if isinstance(meta, Mapping) else None
    old = dict(old) if isinstance(old, Mapping) else {}
    paths = {prompt_label(f): f for f in o.prompt_files or ()}
    for label, rec in (new.get("prompt_files") or {}).items():
        was = old.get(label)
        if isinstance(was, Mapping) and was.get("sha256") != rec["sha256"]:
            raise ConfigError(
                f"--prompt-files {paths[label]}: {folder} holds runs of prompt={label} made with another text "
                f"({was.get('file')}, sha256 {was.get('sha256')}; this file: {rec['sha256']}); rename the file to "
                "run it as a new setting, or use another --out"
            )
    if "prompt_files" in new:
        new["prompt_files"] = {**old, **new["prompt_files"]}
    return new
