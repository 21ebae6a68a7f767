"""A physics model used outside the range its docs give says so, once per rule and process
(docs/scenes.md: local RFT above a wall holds below ~1 link length; RPB's self terms need ~3.2
sphere radii of clearance)."""

from __future__ import annotations

import warnings

import pytest

from jswim.scenes import Scene
from jswim.scenes import ranges
from jswim.scenes.ranges import ModelRangeWarning, range_notes, warn_out_of_range


def test_local_rft_far_above_a_wall_is_out_of_range():
    (note,) = range_notes("purcell", Scene(medium="wall", height=20.0))
    assert "local-rft" in note and "beads" in note
    assert range_notes("purcell", Scene(medium="wall", height=0.8)) == ()
    assert range_notes("purcell", Scene(medium="wall", height=20.0), wall_model="beads") == ()
    assert range_notes("purcell", Scene()) == ()  # the bulk has no wall model


def test_rpb_near_contact_is_out_of_range():
    near = Scene(medium="wall", height=1.5, self_mobility="rpb")
    assert len(range_notes("ng", near)) == 1
    assert range_notes("ng", Scene(medium="wall", height=1.5)) == ()  # exact: holds there
    assert range_notes("ng", Scene(medium="wall", height=10.0, self_mobility="rpb")) == ()


def test_the_warning_is_given_once_per_process(monkeypatch):
    monkeypatch.setattr(ranges, "_warned", set())
    scene = Scene(medium="wall", height=20.0)
    with pytest.warns(ModelRangeWarning, match="outside the model's range"):
        warn_out_of_range("purcell", scene)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        warn_out_of_range("purcell", scene)  # said once: a study builds a model per cell


def test_making_the_world_warns(monkeypatch):
    import jswim

    monkeypatch.setattr(ranges, "_warned", set())
    with pytest.warns(ModelRangeWarning):
        jswim.make("purcell", Scene(medium="wall", height=20.0))


def test_point_forces_between_close_swimmers_are_out_of_range():
    # closest spheres of two swimmers: D side by side; D - 2 d_max in a line (arms at d_max = 10)
    side = Scene(medium="free", swimmers=2, separation=4.0, formation="side")
    (note,) = range_notes("ng", side)
    assert "mobility='rpy'" in note
    assert (
        range_notes("ng", Scene(medium="free", swimmers=2, separation=5.0, formation="side")) == ()
    )
    assert len(range_notes("ng", Scene(medium="free", swimmers=3, separation=24.0))) == 1
    assert range_notes("ng", Scene(medium="free", swimmers=3, separation=30.0)) == ()  # the study's
    rpy = Scene(medium="free", swimmers=2, separation=4.0, formation="side", mobility="rpy")
    assert range_notes("ng", rpy) == ()
    assert ranges.closest_gap(Scene(medium="free", swimmers=2, separation=30.0)) == 10.0
    assert ranges.closest_gap(Scene(medium="free")) is None


def test_a_study_records_its_range_notes_in_its_metadata():
    from jswim.studies.plans import Plan
    from jswim.studies.run import _range_notes
    from jswim.studies.scene_grids import scene_json

    def plan(scene):
        return Plan("r", "stroke", "ng", 1, (1, 1), 0.0, 0, 8, scene=scene_json(scene))

    close = Scene(medium="free", swimmers=2, separation=4.0, formation="side")
    far = Scene(medium="free", swimmers=2, separation=30.0)
    assert _range_notes([plan(close), plan(far), plan(close)]) == list(range_notes("ng", close))
    assert _range_notes([plan(far)]) == []
