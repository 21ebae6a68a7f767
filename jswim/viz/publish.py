"""Publishing a study folder: its figures and its ``report.html``, drawn from what the folder holds.

A study ends at its folder (`jswim.studies.run_study` plans, runs, writes and returns); this is
the step after it, in the pictures layer. ``jswim study ...`` and ``jswim swim`` call it when the
runs are done (``--no-figures`` skips it), notebooks call it as ``jswim.report(folder)`` (`report`), and it
reads the folder only, so it publishes a finished, an interrupted or an old folder alike.
"""

from __future__ import annotations

from pathlib import Path
from typing import NamedTuple

from jswim.figures.plots import draw_figures
from jswim.results import read_metadata, read_run_rows, unfinished_note
from jswim.viz.page import write_report

__all__ = ["Published", "report"]


class Published(NamedTuple):
    """What `report` wrote."""

    #: The figure files (a PNG and a PDF per figure) in ``FOLDER/figures``; empty without figures.
    figures: list[Path]
    #: The page, ``FOLDER/report.html`` (or ``out``).
    page: Path


def report(folder: str | Path, figures: bool = True, out: str | Path | None = None) -> Published:
    """``jswim.report(folder)``, the publish step: draw a study folder's figures into ``FOLDER/figures`` and write its ``report.html``.

    Parameters
    ----------
    folder : path
        A study folder (``metadata.json`` and ``runs.jsonl``), finished or not.
    figures : bool
        Draw the figures (PNG and PDF, `jswim.figures.plots.draw_figures`) and show them on the
        page; ``False``: the page alone, without figures (no matplotlib figure is drawn).
    out : path, optional
        Write the page here instead of ``FOLDER/report.html`` (the figures still go into the folder).

    Returns
    -------
    Published
        The figure files and the page.

    Raises
    ------
    ResultFolderError
        Not a study folder (no ``metadata.json``, or unreadable metadata).
    StudyFolderError
        The figures or the page cannot be written (a read-only folder: pass ``out``).
    """
    folder = Path(folder)
    meta = read_metadata(folder)
    drawn: list[Path] = []
    if figures:
        rows = read_run_rows(folder)
        # A folder that did not finish says so across each figure, as `jswim plot` draws it.
        note = unfinished_note(meta.get("status"), len(rows), meta.get("n_planned"))
        drawn = (
            draw_figures(str(meta.get("study", "?")), rows, folder / "figures", note=note)
            if rows
            else []
        )
    page = write_report(folder, figures="files" if figures else "none", out=out)
    return Published(drawn, page)
