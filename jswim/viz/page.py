"""``report.html``: a study folder as one self-contained page (offline, from the file system).

The page holds the study's settings and identity, its summary table, its figures (inline PNG)
and a run browser: filter the runs by agent, swimmer, direction, noise level, n_ht, variant and
group, pick one, and watch it (drawn in the page from the recorded trajectory, with play, pause,
step and a scrub bar) next to each step's record: for LLM runs the exact prompt sent, every reply
asked for (parse retries included), how it was parsed, HTTP retries, tokens, latency and cost;
for every run the action, ``X/a``, stuck and clear events and where the success criterion found
the stroke's cycles. Nothing is fetched: the script and styles are inline, figures are data URIs,
and no server is needed.

Size and speed: the run list is a small table; each run's steps (body outlines, transcript) are a
gzip-compressed JSON blob of its own, base64 in a ``<script type="text/plain">`` element, decoded
by the browser (``DecompressionStream``) only when that run is opened. A prompt repeats most of
the previous step's, so a transcript compresses ~10-30x.

The page is written only from what the folder records (`jswim.viz.tracks`); a folder never
holds a secret (API keys stay in the environment), and nothing is added here. ``jswim report`` on
an existing folder writes ``report.html`` and nothing else.
"""

from __future__ import annotations

import base64
import dataclasses
import gzip
import html
import io
import json
import math
from pathlib import Path
from typing import Any
from collections.abc import Mapping, Sequence

import numpy as np

from jswim.env.flows import SWIM_SPEED, study_flow
from jswim.errors import ConfigError
from jswim.figures import plots
from jswim.figures.flow_plots import flow_text
from jswim.results.orders import AGENT_ORDER
from jswim.studies.overview import (
    grid_order,
)
from jswim.results import (
    RunRow,
    as_run_row,
    as_run_rows,
    dumps,
    is_failed,
    read_metadata,
    read_run_rows,
    read_transcript,
    unfinished_note,
)
from jswim.viz import worlds
from jswim.viz.skeleton import figure_src, page_html, png_src, write_page, written
from jswim.viz.tracks import Track, track

#: Index columns of the run browser (one row per run), in the order of its filters.
INDEX_KEYS = (
    "run_id",
    "agent",
    "swimmer",
    "direction",
    "zeta",
    "n_ht",
    "variant",
    "group",
    "init",
    "action_set",
    "status",
    "success",
    "steps_to_learn",
    "period",
    "signed_final_x",
    "steps_to_target",
    "steps",
    "cost_usd",
)
FILTER_KEYS = (
    "agent",
    "swimmer",
    "direction",
    "zeta",
    "n_ht",
    "variant",
    "group",
    "init",
    "success",
    "status",
)

#: Longest side of an embedded figure (pixels): the figures are drawn at 300 dpi for print.
FIGURE_PX = 1400


def _axes_key(meta: Mapping[str, Any]) -> Any:
    """Sort key of runs by the study's axes: agent, swimmer, target direction, the grid's group
    order, noise level, n_ht, variant, start, then the replicate (``-r0`` before ``-r1``)."""
    import re

    agents = {a: i for i, a in enumerate(AGENT_ORDER)}
    groups = {g: i for i, g in enumerate(meta.get("group_order") or [])}
    num = lambda v: (
        float(v) if isinstance(v, (int, float)) and not isinstance(v, bool) else float("inf")
    )

    def key(row: Mapping[str, Any]) -> tuple:
        r = as_run_row(row)
        m = re.search(r"-r(\d+)$", str(r.run_id or ""))
        return (
            agents.get(r.agent, len(agents)),
            r.swimmer != "purcell",
            str(r.swimmer),
            -int(r.direction or 1),
            groups.get(r.group, len(groups)),
            str(r.group or ""),
            num(r.zeta),
            num(r.n_ht),
            str(r.variant or ""),
            str(r.init or ""),
            int(m.group(1)) if m else 0,
            str(r.run_id),
        )

    return key


def _round(a: Any, nd: int = 5) -> Any:
    return np.round(np.asarray(a, np.float64), nd).tolist()


