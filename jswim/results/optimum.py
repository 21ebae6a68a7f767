"""A navigation cell's optimum, recorded once: on its ``optimal`` row.

The swimmer's own least time to a target (``optimal_steps``) is one fact per cell (a world:
target, flow, K lattice, start shape), found by the ``optimal`` agent's search after every other
run of the cell, which seeds it (`jswim.studies.kinds.navigate.seed_optimum`). The other rows of the
cell are written before it is known; their ``optimal_steps`` and ``time_ratio`` are read from
the cell's ``optimal`` row ([`with_cell_optimum`][jswim.results.optimum.with_cell_optimum]),
so every row of a cell is measured against the same optimum.
"""

from __future__ import annotations

import dataclasses
from typing import Any, TypeVar
from collections.abc import Sequence

from jswim.results.schema import FAILED_STATUSES as FAILED

__all__ = ["cell_key", "with_cell_optimum"]

R = TypeVar("R")

#: The agent whose row holds its cell's optimum (`jswim.studies.options.OPTIMAL_AGENT`).
_OPTIMAL = "optimal"


def _get(row: Any, name: str) -> Any:
    # a RunRow is read by attribute (it is a Mapping too, of its columns)
    return getattr(row, name, None) if dataclasses.is_dataclass(row) else row.get(name)


def cell_key(row: Any) -> tuple[str, str, int, str] | None:
    """A navigation row's cell: ``(target, flow, K, start shape)`` (``"++"``: the study's own
    start); None for a row with no target."""
    if not _get(row, "target"):
        return None
    k = _get(row, "roc_levels")
    return (_get(row, "target"), _get(row, "flow") or "", int(k or 0), _get(row, "init") or "++")


def with_cell_optimum(rows: Sequence[R]) -> list[R]:
    """``rows`` with each navigation row's ``optimal_steps`` and ``time_ratio`` from its cell's
    ``optimal`` row.

    Parameters
    ----------
    rows : sequence of dict or RunRow
        Run records. A cell with no finished ``optimal`` row among them (a study without the
        agent, an older folder, a subset) keeps what its rows say.

    Returns
    -------
    list
        The rows, same types and order: a cell's rows carry its ``optimal`` row's
        ``optimal_steps`` (None: the search found no way to the target) and ``time_ratio`` =
        steps to the target over it, rounded to 6 digits (None where the run did not reach the
        target or there is no optimum); Zermelo's point has his real-valued least time
        (``zermelo_steps``) over it.
    """
    best: dict[tuple, Any] = {}
    for r in rows:
        key = cell_key(r)
        if key is not None and _get(r, "agent") == _OPTIMAL and _get(r, "status") not in FAILED:
            best.setdefault(key, _get(r, "optimal_steps"))
    if not best:
        return list(rows)
    out = []
    for r in rows:
        key = cell_key(r)
        if key not in best:
            out.append(r)
            continue
        own = best[key]
        steps = _get(r, "zermelo_steps") if _get(r, "agent") == "zermelo" else None
        if steps is None:
            steps = _get(r, "steps_to_target") if _get(r, "reached") else None
        ratio = round(float(steps) / float(own), 6) if own and steps is not None else None
        cols = {"optimal_steps": own, "time_ratio": ratio}
        if dataclasses.is_dataclass(r):
            out.append(dataclasses.replace(r, **cols))
        else:
            out.append({**r, **cols})
    return out
