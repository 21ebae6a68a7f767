"""README.md and the docs pages stay true: their Python examples run, the commands they name exist,
README stays short and every number it keeps is also in a page."""

from __future__ import annotations

import importlib.util
import re
from pathlib import Path

import pytest

from jswim.cli import build_parser

ROOT = Path(__file__).resolve().parents[2]
README = (ROOT / "README.md").read_text()
PAGES = {
    p.relative_to(ROOT / "docs").as_posix(): p.read_text()
    for p in sorted((ROOT / "docs").rglob("*.md"))
}
DOCS = "\n".join(PAGES.values())


def _python_blocks(text):
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


@pytest.mark.parametrize("page", ["README.md", *[p for p in PAGES if _python_blocks(PAGES[p])]])
def test_python_examples_run(page):
    """Each ``python`` block of a page runs on its own (each is written to be pasted alone)."""
    text = README if page == "README.md" else PAGES[page]
    blocks = _python_blocks(text)
    assert blocks
    missing = []
    for code in blocks:
        # A block that teaches a third-party library (Stable-Baselines3, say) runs where it is
        # installed; the others always run.
        absent = [m for m in _imported_packages(code) if importlib.util.find_spec(m) is None]
        if absent:
            missing += absent
            continue
        exec(compile(code, page, "exec"), {})
    if len(missing) == len(blocks):
        pytest.skip(f"{page}'s examples need {', '.join(sorted(set(missing)))}")


def _imported_packages(code):
    """The top-level packages a block imports (its ``import x`` and ``from x import`` lines)."""
    names = re.findall(r"^(?:from|import)\s+([A-Za-z_]\w*)", code, flags=re.M)
    names += re.findall(r"^import .*,\s*([A-Za-z_]\w*)", code, flags=re.M)
    return sorted(set(names))


def test_the_square_gait_example_prints_the_reference_value():
    from jswim import env

    r = env.rollout_moves("purcell", [(2, -1), (1, -1), (2, 1), (1, 1)])
    assert (
        abs(float(r.x[-1]) - 0.19124724) < 1e-8
        and "0.19124724" in README
        and "0.19124724" in PAGES["physics.md"]
    )


def _choices(parser, dest):
    return next(a.choices for a in parser._actions if a.dest == dest)


@pytest.mark.parametrize(
    "name,arg", sorted(set(re.findall(r"`jswim (\w+)(?: (\w+))?", README + DOCS)))
)
def test_listed_commands_exist(name, arg):
    commands = _choices(build_parser(), "command")
    assert name in commands, f"the docs mention `jswim {name}`"
    if name == "study" and arg:
        assert arg in _choices(commands["study"], "name"), f"the docs mention `jswim study {arg}`"


def test_readme_is_short():
    assert len(README.splitlines()) <= 300


def _prose(text):
    """Text outside code fences, with link targets and inline code removed."""
    text = re.sub(r"```.*?```", "", text, flags=re.S)
    text = re.sub(r"\]\([^)]*\)", "]", text)
    return re.sub(r"`[^`]*`", "", text)


def test_every_number_readme_keeps_is_in_a_page():
    numbers = set(re.findall(r"(?<![\w.])\d(?:[\d,]*\d)?(?:\.\d+)?(?![\w])", _prose(README)))
    docs = _prose(DOCS) + DOCS
    missing = sorted(n for n in numbers if len(n.replace(",", "")) > 1 and n not in docs)
    assert not missing, f"README's numbers not in any docs page: {missing}"


def test_readme_links_resolve():
    for target in re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", README):
        if not re.match(r"\w+://", target):
            assert (ROOT / target).exists(), f"README links to a missing {target}"
