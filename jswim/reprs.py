"""Short text and HTML representations for notebooks: what an object is, its status, its counts.

A ``__repr__`` here is a few lines (never the arrays or rows behind it); an ``_repr_html_`` is a
small table, the study's figures as thumbnails, and, for a world, a small picture of it. Each
class keeps its data; these functions only read it, so any result type (a NamedTuple, a
dataclass) can use them by assigning ``__repr__ = reprs.trajectory_text`` and so on.
"""

from __future__ import annotations

import base64
import html
import io
from pathlib import Path
from typing import Any
from collections.abc import Iterable, Mapping, Sequence

__all__ = [
    "MAX_ROWS",
    "SUMMARY_COLUMNS",
    "THUMB_PX",
    "animation_text",
    "count_text",
    "facts_html",
    "figure_png",
    "frame_html",
    "lines",
    "run_result_html",
    "run_result_text",
    "study_html",
    "study_result_html",
    "study_result_text",
    "study_text",
    "thumbnails_html",
    "trajectory_html",
    "trajectory_text",
    "world_html",
]

#: Summary rows shown in an HTML repr (the DataFrame itself holds them all).
MAX_ROWS = 20
#: Width of a figure thumbnail, in CSS pixels (a click opens nothing; the file is named below it).
THUMB_PX = 240


def facts_html(title: str, facts: Mapping[str, Any]) -> str:
    """A title and a two-column table of ``name: value`` facts."""
    rows = "".join(
        f"<tr><th style='text-align:left'>{html.escape(str(k))}</th>"
        f"<td style='text-align:left'>{html.escape(str(v))}</td></tr>"
        for k, v in facts.items()
    )
    return f"<div><b>{html.escape(title)}</b><table>{rows}</table></div>"


#: The summary's columns an HTML repr shows, in this order (the DataFrame keeps every column).
SUMMARY_COLUMNS = (
    "agent",
    "swimmer",
    "direction",
    "group",
    "n",
    "success_rate",
    "success_lo",
    "success_hi",
    "mean_x",
    "mean_x_lo",
    "mean_x_hi",
    "steps_to_learn_median",
    "failed_steps",
    "tokens_per_step",
    "cost_usd",
)


def frame_html(frame: Any, max_rows: int = MAX_ROWS, columns: Sequence[str] | None = None) -> str:
    """A DataFrame (or a list of dicts) as an HTML table of at most ``max_rows`` rows; with
    ``columns``, only those of them it has (all of its columns when it has none)."""
    import pandas as pd  # lazy: only to draw

    df = frame if isinstance(frame, pd.DataFrame) else pd.DataFrame(list(frame))
    if df.empty:
        return ""
    if columns is not None and any(c in df for c in columns):
        df = df[[c for c in columns if c in df]]
    df = df.map(lambda v: "-" if v is None else v)  # JSON's null, as NaN is shown
    more = len(df) - max_rows
    table = df.head(max_rows).to_html(index=False, float_format=lambda v: f"{v:.3g}", na_rep="-")
    return table + (f"<div>... and {more} more rows</div>" if more > 0 else "")


def thumbnails_html(paths: Iterable[str | Path], width: int = THUMB_PX) -> str:
    """The PNG figures among ``paths`` as inline thumbnails (each downscaled to ``width`` px)."""
    cells = []
    for p in paths:
        p = Path(p)
        if p.suffix.lower() != ".png" or not p.is_file():
            continue
        data = base64.b64encode(_thumbnail(p, width)).decode()
        cells.append(
            f"<figure style='display:inline-block;margin:4px'>"
            f"<img src='data:image/png;base64,{data}' width='{width}' alt='{html.escape(p.name)}'/>"
            f"<figcaption style='font-size:small'>{html.escape(p.name)}</figcaption></figure>"
        )
    return "<div>" + "".join(cells) + "</div>" if cells else ""


def _thumbnail(path: Path, width: int) -> bytes:
    """The PNG at ``path`` scaled down to ``width`` pixels wide."""
    from PIL import Image  # lazy: Pillow comes with matplotlib

    with Image.open(path) as im:
        if im.width > width:
            im = im.resize((width, max(1, round(im.height * width / im.width))), Image.LANCZOS)
        buf = io.BytesIO()
        im.save(buf, format="PNG", optimize=True)
    return buf.getvalue()


