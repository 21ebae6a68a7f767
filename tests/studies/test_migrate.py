"""Records of earlier jswim versions in today's form (`jswim.results.migrate`): each old form the
module translates, written here by hand, and a folder holding them read through every reader."""

from __future__ import annotations

import json
import warnings

from jswim.results import StudyStore, read_metadata, read_run_rows, read_runs
from jswim.results.migrate import migrate_metadata, migrate_row

WALL = json.dumps({"medium": "wall", "height": 2.5, "swimmers": 1})


def test_an_old_name_is_renamed_at_any_depth_and_unknown_fields_kept():
    old = {"run_id": "a", "allowed": "two", "extra": {"allowed": 1}, "list": [{"allowed": 2}]}
    assert migrate_row(old) == {
        "run_id": "a",
        "action_set": "two",
        "extra": {"action_set": 1},
        "list": [{"action_set": 2}],
    }
    assert old["allowed"] == "two"  # the caller's record is left as it was


def test_a_purcell_wall_row_without_plane_height_swims_at_the_scene_height():
    old = {"run_id": "a", "swimmer": "purcell", "medium": "wall", "scene": WALL}
    assert migrate_row(old)["plane_height"] == 2.5
    as_dict = {**old, "scene": {"height": 3}}  # a scene given as an object (a user's dict)
    assert migrate_row(as_dict)["plane_height"] == 3.0
    # NG, the free fluid, a row that says it, an unreadable scene: nothing derived
    assert "plane_height" not in migrate_row({**old, "swimmer": "ng"})
    assert "plane_height" not in migrate_row({**old, "medium": "free"})
    assert migrate_row({**old, "plane_height": None})["plane_height"] is None
    assert "plane_height" not in migrate_row({**old, "scene": "not json"})
    assert "plane_height" not in migrate_row({**old, "scene": json.dumps({"height": 10**400})})


def test_a_flow_row_before_the_optimum_had_its_ratio_to_zermelo_as_time_ratio():
    old = {"run_id": "a", "zermelo_steps": 8.0, "steps_to_target": 12, "time_ratio": 1.5}
    new = migrate_row(old)
    assert new["zermelo_ratio"] == 1.5 and "time_ratio" not in new
    today = {**old, "optimal_steps": 10, "time_ratio": 1.2, "zermelo_ratio": 1.5}
    assert migrate_row(today) == today  # a row with its optimum: already today's
    still = {"run_id": "a", "steps_to_target": 12, "time_ratio": 1.2}  # no flow: no Zermelo
    assert migrate_row(still) == still


def test_migrating_twice_changes_nothing():
    old = {
        "run_id": "a",
        "allowed": "all",
        "swimmer": "purcell",
        "medium": "wall",
        "scene": WALL,
        "zermelo_steps": 8.0,
        "time_ratio": 1.5,
    }
    once = migrate_row(old)
    assert migrate_row(once) == once
    meta = {"identity": {"options": {"allowed": "all"}}, "grid": {"runs": 2}}
    assert migrate_metadata(migrate_metadata(meta)) == migrate_metadata(meta)


def test_old_metadata_gets_todays_names_and_its_one_grid_as_grids():
    old = {
        "study": "swim",
        "identity": {"study": "swim", "options": {"allowed": "all", "steps": 6}},
        "grid": {"runs": 2, "zetas": [0.0]},
    }
    new = migrate_metadata(old)
    assert new["identity"] == {"study": "swim", "options": {"action_set": "all", "steps": 6}}
    assert new["grids"] == [{"runs": 2, "zetas": [0.0]}] and new["grid"] == old["grid"]
    both = {**old, "grids": [{"runs": 1}, {"runs": 2}]}  # today's: its grids kept
    assert migrate_metadata(both)["grids"] == [{"runs": 1}, {"runs": 2}]
    bad = {**old, "grids": "edited"}  # no list of grids: the one grid, as for an old folder
    assert migrate_metadata(bad)["grids"] == [{"runs": 2, "zetas": [0.0]}]
    assert "grids" not in migrate_metadata({"study": "swim", "grids": []})


def _old_folder(tmp_path):
    """A folder in the earlier forms: ``allowed``, no ``plane_height``, a Zermelo ``time_ratio``,
    one ``grid``."""
    folder = tmp_path / "old"
    folder.mkdir()
    identity = {"study": "swim", "options": {"allowed": "all", "steps": 2}, "seed": 0}
    meta = {"study": "swim", "identity": identity, "status": "complete", "grid": {"runs": 1}}
    (folder / "metadata.json").write_text(json.dumps(meta))
    base = {"agent": "stroke", "group": "g", "x": [0.1, 0.2], "progress": [0.1, 0.1]}
    rows = [
        {**base, "run_id": "w", "allowed": "all", "swimmer": "purcell", "medium": "wall"}
        | {"scene": WALL},
        {**base, "run_id": "f", "allowed": "two", "swimmer": "ng", "zermelo_steps": 4.0}
        | {"time_ratio": 2.0, "steps_to_target": 8, "reached": True},
    ]
    (folder / "runs.jsonl").write_text("".join(json.dumps(r) + "\n" for r in rows))
    return folder, identity


