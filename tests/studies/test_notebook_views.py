"""What a notebook shows: study progress as one throttled display, short reprs with HTML ones."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from jswim import console, reprs
from jswim.studies.run import StudyResult


class _Handle:
    def __init__(self, shown: list) -> None:
        self.shown = shown

    def update(self, obj) -> None:
        self.shown.append(("update", obj))


@pytest.fixture
def displays(monkeypatch):
    """IPython's ``display`` recorded instead of sent to a frontend."""
    ipd = pytest.importorskip("IPython.display")
    shown: list = []

    def display(obj, display_id=False):
        shown.append(("display", obj))
        return _Handle(shown)

    monkeypatch.setattr(ipd, "display", display)
    return shown


def test_notebook_progress_is_one_display_updated_at_most_every_interval(displays):
    bar = console.NotebookProgress(interval=10.0)
    for i in range(200):  # a study's 0.5 s live ticks and finished runs, as fast as they come
        bar.update("LLM runs", i, 200, f"{i} steps", unit="LLM steps")
    bar.update("done", 200, 200, final=True, unit="LLM steps")
    kinds = [k for k, _ in displays]
    assert kinds == ["display", "update"]  # the first state, then the final one
    last = displays[-1][1]
    assert "200/200 LLM steps (100%)" in repr(last)
    assert '<progress value="200" max="200"' in last._repr_html_()


def test_a_new_phase_is_drawn_at_once(displays):
    bar = console.NotebookProgress(interval=10.0)
    bar.update("Q-learning", 1, 4)
    bar.update("Q-learning", 2, 4)  # within the interval: not drawn
    bar.update("LLM runs", 0, 40)
    assert [repr(o).split("] ")[1] for _, o in displays] == [
        "Q-learning: 1/4 runs (25%)",
        "LLM runs: 0/40 runs (0%)",
    ]


def test_study_progress_choices(capsys, monkeypatch):
    monkeypatch.setattr(console, "in_notebook", lambda: False)

    def mine(*a):
        return None

    with console.study_progress(mine) as tick:
        assert tick is mine  # a callable is used as given
    with console.study_progress(False) as tick:
        assert tick is None
    with console.study_progress(None) as tick:  # no notebook, stderr not a terminal: quiet
        assert tick is None
    with console.study_progress(True) as tick:  # asked for: dated lines on stderr
        tick("llm", 3, 10, "")
    err = capsys.readouterr().err
    assert "LLM runs: 3/10 LLM steps (30%)" in err and "done: 3/10" in err


def test_an_interrupted_study_says_so_in_its_progress(displays, monkeypatch):
    monkeypatch.setattr(console, "in_notebook", lambda: True)
    with pytest.raises(KeyboardInterrupt), console.study_progress(None) as tick:
        tick("llm", 5, 10, "")
        raise KeyboardInterrupt
    assert repr(displays[-1][1]).split("] ")[1].startswith("interrupted: 5/10 LLM steps")


def _result(tmp_path: Path, figures: list[Path]) -> StudyResult:
    summary = [
        {"agent": "llm", "group": f"zeta={z}", "n": 4, "success_rate": 0.25, "mean_x": 0.1}
        for z in (0, 0.1, 0.2)
    ]
    rows = [{"run_id": f"r{i}", "agent": "llm"} for i in range(12)]
    (tmp_path / "metadata.json").write_text('{"study": "noise"}')
    return StudyResult(tmp_path, rows, summary, figures, wall_s=3.21, total=12)


def test_study_result_repr_is_a_few_lines_and_its_html_a_table_with_thumbnails(tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 6))
    ax.plot([0, 1], [0, 1])
    png = tmp_path / "noise.png"
    fig.savefig(png, dpi=100)  # 800 px wide
    plt.close(fig)
    res = _result(tmp_path, [png])
    assert isinstance(res.summary, pd.DataFrame) and len(res.summary) == 3
    text = repr(res)
    assert text.splitlines()[0] == "StudyResult noise: complete; 12 of 12 runs, in 3.2 s"
    assert len(text.splitlines()) == 3 and "jswim.load" in text
    page = res._repr_html_()
    assert page.count("</tr>") == 1 + 3  # header and the three settings
    assert page.count("<img") == 1 and "jswim.load(" in page
    assert len(page) < png.stat().st_size  # a thumbnail, not the figure itself


def test_trajectory_repr_names_steps_and_final_x_not_the_arrays():
    from jswim.env.rollouts import Rollout

    steps = np.arange(1, 41, dtype=np.float32)
    r = Rollout(
        x=0.05 * steps, y=0 * steps, orientation=0 * steps, dofs=np.zeros((40, 2)),
        stuck=steps < 0, progress=0 * steps,
    )  # fmt: skip
    text = repr(r)
    assert len(text.splitlines()) == 2 and len(text) < 200
    assert text.startswith("Rollout: 40 steps; final X 2\n")
    batch = Rollout(*(np.stack([f, f]) for f in r))
    assert repr(batch).startswith("Rollout: 2 rollouts x 40 steps; final X 2, 2\n")
    assert "<img" in r._repr_html_()


def test_world_html_draws_the_paper_swimmer_and_only_facts_otherwise():
    import jswim

    env, _ = jswim.make("ng")
    page = env._repr_html_()
    assert "<img" in page and "D1, D2" in page
    assert "<img" not in reprs.world_html(env)  # no outline given: facts only


def test_a_loaded_study_shows_its_settings_table(tmp_path):
    import json

    import jswim

    groups = [
        {"agent": "llm", "group": "zeta=0", "n": 2},
        {"agent": "llm", "group": "zeta=1", "n": 2},
    ]
    meta = {
        "study": "noise",
        "status": "interrupted",
        "n_planned": 8,
        "summary": {"groups": groups},
    }
    (tmp_path / "metadata.json").write_text(json.dumps(meta))
    (tmp_path / "runs.jsonl").write_text("")
    study = jswim.load(tmp_path)
    assert repr(study).splitlines()[0] == "Study noise: interrupted; 0 of 8 runs"
    page = study._repr_html_()
    assert page.count("</tr>") == 1 + 2 and "zeta=1" in page
