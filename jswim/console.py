"""Tables and progress for a terminal or a log file; nothing is ever cut.

A table is aligned plain text with every cell whole (never ``0…`` for ``0.5``). On a terminal
narrower than the table its columns wrap into blocks that repeat the label columns; anywhere else
(a pipe, ``> log.txt``, CI) it is as wide as its widest cells. Progress is a rich bar on a
terminal and, elsewhere, one dated line per update at most every ``interval`` seconds instead of
a redrawn bar; in a Jupyter notebook it is one display, updated in place
(`NotebookProgress`).
"""

from __future__ import annotations

import contextlib
import html
import shutil
import sys
import time
from dataclasses import dataclass
from typing import IO, Any
from collections.abc import Callable, Iterator, Mapping, Sequence

__all__ = [
    "EMBEDDED_UNPRICED",
    "LOCAL_UNPRICED",
    "PHASE_LABELS",
    "REFERENCE_UNPRICED",
    "Column",
    "NotebookProgress",
    "Progress",
    "Throttle",
    "cost_text",
    "eta",
    "format_duration",
    "in_notebook",
    "is_terminal",
    "phase_ticker",
    "plain_table",
    "print_table",
    "requests_text",
    "study_progress",
    "terminal_width",
]


@dataclass(frozen=True)
class Column:
    """A table column: its header, and whether it holds numbers (right-aligned) or a label.

    The leading label columns of a table identify its rows; they are repeated when a wide table
    wraps into blocks.
    """

    header: str
    numeric: bool = True


def is_terminal(file: IO[str] | None = None) -> bool:
    """Whether ``file`` (default stdout) is an interactive terminal."""
    f = file or sys.stdout
    try:
        return bool(f.isatty())
    except (AttributeError, ValueError):
        return False


def terminal_width(file: IO[str] | None = None) -> int | None:
    """The terminal's width in columns, or ``None`` when ``file`` (default stdout) is not a terminal."""
    return shutil.get_terminal_size().columns if is_terminal(file) else None


def plain_table(
    columns: Sequence[Column],
    rows: Sequence[Sequence[str]],
    title: str | None = None,
    width: int | None = None,
) -> str:
    """The table as aligned text, every cell whole.

    With a ``width`` (a terminal's) that the table exceeds, the columns are wrapped into blocks
    one under the other, each block repeating the leading label columns, the way a wide
    DataFrame is printed; without one (a log file) the table is as wide as its cells.
    """
    cells = [[c.header for c in columns]] + [[str(v) for v in row] for row in rows]
    widths = [max(len(r[j]) for r in cells) for j in range(len(columns))]
    n_keys = next((j for j, c in enumerate(columns) if c.numeric), len(columns))
    blocks = [list(range(len(columns)))]
    if width is not None and sum(widths) + 2 * (len(widths) - 1) > width and n_keys < len(columns):
        key_w = sum(widths[:n_keys]) + 2 * n_keys
        blocks, current, used = [], [], key_w
        for j in range(n_keys, len(columns)):
            if current and used + widths[j] > width:
                blocks.append(list(range(n_keys)) + current)
                current, used = [], key_w
            current.append(j)
            used += widths[j] + 2
        blocks.append(list(range(n_keys)) + current)

    def line(row: Sequence[str], cols: Sequence[int]) -> str:
        parts = [
            row[j].rjust(widths[j]) if columns[j].numeric else row[j].ljust(widths[j]) for j in cols
        ]
        return "  ".join(parts).rstrip()

    out = [title] if title else []
    for b, cols in enumerate(blocks):
        if b:
            out.append("")
        out += [line(cells[0], cols), "  ".join("-" * widths[j] for j in cols)]
        out += [line(r, cols) for r in cells[1:]]
    return "\n".join(out)


def print_table(
    columns: Sequence[Column],
    rows: Sequence[Sequence[str]],
    title: str | None = None,
    file: IO[str] | None = None,
) -> None:
    """Print `plain_table`, wrapped to the terminal's width on a terminal, whole elsewhere."""
    f = file or sys.stdout
    print(plain_table(columns, rows, title, terminal_width(f)), file=f)


def requests_text(counts: Mapping[str, Any]) -> str:
    """``132 sent (12 retries; transient faults: 429 x5, 5xx x4, connection x3)`` from a session's
    or a study's ``requests``, ``retries`` and ``faults`` (by kind)."""
    faults = ", ".join(f"{k} x{n}" for k, n in sorted((counts.get("faults") or {}).items()) if n)
    text = (
        f"{counts.get('requests', 0):.0f} sent ({counts.get('retries', 0):.0f} retries"
        + (f"; transient faults: {faults}" if faults else "; no transient faults")
        + ")"
    )
    unanswered = counts.get("unanswered") or 0
    if unanswered:  # sent whole, no answer: a provider may have billed them (jswim.llm.budget)
        usd = counts.get("unanswered_usd") or 0.0
        text += (
            f"; {unanswered:.0f} got no answer (timed out or cut while waiting) and may have been billed"
            + (f": at most ${usd:.4f}, counted against --max-cost" if usd else "")
        )
    return text


