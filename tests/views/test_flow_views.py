"""Pictures of navigation in a background flow (jswim.figures.flow_plots and the pictures that
draw a run's world): the flow figures exist only where rows ran in a flow, the paths lie over
the flow's streamlines with Zermelo's dashed, unreachable targets are marked, the page's table,
settings and run canvas show the flow, and ``jswim animate`` draws it under the swimmer. A
still-fluid folder lists exactly what it listed before. Screenshots go to test-artifacts/.

The folders are written by hand (rows as the study writes them, `jswim.studies.kinds.navigate`): a
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
from jswim.results import as_run_rows, read_run_rows
from jswim.viz import animate as anim_mod
from jswim.viz.page import report_html
from jswim.viz.publish import report
from tests.browser import browser_or_skip, open_report_run

ARTIFACTS = os.environ.get("JSWIM_TEST_ARTIFACTS", "test-artifacts")
FRACTIONS = (0.0, 0.6, 1.5)
BEARINGS = (90.0, -90.0)  # the uniform stream runs along +y: at 1.5 v the target at -90 is lost
AGENTS = ("controller", "optimal", "random", "zermelo")  # one run per cell each
Q_SEEDS = 6  # Q-learning's runs per cell: enough (>= MIN_LINE_RUNS) for its lines to join
#: Q-learning's seeds that reach the 90-degree target at each flow speed (the first k).
Q_REACHED = {0.0: 6, 0.6: 4, 1.5: 2}
OLD_FIGURES = {"navigate-paths", "navigate-energy", "navigate-bearing"}
FLOW_FIGURES = {
    "navigate-flow-ratio",
    "navigate-flow-paths",
    "navigate-flow-success",
    "navigate-flow-energy",
}
#: The flow study's figures in the page's order: the result first, the paths last.
FLOW_ORDER = [
    "navigate-flow-ratio",
    "navigate-flow-success",
    "navigate-bearing",
    "navigate-flow-energy",
    "navigate-energy",
    "navigate-flow-paths",
    "navigate-paths",
]
STILL_ORDER = ["navigate-ratio", "navigate-bearing", "navigate-energy", "navigate-paths"]
#: The page's navigation table in still fluid (jswim.studies.overview.nav_table's columns).
STILL_HEADS = [
    "target",
    "agent",
    "reached [95% CI]",
    "steps",
    "path ratio",
    "energy",
    "energy/dist",
    "optimal",
    "time ratio [95% CI]",
]


def _best(bearing: float, f: float) -> float | None:
    """Zermelo's least time (steps) in the uniform stream along +y; None where unreachable."""
    v, u = SWIM_SPEED, f * SWIM_SPEED
    if bearing < 0 and f >= 1:
        return None
    return 3.0 / (v + u if bearing > 0 else v - u)


def _own(bearing: float, f: float) -> int | None:
    """The swimmer's own least time: 15 % over Zermelo's point (it must turn)."""
    best = _best(bearing, f)
    return None if best is None else math.ceil(1.15 * best)


ZERMELO = "Zermelo's point (no turning limit, flow at its centre)"


def _row(agent: str, bearing: float, f: float, flow: bool = True, seed: int = 0) -> dict:
    """One run as the navigation study writes it (a fixed target 3 a away)."""
    v, u = SWIM_SPEED, f * SWIM_SPEED
    target = (0.0, 3.0 if bearing > 0 else -3.0)
    best, own = _best(bearing, f), _own(bearing, f)
    reachable = best is not None
    q_reaches = reachable and seed < (Q_REACHED[f] if bearing > 0 else Q_SEEDS)
    n = {
        "controller": math.ceil(1.3 * (best or 60)),
        "qlearning": math.ceil((1.2 + 0.1 * seed) * best) if q_reaches else 70,
        "optimal": own or 60,
        "random": 60,
        "zermelo": math.ceil(best or 40),
    }[agent]
    t = np.arange(1, n + 1) / n
    drift = u * np.arange(1, n + 1)  # the stream carries every swimmer along +y
    if agent == "random":
        x, y = 0.3 * np.sin(6 * t), 0.2 * np.cos(5 * t) - 0.2 + drift
    elif not reachable or (agent == "qlearning" and not q_reaches):  # heads for it, swept back
        x, y = 0.1 * t, -v * np.arange(1, n + 1) + drift
    else:
        x, y = 0.8 * np.sin(np.pi * t), target[1] * t
        if agent == "zermelo":
            x = 0 * t
    reached = agent != "random" and reachable and (agent != "qlearning" or q_reaches)
    steps = n if reached else None
    row = {
        "run_id": f"{agent}-purcell-px-i++-z0-K2-d3b{bearing:g}-uniform{f:g}-r{seed}",
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
        else 20.0 / (1 + f) + 30 * (agent == "random") + 5 * (agent == "qlearning"),
        "target": json.dumps(
            {"bearing": bearing, "budget": None, "distance": 3.0, "kind": "fixed", "radius": 0.25},
            sort_keys=True,
        ),
        "reached": reached,
        "steps_to_target": steps,
        # The swimmer's own optimum and the time over it: every navigation row, still fluid too.
        "optimal_steps": own,
        "time_ratio": (best if agent == "zermelo" else steps) / own if steps and own else None,
    }
    if flow:
        row.update(
            flow=flow_json(study_flow("uniform", f) if f > 0 else Uniform((0.0, 0.0))),
            flow_fraction=f,
            reachable=reachable,
            zermelo_steps=best,
            zermelo_ratio=steps / best if steps and best else None,
        )
    return row


