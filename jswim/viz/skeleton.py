"""The frame every ``report.html`` shares: a study folder's page (`jswim.viz.page`) and a bench's
(`jswim.viz.bench_page`).

A page is self-contained: the packaged styles (and the run browser's script, where the page has
one) are inline, figures are PNG data URIs, and nothing is fetched when it is opened. Its header
holds the title, a status line (``ok`` when finished, else ``unfinished``) and a line naming the
folder, then come the links to its sections and the sections themselves.
"""

from __future__ import annotations

import base64
import datetime as _dt
import html
import io
from importlib import resources
from pathlib import Path
from typing import Any
from collections.abc import Sequence

from jswim.figures.style import RC
from jswim.results import atomic_write, writing

#: A page's file name in its folder.
REPORT = "report.html"


def _asset(name: str) -> str:
    """The text of one of the pages' packaged assets (``report.css``, ``report.js``)."""
    return resources.files("jswim.viz").joinpath("assets", name).read_text(encoding="utf-8")


def written() -> str:
    """Now, as a page says when it was written (UTC, to the minute)."""
    return _dt.datetime.now(_dt.UTC).strftime("%Y-%m-%d %H:%M UTC")


def png_src(data: bytes) -> str:
    """A PNG image as a data URI for ``<img src>``."""
    return "data:image/png;base64," + base64.b64encode(data).decode()


def figure_src(fig: Any, dpi: int) -> str:
    """A matplotlib figure drawn in the figures' style as a PNG data URI; the figure is closed."""
    import matplotlib.pyplot as plt  # lazy: a page without drawn figures needs none

    buf = io.BytesIO()
    with plt.rc_context(RC):
        fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight", pad_inches=0.03)
    plt.close(fig)
    return png_src(buf.getvalue())


def page_html(
    title: str,
    *,
    finished: bool,
    status: str,
    folder: str,
    meta: Sequence[str],
    nav: Sequence[tuple[str, str]],
    body: Sequence[str],
    script: bool = False,
) -> str:
    """A whole page around its sections.

    Parameters
    ----------
    title : str
        The page's title and heading (text).
    finished : bool
        Whether the status line reads as done (class ``ok``) or not (``unfinished``).
    status : str
        The status line (text).
    folder : str
        The folder's name, first on the line under the status.
    meta : sequence of str
        The rest of that line (HTML), each item after a ``·``.
    nav : sequence of (str, str)
        ``(id, label)`` of each section linked from the top of the page.
    body : sequence of str
        The sections (HTML), one line each.
    script : bool
        Add the run browser's script (``report.js``) after ``body``.
    """
    return "\n".join(
        [
            "<!DOCTYPE html>",
            '<html lang="en"><head><meta charset="utf-8"/>',
            '<meta name="viewport" content="width=device-width, initial-scale=1"/>',
            f"<title>{html.escape(title)}</title><style>{_asset('report.css')}</style></head><body>",
            f"<header><h1>{html.escape(title)}</h1>",
            f'<p id="status" class="{"ok" if finished else "unfinished"}">{html.escape(status)}</p>',
            f'<p class="meta">folder <code>{html.escape(folder)}</code>'
            + "".join(f" · {m}" for m in meta)
            + "</p></header>",
            "<nav>"
            + " ".join(f'<a href="#{i}">{html.escape(label)}</a>' for i, label in nav)
            + "</nav>",
            *body,
            *([f"<script>{_asset('report.js')}</script>"] if script else []),
            "</body></html>",
        ]
    )


def write_page(text: str, folder: Path, out: str | Path | None = None) -> Path:
    """Write a page to ``folder``'s ``report.html`` (or ``out``) atomically.

    Raises
    ------
    StudyFolderError
        The page cannot be written (one line, naming ``--out`` as the way out).
    """
    path = Path(out) if out is not None else folder / REPORT
    with writing(path, "choose a writable --out path for the report"):
        atomic_write(path, text)
    return path