def run_payload(t: Track) -> dict[str, Any]:
    """What the page needs to draw and explain one run (see `jswim.viz.tracks`)."""
    steps = []
    for s in t.steps_log[: t.n_steps]:
        atts = []
        for a in s.get("attempts") or []:
            if isinstance(a, dict):
                atts.append(
                    {
                        k: a.get(k)
                        for k in (
                            "text",
                            "parsed",
                            "prompt_tokens",
                            "completion_tokens",
                            "cost_usd",
                            "latency_s",
                            "retries",
                            "cache_hit",
                            "shared",
                            "finish_reason",
                            "constraint",
                            "replayed",
                        )
                        if k in a
                    }
                )
        steps.append(
            {
                "prompt": s.get("prompt"),
                "attempts": atts,
                "options": s.get("options"),
                "n_clears": s.get("n_clears"),
                "x_before": s.get("x_before"),
                "x_after": s.get("x_after"),
            }
        )
    return {
        "planar": bool(t.model.planar),
        "model": t.model.label,
        "label": t.label,
        # Zermelo's row is a point's path: no body, no strokes (jswim.agents.zermelo)
        "point": t.agent == "zermelo",
        "n_dof": t.model.n_dof,
        "lo": t.model.lo,
        "hi": t.model.hi,
        "x": _round(t.x),
        "y": _round(t.y),
        "theta": _round(t.theta),
        "pts": _round(t.points, 4),
        "dofs": _round(t.dofs, 4),
        "dof_names": t.dof_names,
        # every swimmer (N + 1, S, P, 2) and its position (N + 1, S, 2); the wall and obstacles
        "bodies": _round(t.bodies, 4),
        "pos": _round(t.positions, 4),
        # in a flow, its arrows over the run's view (still fluid: no "flow" key, as before)
        **worlds.payload(
            t.world,
            worlds.view_box([t.bodies], [t.world], not t.model.planar, pad=1.0)
            if t.world.flow
            else None,
        ),
        "actions": [list(a) for a in t.actions],
        "stuck": t.stuck.astype(int).tolist(),
        "cleared": t.cleared.astype(int).tolist(),
        "failed": t.failed.astype(int).tolist(),
        "stroke": list(t.stroke) if t.stroke else None,
        "success": t.success,
        "replayed": t.replayed,
        "direction": t.direction,
        "steps": steps,
        "error": t.row.get("error"),
    }


def _finite(obj: Any) -> Any:
    """``obj`` with every NaN or infinity as ``None`` (the page's JSON has no such numbers)."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    return obj


def _blob(obj: Any) -> str:
    raw = json.dumps(_finite(obj), separators=(",", ":"), allow_nan=False).encode()
    return base64.b64encode(gzip.compress(raw, compresslevel=6, mtime=0)).decode("ascii")


def _figure_data(paths: Sequence[Path]) -> list[dict[str, str]]:
    from PIL import Image

    out = []
    for p in paths:
        with Image.open(p) as im:
            im.load()
            if max(im.size) > FIGURE_PX:
                im.thumbnail((FIGURE_PX, FIGURE_PX), Image.LANCZOS)
            buf = io.BytesIO()
            im.save(buf, format="PNG", optimize=True)
        out.append({"name": p.stem, "src": png_src(buf.getvalue())})
    return out


def _drawn_figures(
    study: str, rows: Sequence[Mapping[str, Any]], note: str | None
) -> list[dict[str, str]]:
    """The study's figures drawn in memory (no file written), as PNG data URIs."""
    figs = plots.study_figures(study, [r for r in rows if not is_failed(r)], note=note)
    return [{"name": name, "src": figure_src(fig, dpi=170)} for name, fig in figs.items()]