def _folder(path: Path, flow: bool = True) -> Path:
    rows = [
        _row(a, b, f, flow, seed)
        for b in BEARINGS
        for f in (FRACTIONS if flow else (0.0,))
        for a in (*AGENTS, "qlearning")
        if flow or a != "zermelo"
        for seed in range(Q_SEEDS if a == "qlearning" else 1)
    ]
    path.mkdir(parents=True)
    options = {
        "agents": ["controller", "optimal", "qlearning", "random"],
        "flow": "uniform" if flow else "",
        "seed": 0,
    }
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


def _by_gid(ax, gid: str) -> list:
    """The artists of ``ax`` drawn with ``gid`` (`jswim.figures.navigation_plots.draw_series`'s
    ``points:AGENT``, ``bars:AGENT``, ``joins:AGENT``)."""
    return [a for a in ax.get_children() if a.get_gid() == gid]


def _bars(ax, agent: str) -> list[tuple[float, float, float]]:
    """``(x, lo, hi)`` of each of an agent's error bars on ``ax``."""
    (bars,) = _by_gid(ax, f"bars:{agent}")
    return [(seg[0][0], seg[0][1], seg[1][1]) for seg in bars.get_segments()]


def _ys(ax, gid: str) -> np.ndarray:
    (line,) = _by_gid(ax, gid)
    return np.asarray(line.get_ydata(), float)


def _words(fig) -> str:
    """Every text of a figure: titles, labels, tick labels, legends and notes."""
    out = [t.get_text() for t in fig.texts]
    if fig._suptitle is not None:
        out.append(fig._suptitle.get_text())
    for ax in fig.axes:
        out += [ax.get_title(), ax.get_xlabel(), ax.get_ylabel()]
        out += [t.get_text() for t in ax.get_xticklabels() + ax.texts]
    for leg in fig.legends:
        out += [t.get_text() for t in leg.get_texts()]
    return "\n".join(out)


def test_flow_figures_only_where_rows_ran_in_a_flow(flow_folder, still_folder, flow_figs):
    assert set(flow_figs) == OLD_FIGURES | FLOW_FIGURES
    still = study_figures("navigate", read_run_rows(still_folder))
    # Still fluid: today's figures and the ratio to the swimmer's own optimum (its rows have it).
    assert set(still) == OLD_FIGURES | {"navigate-ratio"}
    assert flow_figures(read_run_rows(still_folder)) == {}
    # A still folder of an earlier jswim (no optimum): exactly the figures it had.
    old = [
        {k: v for k, v in r.items() if k not in ("optimal_steps", "time_ratio")}
        for r in read_run_rows(still_folder)
    ]
    assert set(study_figures("navigate", old)) == OLD_FIGURES
    # Rates in different flows are never averaged: one bearing panel per flow speed.
    titles = [ax.get_title() for ax in flow_figs["navigate-bearing"].axes]
    assert titles == ["targets 3 a away\nstill fluid"] + [
        f"targets 3 a away\nuniform {f:g} v" for f in FRACTIONS[1:]
    ]
    assert [ax.get_title() for ax in still["navigate-bearing"].axes] == ["targets 3 a away"]


