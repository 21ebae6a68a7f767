"""The built docs site: no page shows a raw Sphinx role, and the API pages list public names.

Builds the site once with mkdocs (the ``docs`` extra; skipped without it), with no warning,
reads every built page's text and, where Chromium is installed, looks at one API page in the
browser as a reader would (its rendered text and its cross-reference links). CI's docs step
(``.ci/docs``) fails on a broken cross-reference.
"""

from __future__ import annotations

import html
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.browser import browser_or_skip

ROOT = Path(__file__).resolve().parents[2]

#: A Sphinx role as mkdocstrings leaves it: ":class:" then the name (in backticks or as code).
RAW_ROLE = re.compile(r":(?:py:)?(?:class|meth|func|mod|attr|data|exc|obj|const):\s*[`A-Za-z_]")


def _text(page: Path) -> str:
    """A page's visible text: scripts, styles and tags removed, entities decoded."""
    raw = page.read_text(encoding="utf-8")
    raw = re.sub(r"<(script|style)\b.*?</\1>", " ", raw, flags=re.DOTALL | re.IGNORECASE)
    return html.unescape(re.sub(r"<[^>]+>", "", raw))


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    pytest.importorskip("mkdocs", reason="the docs extra: pip install -e '.[docs]'")
    pytest.importorskip("mkdocstrings", reason="the docs extra: pip install -e '.[docs]'")
    out = tmp_path_factory.mktemp("site")
    # no --quiet: it drops warnings before --strict counts them
    built = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        env={**os.environ, "NO_MKDOCS_2_WARNING": "1"},
    )
    log = built.stdout + built.stderr
    warned = [line for line in log.splitlines() if line.startswith(("WARNING", "ERROR"))]
    assert built.returncode == 0 and not warned, "\n".join(warned) or log[-2000:]
    return out


def test_the_checker_sees_a_raw_role(tmp_path):
    page = tmp_path / "index.html"
    page.write_text("<p>Returns a <code>Trajectory</code> (see :class:<code>Trajectory</code>)</p>")
    assert RAW_ROLE.search(_text(page))
    page.write_text('<p>Returns a <a href="#x"><code>Trajectory</code></a> at 12:30 :)</p>')
    assert not RAW_ROLE.search(_text(page))


def test_no_built_page_shows_a_raw_role(site):
    pages = sorted(site.rglob("*.html"))
    assert any(p.parent.name == "prompt" and p.parent.parent.name == "api" for p in pages)
    found = {
        str(p.relative_to(site)): m.group(0) for p in pages if (m := RAW_ROLE.search(_text(p)))
    }
    assert not found, f"pages showing a raw Sphinx role: {found}"


def test_api_pages_list_public_names_only(site):
    ids = set()
    for page in (site / "api").rglob("*.html"):
        ids |= set(re.findall(r'id="(jswim\.[\w.]+)"', page.read_text(encoding="utf-8")))
    assert "jswim.prompt.PromptTemplate" in ids and "jswim.gym" in ids
    private = sorted(i for i in ids if any(part.startswith("_") for part in i.split(".")[1:]))
    assert not [i for i in private if not i.startswith("jswim._io")], private
    # Imported names are not listed again under the importing module.
    assert "jswim.agents.pair_prompt.SwimmerText" not in ids


def test_an_api_page_in_the_browser_shows_links_not_roles(site):
    with browser_or_skip() as b:
        b.open((site / "api" / "prompt" / "index.html").as_uri())
        text = b.eval("document.body.innerText")
        assert "PromptTemplate" in text
        assert not RAW_ROLE.search(text), RAW_ROLE.search(text).group(0)
        links = b.eval(
            "[...document.querySelectorAll('a.autorefs')].map(a => a.getAttribute('href'))"
        )
        assert links and all(h and "#jswim." in h for h in links), links[:5]


def test_ci_docs_step_fails_on_a_broken_reference(tmp_path):
    # .ci/docs on a copy of the sources: it passes, then fails once a docstring links to a name
    # the API pages do not hold, naming it (a build with --quiet passed both ways)
    pytest.importorskip("mkdocstrings", reason="the docs extra: pip install -e '.[docs]'")
    ignore = shutil.ignore_patterns("__pycache__", "*.pyc")
    for part in ("jswim", "docs", ".ci"):
        shutil.copytree(ROOT / part, tmp_path / part, ignore=ignore)
    shutil.copy(ROOT / "mkdocs.yml", tmp_path)
    step = ["bash", str(tmp_path / ".ci" / "docs"), sys.executable, "-m", "mkdocs"]
    passed = subprocess.run(step, capture_output=True, text=True, timeout=300)
    assert passed.returncode == 0, passed.stdout + passed.stderr
    assert "INFO" not in passed.stdout  # the INFO lines are left out
    row = tmp_path / "jswim" / "results" / "row.py"
    text = row.read_text(encoding="utf-8")
    good = "[`jswim.env.flows`][jswim.env.flows]"
    assert good in text
    row.write_text(text.replace(good, "[`jswim.env.flows`][jswim.env.no_such_name]", 1))
    failed = subprocess.run(step, capture_output=True, text=True, timeout=300)
    assert failed.returncode != 0, failed.stdout
    assert "jswim.env.no_such_name" in failed.stdout and "WARNING" in failed.stdout