def test_an_old_folder_reads_in_todays_form_through_every_reader(tmp_path):
    folder, identity = _old_folder(tmp_path)
    runs = {r["run_id"]: r for r in read_runs(folder)}
    assert runs["w"]["action_set"] == "all" and runs["w"]["plane_height"] == 2.5
    assert runs["f"]["zermelo_ratio"] == 2.0 and "time_ratio" not in runs["f"]
    assert not any("allowed" in r for r in runs.values())
    rows = {r.run_id: r for r in read_run_rows(folder)}
    assert rows["w"].plane_height == 2.5 and rows["f"].action_set == "two"
    assert rows["f"].zermelo_ratio == 2.0 and rows["f"].time_ratio is None
    meta = read_metadata(folder)
    assert meta["identity"]["options"]["action_set"] == "all" and meta["grids"] == [{"runs": 1}]
    # A session resumes it: settings compared in today's form, the folder's grid handed on.
    seen = []
    today = {**identity, "options": {"action_set": "all", "steps": 2}}
    with StudyStore(folder, "swim", today, extra=lambda before: seen.append(before) or {}) as s:
        assert s.done_ids() == {"w", "f"}
    assert seen[0]["grids"] == [{"runs": 1}] and seen[0]["identity"] == today


def test_a_wrong_typed_old_field_is_skipped_under_the_name_the_file_gives_it(tmp_path):
    folder, _ = _old_folder(tmp_path)
    with open(folder / "runs.jsonl", "a") as fh:
        fh.write(json.dumps({"run_id": "bad", "allowed": 5}) + "\n")
        fh.write(json.dumps({"run_id": "worse", "zermelo_steps": 4.0, "time_ratio": "x"}) + "\n")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ids = {r["run_id"] for r in read_runs(folder)}
    assert ids == {"w", "f"}
    said = " ".join(str(w.message) for w in caught)
    assert "'allowed' is 5, not text" in said and "'time_ratio' is 'x', not a number" in said


def test_todays_rows_written_and_read_back_are_unchanged(tmp_path):
    plain = {"run_id": "a", "agent": "random", "action_set": "all", "x": [0.1]}
    nav = {**plain, "run_id": "b", "optimal_steps": 4, "time_ratio": 1.25, "zermelo_steps": 4.5}
    with StudyStore(tmp_path / "s", "swim", {"a": 1}) as s:
        s.add_runs([plain, nav])
    assert read_runs(tmp_path / "s") == [plain, nav]


# -- jswim migrate FOLDER: the folder stored in today's form, read the same ----------------------


def _everything(folder):
    """What the readers give of a folder, the rows' key order included (metadata.json is
    written with sorted keys, today as before)."""
    return (
        [list(r.items()) for r in read_runs(folder)],
        [list(r.to_dict().items()) for r in read_run_rows(folder)],
        read_metadata(folder),
    )


def test_jswim_migrate_stores_an_old_folder_in_todays_form_and_it_reads_the_same(tmp_path, capsys):
    from jswim import cli

    folder, identity = _old_folder(tmp_path)
    with open(folder / "runs.jsonl", "a") as fh:  # a skipped line and a torn one: kept as they are
        fh.write('{"run_id": "bad", "allowed": 5}\n{"run_id": "to')
    paid = {"calls.jsonl": b'{"run": "w", "n": 0}\n', "requests.jsonl": b'{"session": 1}\n'}
    for name, data in paid.items():
        (folder / name).write_bytes(data)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        before = _everything(folder)
        assert cli.main(["migrate", str(folder)]) == 0
        after = _everything(folder)
    assert after == before
    out = capsys.readouterr().out
    assert "metadata.json: rewritten" in out and "runs.jsonl: 2 run records rewritten" in out
    text = (folder / "runs.jsonl").read_text()
    assert text.endswith('{"run_id": "bad", "allowed": 5}\n{"run_id": "to')
    stored = [json.loads(line) for line in text.splitlines()[:2]]
    assert stored[0]["action_set"] == "all" and stored[0]["plane_height"] == 2.5
    assert stored[1]["zermelo_ratio"] == 2.0 and "time_ratio" not in stored[1]
    meta = json.loads((folder / "metadata.json").read_text())
    assert meta["identity"]["options"] == {"action_set": "all", "steps": 2}
    assert meta["grids"] == [{"runs": 1}]
    assert {n: (folder / n).read_bytes() for n in paid} == paid  # the paid calls untouched
    today = {**identity, "options": {"action_set": "all", "steps": 2}}
    with StudyStore(folder, "swim", today) as s:  # the same settings resume it
        assert s.done_ids() == {"w", "f"}
    assert cli.main(["migrate", str(folder)]) == 0  # the store rewrote only its status
    assert "already in today's form" in capsys.readouterr().out


def test_jswim_migrate_refuses_bad_input_in_one_line(tmp_path, capsys):
    from jswim import cli
    from jswim._io.folderlock import FolderLock

    assert cli.main(["migrate", str(tmp_path / "nothing")]) == 2
    folder, _ = _old_folder(tmp_path)
    with FolderLock(folder):  # a live session holds it
        assert cli.main(["migrate", str(folder)]) == 2
    (tmp_path / "list").mkdir()
    (tmp_path / "list" / "metadata.json").write_text("[]")
    assert cli.main(["migrate", str(tmp_path / "list")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3 and all(line.startswith("jswim: error: ") for line in err), err
    assert "not a jswim study folder" in err[0] and "in use by another" in err[1]
    assert "allowed" in (folder / "runs.jsonl").read_text()  # nothing rewritten while held
