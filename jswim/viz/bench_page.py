"""A bench folder's page (``report.html``): the leaderboard, its figure and every part's page.

``jswim report BENCH`` writes the bench's own page and, so that its links lead somewhere, each study
folder's page (``<model>/<part>/report.html``, ``reference/<part>/...``, ``baselines/<part>/...``).
A model's or the reference rule's part page holds its figures drawn with the bench's Q-learning and
random runs of that part beside the model's (the baselines run once for all models, in
``baselines/<part>``). Read only from the folders (``bench.json``, ``leaderboard.json`` and the
study folders), like the leaderboard itself.
"""

from __future__ import annotations

import html
import json
from pathlib import Path
from typing import Any
from collections.abc import Mapping, Sequence

from jswim.errors import ConfigError
from jswim.bench.runner import BASELINES, REFERENCE, read_record
from jswim.bench.leaderboard import cells, missing_text, row_key, valid_rows
from jswim.figures.leaderboard import figure_object
from jswim.viz.page import write_report
from jswim.viz.skeleton import REPORT, figure_src, page_html, write_page, written

BENCH_FILE = "bench.json"


def is_bench(folder: str | Path) -> bool:
    """Whether ``folder`` is a bench folder (it holds ``bench.json``)."""
    return (Path(folder) / BENCH_FILE).is_file()


def read_bench(folder: Path) -> tuple[dict[str, Any], dict[str, Any]]:
    """``bench.json`` and ``leaderboard.json`` as the page reads them: a damaged suite is one
    line (the page cannot say which parts exist); damaged models, statuses, rows and missing
    rows are left out.

    Raises
    ------
    ConfigError
        The bench file is missing or unreadable, or its suite is damaged.
    """
    meta = dict(read_record(folder / BENCH_FILE))
    suite = meta.get("suite")
    parts = suite.get("parts") if isinstance(suite, dict) else None
    if not (
        isinstance(parts, list)
        and all(isinstance(p, dict) and isinstance(p.get("name"), str) for p in parts)
    ):
        raise ConfigError(
            f"{folder}/{BENCH_FILE}: 'suite' is no suite definition (its parts are missing or of "
            "the wrong type); the same jswim bench command writes it again"
        )
    models = meta.get("models")
    meta["models"] = [
        m for m in (models if isinstance(models, list) else []) if isinstance(m, dict)
    ]
    if not isinstance(meta.get("model_status"), dict):
        meta["model_status"] = {}
    try:
        board = dict(read_record(folder / "leaderboard.json"))
    except ConfigError:
        board = {}
    missing = board.get("missing")
    board["rows"] = valid_rows(board.get("rows"))
    board["missing"] = [
        m
        for m in (missing if isinstance(missing, list) else [])
        if isinstance(m, dict) and all(k in m for k in ("row", "part", "why"))
    ]
    return meta, board


def part_folders(folder: Path, meta: Mapping[str, Any]) -> list[tuple[str, str, str, Path]]:
    """``(label, kind, part, folder)`` of every study folder of the bench that exists."""

    parts = [p["name"] for p in (meta.get("suite") or {}).get("parts") or []]
    labels = [(m.get("name"), "llm") for m in meta.get("models") or []]
    labels += [(REFERENCE, "reference"), (BASELINES, "baseline")]
    return [
        (label, kind, part, folder / label / part)
        for part in parts
        for label, kind in labels
        if (folder / label / part / "metadata.json").exists()
    ]


def _row_folder(r: Mapping[str, Any]) -> str:

    label = (
        BASELINES
        if r["kind"] == "baseline"
        else REFERENCE
        if r["kind"] == "reference"
        else r["row"]
    )
    return f"{label}/{r['part']}"


def _table(rows: Sequence[Mapping[str, Any]], folder: Path) -> str:

    # The page's titles of leaderboard.cells' columns.
    head = {
        "part": "part",
        "swimmer": "swimmer",
        "dir": "dir",
        "group": "group",
        "row": "row",
        "n": "n",
        "success": "success p [95% CI]",
        "steps": "steps to learn, median [IQR] (k of n)",
        "mean_x": "X/a end toward the target [95% CI]",
        "fail": "fail",
        "tok/step": "tok/step",
        "cost": "suite cost",
    }
    numeric = {"n", "fail", "tok/step"}
    out = [
        '<table class="summary" id="leaderboard"><thead><tr>'
        + "".join(
            f'<th class="{"num" if k in numeric else ""}">{html.escape(h)}</th>'
            for k, h in head.items()
        )
        + "</tr></thead><tbody>"
    ]
    for r in sorted(rows, key=row_key):
        target = _row_folder(r)
        c = cells(r)
        link = (
            f'<a href="{html.escape(f"{target}/{REPORT}")}">{html.escape(c["row"])}</a>'
            if (folder / target).is_dir()
            else html.escape(c["row"])
        )
        tds = [
            f'<td class="{"num" if k in numeric else ""}'
            + (f' kind-{r["kind"]}">{link}' if k == "row" else f'">{html.escape(c[k])}')
            + "</td>"
            for k in head
        ]
        out.append(f'<tr class="kind-{r["kind"]}">' + "".join(tds) + "</tr>")
    out.append("</tbody></table>")
    return "".join(out)


