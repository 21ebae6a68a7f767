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

import ctypes
import gc
import os
import re
import resource
import shutil
import subprocess
import sys
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


def pytest_configure(config):
    """With ``-n N`` and no ``--dist``: whole files to a worker (pytest-xdist's ``loadfile``), so a
    module's module-scoped fixtures (small studies) are built once and its programs compiled once;
    xdist's default (``load``) split such modules between the workers, which built them twice."""
    if getattr(config.option, "dist", "no") == "load" and not any(
        a.startswith("--dist") for a in config.invocation_params.args
    ):
        config.option.dist = "loadfile"
    _fast_tier_codegen(config)


def _fast_tier_codegen(config):
    """The fast tier compiles cheaply: LLVM at -O0 and XLA's classic CPU fusion emitters.

    Much of the fast tier's time is XLA compiling programs that then run a few steps. Two flags
    go into ``XLA_FLAGS`` (each one only where the caller has not set it):

    - ``--xla_backend_optimization_level=0``: LLVM at -O0. The HLO passes are unchanged, and
      LLVM does not reorder floating point without fast-math at any level. On 2026-12-03 the
      tier took 4:15 in place of 5:11.
    - ``--xla_cpu_use_fusion_emitters=false``: fusions go through XLA's older IR emitters in
      place of the MLIR fusion emitters, which spend longer compiling each small program. On
      2026-12-04 the tier went from 420 to 301 CPU-s (3:49 to 3:02 wall), every test passing.

    The slow tier (``-m`` naming slow or model) and ``-m ""`` keep XLA's defaults, the code users
    run. XLA reads ``XLA_FLAGS`` when the backend starts (the first computation, after this hook);
    the controller sets them and every xdist worker inherits them. XLA aborts the process on a
    flag it does not know, and the fusion-emitter flag is recent (pyproject allows older jaxlibs),
    so that one is tried first in a throwaway interpreter (:func:`_xla_accepts`).
    """
    expr = config.option.markexpr or ""
    if (
        os.environ.get("PYTEST_XDIST_WORKER")
        or not expr
        or re.search(r"(?<!not )\b(slow|model)\b", expr)
    ):
        return
    flags = os.environ.get("XLA_FLAGS", "")
    if "xla_backend_optimization_level" not in flags:
        flags = f"{flags} --xla_backend_optimization_level=0".strip()
    emitters = "--xla_cpu_use_fusion_emitters=false"
    if "xla_cpu_use_fusion_emitters" not in flags and _xla_accepts(config, emitters):
        flags = f"{flags} {emitters}".strip()
    os.environ["XLA_FLAGS"] = flags


def _xla_accepts(config, flag: str) -> bool:
    """Whether this jaxlib's XLA starts with ``flag`` (a child interpreter runs one computation).

    About 2 s; the answer is kept in pytest's cache (``.pytest_cache``) per jaxlib version.
    """
    import jaxlib

    key = f"jswim/xla-accepts/{jaxlib.__version__}/{flag.lstrip('-')}"
    cache = getattr(config, "cache", None)  # absent under -p no:cacheprovider
    known = cache.get(key, None) if cache is not None else None
    if known is not None:
        return bool(known)
    env = {**os.environ, "XLA_FLAGS": flag, "JAX_PLATFORMS": "cpu"}
    try:
        ok = (
            subprocess.run(
                [sys.executable, "-c", "import jax.numpy as j; j.zeros(1).block_until_ready()"],
                env=env,
                capture_output=True,
                timeout=120,
                check=False,
            ).returncode
            == 0
        )
    except (OSError, subprocess.TimeoutExpired):
        return False
    if cache is not None:
        cache.set(key, ok)
    return ok


def pytest_unconfigure(config):
    if _made_here and not os.environ.get("PYTEST_XDIST_WORKER"):
        shutil.rmtree(_ROOT, ignore_errors=True)


def _malloc_trim() -> None:
    try:  # glibc only: hand the heap that XLA's compiles freed back to the system
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass


