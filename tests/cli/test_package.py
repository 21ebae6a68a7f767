"""The package's top level and its error root."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

import jswim
from jswim import errors


def test_top_level_names_are_the_owners_and_load_lazily():
    code = (
        "import sys, jswim; assert 'jax' not in sys.modules, 'import jswim loaded jax'; "
        "jswim.rollout; assert 'jax' in sys.modules"
    )
    subprocess.run([sys.executable, "-c", code], check=True, cwd=str(Path(__file__).parents[2]))
    from jswim import env, results, studies
    from jswim.env import episodes

    assert (
        jswim.rollout is episodes.rollout  # the protocol's one rollout
        and jswim.step_batch is env.step_batch
        and jswim.reset is env.reset
    )
    assert jswim.make_params is env.make_params and jswim.step is env.step
    assert jswim.run_study is studies.run_study and jswim.load is results.load
    assert {"rollout", "make_params", "reset", "step", "step_batch", "run_study", "load"} <= set(
        jswim.__all__
    )
    assert "Where to start" in jswim.__doc__ and "docs/design.md" in jswim.__doc__
    with pytest.raises(AttributeError):
        jswim.no_such_name


def test_subpackages_resolve_after_import_jswim_alone():
    # the names the docs use (jswim.env.rollout_moves, jswim.agents.qlearning.train) resolve in a
    # fresh interpreter after `import jswim` alone, and nothing heavy loads before they are used
    code = (
        "import sys, jswim; assert 'jax' not in sys.modules; "
        "assert 'env' in dir(jswim) and 'qlearning' in dir(jswim.agents); "
        "jswim.env.rollout_moves; jswim.agents.qlearning.train; jswim.scenes.Scene; "
        "jswim.agents.steering.run; jswim.agents.ppo.train; jswim.results.load"
    )
    subprocess.run([sys.executable, "-c", code], check=True, cwd=str(Path(__file__).parents[2]))
    with pytest.raises(AttributeError):
        jswim.agents.no_such_agent


def test_help_starts_light():
    # `jswim --help` and `jswim` alone: the outline of the commands, without JAX, NumPy or httpx
    # (the study grids load JAX; the LLM client httpx), and `python -m jswim.cli` is the command too.
    code = (
        "import sys, runpy; sys.argv = ['jswim', '--help']\n"
        "try:\n    runpy.run_module('jswim.cli', run_name='__main__')\nexcept SystemExit as e:\n"
        "    assert e.code == 0, e.code\n"
        "heavy = [m for m in ('jax', 'numpy', 'httpx') if m in sys.modules]\n"
        "assert not heavy, f'jswim --help imported {heavy}'"
    )
    out = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        cwd=str(Path(__file__).parents[2]),
    )
    assert out.returncode == 0, out.stderr
    assert "swim" in out.stdout and "bench" in out.stdout


def test_every_error_class_is_defined_in_the_tree():
    # errors.py holds every public exception class (the tree); others may only re-export them.
    import ast

    from jswim._io import folderlock
    from jswim.llm import budget, server_response

    outside = []
    for path in Path(jswim.__file__).parent.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if (
                isinstance(node, ast.ClassDef)
                and not node.name.startswith("_")
                and any(
                    getattr(b, "id", getattr(b, "attr", "")).endswith(("Error", "Exception"))
                    for b in node.bases
                )
            ):
                outside += [f"{path.name}:{node.name}"] if path.name != "errors.py" else []
    assert not outside, outside
    assert (
        budget.BudgetExhausted is errors.BudgetExhausted
        and server_response.MalformedReply is errors.MalformedReply
    )
    assert folderlock.FolderBusyError is errors.FolderBusyError and issubclass(
        errors.MalformedReply, ValueError
    )


def test_every_user_error_derives_from_the_root():
    for cls in (
        errors.ConfigError,
        errors.PositionBelowMinimumError,
        errors.LLMError,
        errors.LLMServerError,
        errors.LLMRequestError,
        errors.LLMResponseError,
        errors.LocalModelError,
        errors.ResultFolderError,
        errors.BudgetExhausted,
        errors.MalformedReply,
        errors.FolderBusyError,
        errors.StudyFolderError,
    ):
        assert issubclass(cls, errors.JswimError)
        assert cls.__name__ in errors.__doc__  # the tree in the docstring names every class
    assert issubclass(errors.ConfigError, ValueError) and issubclass(errors.LLMError, RuntimeError)
    from jswim.llm import ClientSettings

    with pytest.raises(errors.ConfigError, match="temperature"):
        ClientSettings(temperature=5.0)
    with pytest.raises(errors.ConfigError, match="constrain"):
        ClientSettings(constrain="regex")


#: Packages whose __init__ names its public surface (agents: the pipeline's rework names it).
CURATED = (
    "jswim",
    "jswim._io",
    "jswim.agents",
    "jswim.bench",
    "jswim.cli",
    "jswim.env",
    "jswim.figures",
    "jswim.judging",
    "jswim.llm",
    "jswim.prompt",
    "jswim.results",
    "jswim.scenes",
    "jswim.studies",
    "jswim.swimmers",
    "jswim.viz",
)


def test_the_top_level_offers_the_first_four_first():
    assert jswim.__all__[:4] == ["make", "rollout", "run_study", "load"]
    assert "jswim.make" in jswim.__doc__ and "jswim.rollout(env, params, key" in jswim.__doc__


def test_every_package_names_its_public_surface_and_each_name_resolves():
    import importlib

    for name in CURATED:
        package = importlib.import_module(name)
        names = package.__all__
        assert names and len(set(names)) == len(names), name
        assert not [n for n in names if n.startswith("_") and n != "__version__"], name
        for n in names:
            assert getattr(package, n) is not None, f"{name}.{n}"


def test_no_alias_module_is_left():
    # 0.x: a moved module leaves no alias behind (CHANGELOG.md lists the old paths).
    old_paths = ("plots", "gait", "jsonl", "lattice", "stats", "shape_judge", "folderlock")
    for old in (*old_paths, "permissions", "interrupts", "scene_plots", "figure_style"):
        assert not (Path(jswim.__file__).parent / f"{old}.py").exists(), old


def test_docstrings_cross_reference_in_the_syntax_the_site_renders():
    # mkdocstrings shows a Sphinx role (:class:`X`) as raw text; the site's syntax is
    # [`X`][jswim.module.X] (or `X` where the target is not in the API pages).
    import re

    role = re.compile(r":(?:py:)?(?:class|meth|func|mod|attr|data|exc|obj|const):`")
    found = [
        f"{path.relative_to(Path(jswim.__file__).parents[1])}:{i}"
        for path in sorted(Path(jswim.__file__).parent.rglob("*.py"))
        for i, line in enumerate(path.read_text().splitlines(), 1)
        if role.search(line)
    ]
    assert not found, "Sphinx roles (write [`X`][jswim.path.X]): " + ", ".join(found)