def format_duration(seconds: float) -> str:
    """``"42s"``, ``"3m05s"``, ``"1h02m"``."""
    s = round(max(0.0, seconds))
    if s < 60:
        return f"{s}s"
    if s < 3600:
        return f"{s // 60}m{s % 60:02d}s"
    return f"{s // 3600}h{(s % 3600) // 60:02d}m"


def eta(elapsed_s: float, fraction: float) -> str | None:
    """Time left if the rest goes as fast as the ``fraction`` done in ``elapsed_s``; ``None`` before any."""
    if fraction <= 0 or elapsed_s <= 0:
        return None
    return format_duration(elapsed_s * (1 - min(fraction, 1.0)) / fraction)


class Throttle:
    """When a progress display redraws: on a change of phase, on the final update, and otherwise at
    most every ``interval`` seconds (the log lines of `Progress`, the notebook output of
    `NotebookProgress`).

    Parameters
    ----------
    interval : float
        Seconds between redraws within a phase.
    """

    def __init__(self, interval: float) -> None:
        self.interval = interval
        self.t0 = time.monotonic()
        self._last: tuple[str, float] | None = None

    def due(self, label: str, final: bool = False) -> float | None:
        """The time (``time.monotonic``) to redraw ``label`` now, or ``None`` to skip this update."""
        now = time.monotonic()
        if (
            not final
            and self._last is not None
            and self._last[0] == label
            and now - self._last[1] < self.interval
        ):
            return None
        self._last = (label, now)
        return now


class Progress:
    """Progress of a long job: a rich bar on a terminal, dated log lines elsewhere.

    Use as a context manager and call `update` as often as you like; in a log it prints a
    line when the phase changes, when the job ends, and otherwise at most every ``interval``
    seconds. ``info`` (e.g. the study's step count and ETA) is printed as given.

    Parameters
    ----------
    file : text stream, optional
        Where progress goes (default stderr, so a table on stdout stays clean).
    interval : float
        Seconds between log lines within a phase (not on a terminal).
    """

    def __init__(self, file: IO[str] | None = None, interval: float = 10.0) -> None:
        self.file = file or sys.stderr
        self.throttle = Throttle(interval)
        self.terminal = is_terminal(self.file)
        self._bar: Any = None
        self._task: Any = None
        self.state: tuple[str, int, int, str, str] = ("start", 0, 0, "", "runs")

    def __enter__(self) -> Progress:
        if self.terminal:
            from rich.console import Console  # lazy: rich only when writing to a terminal
            from rich.progress import BarColumn, MofNCompleteColumn, TextColumn, TimeElapsedColumn
            from rich.progress import Progress as Bar

            # A short bar leaves room for the status text (steps, ETA, requests in flight).
            self._bar = Bar(
                TextColumn("[bold]{task.description}"),
                BarColumn(bar_width=20),
                MofNCompleteColumn(),
                TimeElapsedColumn(),
                TextColumn("{task.fields[info]}"),
                console=Console(file=self.file),
            )
            self._bar.__enter__()
            self._task = self._bar.add_task("runs", total=None, info="")
        return self

    def __exit__(self, *exc: Any) -> None:
        if self._bar is not None:
            self._bar.__exit__(*exc)
            self._bar = None

    def stop(self) -> None:
        """End the bar early (before printing an interruption message)."""
        self.__exit__(None, None, None)

    def update(
        self,
        label: str,
        done: int,
        total: int,
        info: str = "",
        final: bool = False,
        unit: str = "runs",
    ) -> None:
        """Show ``label`` with ``done`` of ``total`` (counted in ``unit`` in a log) and ``info``."""
        self.state = (label, done, total, info, unit)
        if self._bar is not None:
            self._bar.update(self._task, completed=done, total=total, description=label, info=info)
            return
        now = self.throttle.due(label, final)
        if now is None:
            return
        pct = f" ({100 * done / total:.0f}%)" if total else ""
        text = f"[{format_duration(now - self.throttle.t0):>6}] {label}: {done}/{total} {unit}{pct}"
        print(text + (f" · {info}" if info else ""), file=self.file, flush=True)


def in_notebook() -> bool:
    """Whether this runs in a Jupyter kernel (a notebook, JupyterLab, nbconvert, VS Code)."""
    ipython = sys.modules.get("IPython")  # never imported here: a kernel has imported it already
    shell = ipython.get_ipython() if ipython is not None else None
    return shell is not None and getattr(shell, "kernel", None) is not None


