"""Hand-edited and foreign study folders (issue 61, item 2): every reader (show, report, compare,
plot, animate, ``jswim.load``) answers a field it cannot use with one line naming the file (and
the line of ``runs.jsonl``) and the field, shows the rest and exits 2; never a traceback. The
resume refuses a hand-edited identity in one line and rewrites a hand-edited derived field.

The fields are checked where rows and metadata are read (`jswim.results.schema.run_problem`,
`jswim.results.read.clean_metadata`), so each case below stands for its kind: a row's typed
field, its ``flow``/``target``/``scene`` JSON, a required field, a metadata grid or identity
field, a file that is no metadata.

``tests/data/navigate-flow``: six rows (controller and Zermelo, a fixed and a moving target, in
still fluid and a shear at 0.5 v) of a real ``jswim study navigate --flow shear --flows 0,0.5
--distances 3 --bearings 90 --runs 0 --q-runs 1 --train-episodes 1 --steps 10`` folder, its
metadata as written but for ``n_planned``/``n_runs`` (6). A study in a flow takes minutes here,
reading these rows seconds.
"""

from __future__ import annotations

import json
import shutil
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

import jswim
from jswim import cli
from jswim._io.jsonl import SkippedRecord, forget_warnings

DATA = Path(__file__).resolve().parents[1] / "data"
FLOW = DATA / "navigate-flow"
OLD = DATA / "folder-54c2edb"  # a `jswim swim` folder of an old commit (50 steps, 5 runs)
ZERMELO_05 = 4  # runs.jsonl line of Zermelo's run at shear 0.5 v (fixed target)


def put(path: str, value: Any) -> Callable[[dict], None]:
    """An edit setting the dotted field ``path`` of a record to ``value``."""

    def edit(rec: dict) -> None:
        *parents, leaf = path.split(".")
        for k in parents:
            rec = rec[k]
        rec[leaf] = value

    return edit


def drop(field: str) -> Callable[[dict], None]:
    return lambda rec: rec.pop(field)


def copy(src: Path, tmp_path: Path) -> Path:
    out = tmp_path / src.name
    shutil.copytree(src, out)
    return out


def edit_meta(folder: Path, edit: Callable[[dict], None]) -> None:
    meta = json.loads((folder / "metadata.json").read_text())
    edit(meta)
    (folder / "metadata.json").write_text(json.dumps(meta))


def edit_row(folder: Path, line: int, edit: Callable[[dict], None]) -> None:
    lines = (folder / "runs.jsonl").read_text().splitlines()
    rec = json.loads(lines[line - 1])
    edit(rec)
    lines[line - 1] = json.dumps(rec)
    (folder / "runs.jsonl").write_text("\n".join(lines) + "\n")


def one_line(capsys, argv: list[str], *names: str) -> str:
    """Run ``jswim ARGV``: exit 2, no traceback, and exactly one line on stderr, which holds
    every one of ``names`` (the file, the field)."""
    rc = cli.main(argv)
    err = capsys.readouterr().err
    assert "Traceback" not in err, err
    lines = err.strip().splitlines()
    assert rc == 2 and len(lines) == 1, (rc, err)
    for name in names:
        assert name in lines[0], (name, lines[0])
    return lines[0]


def reader(cmd: str, folder: Path, tmp_path: Path) -> list[str]:
    """The command line of one reader of ``folder`` (writing into ``tmp_path`` where it writes)."""
    return {
        "show": ["show", str(folder)],
        "report": ["report", str(folder), "--figures", "none", "--out", str(tmp_path / "r.html")],
        "compare": ["compare", str(folder), str(FLOW if "navigate" in folder.name else OLD)],
        "plot": ["plot", str(folder)],
        "animate": ["animate", str(folder), "--max", "1", "--dpi", "20"],
    }[cmd] + (["--out", str(tmp_path / "a.gif")] if cmd == "animate" else [])


@pytest.mark.parametrize("cmd", ["show", "report", "compare"])
def test_the_shipped_flow_folder_reads_whole(cmd, capsys, tmp_path):
    # The baseline of every case below: the unedited folder is exit 0 with nothing on stderr.
    assert cli.main(reader(cmd, FLOW, tmp_path)) == 0
    assert capsys.readouterr().err == ""


