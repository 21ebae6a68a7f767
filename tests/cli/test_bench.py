"""`jswim bench` end to end: two fake servers (plain; behaving as OpenAI's reasoning models) and the
reference rule, the core suite at tiny sizes (--runs/--q-runs/--steps, the documented size
overrides), a model whose server is down, Ctrl-C and the same command resuming with no call paid
twice, the dry run's prices, and the leaderboard's files."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from jswim import cli
from jswim.bench.leaderboard import FIELDS
from jswim.figures import leaderboard as leaderboard_figure
from jswim.bench.models_file import load_models_file, parse_model_option
from jswim.errors import ConfigError
from tests.fakeserver import FakeServer, hash_reply, reasoning_model

ROOT = Path(__file__).resolve().parents[2]
SIZES = ["--runs", "1", "--q-runs", "2", "--steps", "12"]


def journal(folder: Path) -> list[dict]:
    path = folder / "calls.jsonl"
    return (
        [json.loads(ln) for ln in path.read_text().splitlines() if ln.strip()]
        if path.exists()
        else []
    )


def models_file(tmp_path: Path, plain: str, reasoning: str) -> Path:
    path = tmp_path / "models.toml"
    path.write_text(f'''
[[models]]
name = "plain"
base_url = "{plain}"
model = "fake-plain"
concurrency = 4

[[models]]
name = "gpt-5"
base_url = "{reasoning}"
model = "gpt-5"
max_cost = 5.0

[[models]]
name = "down"
base_url = "http://127.0.0.1:9/v1"
model = "nothing-listens"

[prices]
as_of = "2026-11"
"gpt-5" = [1.25, 10.0]
''')
    return path


def bench(*args: str) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    return subprocess.Popen(
        [sys.executable, "-m", "jswim", "bench", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        cwd=ROOT,
    )


@pytest.mark.slow
def test_core_bench_three_servers_down_one_interrupt_and_resume(tmp_path):
    out = tmp_path / "b"
    with (
        FakeServer(reply=hash_reply, latency=0.2) as plain,
        FakeServer(reply=reasoning_model(hash_reply), latency=0.2) as rsn,
    ):
        models = models_file(tmp_path, plain.url, rsn.url)
        first = bench(str(models), "--suite", "core", "--out", str(out), *SIZES)
        deadline = time.monotonic() + 300
        while time.monotonic() < deadline and not journal(out / "plain" / "curves"):
            time.sleep(0.1)
        assert journal(out / "plain" / "curves"), first.communicate()
        first.send_signal(signal.SIGINT)
        _, err1 = first.communicate(timeout=120)
        assert (
            first.returncode == 130
            and "Run the same command to resume" in err1
            and "Traceback" not in err1
        )
        assert json.loads((out / "bench.json").read_text())["status"] == "interrupted"
        paid_before = {m: len(journal(out / m / "curves")) for m in ("plain", "gpt-5")}

        second = bench(str(models), "--suite", "core", "--out", str(out), *SIZES)
        text, err2 = second.communicate(timeout=600)
        answered = {"plain": plain.n_answered, "gpt-5": rsn.n_answered}
    assert second.returncode == 2, err2  # one model failed: the others finished
    assert "model down" in err2 and "cannot reach" in err2 and "Traceback" not in err2
    # The leaderboard: every model and the reference, each baseline once per setting.
    rows = json.loads((out / "leaderboard.json").read_text())["rows"]
    assert json.loads((out / "leaderboard.json").read_text())["schema"] == list(FIELDS)
    for label in ("plain", "gpt-5", "reference"):
        assert {(r["part"], r["swimmer"], r["direction"]) for r in rows if r["row"] == label} == {
            ("curves", "purcell", 1),
            ("curves", "purcell", -1),
            ("curves", "ng", 1),
            ("curves", "ng", -1),
            ("noise", "purcell", 1),
            ("noise", "ng", 1),
        }
    base = [
        (r["row"], r["part"], r["swimmer"], r["direction"]) for r in rows if r["kind"] == "baseline"
    ]
    assert len(base) == len(set(base)) == 2 * 6 and not any(r["row"] == "down" for r in rows)
    assert "reference (rule, not an LLM)" in text and "Q-learning" in text and "random" in text
    assert (
        "missing rows: down curves (failed: cannot reach" in text
        and "missing rows: down noise (not run: down stopped at curves (failed" in text
    )
    assert "gpt-5: gpt-5 accepts only temperature 1" in text  # the deviation from T = 0, printed
    assert all((out / f"leaderboard.{ext}").exists() for ext in ("csv", "png", "pdf"))
    gpt5 = [r for r in rows if r["row"] == "gpt-5"]
    assert all(r["priced"] and r["suite_cost_usd"] > 0 for r in gpt5)
    assert all(r["priced"] is False for r in rows if r["row"] == "plain")  # no price: said, not $0
    status = json.loads((out / "bench.json").read_text())["model_status"]
    assert status["plain"] == status["gpt-5"] == "complete" and status["down"].startswith("failed")
    # No call paid twice: every (run, call index) journaled once, and the servers answered no more
    # than the journals hold plus what was in flight at Ctrl-C (4 + 16 requests at most).
    for m in ("plain", "gpt-5"):
        calls = [c for part in ("curves", "noise") for c in journal(out / m / part)]
        assert len({(c["run"], c["n"]) for c in calls}) == len(calls)
        assert len(calls) <= answered[m] <= len(calls) + 20
        assert len(journal(out / m / "curves")) >= paid_before[m]
    # Each model's results are an ordinary study folder: show reads it.
    assert cli.main(["show", str(out / "gpt-5" / "curves")]) == 0


@pytest.mark.slow  # a bench dry run of every suite part (57 s under load 8)
def test_dry_run_prices_every_model_and_core_on_gpt4o_is_at_most_3_dollars(tmp_path, capsys):
    models = models_file(tmp_path, "http://127.0.0.1:9/v1", "http://127.0.0.1:9/v1")
    assert cli.main(["bench", str(models), "--dry-run", "--out", str(tmp_path / "b"), *SIZES]) == 0
    text = capsys.readouterr().out
    est = json.loads(text.strip().splitlines()[-1])
    assert set(est["models"]) == {"plain", "gpt-5", "down"}
    assert est["models"]["gpt-5"]["priced"] and est["models"]["gpt-5"]["prices_as_of"] == "2026-11"
    assert not est["models"]["plain"]["priced"] and "not priced" in text
    assert est["models"]["plain"]["calls"] == 6 * 12  # six settings x one run x 12 steps
    assert not (tmp_path / "b").exists()  # nothing written
    # The suite as defined (no size override) on gpt-4o at the built-in list prices.
    assert (
        cli.main(
            ["bench", "--model", "base_url=https://api.openai.com/v1,model=gpt-4o", "--dry-run"]
        )
        == 0
    )
    est = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
    assert est["models"]["gpt-4o"]["calls"] == 3000 and est["total_usd"] <= 3.0


def test_models_file_mistakes_are_one_line(tmp_path):
    bad = tmp_path / "m.toml"
    for text, words in [
        ('[[models]]\nname = "x"\n', "needs base_url"),
        ('[[models]]\nbase_url = "http://a/v1"\nmodel = "m"\ncolour = 1\n', "unknown key 'colour'"),
        (
            '[[models]]\nbase_url = "http://a/v1"\nmodel = "m"\nname = "baselines"\n',
            "bench's own row",
        ),
        ('[suites.x]\nstudy = "nope"\n', "study must be one of"),
        (
            '[suites.x]\nstudy = "swim"\noptions = { temperatures = [0, 0.5] }\n',
            "jswim swim takes no --temperatures",
        ),
        (
            '[suites.x]\nstudy = "history"\noptions = { q_runs = 3 }\n',
            "history study has no use for q_runs",
        ),
        ("[[models]\n", "not valid TOML"),
    ]:
        bad.write_text(text)
        with pytest.raises(ConfigError, match=words):
            load_models_file(bad)
    assert parse_model_option("base_url=http://a/v1,model=m,concurrency=3").get("concurrency") == 3
    assert cli.main(["bench", str(tmp_path / "missing.toml")]) == 2


@pytest.mark.slow  # a bench run end to end, twice (22 s under load 8)
def test_bench_samples_grow_a_folder_and_show_in_the_leaderboard(tmp_path, capsys):
    import dataclasses

    from jswim.bench import leaderboard, runner
    from jswim.bench.suites import CORE

    models = (parse_model_option("base_url=http://127.0.0.1:9/v1,model=m"),)
    out = tmp_path / "b"
    suite = dataclasses.replace(CORE, sizes=(("runs", 1),))
    runner.open_folder(out, runner.definition(suite, models, True, True))[1].release()
    grown = dataclasses.replace(suite, samples=3)
    meta, lock = runner.open_folder(
        out, runner.definition(grown, models, True, True)
    )  # not another definition
    lock.release()
    assert meta["samples"] == 3
    jobs = runner.plan(models, grown, out, prices_file=None, reference_url="http://127.0.0.1:1/v1")
    for j in jobs:
        i = j.argv.index("--samples")
        assert j.argv[i + 1] == "3"
    with pytest.raises(
        ConfigError, match="another suite definition"
    ):  # a size is part of the definition
        runner.open_folder(
            out,
            runner.definition(dataclasses.replace(grown, sizes=(("runs", 2),)), models, True, True),
        )
    # The dry run prices every sample: three times the calls of one.
    args = [
        "bench",
        "--model",
        "base_url=http://127.0.0.1:9/v1,model=gpt-4o",
        "--dry-run",
        "--out",
        str(tmp_path / "d"),
        "--runs",
        "1",
        "--steps",
        "4",
    ]
    assert cli.main(args) == 0
    one = json.loads(capsys.readouterr().out.strip().splitlines()[-1])["models"]["gpt-4o"]["calls"]
    assert cli.main([*args, "--samples", "3"]) == 0
    three = json.loads(capsys.readouterr().out.strip().splitlines()[-1])["models"]["gpt-4o"][
        "calls"
    ]
    assert one == 6 * 4 and three == 3 * one
    assert cli.main([*args, "--samples", "0"]) == 2
    # A row pooling samples says how many.
    row = {
        "row": "m",
        "kind": "llm",
        "part": "curves",
        "swimmer": "purcell",
        "direction": 1,
        "group": "",
        "n": 3,
        "samples": 3,
        "success": 0.0,
        "success_lo": 0.0,
        "success_hi": 0.56,
        "learned": 0,
        "steps_median": None,
        "steps_q25": None,
        "steps_q75": None,
        "mean_x": 0.1,
        "failed_steps": 0,
        "tokens_per_step": 100.0,
        "suite_cost_usd": 0.0,
        "priced": False,
        "status": "complete",
    }
    text = leaderboard.table_text([row])
    header, line = [ln for ln in text.splitlines() if ln.strip() and not set(ln) <= set("-+ |")][:2]
    assert "samples" in header and "- (0 of 3)" in line


def test_leaderboard_figure_draws_rows_at_p_0_and_1_for_any_n(tmp_path):
    from jswim.judging.stats import wilson_interval

    rows = []
    for n in (
        6,
        11,
        21,
    ):  # sizes where Wilson's bounds rounded past p (an interrupted part holds any n)
        for k in (0, n):
            lo, hi = wilson_interval(k, n)
            rows.append(
                {
                    "row": f"m{n}-{k}",
                    "kind": "llm",
                    "part": "curves",
                    "swimmer": "purcell",
                    "direction": 1,
                    "group": "",
                    "n": n,
                    "samples": 1,
                    "success": k / n,
                    "success_lo": lo,
                    "success_hi": hi,
                }
            )
    paths = leaderboard_figure.figure(tmp_path, rows)
    assert any(p.suffix == ".png" and p.stat().st_size > 0 for p in paths)


def test_dry_run_warns_when_a_models_cap_is_below_its_estimate(tmp_path, capsys):
    base = [
        "bench",
        "--dry-run",
        "--out",
        str(tmp_path / "d"),
        "--runs",
        "1",
        "--steps",
        "4",
        "--model",
    ]
    assert (
        cli.main(
            [*base, "base_url=http://127.0.0.1:9/v1,model=gpt-4o,max_cost=0.001,price_local=true"]
        )
        == 0
    )
    text = capsys.readouterr().out
    assert (
        "warning: gpt-4o: its max_cost $0.001 is below the estimated" in text
        and "would stop at the cap" in text
    )
    assert (
        cli.main(
            [*base, "base_url=http://127.0.0.1:9/v1,model=gpt-4o,max_cost=100,price_local=true"]
        )
        == 0
    )
    assert "max_cost" not in capsys.readouterr().out


def test_show_on_a_bench_folder_prints_its_leaderboard(tmp_path, capsys):
    from jswim.bench import leaderboard, runner
    from jswim.bench.suites import CORE

    out = tmp_path / "b"
    models = (parse_model_option("base_url=http://127.0.0.1:9/v1,model=m"),)
    meta, lock = runner.open_folder(
        out,
        {
            **runner.definition(CORE, models, True, True),
            "status": "complete",
            "model_status": {"m": "complete", "down": "failed: cannot reach it"},
        },
    )
    lock.release()
    assert cli.main(["show", str(out)]) == 0
    assert "no leaderboard yet" in capsys.readouterr().out
    row = {
        "row": "m",
        "kind": "llm",
        "part": "curves",
        "swimmer": "ng",
        "direction": -1,
        "group": "",
        "n": 10,
        "samples": 1,
        "success": 0.3,
        "success_lo": 0.11,
        "success_hi": 0.6,
        "learned": 3,
        "steps_median": 21.0,
        "steps_q25": 18.0,
        "steps_q75": 30.0,
        "mean_x": 0.2,
        "failed_steps": 1,
        "tokens_per_step": 240.0,
        "suite_cost_usd": 1.25,
        "priced": True,
        "status": "complete",
    }
    leaderboard.write_files(out, [row], meta)
    assert cli.main(["show", str(out)]) == 0
    text = capsys.readouterr().out
    assert "bench core (seed 0)" in text and "down: failed: cannot reach it" in text
    assert "21 (3 of 10)" in text and "1.2500" in text  # 3 that learned: the median, no IQR


def test_leaderboard_figure_draws_x_a_beside_success_and_labels_every_panel():

    rows = []
    for part, sw, d in (("curves", "purcell", 1), ("curves", "purcell", -1), ("curves", "ng", 1)):
        for name, kind, mx in (
            ("m", "llm", 0.12),
            ("Q-learning", "baseline", 0.4),
            ("random", "baseline", -0.05),
        ):
            rows.append(
                {
                    "row": name,
                    "kind": kind,
                    "part": part,
                    "swimmer": sw,
                    "direction": d,
                    "group": "",
                    "n": 10,
                    "samples": 1,
                    "success": 0.0,
                    "success_lo": 0.0,
                    "success_hi": 0.28,
                    "mean_x": mx,
                    "mean_x_lo": mx - 0.05,
                    "mean_x_hi": mx + 0.05,
                }
            )
    fig = leaderboard_figure.figure_object(rows)
    fig.canvas.draw()
    shown = [ax for ax in fig.axes if ax.axison]
    assert len(shown) == 2 * 3  # success p and X/a per setting
    for ax in shown:  # every panel, the top-right ones too, has its own x tick labels
        assert any(t.get_text() for t in ax.get_xticklabels()), ax.get_xlabel()
    xa = [ax for ax in shown if ax.get_xlabel().startswith("X/a end toward")]
    assert len(xa) == 3 and "toward -x" in xa[1].get_xlabel()
    # The X/a panel places each row at its mean: Q-learning (0.4) right of the model (0.12).
    xs = {
        round(float(line.get_xdata()[0]), 3)
        for line in xa[0].get_lines()
        if len(line.get_xdata()) == 1
    }
    assert {0.12, 0.4, -0.05} <= xs
