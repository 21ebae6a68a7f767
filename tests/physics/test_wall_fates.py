"""Fates above the wall. The wall study's stroke rows (the square gait from the study's own
start, its plans and fate rule) at the default heights, tilts and horizon: trapped near the
wall, gliding above (no level start escapes: they glide on long orbits, docs/scenes.md), and
escaped from the default nose-up start at 10 a; a nose-up start escapes over a long run too;
and the scene default is the exact self-mobility near contact."""

import json

import numpy as np
import pytest

from jswim.scenes import Scene
from jswim.studies import StudyOptions
from jswim.studies import baselines
from jswim.studies import get
from jswim.studies.specs import build


FREE_CYCLE = (
    0.17209144  # the square stroke per cycle in the unbounded point-force solve (docs/scenes.md)
)


def test_wall_study_defaults_are_long_enough_for_fates():
    assert get("wall").steps >= 400 and StudyOptions().steps is None
    assert min(StudyOptions().heights) <= 1.5 and max(StudyOptions().heights) >= 10.0
    # level starts and one nose-up start; the tilted one runs where it clears the wall
    assert 0.0 in StudyOptions().tilts and max(StudyOptions().tilts) > 0.5
    # fates below 1.5 a rest on Brenner's normal mobility, not the RPB series
    assert Scene(medium="wall").self_mobility == "exact"


@pytest.mark.slow  # 400 steps of the coupled wall solve from eight starts: ~1 min under load
def test_wall_study_stroke_rows_show_trapped_escaped_and_gliding():
    plans = [
        p
        for p in build("wall", StudyOptions(agents=("stroke",)))
        if p.agent == "stroke" and p.group.startswith("h=")
    ]
    assert plans and all(p.steps == get("wall").steps for p in plans)
    rows = [r for p in plans for r in baselines.baseline_rows([p], 50)]  # one scene per call
    fates = {(r["start_height"], json.loads(r["scene"])["tilt"]): r["fate"] for r in rows}
    level = [fates[k] for k in sorted(fates) if k[1] == 0.0]
    assert level == ["trapped"] * 2 + ["gliding"] * 4, fates
    tilted = {k: f for k, f in fates.items() if k[1] != 0.0}
    # 0.8 rad clears the wall from 10 a up; from 10 a it doubles its height within the horizon
    assert tilted == {(10.0, 0.8): "escaped", (50.0, 0.8): "gliding"}, fates
    assert set(fates.values()) == {"trapped", "escaped", "gliding"}
    # the escape is self-propulsion along the axis: far from the wall the swimmer rises at the
    # free stroke's speed times sin(tilt), cycle by cycle (the wall turns it nose down slowly)
    up = next(r for r in rows if json.loads(r["scene"])["tilt"] and r["start_height"] == 10.0)
    z = np.array([h[0] for h in up["heights"]])
    tilt = np.array([t[0] for t in up["tilts"]])
    rise = FREE_CYCLE * np.sin(np.concatenate([[0.8], tilt[3::4][:-1]])).sum()
    assert z[-1] - 10.0 == pytest.approx(rise, rel=0.05)


@pytest.mark.slow  # 1200 square cycles from two starts: ~2 min under load
def test_a_nose_up_start_escapes_and_a_level_one_glides():
    import jax.numpy as jnp
    import numpy as np

    from jswim.env import scene_rollout_batch
    from jswim.scenes import batch_starts, scene_params

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