def test_figures_come_in_order_of_importance(flow_figs, still_folder, flow_folder, tmp_path):
    import shutil

    from PIL import Image

    from jswim.figures.plots import figure_order

    assert list(flow_figs) == FLOW_ORDER  # the ratio first, success second, the paths last
    assert list(study_figures("navigate", read_run_rows(still_folder))) == STILL_ORDER
    assert figure_order("navigate", sorted(FLOW_ORDER)) == FLOW_ORDER
    assert figure_order("curves", ["b", "a"]) == ["a", "b"]  # other studies: by name
    # The folder's files (listed by name) go on the page in that order too.
    folder = tmp_path / "f"
    shutil.copytree(flow_folder, folder)
    (folder / "figures").mkdir()
    for name in FLOW_ORDER:
        Image.new("RGB", (4, 4)).save(folder / "figures" / f"{name}.png")
    page = report_html(folder, figures="files")
    assert re.findall(r'<figure><img alt="([^"]+)"', page) == FLOW_ORDER


def test_every_flow_figure_names_its_flow(flow_figs):
    for name, fig in flow_figs.items():
        assert "uniform" in _words(fig), name
    for name in FLOW_FIGURES - {"navigate-flow-paths"}:  # and each of its panels
        for ax in flow_figs[name].axes:
            if ax.get_visible():
                assert ax.get_title().endswith("\nuniform flow"), (name, ax.get_title())


def test_ratio_to_the_optimum_with_intervals_and_zermelos_point(flow_figs):
    from jswim.judging.stats import median_interval

    fig = flow_figs["navigate-flow-ratio"]
    b90, b270 = fig.axes
    assert (b90.get_title(), b270.get_title()) == (
        "fixed d=3 b=90\nuniform flow",
        "fixed d=3 b=-90\nuniform flow",
    )
    # Q-learning's six seeds in still fluid: the median and its bootstrap 95 % interval.
    best, own = _best(90.0, 0.0), _own(90.0, 0.0)
    ratios = [math.ceil((1.2 + 0.1 * s) * best) / own for s in range(Q_SEEDS)]
    m, lo, hi = median_interval(ratios)
    assert lo < m < hi
    assert _ys(b90, "points:qlearning")[0] == pytest.approx(m)
    x, blo, bhi = _bars(b90, "qlearning")[0]
    assert (blo, bhi) == pytest.approx((lo, hi)) and x == pytest.approx(0.0, abs=0.05)
    # The controller's one run a cell: its ratio, no line between its cells.
    ctrl = [math.ceil(1.3 * _best(90.0, f)) / _own(90.0, f) for f in FRACTIONS]
    assert np.allclose(_ys(b90, "points:controller"), ctrl)
    assert _by_gid(b90, "joins:controller") == [] and _by_gid(b270, "joins:controller") == []
    # Q-learning reached at 90 degrees with 6, 4, 2 seeds: no cell pair of 5 to join; at -90
    # with 6 and 6 (then unreachable): one line, its two cells.
    assert _by_gid(b90, "joins:qlearning") == []
    joined = _ys(b270, "joins:qlearning")
    assert np.isfinite(joined[:2]).all() and np.isnan(joined[2])
    # The optimum's own rows are the line at 1, the random policy never reached: no series.
    assert not _by_gid(b90, "points:optimal") and not _by_gid(b90, "points:random")
    assert any(list(ln.get_ydata()) == [1.0, 1.0] for ln in b90.get_lines())
    # Zermelo's point: its own line, his least time over the swimmer's (below 1: no turning).
    zermelo = _ys(b90, "zermelo-ratio")
    assert np.allclose(zermelo, [_best(90.0, f) / _own(90.0, f) for f in FRACTIONS])
    assert np.all(zermelo < 1)
    assert np.isnan(_ys(b270, "zermelo-ratio")[2])  # unreachable at 1.5 v
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "Zermelo's point (no turning limit, flow at its centre)" in legend
    assert "Q-learning (n=6)" in legend and "steering controller (n=1)" in legend
    assert "optimal (the swimmer's own least time) = 1" in legend


def test_an_older_flow_folder_draws_its_ratio_to_zermelo(flow_folder):
    from jswim.figures.flow_plots import flow_ratio_figure

    # Rows of an earlier jswim: time_ratio was the ratio to Zermelo, no optimum.
    old = []
    for r in read_run_rows(flow_folder):
        d = {k: v for k, v in r.items() if k not in ("optimal_steps", "time_ratio")}
        old.append({**d, "time_ratio": d.pop("zermelo_ratio", None)})
    fig = flow_ratio_figure(as_run_rows(old))  # read as an old folder is
    b90 = fig.axes[0]
    ctrl = [math.ceil(1.3 * _best(90.0, f)) / _best(90.0, f) for f in FRACTIONS]
    assert np.allclose(_ys(b90, "points:controller"), ctrl)
    assert not _by_gid(b90, "zermelo-ratio")  # he is the yardstick here: the line at 1
    assert "older folder" in _words(fig) and "Zermelo's least" in b90.get_ylabel()


