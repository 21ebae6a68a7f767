"""The package reads run rows as typed :class:`jswim.results.RunRow` attributes.

Two guards: an AST scan that fails when a reader module goes back to reading a run row by string
key (``r["final_x"]``, ``row.get("cost_usd")``), and the readers (figures, report page, show,
animation, summaries) run on the rows of a folder an earlier version wrote, read both ways.
"""

from __future__ import annotations

import ast
import dataclasses
import json
import math
import shutil
from pathlib import Path

from jswim.results import RunRow, as_run_row, as_run_rows, read_run_rows, read_runs

ROOT = Path(__file__).resolve().parents[2]
OLD = ROOT / "tests" / "data" / "folder-54c2edb"

#: The modules that read run rows (figures, the report page, animation, show/compare, summaries, tables).
#: (jswim/figures/leaderboard.py is left out: it draws the leaderboard's rows, not run rows.)
READERS = sorted(
    str(p.relative_to(ROOT))
    for p in (ROOT / "jswim" / "figures").glob("*.py")
    if p.name != "leaderboard.py"
) + [
    "jswim/viz/tracks.py",
    "jswim/viz/animate.py",
    "jswim/viz/page.py",
    "jswim/viz/worlds.py",
    "jswim/studies/overview.py",
    "jswim/studies/report.py",
    "jswim/studies/run.py",
    "jswim/studies/scene_studies.py",
    "jswim/studies/baselines.py",
    "jswim/studies/session.py",
    "jswim/results/tables.py",
    "jswim/results/store.py",
    "jswim/results/load.py",
    "jswim/cli/study.py",
]
#: The names readers give a run row.
ROW_NAMES = {"r", "row", "rows", "r0", "run", "first", "ref"}
#: String-key reads on those names that are not run-row reads, each with its reason:
#: (module, name, key) -> why.
ALLOWED = {
    (
        "jswim/studies/run.py",
        "r",
        "run_id",
    ): "StudyResult.rows are read_runs' dicts, kept for users",
    ("jswim/cli/study.py", "first", "run_id"): "StudyResult.failed_runs entries, not run rows",
    ("jswim/cli/study.py", "first", "error"): "StudyResult.failed_runs entries, not run rows",
}
FIELDS = {f.name for f in dataclasses.fields(RunRow)}


def _string_key_reads(path: Path) -> list[tuple[int, str, str]]:
    """``(line, name, key)`` of every ``name["key"]`` and ``name.get("field", ...)`` on a row name."""
    out = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if (
            isinstance(node, ast.Subscript)
            and isinstance(node.value, ast.Name)
            and node.value.id in ROW_NAMES
            and isinstance(node.slice, ast.Constant)
            and isinstance(node.slice.value, str)
        ):
            out.append((node.lineno, node.value.id, node.slice.value))
        elif (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Attribute)
            and node.func.attr == "get"
            and isinstance(node.func.value, ast.Name)
            and node.func.value.id in ROW_NAMES
            and node.args
            and isinstance(node.args[0], ast.Constant)
            and node.args[0].value in FIELDS
        ):
            out.append((node.lineno, node.func.value.id, node.args[0].value))
    return out


def test_reader_modules_read_run_rows_by_attribute_not_by_string_key():
    bad = [
        f"{m}:{line}: {name}[{key!r}]"
        for m in READERS
        for line, name, key in _string_key_reads(ROOT / m)
        if (m, name, key) not in ALLOWED
    ]
    assert not bad, "read a RunRow attribute (row.final_x), not a string key:\n" + "\n".join(bad)


def test_the_scan_finds_string_key_reads(tmp_path):
    """The guard itself: each kind of read it must catch is caught, attribute reads are not."""
    src = tmp_path / "m.py"
    src.write_text(
        'a = r["final_x"]\nb = row.get("cost_usd")\nc = row.get("beside")\nd = r.final_x\ne = t["x"]\n'
    )
    assert _string_key_reads(src) == [(1, "r", "final_x"), (2, "row", "cost_usd")]


def test_the_allow_list_names_reads_that_exist():
    """An entry whose read is gone is dropped from ALLOWED (it would let a new one through)."""
    found = {(m, name, key) for m in READERS for _, name, key in _string_key_reads(ROOT / m)}
    assert set(ALLOWED) <= found


def test_as_run_rows_passes_rows_through_and_converts_dicts():
    dicts = read_runs(OLD)
    typed = as_run_rows(dicts)
    assert all(isinstance(r, RunRow) for r in typed) and as_run_rows(typed)[0] is typed[0]
    assert as_run_row(typed[1]) is typed[1] and as_run_row(dicts[1]).run_id == dicts[1]["run_id"]
    assert [r.final_x for r in read_run_rows(OLD)] == [d["final_x"] for d in dicts]


# -- the readers on an old folder, its rows as dicts and as RunRows -----------------------------