class NotebookProgress:
    """Progress of a long job as one output of a notebook cell, updated in place.

    The same interface as `Progress`. It shows an HTML bar (a plain-text line for
    frontends without HTML) through IPython's ``display(..., display_id=True)`` and updates that
    one output, at most every ``interval`` seconds within a phase, so a cell gets one display
    however long the job; JupyterLab redraws it, and a notebook executed by nbconvert keeps its
    last state. May be updated from a worker thread (the study's event loop).
    """

    def __init__(self, interval: float = 1.0) -> None:
        self.throttle = Throttle(interval)
        self._handle: Any = None
        self.state: tuple[str, int, int, str, str] = ("start", 0, 0, "", "runs")

    def __enter__(self) -> NotebookProgress:
        return self

    def __exit__(self, *exc: Any) -> None:
        pass

    def stop(self) -> None:
        """Nothing to close: the output stays as last drawn."""

    def update(
        self,
        label: str,
        done: int,
        total: int,
        info: str = "",
        final: bool = False,
        unit: str = "runs",
    ) -> None:
        """Show ``label`` with ``done`` of ``total`` ``unit`` and ``info`` (throttled)."""
        self.state = (label, done, total, info, unit)
        now = self.throttle.due(label, final)
        if now is None:
            return
        view = _ProgressView(*self.state, elapsed=now - self.throttle.t0)
        if self._handle is None:
            from IPython.display import display  # lazy: only inside a kernel

            self._handle = display(view, display_id=True)
        else:
            self._handle.update(view)


@dataclass(frozen=True)
class _ProgressView:
    """One state of a `NotebookProgress`, drawn as HTML or as one line of text."""

    label: str
    done: int
    total: int
    info: str
    unit: str
    elapsed: float

    def __repr__(self) -> str:
        pct = f" ({100 * self.done / self.total:.0f}%)" if self.total else ""
        text = f"[{format_duration(self.elapsed)}] {self.label}: {self.done}/{self.total} {self.unit}{pct}"
        return text + (f" · {self.info}" if self.info else "")

    def _repr_html_(self) -> str:
        bar = (
            f'<progress value="{self.done}" max="{self.total}" style="width:14em"></progress>'
            if self.total
            else '<progress style="width:14em"></progress>'
        )
        info = f" · {html.escape(self.info)}" if self.info else ""
        return (
            f'<div style="font-family:monospace">{bar} <b>{html.escape(self.label)}</b> '
            f"{self.done}/{self.total} {html.escape(self.unit)} · "
            f"{format_duration(self.elapsed)}{info}</div>"
        )


#: A study's progress phases (``jswim.studies.session.ProgressFn``) as a person reads them.
PHASE_LABELS = {
    "llm": "LLM runs",
    "llm-live": "LLM runs",
    "qlearning": "Q-learning",
    "random": "random policy",
    "ppo": "PPO",  # real-valued in the continuous and scene studies, categorical in navigation
    "controller": "steering controller",
    "zermelo": "Zermelo's point path",
    "optimal": "the swimmer's optimum",
    "mpc": "model-predictive agent",
    "stroke": "fixed strokes",
    "start": "start",
    "resume": "resume",
}

ProgressFn = Callable[[str, int, int, str], None]


def phase_ticker(bar: Progress | NotebookProgress) -> ProgressFn:
    """A study's ``progress(phase, done, total, info)`` callback that draws on ``bar``."""

    def tick(phase: str, done: int, total: int, info: str = "") -> None:
        bar.update(
            PHASE_LABELS.get(phase, "runs"),
            done,
            total,
            info,
            unit="LLM steps" if phase.startswith("llm") else "runs",
        )

    return tick


@contextlib.contextmanager
def study_progress(progress: ProgressFn | bool | None) -> Iterator[ProgressFn | None]:
    """The callback a study reports to, from what the caller asked for.

    ``None`` (automatic): one updating display in a notebook, the bar on a terminal, nothing
    elsewhere (a script's log stays clean); ``True``: the same, with dated lines where there is
    no terminal; ``False``: nothing; a callable: itself, untouched. An automatic display ends
    with the outcome: ``done``, or ``interrupted`` with what is kept.
    """
    if callable(progress):
        yield progress
        return
    if progress is False or (
        progress is None and not in_notebook() and not is_terminal(sys.stderr)
    ):
        yield None
        return
    bar: Progress | NotebookProgress = NotebookProgress() if in_notebook() else Progress()
    with bar:
        tick = phase_ticker(bar)
        try:
            yield tick
        except KeyboardInterrupt:
            _, done, total, _, unit = bar.state
            bar.update("interrupted", done, total, "kept; the same call resumes", True, unit)
            raise
        _, done, total, info, unit = bar.state
        bar.update("done", done, total, info, True, unit)


#: Why a call is not priced, in the words every cost line uses (`cost_text`).
EMBEDDED_UNPRICED = "the embedded model runs on this machine"
REFERENCE_UNPRICED = "a rule on this machine, not an LLM"
LOCAL_UNPRICED = "a server on this machine or the LAN, with no list price for its model"


def cost_text(
    cost_usd: float | None, unpriced: str | None = None, source: str | None = None
) -> str:
    """One wording for a cost everywhere (``jswim swim``/``study``, ``show``, the leaderboard, the pages).

    ``unpriced``: why the calls have no price (then ``not priced (WHY); $0 counted``, never a bare
    ``$0`` or ``free``); ``source``: where a price came from (``list prices of 2025-04``).
    """
    if unpriced:
        return f"not priced ({unpriced}); $0 counted"
    if cost_usd is None:
        return "-"
    return f"${cost_usd:.4f}" + (f" ({source})" if source else "")
