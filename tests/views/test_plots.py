"""One image test per figure kind: axis labels, series count, one panel per target direction.

The rows are synthetic: runs toward +x move +x, runs toward -x move -x, so a figure that pooled the
two directions (or plotted raw X) would show a mean near 0 or negative; the target-direction mean
is positive in every panel.
"""

from __future__ import annotations

import numpy as np
import pytest
from matplotlib.container import ErrorbarContainer
from PIL import Image

from jswim import figures
from jswim.figures import plots
from jswim.results import unfinished_note

SPEED = {"llm": 0.04, "qlearning": 0.02, "random": 0.0}


def _rows(
    agents=("llm", "qlearning", "random"),
    swimmers=("ng", "purcell"),
    directions=(1, -1),
    runs=3,
    steps=12,
    **extra,
):
    rows = []
    for sw in swimmers:
        for d in directions:
            for agent in agents:
                for k in range(runs):
                    v = SPEED[agent] * (1 + 0.1 * k)
                    x = [d * v * (n + 1) for n in range(steps)]
                    rows.append(
                        {
                            "run_id": f"{agent}-{sw}-{d}-{k}",
                            "agent": agent,
                            "swimmer": sw,
                            "direction": d,
                            "init": "++",
                            "x": x,
                            "final_x": x[-1],
                            "signed_final_x": d * x[-1],
                            "success": agent == "llm" and k > 0,
                            "steps_to_learn": 2 if agent == "llm" and k > 0 else None,
                            "period": 4,
                            "actions": [[2, -1], [1, -1], [2, 1], [1, 1]] * (steps // 4),
                            "group": "",
                            "zeta": 0.0,
                            "n_ht": None,
                            **extra,
                        }
                    )
    return rows


def _panels(fig):
    return [ax for ax in fig.axes if ax.get_title() and ax.axison and ax.get_xlabel() != ""]


def _labelled_lines(ax):
    return [ln for ln in ax.get_lines() if not ln.get_label().startswith("_")]


def _saved_width_in(fig, tmp_path, name):
    paths = figures.save(fig, tmp_path, name, dpi=100)
    assert [p.suffix for p in paths] == [".png", ".pdf"] and all(
        p.stat().st_size > 0 for p in paths
    )
    return Image.open(paths[0]).size[0] / 100


def test_curves_plot_target_direction_per_panel(tmp_path):
    rows = _rows()
    fig = figures.curves_figure(rows, cycles=figures.learned_cycles(rows))
    panels = [ax for ax in fig.axes if ax.get_xlabel() == "step n"]
    titles = [ax.get_title() for ax in panels]
    assert titles == [
        "Purcell three-link, target +x",
        "Purcell three-link, target \u2212x",
        "NG three-sphere, target +x",
        "NG three-sphere, target \u2212x",
    ]
    for ax in panels:
        minus = "\u2212x" in ax.get_title()
        assert ax.get_ylabel() == ("\u2212X/a" if minus else "X/a")
        lines = _labelled_lines(ax)
        # one mean per agent and the signature-gait reference, never a pooled mean
        assert sorted(
            ln.get_label().split(",")[0]
            for ln in lines
            if ln.get_label() != figures.REFERENCE_STYLE["label"]
        ) == ["LLM", "Q-learning", "random policy"]
        llm = next(ln for ln in lines if ln.get_label().startswith("LLM"))
        expected = SPEED["llm"] * np.mean([1.0, 1.1, 1.2]) * 12
        assert llm.get_ydata()[-1] == pytest.approx(expected)  # positive toward -x too
    ref = next(
        ln
        for ln in _labelled_lines(panels[0])
        if ln.get_label() == figures.REFERENCE_STYLE["label"]
    )
    # Purcell's square gait from (+,+): 0.19124724 a per 4-step cycle (DESIGN.md), 3 cycles in 12 steps
    assert ref.get_ydata()[12] == pytest.approx(3 * 0.19124724, rel=1e-6)
    sketches = [ax for ax in fig.axes if ax.get_title().startswith("stroke cycle learned by LLM")]
    assert len(sketches) == 4
    assert _saved_width_in(fig, tmp_path, "curves") <= figures.PAGE_IN + 0.05


def test_curves_single_panel_fits_one_column_and_has_no_blank_sketch_row(tmp_path):
    rows = [
        r for r in _rows(agents=("random",)) if r["swimmer"] == "purcell" and r["direction"] == 1
    ]
    fig = figures.curves_figure(
        rows, cycles=figures.learned_cycles(rows), note="UNFINISHED STUDY: 3 of 9 runs"
    )
    assert fig.get_size_inches()[0] == figures.COLUMN_IN
    assert not figures.learned_cycles(rows)
    assert len([ax for ax in fig.axes if ax.axison]) == 1  # no empty row for a cycle nobody learned
    assert fig._suptitle is not None and "UNFINISHED" in fig._suptitle.get_text()
    assert _saved_width_in(fig, tmp_path, "one") <= figures.COLUMN_IN + 0.05


def test_history_has_one_series_per_n_ht_and_none_hidden():
    rows = []
    for h in (1, 2, 4, 8):
        rows += [
            {**r, "n_ht": h, "run_id": f"{r['run_id']}-h{h}"}
            for r in _rows(agents=("llm",), runs=1)
        ]
    fig = figures.history_figure(rows)
    panels = [ax for ax in fig.axes if ax.get_xlabel() == "step n"]
    assert len(panels) == 4
    for ax in panels:
        series = [ln for ln in _labelled_lines(ax) if ln.get_label().startswith("n_ht")]
        assert [ln.get_label() for ln in series] == ["n_ht = 1", "n_ht = 2", "n_ht = 4", "n_ht = 8"]
        # identical curves here: each later one is thinner and on top, so the first stays visible
        widths = [ln.get_linewidth() for ln in series]
        assert widths == sorted(widths, reverse=True) and len(set(widths)) == 4
        assert len({ln.get_marker() for ln in series}) == 4
        assert series[0].get_ydata()[-1] > 0


@pytest.mark.parametrize(
    "kind",
    [  # each draws and saves a grid figure (~2.3 CPU-s): one in the fast tier
        "noise",
        pytest.param("ablation", marks=pytest.mark.slow),
        pytest.param("inits", marks=pytest.mark.slow),
    ],
)
def test_grid_figures_show_p_and_mean_per_agent_and_direction(kind, tmp_path):
    if kind == "noise":
        rows = [
            {**r, "zeta": z, "run_id": f"{r['run_id']}-{z}"}
            for z in (0.0, 0.5, 3.0)
            for r in _rows()
        ]
        fig = figures.noise_figure(rows)
        n_values, agents = 3, 3
    elif kind == "ablation":
        rows = [
            {**r, "group": g, "run_id": f"{r['run_id']}-{g}"}
            for g in ("full", "-S1", "-S3")
            for r in _rows(agents=("llm",))
        ]
        fig = figures.ablation_figure(rows)
        n_values, agents = 3, 1
    else:
        rows = [
            {**r, "group": f"init {g}", "run_id": f"{r['run_id']}-{g}"}
            for g in ("++", "-+")
            for r in _rows(agents=("llm",))
        ]
        fig = figures.inits_figure(rows)
        n_values, agents = 2, 1
    p_axes = [ax for ax in fig.axes if ax.get_ylabel().startswith("success rate p")]
    x_axes = [ax for ax in fig.axes if ax.get_ylabel().startswith("mean")]
    assert len(p_axes) == len(x_axes) == 4
    assert [ax.get_title() for ax in p_axes] == [
        "Purcell three-link, target +x",
        "NG three-sphere, target +x",
        "Purcell three-link, target \u2212x",
        "NG three-sphere, target \u2212x",
    ]
    for ax in p_axes + x_axes:
        bars = [c for c in ax.containers if isinstance(c, ErrorbarContainer)]
        assert len(bars) == agents
        xs = np.concatenate([c.lines[0].get_xdata() for c in bars])
        assert len(set(np.round(xs, 9))) == agents * n_values  # offset: no two agents' bars on top
        colors = {c.lines[0].get_color() for c in bars}
        assert len(colors) == agents
    for i, ax in enumerate(x_axes):
        minus = i >= 2  # the second column is the -x target
        assert ax.get_ylabel().startswith("mean \u2212X/a" if minus else "mean X/a")
        llm = next(
            c
            for c in ax.containers
            if isinstance(c, ErrorbarContainer) and c.get_label().startswith("LLM")
        )
        assert np.all(llm.lines[0].get_ydata() > 0)  # target-direction displacement, not raw X
    bottom = [ax for ax in fig.axes if ax.get_xlabel()]
    assert bottom and all(ax.get_xlabel() != "group" for ax in bottom)
    if kind == "ablation":
        assert [t.get_text() for t in bottom[0].get_xticklabels()] == [
            "full",
            "\u2212S1",
            "\u2212S3",
        ]
    assert _saved_width_in(fig, tmp_path, kind) <= figures.PAGE_IN + 0.05


def test_noise_figure_for_one_direction_fits_one_column(tmp_path):
    rows = [{**r, "zeta": z} for z in (0.0, 1.0) for r in _rows(directions=(1,))]
    fig = figures.noise_figure(rows)
    assert fig.get_size_inches()[0] == figures.COLUMN_IN
    assert _saved_width_in(fig, tmp_path, "noise1") <= figures.COLUMN_IN + 0.05


def test_competence_panels_per_direction():
    rows = [
        {**r, "entry": r["agent"] if r["agent"] == "llm" else f"{r['agent']} (all)"}
        for r in _rows()
    ]
    fig = figures.competence_figure(rows, ["llm", "qlearning (all)", "random (all)"])
    titles = [ax.get_title() for ax in fig.axes]
    assert sum("success rate p" in t for t in titles) == 4
    assert any("target \u2212x: mean \u2212X/a" in t for t in titles)
    for ax in fig.axes:
        assert len([c for c in ax.containers if isinstance(c, ErrorbarContainer)]) == 3


def test_unfinished_note():
    assert unfinished_note("complete", 10, 10) is None
    assert unfinished_note("complete", 10, None) is None
    assert unfinished_note("running", 4, 10) == "UNFINISHED STUDY: 4 of 10 runs done (running)"


def test_temperature_figure_shows_p_steps_to_learn_with_iqr_and_k_of_n():
    # Four runs per T: steps to learn 4, 6, 8 and one that never learned at T=0; none learned at T=1.
    rows = []
    for sw in ("purcell", "ng"):
        for d in (1, -1):
            for t, steps in ((0.0, [4, 6, 8, None]), (1.0, [None] * 4)):
                for k, s in enumerate(steps):
                    rows.append(
                        {
                            "run_id": f"{sw}{d}{t}{k}",
                            "agent": "llm",
                            "swimmer": sw,
                            "direction": d,
                            "temperature": t,
                            "success": s is not None,
                            "steps_to_learn": s,
                            "signed_final_x": 0.1 * d,
                            "final_x": 0.1,
                            "group": f"T={t:g}",
                        }
                    )
    fig = figures.study_figures("temperature", rows)["temperature"]
    learn = [ax for ax in fig.axes if ax.get_ylabel().startswith("steps to learn")]
    assert len(learn) == 4  # both swimmers and both directions
    for ax in learn:
        (bars,) = [c for c in ax.containers if isinstance(c, ErrorbarContainer)]
        x, y = bars.lines[0].get_data()
        assert list(x) == [0.0] and list(y) == [6.0]  # only T=0 has a median: of 4, 6, 8
        (seg,) = bars.lines[2][0].get_segments()
        assert seg[0][1] == pytest.approx(5.0) and seg[1][1] == pytest.approx(
            7.0
        )  # the IQR of 4, 6, 8
        assert sorted(
            t.get_text() for t in ax.texts if "/" in t.get_text() and ":" not in t.get_text()
        ) == ["0/4", "3/4"]
    assert sum(ax.get_ylabel().startswith("success rate") for ax in fig.axes) == 4
    # X/a equal everywhere, up to rounding (-8e-17 where a swimmer never moved): a readable axis.
    rows = [{**r, "signed_final_x": -8.3e-17 * (1 + i % 2)} for i, r in enumerate(rows)]
    fig = figures.study_figures("temperature", rows)["temperature"]
    for ax in (ax for ax in fig.axes if ax.get_ylabel().startswith("mean")):
        lo, hi = ax.get_ylim()
        assert hi - lo >= 0.1


def test_continuous_figures_returns_one_grid_and_a_curve_per_lattice(monkeypatch):
    # The study's figure selection, its drawing stubbed: the grid over K and one curves figure per group.
    monkeypatch.setattr(plots, "grid_figure", lambda rows, key, **kw: ("grid", key))
    monkeypatch.setattr(
        plots, "curves_figure", lambda rows, cycles=None, note=None: ("curves", len(rows))
    )
    monkeypatch.setattr(plots, "learned_cycles", lambda rows: {})
    rows = [{"group": g} for g in ("K=1", "K=2", "K=2", "continuous")]
    figs = figures.study_figures("continuous", rows)
    assert figs == {
        "continuous": ("grid", "group"),
        "continuous-K1": ("curves", 1),
        "continuous-K2": ("curves", 2),
        "continuous-real": ("curves", 1),
    }