def _figures(
    folder: Path, study: str, rows: Sequence[Mapping[str, Any]], note: str | None, figures: str
) -> tuple[list[dict[str, str]], str]:
    """Figures for the page and a line saying where they come from.

    ``figures``: ``"files"`` (the folder's ``figures/*.png``), ``"draw"`` (drawn now, in memory),
    ``"auto"`` (the files when they are newer than the last finished run, else drawn), ``"none"``.
    """
    if figures == "none" or not rows:
        return (
            [],
            "no figures (drawn without them; jswim report FOLDER adds them)"
            if rows
            else "no finished runs yet",
        )
    pngs = sorted((folder / "figures").glob("*.png")) if (folder / "figures").is_dir() else []
    # In the study's order of importance (the navigation study's ratio first), not by name.
    by_name = {p.stem: p for p in pngs}
    pngs = [by_name[n] for n in plots.figure_order(study, by_name)]
    runs_file = folder / "runs.jsonl"
    fresh = (
        bool(pngs)
        and runs_file.exists()
        and all(p.stat().st_mtime >= runs_file.stat().st_mtime for p in pngs)
    )
    if figures == "files" or (figures == "auto" and fresh):
        if pngs:
            return _figure_data(pngs), "figures: the folder's figures/*.png"
    return _drawn_figures(
        study, rows, note
    ), "figures: drawn from the runs when this page was written"


def _status(meta: Mapping[str, Any], rows: Sequence[Mapping[str, Any]]) -> tuple[bool, str]:
    planned = meta.get("n_planned")
    done = len([r for r in rows if not is_failed(r)])
    status = meta.get("status", "unknown")
    finished = status == "complete" and (not isinstance(planned, int) or done >= planned)
    if finished:
        return True, f"complete: {done} runs"
    of = f" of {planned}" if isinstance(planned, int) else ""
    return False, f"UNFINISHED STUDY: {done}{of} runs done (status {status})"


def _summary_html(study: str, rows: Sequence[Mapping[str, Any]]) -> str:
    """The study's tables (`jswim.studies.tables.study_tables`), its summary first."""
    from jswim.studies.overview import study_tables  # lazy: the tables load the study kinds (JAX)

    tables = study_tables(study, rows)
    if not tables:
        return "<p>No finished runs yet.</p>"
    return "".join(
        (f"<h3>{html.escape(t.title.capitalize())}</h3>" if t.heading else "")
        + _table_html(t.columns, t.cells, t.key)
        + f'<p class="note">{html.escape(" ".join(t.notes))}</p>'
        for t in tables
    )


def range_notes_of(rows: Sequence[Mapping[str, Any]]) -> list[str]:
    """The physics models ``rows`` used outside their stated range (`jswim.scenes.ranges`), each
    once: the lines a run warned of, for the page."""
    from jswim.scenes import Scene  # lazy: the scenes load JAX
    from jswim.scenes.ranges import range_notes  # lazy: as above

    notes: dict[str, None] = {}
    for swimmer, scene in {(r.swimmer, r.scene) for r in as_run_rows(rows) if r.scene}:
        try:
            sc = Scene.from_dict(json.loads(scene))
        except (ValueError, TypeError):  # a damaged row: its page still draws
            continue
        notes.update(dict.fromkeys(range_notes(str(swimmer), sc)))
    return list(notes)


def _ranges_html(rows: Sequence[Mapping[str, Any]]) -> str:
    notes = range_notes_of(rows)
    return "".join(
        f'<p class="note range" id="model-range-{i}">outside the model\'s range: {html.escape(n)}</p>'
        for i, n in enumerate(notes)
    )


def _table_html(cols: Sequence[Any], cells: Sequence[Sequence[str]], table_id: str) -> str:
    head = "".join(
        f'<th class="{"num" if c.numeric else ""}">{html.escape(c.header)}</th>' for c in cols
    )
    body = "".join(
        "<tr>"
        + "".join(
            f'<td class="{"num" if c.numeric else ""}">{html.escape(v)}</td>'
            for c, v in zip(cols, r)
        )
        + "</tr>"
        for r in cells
    )
    return (
        f'<div class="table-wrap"><table class="summary" id="{table_id}"><thead><tr>{head}</tr></thead>'
        f"<tbody>{body}</tbody></table></div>"
    )


def _settings(meta: Mapping[str, Any]) -> dict[str, Any]:
    """The metadata shown as settings: everything but the summary (shown as the table) and the
    (long) prompt template, which has its own block."""
    return {k: v for k, v in meta.items() if k not in ("summary", "prompt_template")}


#: Settings that shape what an LLM is sent or the moves a learner is offered: nothing to say of a
#: study of fixed strokes alone.
_AGENT_SETTINGS = ("action_set", "x_min", "n_ht", "constrain", "max_tokens", "temperature")
#: Settings shown in the full record only (the compact block shows what defines this study).
_NOT_COMPACT = ("horizon", "share_identical")


