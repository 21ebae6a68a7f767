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

[`load`][jswim.results.load.load] reads a folder (finished or not, read-only) into pandas DataFrames.
A folder an earlier jswim wrote is read in today's form: its records are migrated as they come
off disk, in one module ([`jswim.results.migrate`][jswim.results.migrate]).

Files are plain: JSON without ``NaN``/``Infinity`` (non-finite numbers are written as ``null``,
so any language's parser reads them) and the same permissions for every file (owner only, ``0600``,
unless the umask lets the group write: `jswim._io.permissions`; a rewritten file keeps its mode). A folder that cannot
be written (read-only, full disk) is a [`StudyFolderError`][jswim.errors.StudyFolderError] naming the folder and the cause.
"""

from jswim._io.atomic import atomic_write, dumps, plain_json, write_json  # noqa: F401  (read from here by studies and bench)
from jswim.results.load import TRAJECTORY_KEYS, Study, load
from jswim.results.read import (
    CALL_COLUMNS,
    TRANSCRIPT_COLUMNS,
    clean_metadata,
    read_calls,
    read_metadata,
    read_run_rows,
    read_runs,
    read_transcript,
    transcript_steps,
    unfinished_note,
)
from jswim.results.migrate import RENAMED
from jswim.results.row import RunRow, as_run_row, as_run_rows
from jswim.results.schema import FAILED_STATUSES, SCALAR_TYPES, is_failed, run_problem
from jswim.results.store import (
    FILE_MODE,
    META,
    RESERVE,
    RESERVE_MIN_BYTES,
    RUNS,
    StudyFolderError,
    StudyStore,
    identity_differences,
    writing,
)
from jswim.results.tables import arrow_table, write_tables

__all__ = [
    "CALL_COLUMNS",
    "FAILED_STATUSES",
    "FILE_MODE",
    "META",
    "RENAMED",
    "RESERVE",
    "RESERVE_MIN_BYTES",
    "RUNS",
    "SCALAR_TYPES",
    "TRAJECTORY_KEYS",
    "TRANSCRIPT_COLUMNS",
    "RunRow",
    "Study",
    "StudyFolderError",
    "StudyStore",
    "arrow_table",
    "as_run_row",
    "as_run_rows",
    "clean_metadata",
    "identity_differences",
    "is_failed",
    "load",
    "read_calls",
    "read_metadata",
    "read_run_rows",
    "read_runs",
    "read_transcript",
    "run_problem",
    "transcript_steps",
    "unfinished_note",
    "write_tables",
    "writing",
]
