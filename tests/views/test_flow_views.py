"""Pictures of navigation in a background flow (jswim.figures.flow_plots and the pictures that
draw a run's world): the flow figures exist only where rows ran in a flow, the paths lie over
the flow's streamlines with Zermelo's dashed, unreachable targets are marked, the page's table,
settings and run canvas show the flow, and ``jswim animate`` draws it under the swimmer. A
still-fluid folder lists exactly what it listed before. Screenshots go to test-artifacts/.

The folders are written by hand (rows as the study writes them, `jswim.studies.navigate`): a
study in a flow takes minutes on this machine, a figure of its rows seconds.
"""

from __future__ import annotations

import base64
import dataclasses
import gzip
import json
import math
import os
import re
from pathlib import Path

import numpy as np
import pytest
from matplotlib.collections import LineCollection
from matplotlib.colors import to_rgba

from jswim.env.flows import SWIM_SPEED, Uniform, flow_json, study_flow
from jswim.figures.flow_plots import FLOW_COLOR, flow_figures
from jswim.figures.plots import study_figures
from jswim.results import read_run_rows
from jswim.viz import animate as anim_mod
from jswim.viz.page import report_html
from jswim.viz.publish import report
from tests.browser import browser_or_skip, open_report_run

ARTIFACTS = os.environ.get("JSWIM_TEST_ARTIFACTS", "test-artifacts")
FRACTIONS = (0.0, 0.6, 1.5)
BEARINGS = (90.0, -90.0)  # the uniform stream runs along +y: at 1.5 v the target at -90 is lost
AGENTS = ("controller", "random", "zermelo")
OLD_FIGURES = {"navigate-paths", "navigate-energy", "navigate-bearing"}
FLOW_FIGURES = {"navigate-flow-paths", "navigate-flow-success", "navigate-flow-energy"}


def _row(agent: str, bearing: float, f: float, flow: bool = True) -> dict:
    """One run as the navigation study writes it (a fixed target 3 a away)."""
    v, u = SWIM_SPEED, f * SWIM_SPEED
    target = (0.0, 3.0 if bearing > 0 else -3.0)
    reachable = not (bearing < 0 and f >= 1)
    best = 3.0 / (v + u if bearing > 0 else v - u) if reachable else None
    n = {
        "controller": math.ceil(1.3 * (best or 60)),
        "random": 60,
        "zermelo": math.ceil(best or 40),
    }[agent]
    t = np.arange(1, n + 1) / n
    drift = u * np.arange(1, n + 1)  # the stream carries every swimmer along +y
    if agent == "random":
        x, y = 0.3 * np.sin(6 * t), 0.2 * np.cos(5 * t) - 0.2 + drift
    elif not reachable:  # heads for it, swept back
        x, y = 0.1 * t, -v * np.arange(1, n + 1) + drift
    else:
        x, y = 0.8 * np.sin(np.pi * t), target[1] * t
        if agent == "zermelo":
            x = 0 * t
    reached = agent != "random" and reachable
    steps = n if reached else None
    row = {
        "run_id": f"{agent}-purcell-px-i++-z0-K2-d3b{bearing:g}-uniform{f:g}-r0",
        "agent": agent,
        "swimmer": "purcell",
        "direction": 1,
        "zeta": 0.0,
        "init": "" if agent == "zermelo" else "++",
        "roc_levels": 2,
        "group": f"fixed d=3 b={bearing:g}" + (f", uniform {f:g}v" if flow else ""),
        "status": "done",
        "steps": n,
        "success": reached,
        "x": x.tolist(),
        "y": y.tolist(),
        "orientation": [math.pi / 2] * n,
        "actions": [] if agent == "zermelo" else [[1 + k % 2, 1] for k in range(n)],
        "energy": None if agent == "zermelo" else 60.0,
        "energy_per_distance": None
        if agent == "zermelo"
        else 20.0 / (1 + f) + 30 * (agent == "random"),
        "target": json.dumps(
            {"bearing": bearing, "budget": None, "distance": 3.0, "kind": "fixed", "radius": 0.25},
            sort_keys=True,
        ),
        "reached": reached,
        "steps_to_target": steps,
    }
    if flow:
        row.update(
            flow=flow_json(study_flow("uniform", f) if f > 0 else Uniform((0.0, 0.0))),
            flow_fraction=f,
            reachable=reachable,
            zermelo_steps=best,
            time_ratio=steps / best if steps and best else None,
        )
    return row