def _old_folder(tmp_path: Path) -> Path:
    """The 54c2edb folder under its older name for ``action_set`` (``allowed``), with a column
    this version does not know, and a failed LLM run (no result: None fields) appended."""
    folder = tmp_path / "old"
    shutil.copytree(OLD, folder)
    recs = [
        json.loads(line) for line in (OLD / "runs.jsonl").read_text().splitlines() if line.strip()
    ]
    for rec in recs:
        rec["allowed"] = rec.pop("action_set")
        rec["legacy_note"] = "kept"
    failed = {
        "run_id": "llm-purcell-px-i++-z0-r9",
        "agent": "llm",
        "swimmer": "purcell",
        "direction": 1,
        "group": "",  # every row has its cell (the row readers skip one without: issue 61)
        "status": "llm_error",
        "error": "server gone",
        "x": [],
        "actions": [],
        "progress": [],
        "final_x": None,
        "signed_final_x": None,
        "steps": 0,
    }
    (folder / "runs.jsonl").write_text("".join(json.dumps(r) + "\n" for r in recs + [failed]))
    return folder


def test_a_row_written_before_plane_height_gets_it_by_the_old_rule():
    from jswim.viz.worlds import from_above, world_of

    scene = json.dumps({"medium": "wall", "height": 2.5, "swimmers": 1})
    old = {"run_id": "a", "agent": "stroke", "swimmer": "purcell", "scene": scene, "medium": "wall"}
    assert as_run_row(old).plane_height == 2.5
    assert from_above(old) and world_of(old).extra == {"plane_height": 2.5}
    ng = {**old, "swimmer": "ng"}  # NG's wall scene: drawn in its vertical plane, the wall below
    assert as_run_row(ng).plane_height is None and not from_above(ng) and world_of(ng).wall
    # a new row says it itself, whatever its swimmer's name
    new = {**ng, "swimmer": "mine", "plane_height": 4.0}
    assert from_above(new) and world_of(new).extra == {"plane_height": 4.0}
    assert "plane_height" not in as_run_row(ng).to_dict()  # written only when set


def test_read_run_rows_renames_old_keys_keeps_unknown_ones_and_failed_rows(tmp_path):
    folder = _old_folder(tmp_path)
    rows = read_run_rows(folder)
    assert len(rows) == 6 and {r.action_set for r in rows[:5]} == {"all"}
    assert all(r.other == {"legacy_note": "kept"} for r in rows[:5])
    last = rows[-1]
    assert (
        last.status == "llm_error"
        and last.final_x is None
        and last.cost_usd is None
        and last.learned is None
    )


def test_summaries_agree_on_dict_and_typed_rows_and_match_the_file(tmp_path):
    from jswim.studies.report import summarize

    folder = _old_folder(tmp_path)
    dicts, typed = read_runs(folder), read_run_rows(folder)
    by_dicts, by_typed = summarize(dicts), summarize(typed)
    assert (
        by_dicts == by_typed and len(by_typed) == 3
    )  # llm, qlearning, random; the failed run left out
    raw = [
        json.loads(line) for line in (OLD / "runs.jsonl").read_text().splitlines() if line.strip()
    ]
    q = next(g for g in by_typed if g["agent"] == "qlearning")
    want = [r["signed_final_x"] for r in raw if r["agent"] == "qlearning"]
    assert q["n"] == len(want) == 2 and math.isclose(q["mean_x"], sum(want) / len(want))
    llm = next(g for g in by_typed if g["agent"] == "llm")
    assert llm["n"] == 1 and llm["cost_usd"] == 0.0 and llm["tokens_per_step"] > 0


def test_figures_page_show_and_animation_work_on_an_old_folder(tmp_path):
    from jswim.figures.plots import study_figures
    from jswim.studies.overview import StudyFolder, show_text
    from jswim.viz import animate
    from jswim.viz.page import write_report

    folder = _old_folder(tmp_path)
    dicts, typed = read_runs(folder), read_run_rows(folder)
    done = [r for r in typed if r.status == "done"]
    for rows in (dicts[:5], done):  # users pass read_runs' dicts, the package RunRows
        figs = study_figures("swim", rows)
        assert list(figs) == ["swim"] and figs["swim"].axes
    s = StudyFolder(folder)
    assert all(isinstance(r, RunRow) for r in s.rows) and s.usage()["calls"] == 12
    text = show_text(folder)
    assert "runs: 6 (llm 2, qlearning 2, random 2)" in text
    page = write_report(folder, figures="none").read_text()
    assert page.count('<script type="text/plain" id="run-') == 6
    a = animate.build(folder)
    assert [t.agent for t in a.tracks] == ["llm", "qlearning", "random"]
    assert a.tracks[0].row["legacy_note"] == "kept"  # the unknown column reaches the track's row