#: A process holding more than this after a module drops JAX's compiled programs (GB, resident).
#: Kept below it, a later module reuses them in memory (no retracing, relowering, reloading).
_KEEP_PROGRAMS_BELOW_GB = float(os.environ.get("JSWIM_TEST_KEEP_PROGRAMS_GB", "0.8"))


def _resident_gb() -> float | None:
    try:  # Linux: the resident set now (not the peak)
        with open("/proc/self/statm") as fh:
            return int(fh.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 1e9
    except (OSError, ValueError, IndexError):
        return None


@pytest.fixture(autouse=True, scope="module")
def _fresh_jax_caches():
    """After each module, close the figures it left open; past a memory budget, drop JAX's
    in-memory compiled programs too.

    Keeping every program any earlier module compiled grew the full run's peak resident set to
    5.8 GB; dropping them after every module made each later module retrace, relower and reload
    from the session's persistent cache what it shared with earlier ones. So they are dropped
    only once the process holds more than ``_KEEP_PROGRAMS_BELOW_GB``.
    """
    yield
    plt = sys.modules.get("matplotlib.pyplot")
    if plt is not None:
        plt.close("all")  # pyplot keeps every figure a test made and did not close
    rss = _resident_gb()
    if rss is None or rss > _KEEP_PROGRAMS_BELOW_GB:
        jax.clear_caches()
        gc.collect()
        _malloc_trim()


# -- peak resident set: one line at the end of every run, per process ------------------------------


def _peak_rss_gb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e6  # Linux reports KiB


def pytest_sessionfinish(session):
    workeroutput = getattr(session.config, "workeroutput", None)
    if workeroutput is not None:  # an xdist worker: tell the controller its peak
        workeroutput["peak_rss_gb"] = _peak_rss_gb()


_worker_peaks: dict[str, float] = {}


@pytest.hookimpl(optionalhook=True)  # pytest-xdist's hook: absent without it
def pytest_testnodedown(node, error):
    peak = getattr(node, "workeroutput", {}).get("peak_rss_gb")
    if peak is not None:
        _worker_peaks[node.gateway.id] = peak


def pytest_terminal_summary(terminalreporter):
    parts = [f"{w} {gb:.2f} GB" for w, gb in sorted(_worker_peaks.items())]
    parts.append(f"this process {_peak_rss_gb():.2f} GB")
    total = sum(_worker_peaks.values()) + _peak_rss_gb()
    terminalreporter.write_line(
        f"peak resident set: {', '.join(parts)}"
        + (f" (together at most {total:.2f} GB)" if _worker_peaks else "")
    )


@pytest.fixture(scope="session")
def small_swim_study() -> Path:
    """A complete small swim study, built once per session and shared by every worker.

    Purcell and NG toward +x and -x, 8 steps: 1 LLM run (the fake server's hash replies), 3
    Q-learning and 3 random runs per setting (28 runs), no figures. Tests read it and never write
    to it (copy it first). The first process to ask builds it under a file lock; the others wait
    and reuse it, so the session pays for its compiles and runs once.
    """
    from filelock import FileLock

    from jswim.studies.options import StudyOptions
    from jswim.studies.run import run_study
    from jswim.viz.publish import report
    from tests.fakeserver import FakeServer, hash_reply

    home = _ROOT / "studies"
    home.mkdir(exist_ok=True)
    folder, built = home / "swim-small", home / "swim-small.built"
    with FileLock(str(home / "swim-small.lock")):
        if not built.exists():
            shutil.rmtree(folder, ignore_errors=True)  # a build cut short by a failed test
            with FakeServer(reply=hash_reply, latency=0.001) as srv:
                opts = StudyOptions(
                    swimmers=("purcell", "ng"), directions=(1, -1), steps=8, runs=1, q_runs=3
                )
                run_study("swim", opts, srv.backend(), folder)
            report(folder, figures=False)  # the publish step: the page, without figures
            built.touch()
    return folder


@pytest.fixture
def float32():
    """Run the test with x64 off, as a user's session is by default."""
    with jax.enable_x64(False):
        yield