def applicable_settings(
    meta: Mapping[str, Any], rows: Sequence[Mapping[str, Any]] | None = None
) -> list[tuple[str, str]]:
    """``(name, value)`` of the settings that apply to the folder's study, for the settings block.

    From the identity's options and the recorded grid: values left unset (``None``) and options
    or grid axes the study has no use for (its `jswim.studies.study.Study.ignores`; a
    study's own options only on that study) are left out; the full record
    stays one click away. ``agents`` are those that ran (``rows``, where given), the success
    rule the study's own (a navigation study's: the target reached within its budget).
    """
    from jswim.studies.specs import own_options  # lazy: the study kinds load JAX
    from jswim.studies.study import find  # lazy: as above

    study = str(meta.get("study", "?"))
    spec = find(study)
    ident = meta.get("identity") or {}
    ignores = set(spec.ignores if spec else ())
    owned = set(own_options())
    out: list[tuple[str, str]] = [("study", study)]
    backend = ident.get("backend") or {}
    # A study of fixed strokes alone has no LLM and no learner: no model, and none of the
    # settings that shape a prompt or the moves on offer.
    strokes_only = _strokes_only(study)
    if backend and _names_a_model(meta, as_run_rows(rows or ())):
        # A sweep sets each run's temperature: the backend's own is not what the runs used.
        swept = (meta.get("grid") or {}).get("temperatures") or (
            spec.temperatures if spec else None
        )
        temperature = "per run (temperatures below)" if swept else backend.get("temperature")
        out.append(
            (
                "model",
                f"{backend.get('model')} ({backend.get('kind')}), temperature {temperature}, "
                f"constrain {backend.get('constrain')}",
            )
        )
        if swept and not (meta.get("grid") or {}).get("temperatures"):
            out.append(("temperatures", ", ".join(f"{t:g}" for t in swept)))
    fmt = lambda v: ", ".join(map(str, v)) if isinstance(v, (list, tuple)) else str(v)
    ran = _agents_ran(rows)

    def own(k: str) -> bool:
        return k not in ignores and (k not in owned or (spec is not None and k in spec.own_options))

    grid = meta.get("grid") or {}
    for k, v in sorted((ident.get("options") or {}).items()):
        if v is None or not own(k) or k in _NOT_COMPACT or (strokes_only and k in _AGENT_SETTINGS):
            continue
        if k == "agents" and ran:
            v = ran
        if k == "flow":  # named with its speeds and layout; still fluid ("") goes unsaid
            if v:
                out.append(("flow", study_flow_text(str(v), grid.get("flows") or ())))
            continue
        notes = spec.setting_notes if spec else {}
        out.append((k, notes.get(k, "{v}").format(v=fmt(v))))
    variants = meta.get("llm_variants")
    if spec is not None and spec.variants_grid and isinstance(variants, list) and variants:
        out.append(("llm_variants", fmt(variants)))
    levels = meta.get("roc_levels")
    said_levels = isinstance(levels, list) and bool(levels) and levels != [1]
    if said_levels:  # the paper's K = 1 goes unsaid; K = 0 is the real-valued ROCs of PPO
        lattice = ", ".join(str(k) for k in levels if k)
        real = "real-valued ROCs (PPO)" if 0 in levels else ""
        out.append(("roc_levels", "; ".join(t for t in (lattice, real) if t)))
    for k, v in sorted(grid.items()):
        if v is None or not own(k) or (k == "roc_levels_grid" and said_levels):
            continue
        if k == "flows":  # the flow's line says them (and still fluid has none)
            continue
        out.append((k, fmt(v)))
    if spec is not None and not spec.judged:  # navigation: success is the target reached
        from jswim.env.targets import BUDGET_SAFETY  # lazy: as own_options

        out.append(
            (
                "success rule",
                "the target reached: the centroid within the target's radius of it (a path: its "
                "last waypoint; a moving target: where it is then) within the target's step budget "
                f"(the steering controller's estimated steps times {BUDGET_SAFETY:g}, unless --steps)",
            )
        )
    elif meta.get("success_criterion"):
        out.append(
            (
                "success criterion",
                fmt(meta["success_criterion"])
                if not isinstance(meta["success_criterion"], Mapping)
                else json.dumps(meta["success_criterion"], sort_keys=True),
            )
        )
    return out


