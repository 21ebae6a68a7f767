"""A school's rows drawn: the school figure and the report page's world (every swimmer's start)."""

import json

from jswim.figures.scene_plots import school_figures
from jswim.viz.worlds import world_of


def _row(n, d, form, per_cycle):
    scene = {
        "medium": "free",
        "swimmers": n,
        "separation": d,
        "height": 10.0,
        "tilt": 0.0,
        "obstacles": [],
    }
    if form != "line":
        scene["formation"] = form
    return {
        "agent": "stroke",
        "scene": json.dumps(scene),
        "n_swimmers": n,
        "separation": d if n > 1 else None,
        "per_cycle": per_cycle,
        "direction": 1,
        "variant": "phase0",
        "x": [0.1, 0.2],
        "y": [10.0, 10.0],
        "steps": 2,
        "signed_final_x": 0.2,
    }


def test_school_figure_and_world():
    rows = [
        _row(1, 30.0, "line", 0.172),
        _row(3, 30.0, "line", 0.1705),
        _row(3, 30.0, "side", 0.1716),
    ]
    figs = school_figures(rows)
    assert list(figs) == ["school"]
    ax = figs["school"].axes[0]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "line, D=30" in labels and "side, D=30" in labels
    side = world_of(rows[2])
    assert side.start == (
        (0.0, 10.0, 0.0),
        (0.0, 40.0, 0.0),
        (0.0, 70.0, 0.0),
    )  # one above the other
    assert world_of(rows[1]).start[2][:2] == (60.0, 10.0)  # a line: D ahead
    assert "side by side" in side.describe() and "3 swimmers" in world_of(rows[1]).describe()
