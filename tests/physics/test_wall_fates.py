"""The wall study's default horizon shows every fate: its stroke rows (the square gait of the
study's own start, the study's own plans and fate rule) at the default heights and steps come out
trapped, escaped and gliding; and the scene default is the exact self-mobility near contact."""

import pytest

from jswim.scenes import Scene
from jswim.studies import StudyOptions
from jswim.studies import scenes
from jswim.studies.grids import SPECS, build


def test_wall_study_defaults_are_long_enough_for_fates():
    assert SPECS["wall"].steps >= 400 and StudyOptions().steps is None
    assert min(StudyOptions().heights) <= 2.0 and max(StudyOptions().heights) >= 10.0
    # fates below 1.5 a rest on Brenner's normal mobility, not the RPB series
    assert Scene(medium="wall").self_mobility == "exact"


@pytest.mark.slow  # 400 steps of the coupled wall solve at six heights: ~1 min under load
def test_wall_study_stroke_rows_show_trapped_escaped_and_gliding():
    plans = [
        p
        for p in build("wall", StudyOptions(agents=("stroke",)))
        if p.agent == "stroke" and p.group.startswith("h=")
    ]
    assert plans and all(p.steps == SPECS["wall"].steps for p in plans)
    rows = [r for p in plans for r in scenes.run_baselines([p], 50)]  # one scene per call
    fates = {r["start_height"]: r["fate"] for r in rows}
    assert set(fates.values()) == set(scenes.FATES), fates
    low = min(fates)
    assert fates[low] == "trapped" and fates[max(fates)] == "gliding"