def study_flow_text(kind: str, fractions: Sequence[float]) -> str:
    """The settings' line of a study's background flow: its kind, its speeds in units of the
    swimming speed and what it is at the fastest (`jswim.env.flows.study_flow`)."""
    speeds = ", ".join(f"{float(f):g}" for f in fractions) or "?"
    text = f"{kind} at {speeds} times the swimming speed v = {SWIM_SPEED:.4f} a/step"
    try:
        fastest = study_flow(kind, max((float(f) for f in fractions), default=1.0) or 1.0)
    except ConfigError:  # a kind this version does not know: its name is all there is to say
        return text
    return (
        f"{text}; at {fastest.speed / SWIM_SPEED:g} v: {flow_text(fastest).split('; ')[0]}. "
        "Zermelo's optimal point steerer joins the agents as the least-time reference"
    )


def _strokes_only(study: str) -> bool:
    """Whether ``study`` runs fixed strokes alone (the school: it has no use for ``--runs``)."""
    from jswim.studies.study import find  # lazy: the study kinds load JAX

    spec = find(study)
    return spec is not None and spec.strokes_only


def _names_a_model(meta: Mapping[str, Any], rows: Sequence[Any]) -> bool:
    """Whether the page names an LLM: some run is the LLM's, or the grid plans LLM runs (not
    ``--runs 0``, not a study of fixed strokes alone). The title and the settings ask it alike."""
    if any(r.agent == "llm" for r in rows):
        return True
    return (meta.get("grid") or {}).get("runs") != 0 and not _strokes_only(str(meta.get("study")))


def _agents_ran(rows: Sequence[Mapping[str, Any]] | None) -> list[str]:
    """The agents of ``rows`` in the page's order (`AGENT_ORDER`, then as they come)."""
    names = list(dict.fromkeys(r.agent for r in as_run_rows(rows or ())))
    known = [a for a in AGENT_ORDER if a in names]
    return known + [a for a in names if a not in known]


def _settings_html(meta: Mapping[str, Any], rows: Sequence[Mapping[str, Any]] = ()) -> str:
    rows = "".join(
        f"<tr><th>{html.escape(k)}</th><td>{html.escape(v)}</td></tr>"
        for k, v in applicable_settings(meta, rows)
    )
    return (
        f'<table class="settings" id="settings-table"><tbody>{rows}</tbody></table>'
        '<details id="full-record"><summary>the full record (metadata.json, every setting recorded)</summary>'
        f"<pre>{html.escape(json.dumps(_settings(meta), indent=2, sort_keys=True, default=str))}</pre></details>"
    )


def _script_json(obj: Any) -> str:
    """JSON safe inside ``<script>``: no ``</`` can end the element early."""
    return dumps(obj, separators=(",", ":")).replace("</", "<\\/").replace("<!--", "<\\!--")


