"""The numbers the docs pages quote are jswim's: each recomputed from the code by the script that
regenerates it (benchmarks/physics_tables.py, qlearn_tables.py, school_tables.py,
scene_tables.py) and compared with the
number parsed from the page, to the page's decimals. The physics values themselves are checked
against independent ones (closed forms, symmetries, the authors' code) in tests/physics."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _script(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_physics_numbers_of_the_pages_are_the_code_s():
    # square gaits, the corner MDP's discount threshold, NG's strokes (~10 s)
    lines: list[str] = []
    wrong = _script("physics_tables").check(fast=True, say=lines.append)
    assert len(lines) >= 15 and not wrong, "\n".join(wrong)


@pytest.mark.slow  # the K = 20 lattice searches and the three-DOF gait searches (~6 min on 2 shared cores)
def test_the_searched_strokes_of_the_pages_are_the_code_s():
    lines: list[str] = []
    wrong = _script("physics_tables").check(fast=False, say=lines.append)
    assert len(lines) >= 22 and not wrong, "\n".join(wrong)


@pytest.mark.slow  # 80,000 + 7,000 Q-learners (~2 min on 2 shared cores)
def test_the_q_learning_tables_of_the_pages_are_the_code_s(float32):
    # float32, as `jswim qlearn` runs for a user: the learners' uniforms differ in float64
    lines: list[str] = []
    wrong = _script("qlearn_tables").check(say=lines.append)
    assert len(lines) >= 16 and not wrong, "\n".join(wrong)


def _school_table(text: str, title: str) -> tuple[list[float], dict[int, list[float]]]:
    """A school table of scenes.md: its spacings D and, per N, the school's speed per D."""
    import re

    lines = text.split(f"| {title} |", 1)[1].split("\n\n", 1)[0].splitlines()
    spacings = [float(d) for d in re.findall(r"D = ([\d.]+) a", lines[0])]
    rows = {
        int(re.match(r"\| N = (\d+)", ln).group(1)): [
            float(c.split()[0]) for c in ln.strip("|").split("|")[1:]
        ]
        for ln in lines[2:]
        if ln.startswith("| N = ")
    }
    return spacings, rows


@pytest.mark.slow  # nine compilations of the N-swimmer joint step (~1 min on 2 shared cores)
def test_the_school_tables_of_the_scenes_page_are_the_code_s():
    schools = _script("school_tables")
    text = (ROOT / "docs" / "scenes.md").read_text()
    for formation, title in (("line", "line"), ("side", "side by side")):
        spacings, rows = _school_table(text, title)
        assert len(spacings) == 4 and len(rows) >= 4
        for n, page in rows.items():
            mean = schools.school_cycles(n, formation, spacings)["disp"][..., 0].mean(-1)
            assert mean == pytest.approx(page, abs=5e-9), (formation, n)  # the page's 8 decimals


def _row(text: str, label: str) -> list[float]:
    line = next(ln for ln in text.splitlines() if ln.startswith(f"| {label} |"))
    return [float(c.split()[0]) for c in line.strip().strip("|").split("|")[1:]]


@pytest.mark.slow  # a wall rollout per mobility (~1 min on 2 shared cores)
def test_the_wall_tables_of_the_scenes_page_are_the_code_s():
    tables = _script("scene_tables")
    text = (ROOT / "docs" / "scenes.md").read_text()
    page = _row(text, "X per cycle (a)")  # h = 3..50, free, bulk (the paper's formula)
    ours = [
        *tables.wall_cycles("point", tables.WALL_TABLE)["x"],
        tables.lone_cycle("point"),
        _script("physics_tables")._square("ng")[0],
    ]
    assert ours == pytest.approx(page, abs=5e-9)  # the page's 8 decimals
    page = _row(text, "rpy, X per cycle (a)")  # h = 3..50, free
    ours = [*tables.wall_cycles("rpy", tables.WALL_TABLE)["x"], tables.lone_cycle("rpy")]
    assert ours == pytest.approx(page, abs=5e-9)


@pytest.mark.slow  # the work and lattice tables and six controller runs (~40 s on 2 shared cores)
def test_the_energy_and_turning_tables_of_the_physics_page_are_the_code_s():
    assert _script("energy_tables").main(["--check"]) == 0