def figure_png(fig: Any, dpi: int = 72) -> str:
    """A matplotlib figure as an inline ``<img>`` (the figure is closed)."""
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=dpi, bbox_inches="tight")
    plt.close(fig)
    data = base64.b64encode(buf.getvalue()).decode()
    return f"<img src='data:image/png;base64,{data}'/>"


def lines(head: str, *rest: str) -> str:
    """A repr of a few lines: the head, then each further line indented."""
    return "\n".join([head, *(f"  {r}" for r in rest if r)])


def count_text(values: Sequence[Any]) -> str:
    """``"done 6, llm_error 2"``: how many of each value."""
    counts: dict[str, int] = {}
    for v in values:
        counts[str(v)] = counts.get(str(v), 0) + 1
    return ", ".join(f"{k} {n}" for k, n in counts.items())


def trajectory_text(traj: Any) -> str:
    """A rollout's trajectory: steps (and batch), swimmers, final centroid X, the fields it holds."""
    x = _centroid_x(traj)
    head = f"{type(traj).__name__}: " + (_shape_text(x) if x is not None else "no positions")
    if x is not None:
        head += f"; final X {_numbers(x[..., -1])}"
    fields = ", ".join(getattr(traj, "_fields", ()) or vars(traj))
    return lines(head, f"fields: {fields} (jax arrays, the step axis after any batch axis)")


def trajectory_html(traj: Any) -> str:
    """A rollout's trajectory: its counts, and X against the step as a small plot."""
    import numpy as np

    x = _centroid_x(traj)
    if x is None:
        return facts_html(type(traj).__name__, {"positions": "none"})
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(4, 2.2))
    steps = np.arange(1, x.shape[-1] + 1)
    ax.plot(steps, x.reshape(-1, x.shape[-1]).T, lw=1)
    ax.set_xlabel("step n")
    ax.set_ylabel("centroid X")
    facts = {"steps": _shape_text(x), "final X": _numbers(x[..., -1])}
    return facts_html(type(traj).__name__, facts) + figure_png(fig)


def _centroid_x(traj: Any) -> Any:
    """The swimmers' mean centroid X per step, ``(steps,)`` or ``(batch, steps)``, or ``None``."""
    import numpy as np

    x = getattr(traj, "x", None)  # a record of the centroid X itself
    if x is not None and getattr(x, "ndim", 0) >= 1:
        return np.asarray(x, dtype=float)
    pos = getattr(getattr(traj, "obs", None), "position", None)  # (..., steps, S, 2)
    if pos is None or getattr(pos, "ndim", 0) < 3:
        return None
    return np.asarray(pos[..., 0], dtype=float).mean(axis=-1)


def _shape_text(x: Any) -> str:
    if x.ndim == 1:
        return f"{x.shape[0]} steps"
    return f"{x.shape[0]} rollouts x {x.shape[-1]} steps"


def _numbers(v: Any, most: int = 4) -> str:
    import numpy as np

    flat = np.atleast_1d(np.asarray(v)).ravel()
    text = ", ".join(f"{u:.3g}" for u in flat[:most])
    return text + (f", ... ({flat.size})" if flat.size > most else "")


def study_result_text(res: Any) -> str:
    """A finished (or stopped) study session: its study, status, run counts, folder."""
    study = _study_name(res.folder)
    status = f"stopped at the {res.stopped}" if res.stopped else "complete"
    if res.failed_runs:
        status += f", {len(res.failed_runs)} runs failed"
    total = res.total or len(res.rows)
    return lines(
        f"StudyResult {study}: {status}; {len(res.rows)} of {total} runs, in {res.wall_s:.1f} s",
        f"summary: {len(res.summary)} settings (.summary, a DataFrame); figures: {len(res.figures)}",
        f"folder: {res.folder}  (jswim.load(folder): runs and trajectories as DataFrames)",
    )


def _study_name(folder: str | Path) -> str:
    """The study's name from its folder's metadata (the folder's name when unreadable)."""
    import json

    try:
        return str(json.loads(Path(folder, "metadata.json").read_text())["study"])
    except (OSError, ValueError, KeyError, TypeError):
        return Path(folder).name