def report_html(
    folder: str | Path, figures: str = "auto", beside: Sequence[str | Path] = ()
) -> str:
    """The page of a study folder (see the module docstring); reads the folder only.

    Parameters
    ----------
    folder : path
        A study folder, finished or not.
    figures : {"auto", "files", "draw", "none"}
        Where the figures come from (see `_figures`).
    beside : sequence of paths
        Other study folders whose baseline runs (Q-learning, random) are shown beside this
        folder's in the summary, the figures (then drawn) and the run list: a bench's model
        part next to the bench's baselines of that part (`beside_rows`).

    Raises
    ------
    ResultFolderError
        Not a study folder (no ``metadata.json``) or unreadable metadata.
    """
    folder = Path(folder)
    meta = read_metadata(folder)
    own = read_run_rows(folder)
    study = str(meta.get("study", "?"))
    finished, status_text = _status(meta, own)
    note = (
        None if finished else unfinished_note(meta.get("status"), len(own), meta.get("n_planned"))
    )
    extra = []
    if beside:
        extra = beside_rows([Path(b) for b in beside])
        figures = (
            "none" if figures == "none" else "draw"
        )  # the folder's own files lack the baselines
    rows = sorted(
        grid_order(own + extra, meta), key=_axes_key(meta)
    )  # by the study's axes, not finishing order
    figs, fig_source = _figures(folder, study, rows, note, figures)
    if extra:
        fig_source += (
            "; with the bench's Q-learning and random runs of this part beside the model's ("
            + ", ".join(sorted({f"{Path(b).parent.name}/{Path(b).name}" for b in beside}))
            + ")"
        )
    backend = (meta.get("identity") or {}).get("backend") or {}
    # A study with no LLM run (--runs 0: baselines only) names no model.
    model = backend.get("model") if _names_a_model(meta, own) else None
    index, blobs = [], []
    for i, r in enumerate(rows):
        entry = {k: r.get(k) for k in INDEX_KEYS}
        entry["i"] = i
        index.append(entry)
        if r.x:
            t = track(
                r,
                read_transcript(folder, r.run_id)
                if r.agent == "llm" and not r.other.get("beside")
                else None,
            )
            blobs.append(f'<script type="text/plain" id="run-{i}">{_blob(run_payload(t))}</script>')
        else:
            blobs.append(
                f'<script type="text/plain" id="run-{i}">{_blob({"error": r.error, "x": []})}</script>'
            )
    data = {
        "study": study,
        "model": model,
        "finished": finished,
        "status": status_text,
        "folder": folder.name,
        "filters": list(FILTER_KEYS),
        "runs": index,
        "written": written(),
    }
    title = f"jswim {study} study" + (f" · LLM: {model}" if model else "")
    template = meta.get("prompt_template")
    figures_html = "".join(
        f'<figure><img alt="{html.escape(f["name"])}" src="{f["src"]}"/><figcaption>{html.escape(f["name"])}'
        f" ({html.escape(title)})</figcaption></figure>"
        for f in figs
    )
    body = [
        f'<section id="summary"><h2>Summary</h2>{_ranges_html(rows)}{_summary_html(study, rows)}</section>',
        f'<section id="figures"><h2>Figures</h2><p class="note">{html.escape(fig_source)}</p>{figures_html}</section>',
        '<section id="browser"><h2>Runs</h2><div id="filters"></div><p id="run-count"></p>'
        '<div class="browser"><div id="run-list-wrap"><table id="run-list"></table></div>'
        '<div id="viewer"><p id="viewer-empty">Pick a run.</p></div></div></section>',
        '<section id="settings"><h2>Settings and identity</h2>',
        _settings_html(meta, rows),
        (
            "<details><summary>prompt template</summary><pre>"
            f"{html.escape(json.dumps(template, indent=2, sort_keys=True))}</pre></details>"
            if template
            else ""
        ),
        "</section>",
        f'<script type="application/json" id="report-data">{_script_json(data)}</script>',
        *blobs,
    ]
    return page_html(
        title,
        finished=finished,
        status=status_text,
        folder=folder.name,
        meta=[
            f"jswim {html.escape(str(meta.get('jswim_version', '?')))}",
            f"page written {data['written']}",
        ],
        nav=[
            ("summary", "summary"),
            ("figures", "figures"),
            ("browser", "runs"),
            ("settings", "settings"),
        ],
        body=body,
        script=True,
    )


def write_report(
    folder: str | Path,
    figures: str = "auto",
    out: str | Path | None = None,
    beside: Sequence[str | Path] = (),
) -> Path:
    """Write ``report.html`` into ``folder`` (or to ``out``) atomically; nothing else is written.

    Raises
    ------
    ResultFolderError
        Not a study folder; [`jswim.results.StudyFolderError`][jswim.results.StudyFolderError] if the page cannot be written.
    """
    return write_page(report_html(folder, figures=figures, beside=beside), Path(folder), out)


def beside_rows(folders: Sequence[Path]) -> list[RunRow]:
    """Baseline runs (Q-learning, random) of other study folders, to draw beside a model's.

    Each row gains ``beside``, the folder it came from (in `RunRow.other`: no run column).
    """
    out: list[RunRow] = []
    for f in folders:
        out += [
            dataclasses.replace(r, other={**r.other, "beside": str(f)})
            for r in read_run_rows(f)
            if r.agent != "llm"
        ]
    return out