# (reader, the edit, what the line names besides the file)
META_CASES = {
    "grid.flows fast, show": ("show", put("grid.flows", ["fast"]), "'grid.flows'"),
    "grid.flows fast, report": ("report", put("grid.flows", ["fast"]), "'grid.flows'"),
    "grid.flows a number, show": ("show", put("grid.flows", 0.5), "'grid.flows'"),
    "grid.bearings text, report": ("report", put("grid.bearings", "90"), "'grid.bearings'"),
    "grid.runs text, show": ("show", put("grid.runs", "1"), "'grid.runs'"),
    "identity.options text, show": ("show", put("identity.options", "x"), "'identity.options'"),
    "identity.options text, report": (
        "report",
        put("identity.options", "x"),
        "'identity.options'",
    ),
    "identity.backend a list, compare": (
        "compare",
        put("identity.backend", [1]),
        "'identity.backend'",
    ),
    "identity.options.flow a list, show": (
        "show",
        put("identity.options.flow", ["shear"]),
        "'identity.options.flow'",
    ),
    "n_planned text, show": ("show", put("n_planned", "6"), "'n_planned'"),
}


@pytest.mark.parametrize("case", list(META_CASES))
def test_a_hand_edited_metadata_field_is_one_line_and_exit_2(case, capsys, tmp_path):
    cmd, edit, field = META_CASES[case]
    folder = copy(FLOW, tmp_path)
    edit_meta(folder, edit)
    one_line(capsys, reader(cmd, folder, tmp_path), f"{folder}/metadata.json", field)


ROW_CASES = {
    "flow not JSON text, report": ("report", put("flow", "shear"), "'flow'"),
    "flow not JSON text, show": ("show", put("flow", "shear"), "'flow'"),
    "flow a number, report": ("report", put("flow", 5), "'flow'"),
    "flow JSON of a list, plot": ("plot", put("flow", "[1]"), "'flow'"),
    "flow of no kind, report": ("report", put("flow", '{"kind": "vortex"}'), "'flow'"),
    "flow missing a field, show": ("show", put("flow", '{"kind": "shear"}'), "'flow'"),
    "target not JSON text, report": ("report", put("target", "far"), "'target'"),
    "target a number, report": ("report", put("target", 3), "'target'"),
    "target of no kind, report": ("report", put("target", '{"kind": "fixed"}'), "'target'"),
    "flow_fraction text, compare": ("compare", put("flow_fraction", "0.5"), "'flow_fraction'"),
    "path_ratio a list, show": ("show", put("path_ratio", [1]), "'path_ratio'"),
    "steps_to_target text, report": ("report", put("steps_to_target", "3"), "'steps_to_target'"),
    "reached text, report": ("report", put("reached", "yes"), "'reached'"),
    "time_ratio text, compare": ("compare", put("time_ratio", "x"), "'time_ratio'"),
    "energy text, show": ("show", put("energy", "x"), "'energy'"),
    "actions not pairs, report": ("report", put("actions", [1, 2]), "'actions'"),
    "flow_fraction missing, show": ("show", drop("flow_fraction"), "'flow_fraction'"),
    "group a number, show": ("show", put("group", 5), "'group'"),
    "agent a list, compare": ("compare", put("agent", ["zermelo"]), "'agent'"),
    "x text, report": ("report", put("x", "far"), "'x'"),
}


# plot draws every figure of the folder (about 8 s here): its one case runs in the slow tier.
SLOW = pytest.mark.slow


@pytest.mark.parametrize(
    "case", [pytest.param(c, marks=SLOW) if ", plot" in c else c for c in ROW_CASES]
)
def test_a_hand_edited_row_is_one_line_and_exit_2(case, capsys, tmp_path):
    cmd, edit, field = ROW_CASES[case]
    folder = copy(FLOW, tmp_path)
    edit_row(folder, ZERMELO_05, edit)
    one_line(
        capsys, reader(cmd, folder, tmp_path), f"{folder}/runs.jsonl, line {ZERMELO_05}", field
    )


@pytest.mark.parametrize("field", ["group", "agent", "x", "steps"])
@pytest.mark.parametrize("cmd", ["show", "report", "compare"])
def test_a_row_without_a_column_every_reader_needs_reads_as_unset(cmd, field, capsys, tmp_path):
    # Every row jswim writes has them; a record without one (a hand edit, a foreign writer)
    # reads as no cell, no agent, no steps (`RunRow.from_dict`), never a traceback.
    folder = copy(FLOW, tmp_path)
    edit_row(folder, ZERMELO_05, drop(field))
    assert cli.main(reader(cmd, folder, tmp_path)) == 0
    assert capsys.readouterr().err == ""


