"""The derived tables of a study folder: ``runs.parquet``/``runs.csv`` and ``trajectories.parquet``."""

from __future__ import annotations

import csv
import io
import json
import os
from pathlib import Path
from typing import Any
from collections.abc import Iterable

from jswim._io.atomic import atomic_write, dumps
from jswim.results.row import as_run_rows
from jswim.results.schema import SCALAR_TYPES


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
    for r in as_run_rows(runs):
        for i, x in enumerate(r.x or []):
            traj.append(
                {
                    "run_id": r.run_id,
                    "step": i + 1,
                    "x": x,
                    "y": _at(r.y, i),
                    "orientation": _at(r.orientation, i),
                    "action": _at(r.actions, i),
                    "progress": _at(r.progress, i),
                    "stuck": _at(r.stuck, i),
                }
            )
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

    kinds = {
        next((t for t in (bool, int, float, str) if isinstance(v, t)), type(v))
        for v in values
        if v is not None
    }
    if not kinds:
        return pa.null()
    if kinds == {bool}:
        return pa.bool_()
    if kinds == {int}:
        return pa.int64() if all(-(2**63) <= v < 2**63 for v in values if v is not None) else None
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
    return pj.read_json(
        io.BytesIO(data),
        read_options=pj.ReadOptions(block_size=max(1 << 20, len(data) + 1)),
        parse_options=pj.ParseOptions(explicit_schema=schema),
    )


def _at(seq: Any, i: int) -> Any:
    if isinstance(seq, list) and i < len(seq):
        v = seq[i]
        return json.dumps(v) if isinstance(v, (list, dict)) else v
    return None
