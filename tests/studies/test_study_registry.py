"""A study is one object (issue 62): every study kind is one module of `jswim.studies.kinds`,
registered, and nothing else compares a study's name; a new module is a new study, from the
command line to its folder's figures."""

from __future__ import annotations

import ast
import dataclasses
import json
import pkgutil
import textwrap
from pathlib import Path

import pytest

from jswim import cli
from jswim.studies import get, kinds, names, study
from jswim.studies.options import StudyOptions
from jswim.studies.specs import build

ROOT = Path(__file__).resolve().parents[2] / "jswim"


def name_branches(source: str, studies: set[str]) -> list[int]:
    """Lines that compare something holding a study's name (``study``, ``spec.study``,
    ``args.name``, ...) with a study's name, in order."""

    def holds_name(node: ast.AST) -> bool:
        text = ast.unparse(node)
        return "study" in text.lower() or text in ("args.name", "args.command")

    def names_in(node: ast.AST) -> set[str]:
        elts = node.elts if isinstance(node, (ast.Tuple, ast.List, ast.Set)) else [node]
        return {e.value for e in elts if isinstance(e, ast.Constant) and isinstance(e.value, str)}

    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Compare):
            parts = [node.left, *node.comparators]
            if any(names_in(p) & studies for p in parts) and any(holds_name(p) for p in parts):
                out.append(node.lineno)
    return sorted(out)


def test_no_code_compares_a_study_s_name():
    studies = set(names())
    found = {
        str(p.relative_to(ROOT)): lines
        for p in ROOT.rglob("*.py")
        if (lines := name_branches(p.read_text(), studies))
    }
    assert not found, f"branches on a study's name (ask jswim.studies.get instead): {found}"


def test_the_check_finds_a_branch_on_a_study_s_name():
    studies = set(names())
    broken = """
        if study == "navigate":
            pass
        x = 1 if spec.study in ("wall", "pair") else 2
        y = args.name != "swim"
        z = scene.medium == "wall"  # a medium, not a study
    """
    assert name_branches(textwrap.dedent(broken), studies) == [2, 4, 5]


def test_every_study_the_command_line_offers_is_one_registered_module(capsys):
    modules = {m.name for m in pkgutil.iter_modules(kinds.__path__)}
    assert set(names()) == modules  # one module each, the module named as the study
    with pytest.raises(SystemExit):
        cli.main(["study", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    offered = [n for n in names() if get(n).command == "study"]
    assert "NAME " + ", ".join(offered) in text
    assert [n for n in names() if n not in offered] == ["swim"]  # jswim swim


def test_an_unknown_study_is_one_line():
    with pytest.raises(Exception, match="unknown study 'nope'; choose one of curves, history"):
        get("nope")


NEW_STUDY = '''
"""A study added by one file: the n_ht sweep on Purcell's swimmer alone."""
from jswim.studies.plans import Cell
from jswim.studies.study import Study
from jswim.studies.success import gait_rule


def cells(o, swimmer):
    return [Cell("n_ht=1", ("llm", "random"), n_ht=1), Cell("n_ht=3", ("llm",), n_ht=3)]


STUDY = Study(
    name="tiny",
    help="two history lengths on Purcell's swimmer",
    cells=cells,
    runs=2,
    q_runs=3,
    swimmers=("purcell",),
    success=gait_rule,
    order=99,
    figures=("history",),
)
'''


def test_one_file_adds_a_study(tmp_path, monkeypatch, capsys):
    (tmp_path / "tiny.py").write_text(NEW_STUDY)
    monkeypatch.setattr(kinds, "__path__", [*kinds.__path__, str(tmp_path)])
    monkeypatch.setattr(study, "_REGISTRY", {})
    assert names()[-1] == "tiny"
    plans = build("tiny", StudyOptions())
    assert sorted({(p.agent, p.group) for p in plans}) == [
        ("llm", "n_ht=1"),
        ("llm", "n_ht=3"),
        ("random", "n_ht=1"),
    ]
    assert len(plans) == 2 * 2 + 3 and {p.swimmer for p in plans} == {"purcell"}
    with pytest.raises(SystemExit):
        cli.main(["study", "tiny", "--help"])
    assert "The tiny study: two history lengths" in " ".join(capsys.readouterr().out.split())


def _school_row(n: int) -> dict:
    scene = {"medium": "free", "swimmers": n, "separation": 30.0, "obstacles": []}
    return {
        "run_id": f"stroke-ng-N{n}",
        "agent": "stroke",
        "swimmer": "ng",
        "group": f"line, D=30, N={n}",
        "scene": json.dumps(scene),
        "n_swimmers": n,
        "per_cycle": 0.17,
        "direction": 1,
        "x": [0.1, 0.2],
        "steps": 2,
        "signed_final_x": 0.2,
    }


def test_the_tables_are_the_ones_the_study_names_its_summary_first(monkeypatch):
    from jswim.studies.overview import study_tables

    rows = [_school_row(1), _school_row(2)]
    assert [t.key for t in study_tables("school", rows)] == ["summary-table", "scenes"]
    assert [t.key for t in study_tables("curves", rows)] == ["summary-table"]  # no scene table
    # a study of a later jswim: the tables its rows call for
    assert [t.key for t in study_tables("from-the-future", rows)] == ["summary-table", "scenes"]
    school = dataclasses.replace(get("school"), tables=("scenes",))
    monkeypatch.setitem(study._load(), "school", school)
    assert [t.title for t in study_tables("school", rows)] == ["scenes"]
    assert study_tables("school", []) == []
