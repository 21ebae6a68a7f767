"""Shared test setup: dtypes, the session's temporary caches, and the test tiers.

Physics accuracy is asserted in float64, so x64 is on for the suite. Users run with JAX's
default (x64 off, float32), so the ``float32`` fixture runs a test under
``jax.enable_x64(False)``: the dtype users get, in-process (one subprocess test,
tests/env/test_scale.py, also checks a fresh interpreter with JAX's defaults and 4 host devices).

Caches. The exact tables' disk cache (``$JSWIM_TABLE_CACHE``) and JAX's persistent compilation
cache (``$JAX_COMPILATION_CACHE_DIR``, which ``jswim.compile_cache.enable`` leaves as it finds it)
go to one fresh temporary folder per session, never the user's home. The variables are set
before JAX is imported, so this process, every pytest-xdist worker (they inherit the
controller's environment) and every ``jswim`` subprocess a test starts share them; whoever
made the folder removes it at the end.

Tiers. Tests live in one folder per layer (tests/physics, env, judging, prompt, llm, agents,
studies, views, cli, e2e). Everything in tests/e2e (README and docs examples, notebooks) is
``slow``; so are tests marked ``slow`` one by one (compile-heavy, browser). ``model`` tests
start the embedded model. The fast tier is ``pytest -m "not slow and not model"``.
"""

from __future__ import annotations

import os
import shutil
import tempfile
from pathlib import Path

_OWNER = "JSWIM_TEST_CACHE_ROOT"
if os.environ.get(_OWNER) and os.path.isdir(os.environ[_OWNER]):
    _made_here = False  # an xdist worker, or a nested pytest: the session's folder already exists
else:
    os.environ[_OWNER] = tempfile.mkdtemp(prefix="jswim-test-caches-")
    _made_here = True
_ROOT = Path(os.environ[_OWNER])
os.environ["JSWIM_TABLE_CACHE"] = str(_ROOT / "tables")
os.environ["JAX_COMPILATION_CACHE_DIR"] = str(_ROOT / "jax")
# the value jswim.compile_cache uses for the command; JAX's default (1 s) would keep little
os.environ["JAX_PERSISTENT_CACHE_MIN_COMPILE_TIME_SECS"] = "0.05"

import jax  # noqa: E402  (after the cache variables, which JAX reads at import)
import pytest  # noqa: E402

jax.config.update("jax_enable_x64", True)
jax.config.update("jax_compilation_cache_dir", os.environ["JAX_COMPILATION_CACHE_DIR"])
jax.config.update("jax_persistent_cache_min_compile_time_secs", 0.05)

_TESTS = Path(__file__).resolve().parent
#: folders whose every test is in the slow tier
SLOW_FOLDERS = ("e2e",)


def pytest_collection_modifyitems(config, items):
    """Mark by folder: each test gets its layer's marker, and ``slow`` where its folder is slow."""
    for item in items:
        try:
            layer = Path(str(item.fspath)).resolve().relative_to(_TESTS).parts[0]
        except ValueError:
            continue
        if layer.endswith(".py"):
            continue
        item.add_marker(getattr(pytest.mark, layer))
        if layer in SLOW_FOLDERS:
            item.add_marker(pytest.mark.slow)


def pytest_unconfigure(config):
    if _made_here and not os.environ.get("PYTEST_XDIST_WORKER"):
        shutil.rmtree(_ROOT, ignore_errors=True)


@pytest.fixture(autouse=True, scope="module")
def _fresh_jax_caches():
    """Drop JAX's in-memory compiled programs after each module.

    Without this the process keeps every program any earlier module compiled (the full run's
    peak resident set grew to 5.8 GB); what a later module needs again comes back from the
    session's persistent cache on disk.
    """
    yield
    jax.clear_caches()


@pytest.fixture
def float32():
    """Run the test with x64 off, as a user's session is by default."""
    with jax.enable_x64(False):
        yield