def bench_html(folder: str | Path) -> str:
    """The bench's page (see the module docstring); reads the folder only."""

    folder = Path(folder)
    meta, board = read_bench(folder)
    rows = board.get("rows") or []
    missing = board.get("missing") or []
    suite = meta.get("suite") or {}
    title = f"jswim bench {suite.get('name', '?')} (seed {suite.get('seed', '?')})"
    status = meta.get("status", "unknown")
    models = "".join(
        f"<li><b>{html.escape(str(k))}</b>: {html.escape(str(v))}</li>"
        for k, v in (meta.get("model_status") or {}).items()
    )
    pages = part_folders(folder, meta)
    links = "".join(
        f'<li><a href="{html.escape(f"{label}/{part}/{REPORT}")}">{html.escape(label)} · '
        f"{html.escape(part)}</a>"
        + (
            " (Q-learning and random, run once for every model)"
            if kind == "baseline"
            else " (the prompt-only reference rule)"
            if kind == "reference"
            else ""
        )
        + "</li>"
        for label, kind, part, _ in pages
    )
    miss = "".join(f"<li>{html.escape(t)}</li>" for t in missing_text(missing))
    fig = (
        (
            f'<figure><img alt="leaderboard" src="{figure_src(figure_object(rows), dpi=150)}"/><figcaption>leaderboard: success p and X/a '
            "end toward the target, each with its 95% interval (Wilson; bootstrap), per row; blue: models, orange: "
            "the reference rule (not an LLM), grey: Q-learning and random</figcaption></figure>"
        )
        if rows
        else ""
    )
    sizes = suite.get("size_overrides") or {}
    body = [
        '<section id="leaderboard-section"><h2>Leaderboard</h2>'
        + (
            _table(rows, folder)
            if rows
            else "<p>No leaderboard yet: the same jswim bench command writes it.</p>"
        )
        + (
            '<p class="note">success p: the paper\'s criterion, 95% Wilson interval; steps to learn counted from 1 '
            "over the runs that learned; X/a end: mean displacement after the last step, positive toward the "
            "row's target direction; suite cost: what the model's calls cost over the whole suite. Each row links "
            "to its study's page.</p>"
        )
        + (f'<h3>Missing rows</h3><ul id="missing">{miss}</ul>' if miss else "")
        + f"<h3>Models</h3><ul>{models}</ul></section>",
        f'<section id="figure"><h2>Figure</h2>{fig}</section>',
        f'<section id="parts"><h2>Each part\'s page</h2><ul>{links}</ul></section>',
        '<section id="definition"><h2>Definition</h2><details><summary>bench.json (the full record)</summary>'
        f"<pre>{html.escape(json.dumps(meta, indent=2, sort_keys=True, default=str))}</pre></details></section>",
    ]
    said = f"; {len(missing)} study folder(s) gave no rows (below)" if missing else ""
    resized = f"sizes changed from the suite's own: {html.escape(json.dumps(sizes))}"
    return page_html(
        title,
        finished=status == "complete" and not missing,
        status=f"bench {status}{said}",
        folder=folder.name,
        meta=[f"page written {written()}"] + ([resized] if sizes else []),
        nav=[
            ("leaderboard-section", "leaderboard"),
            ("figure", "figure"),
            ("parts", "pages"),
            ("definition", "definition"),
        ],
        body=body,
    )


def write_bench_report(
    folder: str | Path, figures: str = "draw", out: str | Path | None = None, parts: bool = True
) -> Path:
    """Write the bench's ``report.html`` (or ``out``) and, with ``parts``, every study folder's page.

    A model's or the reference rule's part page is drawn with the bench's baselines of that part
    beside it (`jswim.viz.page.report_html`'s ``beside``).

    Raises
    ------
    ConfigError
        Unreadable ``bench.json``; [`jswim.results.StudyFolderError`][jswim.results.StudyFolderError] if a page cannot be written.
    """

    folder = Path(folder)
    meta, _ = read_bench(folder)
    if parts:
        for _label, kind, part, sub in part_folders(folder, meta):
            base = folder / BASELINES / part
            beside = [base] if kind != "baseline" and (base / "metadata.json").exists() else []
            write_report(sub, figures=figures, beside=beside)
    return write_page(bench_html(folder), folder, out)
