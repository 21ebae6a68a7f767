"""The scene and navigation tables ``jswim study`` prints after the usual summary (a study's own
options are declared by the study: `jswim.studies.study.Study.flags`)."""

from __future__ import annotations

from typing import Any
from collections.abc import Sequence

from jswim.console import print_table as show


def _print_nav_table(rows: Sequence[Any]) -> None:
    """The navigation table (`jswim.studies.overview.nav_table`) and its note."""
    from jswim.studies.overview import nav_overview_table, nav_table  # lazy: JAX, for a study

    cols, cells, note = nav_overview_table(rows)
    show(cols, cells, "agents x flows: success, time over the swimmer's optimum, energy")
    print(note)
    cols, cells, note = nav_table(rows)
    show(cols, cells, "navigation: targets reached, steps to the target, path ratio, energy")
    print(note)


def print_table(rows: Sequence[dict[str, Any]]) -> None:
    """The scene table of a study's rows (nothing when it has no scene runs)."""
    from jswim.results import as_run_rows  # lazy: start-up (results loads NumPy)

    rows = as_run_rows(rows)
    if any(r.target for r in rows):
        _print_nav_table(rows)
    if not any(r.scene for r in rows):
        return
    from jswim.studies.scene_studies import (
        columns_note,
        scene_summary,
        table,
        table_note,
    )  # lazy: JAX loads only for a study

    summary = scene_summary(rows)
    cols, cells = table(summary)
    show(cols, cells, "scenes: displacement per stroke cycle, speed per step (second half)")
    print(columns_note(cols))
    if note := table_note(summary):
        print(note)
