"""Fates above the wall. The wall study's stroke rows (the square gait from the study's own
start, its plans and fate rule) at the default heights and horizon: trapped near the wall,
gliding above (no tilt-0 start escapes: they glide on long orbits, docs/scenes.md); a nose-up
start escapes; and the scene default is the exact self-mobility near contact."""

import pytest

from jswim.scenes import Scene
from jswim.studies import StudyOptions
from jswim.studies import baselines
from jswim.studies.specs import SPECS, build


def test_wall_study_defaults_are_long_enough_for_fates():
    assert SPECS["wall"].steps >= 400 and StudyOptions().steps is None
    assert min(StudyOptions().heights) <= 1.5 and max(StudyOptions().heights) >= 10.0
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
    rows = [r for p in plans for r in baselines.run_baselines([p], 50)]  # one scene per call
    fates = {r["start_height"]: r["fate"] for r in rows}
    assert [fates[h] for h in sorted(fates)] == ["trapped"] * 2 + ["gliding"] * 4, fates


@pytest.mark.slow  # 1200 square cycles from two starts: ~2 min under load
def test_a_nose_up_start_escapes_and_a_level_one_glides():
    import jax.numpy as jnp
    import numpy as np

    from jswim.scenes import batch_starts, scene_params, scene_rollout_batch

    p = scene_params("ng", Scene(medium="wall", height=10.0), dtype=jnp.float64)
    square = [(1, -1), (2, -1), (1, 1), (2, 1)]
    r = scene_rollout_batch(
        batch_starts(p, height=np.array([15.0, 3.0]), tilt=np.array([0.3, 0.0])), square * 1200
    )
    z = r.z[:, :, 0]
    up, level = z[0], z[1]
    assert up[-1] > 30.0 and up[-1] > up[-400] and not np.asarray(r.contact)[0].any()
    # the level start rises and comes back: a closed orbit, not an escape
    top = int(np.argmax(level))
    assert level[top] > 9.0 and level[top:].min() < level[top] - 5.0
    assert not np.asarray(r.contact)[1].any()