def study_result_html(res: Any) -> str:
    """The summary table, the figures as thumbnails, and how to load the folder."""
    head = html.escape(study_result_text(res).splitlines()[0])
    load = (
        f"<div><code>jswim.load({html.escape(repr(str(res.folder)))})</code>: every run and "
        "trajectory as a DataFrame</div>"
    )
    table = frame_html(res.summary, columns=SUMMARY_COLUMNS)
    return f"<div><b>{head}</b>{table}{thumbnails_html(res.figures)}{load}</div>"


def study_text(study: Any) -> str:
    """A loaded study folder: name, status, runs by agent, trajectory rows."""
    runs = study.runs
    by_agent = count_text(list(runs["agent"])) if "agent" in runs else ""
    planned = study.metadata.get("n_planned")
    of = f" of {planned}" if planned else ""
    return lines(
        f"Study {study.name}: {study.status}; {len(runs)}{of} runs"
        + (f" ({by_agent})" if by_agent else ""),
        f"trajectories: {len(study.trajectories)} steps; .runs, .trajectories, .calls, "
        ".transcript(run_id)",
        f"folder: {study.folder}",
    )


def study_html(study: Any) -> str:
    """The study's summary (from its metadata) as a table and its figures as thumbnails."""
    head = html.escape(study_text(study).splitlines()[0])
    groups = (study.metadata.get("summary") or {}).get("groups") or []  # one row per setting
    table = frame_html(groups, columns=SUMMARY_COLUMNS) if groups else frame_html(study.runs)
    figures = sorted(Path(study.folder, "figures").glob("*.png"))
    return f"<div><b>{head}</b>{table}{thumbnails_html(figures)}</div>"


def run_result_text(run: Any) -> str:
    """One LLM run: id, status, steps, final X, calls and tokens."""
    x = f"; final X {run.x[-1]:.3g}" if run.x else ""
    error = f"; error: {run.error}" if run.error else ""
    u = run.usage
    return lines(
        f"RunResult {run.run_id}: {run.status}; {run.steps} of {run.spec.n_steps} steps{x}{error}",
        f"{u.calls} calls, {u.prompt_tokens + u.completion_tokens} tokens, "
        f"{run.failed_steps} failed steps, {run.parse_retries} parse retries",
    )


def run_result_html(run: Any) -> str:
    """One LLM run's facts and its X against the step."""
    import numpy as np

    facts = dict(
        zip(
            ("status", "steps", "swimmer", "direction", "zeta", "calls"),
            (
                run.status,
                run.steps,
                run.spec.swimmer,
                run.spec.direction,
                run.spec.zeta,
                run.usage.calls,
            ),
        )
    )
    img = ""
    if run.x:
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(4, 2.2))
        ax.plot(np.arange(1, len(run.x) + 1), run.x, lw=1)
        ax.set_xlabel("step n")
        ax.set_ylabel("centroid X")
        img = figure_png(fig)
    return facts_html(f"RunResult {run.run_id}", facts) + img


def animation_text(anim: Any) -> str:
    """An animation: its title, runs, frames and how to save it."""
    return lines(
        f"Animation {anim.title!r}: {len(anim.tracks)} runs, {anim.n_frames} frames at {anim.fps:g} fps",
        "shown inline in a notebook; .save('runs.gif') or .save('runs.mp4')",
    )


def world_html(env: Any, body: Any = None) -> str:
    """A world's facts and, given its swimmer's ``body`` outline ``(P, 2)``, a small picture."""
    facts = {
        "swimmers": env.n_swimmers,
        "DOFs": ", ".join(env.dof_names),
        "ROC levels K": env.roc_levels,
        "actions": env.n_actions,
    }
    return facts_html(type(env).__name__, facts) + (_body_picture(body) if body is not None else "")


def _body_picture(body: Any) -> str:
    """A swimmer's outline as a small line drawing (spheres and links as dots and lines)."""
    import matplotlib.pyplot as plt
    import numpy as np

    pts = np.asarray(body, dtype=float)
    fig, ax = plt.subplots(figsize=(3, 1.2))
    ax.plot(pts[:, 0], pts[:, 1], "o-", lw=2, ms=4)
    ax.set_aspect("equal")
    ax.axis("off")
    return figure_png(fig)