def test_success_with_wilson_intervals_and_no_line_under_five_runs(flow_figs):
    from jswim.judging.stats import wilson_interval

    fig = flow_figs["navigate-flow-success"]
    b90, b270 = fig.axes
    for ax in (b90, b270):  # every flow speed on every panel's axis
        lo, hi = ax.get_xlim()
        assert lo < 0 < 1.5 < hi
    # Q-learning: 6, 4 and 2 of 6 seeds; Wilson's intervals; a line (6 runs a cell).
    k = [Q_REACHED[f] for f in FRACTIONS]
    assert np.allclose(_ys(b90, "points:qlearning"), [v / Q_SEEDS for v in k])
    for (_, blo, bhi), kk in zip(_bars(b90, "qlearning"), k):
        assert (blo, bhi) == pytest.approx(wilson_interval(kk, Q_SEEDS))
    assert np.allclose(_ys(b90, "joins:qlearning"), [v / Q_SEEDS for v in k])
    # The controller: one run a cell, 1 of 1 each (Wilson: 0.21 to 1); markers, no line.
    assert list(_ys(b90, "points:controller")) == [1.0, 1.0, 1.0]
    for _, blo, bhi in _bars(b90, "controller"):
        assert (blo, bhi) == pytest.approx(wilson_interval(1, 1)) and blo < 0.25
    for agent in ("controller", "optimal", "random"):
        assert _by_gid(b90, f"joins:{agent}") == [] and _by_gid(b270, f"joins:{agent}") == []
    # The lost target: hatched (its flow speed only) and labelled, not dropped.
    hatched = [p for p in b270.patches if p.get_hatch()]
    assert len(hatched) == 1
    x0, x1 = hatched[0].get_x(), hatched[0].get_x() + hatched[0].get_width()
    assert x0 < 1.5 < x1 and x0 > 0.6
    assert any(t.get_text() == "unreachable" for t in b270.texts)
    assert not [p for p in b90.patches if p.get_hatch()]
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert "unreachable (Zermelo cannot reach the target)" in legend
    assert {"Q-learning (n=6)", "steering controller (n=1)", "random policy (n=1)"} <= set(legend)


def test_bearing_success_has_intervals_and_joins_only_full_cells(flow_figs):
    from jswim.judging.stats import wilson_interval

    still, mid, fast = flow_figs["navigate-bearing"].axes[:3]
    # At 0.6 v: Q-learning 6 of 6 at -90 degrees, 4 of 6 at 90; joined (6 runs a cell).
    assert np.allclose(_ys(mid, "joins:qlearning"), [1.0, 4 / 6])
    bounds = [v for b in _bars(mid, "qlearning") for v in b[1:]]
    assert bounds == pytest.approx([*wilson_interval(6, 6), *wilson_interval(4, 6)])
    for ax in (still, mid, fast):
        assert _by_gid(ax, "joins:controller") == []


def test_energy_against_flow_speed_per_agent(flow_figs):
    fig = flow_figs["navigate-flow-energy"]
    assert len(fig.axes) == len(BEARINGS)
    for ax in fig.axes:
        assert ax.get_yscale() == "log" and ax.get_xlabel() == "flow / swim speed"
        ctrl = _ys(ax, "points:controller")
        assert np.allclose(ctrl, [20.0 / (1 + f) for f in FRACTIONS])
        assert _by_gid(ax, "joins:controller") == []  # one run a cell: no line
        assert len(_by_gid(ax, "joins:qlearning")) == 1
    assert any(t.get_text() == "unreachable" for t in fig.axes[1].texts)


@pytest.mark.slow  # seven figures at 300 dpi, PNG and PDF: ~10 CPU-s
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
    # The study's columns (jswim.studies.overview.nav_table), then the page's flow columns.
    assert heads[:9] == STILL_HEADS
    assert {"Zermelo ratio", "flow speed", "reachable"} <= set(heads)
    assert len({"Zermelo", "Zermelo steps"} & set(heads)) == 1  # his least time, once
    assert len(heads) == len(set(heads))
    assert ">1.5 v</td>" in table and ">no</td>" in table  # the lost target says so
    assert ">4/6 [0.30-0.90]</td>" in table  # Q-learning at 90 degrees, 0.6 v: Wilson's interval
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
    assert names == STILL_ORDER  # the ratio to the optimum first (its rows have it)
    table = page[
        page.index('id="summary-table"') : page.index("</table>", page.index('id="summary-table"'))
    ]
    heads = re.findall(r"<th[^>]*>([^<]*)</th>", table)
    assert heads == STILL_HEADS  # no flow column
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
