"""README.md stays true: its Python examples run, and the commands it lists exist."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from jswim.cli import build_parser

README = (Path(__file__).resolve().parents[2] / "README.md").read_text()


def test_python_examples_run():
    blocks = re.findall(r"```python\n(.*?)```", README, flags=re.S)
    assert blocks
    for code in blocks:
        exec(compile(code, "README.md", "exec"), {})


def test_the_square_gait_example_prints_the_reference_value():
    from jswim import env

    r = env.rollout("purcell", [(2, -1), (1, -1), (2, 1), (1, 1)])
    assert abs(float(r.x[-1]) - 0.19124724) < 1e-8 and "0.19124724" in README


def _choices(parser, dest):
    return next(a.choices for a in parser._actions if a.dest == dest)


@pytest.mark.parametrize("name,arg", sorted(set(re.findall(r"`jswim (\w+)(?: (\w+))?", README))))
def test_listed_commands_exist(name, arg):
    commands = _choices(build_parser(), "command")
    assert name in commands, f"README mentions `jswim {name}`"
    if name == "study" and arg:
        assert arg in _choices(commands["study"], "name"), f"README mentions `jswim study {arg}`"