def _folder(path: Path, flow: bool = True) -> Path:
    rows = [
        _row(a, b, f, flow)
        for b in BEARINGS
        for f in (FRACTIONS if flow else (0.0,))
        for a in AGENTS
        if flow or a != "zermelo"
    ]
    path.mkdir(parents=True)
    options = {"agents": ["controller", "random"], "flow": "uniform" if flow else "", "seed": 0}
    grid = {"bearings": list(BEARINGS), "distances": [3.0], "flows": list(FRACTIONS), "runs": 0}
    meta = {
        "study": "navigate",
        "status": "complete",
        "n_planned": len(rows),
        "jswim_version": "test",
        "identity": {"options": options},
        "grid": grid,
    }
    (path / "metadata.json").write_text(json.dumps(meta))
    (path / "runs.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    return path


@pytest.fixture(scope="module")
def flow_folder(tmp_path_factory) -> Path:
    return _folder(tmp_path_factory.mktemp("flow") / "navigate-uniform")


@pytest.fixture(scope="module")
def still_folder(tmp_path_factory) -> Path:
    return _folder(tmp_path_factory.mktemp("still") / "navigate-still", flow=False)


@pytest.fixture(scope="module")
def flow_figs(flow_folder):
    import matplotlib.pyplot as plt

    figs = study_figures("navigate", read_run_rows(flow_folder))
    yield figs
    for fig in figs.values():
        plt.close(fig)


def _flow_lines(ax) -> list:
    rgba = to_rgba(FLOW_COLOR)
    return [
        c
        for c in ax.collections
        if isinstance(c, LineCollection)
        and len(c.get_segments())
        and np.allclose(c.get_colors()[0], rgba)
    ]


def _blob(page: str, i: int) -> dict:
    m = re.search(rf'<script type="text/plain" id="run-{i}">([^<]*)</script>', page)
    return json.loads(gzip.decompress(base64.b64decode(m.group(1))))


def _index(page: str) -> list[dict]:
    m = re.search(r'<script type="application/json" id="report-data">(.*?)</script>', page, re.S)
    return json.loads(m.group(1))["runs"]


# -- figures ---------------------------------------------------------------------------------------


def test_flow_figures_only_where_rows_ran_in_a_flow(flow_folder, still_folder, flow_figs):
    assert set(flow_figs) == OLD_FIGURES | FLOW_FIGURES
    still = study_figures("navigate", read_run_rows(still_folder))
    assert set(still) == OLD_FIGURES  # a still-fluid folder: exactly today's figures
    assert flow_figures(read_run_rows(still_folder)) == {}
    # Rates in different flows are never averaged: one bearing panel per flow speed.
    titles = [ax.get_title() for ax in flow_figs["navigate-bearing"].axes]
    assert titles == ["targets 3 a away\nstill fluid"] + [
        f"targets 3 a away\nuniform {f:g} v" for f in FRACTIONS[1:]
    ]
    assert [ax.get_title() for ax in still["navigate-bearing"].axes] == ["targets 3 a away"]


def test_paths_lie_over_the_streamlines_with_zermelo_dashed(flow_figs):
    fig = flow_figs["navigate-flow-paths"]
    axes = [ax for ax in fig.axes if ax.get_visible()]
    assert len(axes) == len(BEARINGS) * len(FRACTIONS)  # one panel per target and flow speed
    for ax in axes:
        moving = "uniform 0 v" not in ax.get_title() and "still" not in ax.get_title()
        # Streamlines wherever the fluid moves; none in the still reference.
        assert bool(_flow_lines(ax)) == moving, ax.get_title()
        if moving:  # under the paths
            assert max(c.get_zorder() for c in _flow_lines(ax)) < min(
                ln.get_zorder() for ln in ax.get_lines()
            )
        labels = {ln.get_label(): ln for ln in ax.get_lines()}
        assert labels["Zermelo (least time)"].get_linestyle() == "--"
        assert {"steering controller", "random policy"} <= set(labels)
    lost = [ax for ax in axes if "b=-90" in ax.get_title() and "1.5 v" in ax.get_title()]
    assert len(lost) == 1 and any("unreachable" in t.get_text() for t in lost[0].texts)
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "flow streamlines" in legend and "Zermelo (least time)" in legend


def test_success_and_time_ratio_mark_the_unreachable_target(flow_figs):
    fig = flow_figs["navigate-flow-success"]
    (top90, top270), (low90, low270) = np.asarray(fig.axes).reshape(2, 2)
    assert top90.get_title() == "fixed d=3 b=90" and top270.get_title() == "fixed d=3 b=-90"
    for ax in (top90, low90, top270, low270):  # every flow speed on every panel's axis
        lo, hi = ax.get_xlim()
        assert lo < 0 < 1.5 < hi
    agents = {"steering controller", "random policy"}
    assert {ln.get_label() for ln in top90.get_lines()} == agents
    controller = next(ln for ln in top90.get_lines() if ln.get_label() == "steering controller")
    assert list(controller.get_ydata()) == [1.0, 1.0, 1.0]
    # The lost target: hatched (its flow speed only) and labelled on both panels, not dropped.
    for ax in (top270, low270):
        hatched = [p for p in ax.patches if p.get_hatch()]
        assert len(hatched) == 1
        x0, x1 = hatched[0].get_x(), hatched[0].get_x() + hatched[0].get_width()
        assert x0 < 1.5 < x1 and x0 > 0.6
        assert any(t.get_text() == "unreachable" for t in ax.texts)
    assert not [p for p in top90.patches if p.get_hatch()]
    # Time over Zermelo's: the controller's ratio where it reached the target, none where lost.
    ratio = next(
        ln for ln in low270.get_lines() if ln.get_color() == "black" and ln.get_marker() == "x"
    )
    y = np.asarray(ratio.get_ydata(), float)
    assert np.all(y[:2] > 1.0) and np.isnan(y[2])
    assert any(ln.get_label() == "Zermelo (least time)" for ln in low90.get_lines())
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "unreachable (Zermelo cannot reach the target)" in legend


def test_energy_against_flow_speed_per_agent(flow_figs):
    fig = flow_figs["navigate-flow-energy"]
    assert len(fig.axes) == len(BEARINGS)
    for ax in fig.axes:
        assert {ln.get_label() for ln in ax.get_lines()} == {"steering controller", "random policy"}
        assert ax.get_yscale() == "log" and ax.get_xlabel() == "flow / swim speed"
        controller = next(ln for ln in ax.get_lines() if ln.get_label() == "steering controller")
        assert np.allclose(controller.get_ydata(), [20.0 / (1 + f) for f in FRACTIONS])
    assert any(t.get_text() == "unreachable" for t in fig.axes[1].texts)


@pytest.mark.slow  # six figures at 300 dpi, PNG and PDF: ~10 CPU-s
def test_publish_writes_the_flow_figures(flow_folder, tmp_path):
    import shutil

    from PIL import Image

    folder = tmp_path / "f"
    shutil.copytree(flow_folder, folder)
    pub = report(folder)
    pngs = {p.stem: p for p in pub.figures if p.suffix == ".png"}
    assert set(pngs) == OLD_FIGURES | FLOW_FIGURES
    for name in FLOW_FIGURES:
        with Image.open(pngs[name]) as im:
            assert min(im.size) > 300
            assert len(np.unique(np.asarray(im.convert("L")))) > 10  # drawn, not blank
        assert (folder / "figures" / f"{name}.pdf").stat().st_size > 1000


# -- the page ----------------------------------------------------------------------------------------


def test_page_table_settings_and_canvas_data_show_the_flow(flow_folder):
    page = report_html(flow_folder, figures="none")
    table = page[
        page.index('id="summary-table"') : page.index("</table>", page.index('id="summary-table"'))
    ]
    heads = re.findall(r"<th[^>]*>([^<]*)</th>", table)
    assert {"flow speed", "reachable", "time ratio"} <= set(heads)
    assert len({"Zermelo", "Zermelo steps"} & set(heads)) == 1  # his least time, once
    assert len(heads) == len(set(heads))
    assert ">1.5 v</td>" in table and ">no</td>" in table  # the lost target says so
    settings = page[page.index('id="settings-table"') : page.index('id="full-record"')]
    assert "<th>flow</th>" in settings and "<th>flows</th>" not in settings
    assert "uniform at 0, 0.6, 1.5 times the swimming speed" in settings
    assert "uniform stream" in settings and "Zermelo" in settings
    runs = _index(page)
    i = next(
        r["i"] for r in runs if r["run_id"] == "controller-purcell-px-i++-z0-K2-d3b90-uniform0.6-r0"
    )
    d = _blob(page, i)
    assert d["flow"]["label"] == "uniform 0.6 v"
    assert "background flow: uniform stream" in d["flow"]["legend"]
    arrows = np.asarray(d["flow"]["arrows"])
    assert len(arrows) > 50 and np.allclose(arrows[:, 3], 0.6 * SWIM_SPEED, atol=1e-5)
    assert np.allclose(arrows[:, 2], 0.0) and d["flow"]["max"] == pytest.approx(0.6 * SWIM_SPEED)
    # The arrows cover the run's path and its target.
    assert arrows[:, 0].min() < -0.5 and arrows[:, 0].max() > 0.8
    assert arrows[:, 1].min() < 0 and arrows[:, 1].max() > 3.25
    assert "flow: uniform 0.6 v" in d["world"]


def test_still_fluid_page_lists_what_it_listed(still_folder):
    page = report_html(still_folder, figures="draw")
    names = re.findall(r'<figure><img alt="([^"]+)"', page)
    assert set(names) == OLD_FIGURES
    table = page[
        page.index('id="summary-table"') : page.index("</table>", page.index('id="summary-table"'))
    ]
    heads = re.findall(r"<th[^>]*>([^<]*)</th>", table)
    assert heads == ["target", "agent", "reached", "steps", "path ratio", "energy", "energy/dist"]
    settings = page[page.index('id="settings-table"') : page.index('id="full-record"')]
    assert "<th>flow</th>" not in settings and "<th>flows</th>" not in settings
    for r in _index(page):
        d = _blob(page, r["i"])
        assert "flow" not in d and "flow" not in d["world"]


# -- the animation -------------------------------------------------------------------------------------


def _flow_artists(fig) -> list:
    return [a for ax in fig.axes for a in ax.get_children() if a.get_gid() == "flow"]


def test_animation_draws_the_flow_under_the_swimmer(flow_folder, still_folder):
    import matplotlib.pyplot as plt

    rows = read_run_rows(flow_folder)
    ids = [r.run_id for r in rows if r.agent == "controller" and r.flow_fraction == 0.6]
    anim = anim_mod.build(flow_folder, run_ids=ids)
    fig, draw = anim.figure()
    try:
        draw(10)
        flow = _flow_artists(fig)
        for ax in fig.axes:  # each panel's streamlines and their arrowheads
            mine = [a for a in ax.get_children() if a.get_gid() == "flow"]
            assert sum(isinstance(a, LineCollection) for a in mine) == 1 and len(mine) > 1
        swimmer = [ln for ln in fig.axes[0].get_lines() if ln.get_color() == "black"]
        assert all(a.get_zorder() < min(ln.get_zorder() for ln in swimmer) for a in flow)
        labels = [t.get_text() for ax in fig.axes for t in ax.texts if t.get_gid() == "flow-label"]
        assert labels == ["flow: uniform 0.6 v"] * len(ids)
    finally:
        plt.close(fig)
    assert anim.frame_png(10)[:4] == b"\x89PNG"
    # Still fluid: no flow layer, no label.
    still = anim_mod.build(still_folder)
    fig, draw = still.figure()
    try:
        assert _flow_artists(fig) == []
        assert not [t for ax in fig.axes for t in ax.texts if t.get_gid() == "flow-label"]
    finally:
        plt.close(fig)


def test_a_row_without_a_readable_flow_draws_none(flow_folder):
    from jswim.viz.worlds import payload, world_of

    r = dataclasses.replace(read_run_rows(flow_folder)[3], flow='{"kind": "vortex-street"}')
    w = world_of(r)
    assert w.flow_object() is None
    assert payload(w, (0, 1, 0, 1))["flow"]["arrows"] == []


# -- in a real browser -------------------------------------------------------------------------------


@pytest.mark.slow
def test_flow_page_in_chromium(flow_folder, tmp_path):
    import shutil

    folder = tmp_path / "f"
    shutil.copytree(flow_folder, folder)
    page = report(folder).page
    run = next(
        r.run_id
        for r in read_run_rows(folder)
        if r.agent == "controller" and r.flow_fraction == 0.6
    )
    still = next(
        r.run_id
        for r in read_run_rows(folder)
        if r.agent == "controller" and r.flow_fraction == 0.0
    )
    with browser_or_skip(height=1100) as b:
        open_report_run(b, page, run)
        arrows = b.eval("window.jswimReport.flowArrows()")
        legend = b.eval(
            "(() => { var e = document.getElementById('flow-legend');"
            " return e ? [e.textContent, e.offsetWidth, e.offsetHeight] : null; })()"
        )
        # Flow-blue pixels on the canvas (the fluid is #eaf3fa, the arrows #7ea6c8).
        blue = b.eval(
            "(() => { var c = document.getElementById('swim'), d = c.getContext('2d')"
            ".getImageData(0, 0, c.width, c.height).data, n = 0;"
            " for (var i = 0; i < d.length; i += 4) if (Math.abs(d[i] - 126) < 14 &&"
            " Math.abs(d[i + 1] - 166) < 14 && Math.abs(d[i + 2] - 200) < 14) n++; return n; })()"
        )
        b.screenshot(os.path.join(ARTIFACTS, "report-navigate-flow.png"))
        figs = b.eval(
            "Array.from(document.querySelectorAll('#figures img')).map(i =>"
            " [i.alt, i.naturalWidth, i.naturalHeight, i.getBoundingClientRect().width])"
        )
        open_report_run(b, page, still)  # speed 0: the legend says still fluid, no arrows
        still_arrows = b.eval("window.jswimReport.flowArrows()")
        still_legend = b.eval("document.getElementById('flow-legend').textContent")
        b.eval("document.getElementById('figures').scrollIntoView()")
        b.screenshot(os.path.join(ARTIFACTS, "report-navigate-flow-figures.png"))
        assert b.errors == []
    assert arrows > 50 and blue > 500
    assert (
        legend[0].startswith("background flow: uniform stream")
        and legend[1] > 100
        and legend[2] > 5
    )
    shown = {name: (w, h, box) for name, w, h, box in figs}
    assert set(shown) >= OLD_FIGURES | FLOW_FIGURES
    for name in FLOW_FIGURES:
        w, h, box = shown[name]
        assert w > 300 and h > 150 and box > 100
    assert still_arrows == 0 and "still fluid" in still_legend


@pytest.mark.parametrize("kind", ["uniform", "shear", "poiseuille", "taylor-green"])
def test_every_flow_kind_is_drawn_and_sampled_where_it_moves(kind):
    import matplotlib.pyplot as plt

    from jswim.figures.flow_plots import draw_flow, flow_text
    from jswim.viz.worlds import World, flow_arrows

    flow = study_flow(kind, 0.9)
    fig, ax = plt.subplots()
    try:
        drawn = draw_flow(ax, flow, (-4.0, 4.0, -4.0, 4.0))
        assert isinstance(drawn[0], LineCollection) and len(drawn[0].get_segments()) > 10
    finally:
        plt.close(fig)
    f = flow_arrows(World(flow=flow_json(flow), flow_fraction=0.9), (-1.0, 4.0, -1.0, 4.0))
    a = np.asarray(f["arrows"])
    assert np.allclose(a[:, 2:], np.asarray(flow.velocity(a[:, :2])), atol=1e-5)
    # The lattice holds the box, widened to the canvas's shape (it shows more across than up).
    assert a[:, 0].min() <= -1.0 and a[:, 0].max() >= 4.0 and a[:, 1].min() <= -1.0
    assert a[:, 0].max() - a[:, 0].min() > 2 * (a[:, 1].max() - a[:, 1].min())
    assert f["label"] == f"{kind} 0.9 v" and flow_text(flow) in f["legend"]