def test_what_can_be_read_is_still_shown(capsys, tmp_path):
    folder = copy(FLOW, tmp_path)
    edit_meta(folder, put("grid.flows", ["fast"]))
    edit_row(folder, ZERMELO_05, put("flow", "shear"))
    assert cli.main(["show", str(folder)]) == 2
    printed = capsys.readouterr()
    assert "runs: 5 (controller 2, zermelo 3)" in printed.out  # the other five rows
    assert "flow shear at ? v" in printed.out  # the speeds the edit lost, and only them
    assert len(printed.err.strip().splitlines()) == 2  # one line per field
    page = tmp_path / "r.html"
    assert cli.main(["report", str(folder), "--figures", "none", "--out", str(page)]) == 2
    assert page.stat().st_size > 10_000 and "Traceback" not in capsys.readouterr().err


@pytest.mark.parametrize(
    "text, says",
    [("", "unreadable"), ("[1, 2]", "a JSON list"), ("null", "a JSON null")],
    ids=["empty", "a list", "null"],
)
@pytest.mark.parametrize("cmd", ["show", "report", "compare", "plot"])  # refused before drawing
def test_a_metadata_file_that_is_no_object_is_one_line(cmd, text, says, capsys, tmp_path):
    folder = copy(FLOW, tmp_path)
    (folder / "metadata.json").write_text(text)
    one_line(capsys, reader(cmd, folder, tmp_path), f"{folder}/metadata.json", says)


@pytest.mark.slow  # draws a 12-step animation (about 10 s here)
def test_animate_of_an_old_folder_with_a_hand_edited_row(capsys, tmp_path):
    folder = copy(OLD, tmp_path)
    edit_row(folder, 2, put("n_ht", "3"))
    one_line(capsys, reader("animate", folder, tmp_path), f"{folder}/runs.jsonl, line 2", "'n_ht'")
    assert (tmp_path / "a.gif").stat().st_size > 0  # the other runs still drawn
    edit_meta(folder, put("identity.backend.model", 5))
    edit_row(folder, 2, put("n_ht", None))
    one_line(capsys, reader("show", folder, tmp_path), "'identity.backend.model'")


def test_load_warns_once_per_field_and_returns_the_rest(tmp_path):
    folder = copy(FLOW, tmp_path)
    edit_meta(folder, put("grid.flows", ["fast"]))
    edit_row(folder, ZERMELO_05, put("flow", 5))
    forget_warnings()
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        study = jswim.load(folder)
        assert len(study.trajectories) > 0  # read, as a notebook would
    lines = [str(w.message) for w in said if issubclass(w.category, SkippedRecord)]
    assert len(lines) == 2, lines
    assert "metadata.json: 'grid.flows' is ['fast']" in lines[0]
    assert "runs.jsonl, line 4: 'flow' is 5, not text" in lines[1]
    assert len(study.runs) == 5 and "flows" not in study.metadata["grid"]
    assert study.metadata["grid"]["bearings"] == [90.0]  # the fields beside it kept


# -- the resume ------------------------------------------------------------------------------------

NAV = ["study", "navigate", "--flow", "shear", "--flows", "0,0.5", "--distances", "3"]
NAV += ["--bearings", "90", "--runs", "0", "--q-runs", "1", "--train-episodes", "1"]
NAV += ["--steps", "10", "--no-figures", "--dry-run"]


@pytest.mark.slow  # opens the store: the navigate grid is planned (about 5 s here)
def test_the_resume_refuses_a_hand_edited_identity_in_one_line(capsys, tmp_path):
    folder = copy(FLOW, tmp_path)
    edit_meta(folder, put("identity.options.flow", 3))
    before = (folder / "metadata.json").read_bytes()
    rc = cli.main([*NAV[:-1], "--out", str(folder)])  # not a dry run: the store opens
    err = capsys.readouterr().err
    errors = [ln for ln in err.splitlines() if ln.startswith("jswim: error:")]
    assert rc == 2 and len(errors) == 1 and "Traceback" not in err, err
    assert "options.flow" in errors[0] and str(folder) in errors[0]
    assert (folder / "metadata.json").read_bytes() == before  # the folder left as it was


def test_the_resume_plans_a_hand_edited_row_again(capsys, tmp_path):
    folder = copy(FLOW, tmp_path)
    edit_row(folder, ZERMELO_05, put("flow", "shear"))
    assert cli.main([*NAV, "--out", str(folder)]) == 0  # a dry run: it plans, writes nothing
    err = capsys.readouterr().err
    assert "Traceback" not in err
    said = [ln for ln in err.splitlines() if str(folder) in ln]
    assert len(said) == 1 and f"runs.jsonl, line {ZERMELO_05}: 'flow'" in said[0], err
