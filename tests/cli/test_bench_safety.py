"""A bench folder is as safe as a study folder: one lock, one exact budget over its parts, no
child left behind, nothing secret on a command line or in its files, a status that says what
happened, and one line (exit 2) for any input of the wrong type."""

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
from jswim.bench import runner
from jswim.bench.models_file import parse_model_option
from tests.fakeserver import FakeServer, hash_reply

ROOT = Path(__file__).resolve().parents[2]

TINY = """
[suites.tiny]
study = "swim"
options = {{ runs = 1, q_runs = 0, steps = {steps}, swimmer = "purcell", direction = "+x" }}
"""


def models_file(tmp_path: Path, body: str, steps: int = 4) -> Path:
    p = tmp_path / "models.toml"
    p.write_text(body + TINY.format(steps=steps))
    return p


def entry(url: str, **more: str) -> str:
    extra = "".join(f"\n{k} = {v}" for k, v in more.items())
    return f'[[models]]\nname = "m"\nbase_url = "{url}"\nmodel = "fake"{extra}\n'


@pytest.mark.parametrize(
    "more, said",
    [
        ({"price_local": '"false"'}, "price_local must be true or false"),
        ({"max_cost": "true"}, "max_cost must be a number"),
        ({"concurrency": '"8"'}, "concurrency must be a whole number"),
        ({"extra": "5"}, "extra must be a table"),
        ({"omit_fields": '"seed"'}, "omit_fields must be a list"),
    ],
)
def test_a_models_file_value_of_the_wrong_type_is_one_line(tmp_path, capsys, more, said):
    path = models_file(tmp_path, entry("http://127.0.0.1:9/v1", **more))
    assert cli.main(["bench", str(path), "--suite", "tiny", "--dry-run"]) == 2
    err = capsys.readouterr().err
    assert said in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize(
    "tail, said",
    [
        ('[prices]\nfake = "12"\n', "must be [prompt, completion]"),
        ("prices = 5\n", "prices must be a table"),
        ("suites = 5\n", "suites must be tables"),
        ("models = 5\n", "models must be an array"),
    ],
)
def test_a_models_file_table_of_the_wrong_type_is_one_line(tmp_path, capsys, tail, said):
    p = tmp_path / "models.toml"
    head = (
        entry("http://127.0.0.1:9/v1")
        if not tail.startswith(("models", "prices", "suites"))
        else ""
    )
    p.write_text(tail + "\n" + head)
    assert cli.main(["bench", str(p), "--dry-run"]) == 2
    err = capsys.readouterr().err
    assert said in err and "Traceback" not in err


def test_a_models_option_price_local_takes_only_true_or_false(capsys):
    assert (
        parse_model_option("base_url=http://h/v1,model=m,price_local=false").get("price_local")
        is False
    )
    assert (
        cli.main(
            ["bench", "--model", "base_url=http://h/v1,model=m,price_local=maybe", "--dry-run"]
        )
        == 2
    )
    assert "expected true or false" in capsys.readouterr().err


def test_a_fifo_or_a_device_is_no_models_or_prices_file(tmp_path, capsys):
    fifo = tmp_path / "models.toml"
    os.mkfifo(fifo)
    assert cli.main(["bench", str(fifo), "--dry-run"]) == 2  # returns: no hang on open or read
    assert "not a regular file" in capsys.readouterr().err
    from jswim.errors import ConfigError
    from jswim.llm.prices import load_prices

    with pytest.raises(ConfigError, match="not a regular file"):
        load_prices("/dev/zero")  # never read whole


def bench_args(out: Path, *more: str) -> list[str]:
    return [
        "bench",
        "--model",
        "base_url=http://127.0.0.1:9/v1,model=m",
        "--no-reference",
        "--no-baselines",
        "--runs",
        "1",
        "--steps",
        "4",
        "--suite",
        "core",
        "--out",
        str(out),
        *more,
    ]


@pytest.mark.parametrize(
    "record",
    ["[]", "null", '{"suite": 5}', '"text"', "{"],
    ids=["list", "null", "suite 5", "text", "not json"],
)
def test_a_bench_record_of_the_wrong_type_is_one_line(tmp_path, capsys, record):
    out = tmp_path / "b"
    out.mkdir()
    (out / "bench.json").write_text(record)
    assert cli.main(bench_args(out)) == 2
    err = capsys.readouterr().err
    assert ("bench.json" in err or "another suite definition" in err) and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
    assert cli.main(["show", str(out)]) in (0, 2)
    assert "Traceback" not in capsys.readouterr().err


def test_out_as_a_file_is_one_line(tmp_path, capsys):
    f = tmp_path / "file"
    f.write_text("x")
    assert cli.main(bench_args(f)) == 2
    assert "is a file" in capsys.readouterr().err and f.read_text() == "x"


def test_a_second_bench_on_the_same_folder_is_refused(tmp_path, capsys):
    from jswim._io.folderlock import FolderLock

    out = tmp_path / "b"
    out.mkdir()
    lock = FolderLock(out).acquire()  # another session holds the bench
    try:
        assert cli.main(bench_args(out)) == 2
        assert "in use" in capsys.readouterr().err
    finally:
        lock.release()


def test_show_reads_a_leaderboard_with_damaged_rows(tmp_path, capsys):
    from jswim.bench.suites import CORE

    out = tmp_path / "b"
    models = (parse_model_option("base_url=http://127.0.0.1:9/v1,model=m"),)
    meta, lock = runner.open_folder(out, runner.definition(CORE, models, False, False))
    lock.release()
    (out / "leaderboard.json").write_text(json.dumps({"rows": [{"row": "m"}, 5], "missing": 3}))
    assert cli.main(["show", str(out)]) == 0
    (out / "leaderboard.json").write_text("[1]")
    meta["model_status"] = "x"
    meta["samples"] = "many"
    (out / "bench.json").write_text(json.dumps(meta))
    assert cli.main(["show", str(out)]) == 0
    assert "Traceback" not in capsys.readouterr().err


def test_secrets_are_kept_out_of_the_record_and_the_log(tmp_path):
    m = parse_model_option("base_url=http://user:hunter2@127.0.0.1:9/v1,model=m")
    assert "hunter2" not in json.dumps(m.describe())
    shown = runner.shown_argv(
        ["--base-url", "http://user:hunter2@h/v1", "--extra-field", 'user="sk-abc123"']
    )
    assert "hunter2" not in shown and "sk-abc123" not in shown and "--extra-field user=..." in shown


class _Proc:
    returncode = 0

    def poll(self):
        return 0


def test_each_part_gets_what_the_models_cap_leaves_exactly_and_no_secret_on_its_command_line(
    tmp_path, monkeypatch
):
    from jswim.bench.suites import CORE
    from jswim.llm.ledger import RequestLedger

    m = parse_model_option("base_url=http://user:hunter2@127.0.0.1:9/v1,model=m,max_cost=0.0000015")
    out = tmp_path / "b"
    jobs = runner.plan([m], CORE, out, prices_file=None, reference_url=None, baselines=False)
    # An earlier part sent a request that got no answer: it still counts against the model's cap.
    earlier = jobs[1].folder
    earlier.mkdir(parents=True)
    ledger = RequestLedger(earlier)
    ledger.sent(0.0000005)
    ledger.close()
    seen = []

    def popen(argv, **kw):
        seen.append((argv, kw["env"]))
        return _Proc()

    monkeypatch.setattr(runner.subprocess, "Popen", popen)
    runner.run_jobs(jobs, out, {}, lambda text: None)
    argv, env = seen[0]
    assert "hunter2" not in " ".join(argv)  # the command line has no argument at all
    given = json.loads(env["JSWIM_BENCH_ARGV"])
    cap = float(given[given.index("--max-cost") + 1])
    assert cap == 0.0000015 - 0.0000005  # exact: never rounded to 6 decimals
    assert "hunter2" not in (jobs[0].log).read_text()


@pytest.mark.slow  # a bench of real child studies, a kill -9 and a resume (~20 s)
def test_kill_9_of_the_bench_takes_its_children_and_the_same_command_resumes(tmp_path, capsys):
    out = tmp_path / "b"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    with FakeServer(reply=hash_reply, latency=0.3) as srv:
        path = models_file(tmp_path, entry(srv.url), steps=30)
        cmd = [sys.executable, "-m", "jswim", "bench", str(path), "--suite", "tiny"]
        cmd += ["--no-reference", "--no-baselines", "--out", str(out)]
        first = subprocess.Popen(cmd, env=env, cwd=ROOT, stderr=subprocess.PIPE, text=True)
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and srv.n_requests < 2:
            time.sleep(0.1)
        kids = subprocess.run(
            ["ps", "-o", "pid=", "--ppid", str(first.pid)], capture_output=True, text=True
        ).stdout.split()
        assert kids, "the bench started no child"
        first.send_signal(signal.SIGKILL)
        first.wait()
        time.sleep(1.0)
        for pid in map(int, kids):
            alive = (
                Path(f"/proc/{pid}").exists()
                and "Z" not in Path(f"/proc/{pid}/stat").read_text().split()[2]
            )
            assert not alive, f"child {pid} outlived the bench"
        assert cli.main(["show", str(out)]) == 0  # bench.json still says running: show knows
        assert "no live session holds the folder" in capsys.readouterr().out
        again = subprocess.run(cmd, env=env, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stderr
    assert json.loads((out / "bench.json").read_text())["status"] == "complete"


@pytest.mark.slow  # a bench of one child study (~8 s)
def test_a_bench_whose_every_model_failed_says_failed(tmp_path):
    out = tmp_path / "b"
    path = models_file(tmp_path, entry("http://127.0.0.1:9/v1"))
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    cmd = [sys.executable, "-m", "jswim", "bench", str(path), "--suite", "tiny"]
    cmd += ["--no-reference", "--no-baselines", "--out", str(out)]
    done = subprocess.run(cmd, env=env, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert json.loads((out / "bench.json").read_text())["status"] == "failed"


def test_report_of_a_bench_to_another_file_writes_nothing_in_its_parts(
    tmp_path, monkeypatch, capsys
):
    from jswim.bench.suites import CORE
    from jswim.viz import bench_page

    out = tmp_path / "b"
    models = (parse_model_option("base_url=http://127.0.0.1:9/v1,model=m"),)
    runner.open_folder(out, runner.definition(CORE, models, False, False))[1].release()
    part = out / "m" / "curves"
    monkeypatch.setattr(
        bench_page, "part_folders", lambda folder, meta: [("m", "llm", "curves", part)]
    )
    written = []
    monkeypatch.setattr(bench_page, "write_report", lambda sub, **kw: written.append(sub))
    page = tmp_path / "elsewhere.html"
    assert cli.main(["report", str(out), "--out", str(page), "--figures", "none"]) == 0
    assert written == [] and page.exists() and not part.exists()
    assert cli.main(["report", str(out), "--figures", "none"]) == 0
    assert written == [part]  # without --out the parts' pages are drawn, as before


def test_a_bench_folder_that_cannot_be_written_is_one_line(tmp_path, monkeypatch, capsys):
    def refuse(path, text):
        raise PermissionError(13, "Permission denied", str(path))

    monkeypatch.setattr(runner, "atomic_write", refuse)  # a read-only folder (root ignores modes)
    assert cli.main(bench_args(tmp_path / "b")) == 2
    err = capsys.readouterr().err
    assert "cannot write" in err and "Permission denied" in err and "Traceback" not in err


def test_missing_rows_quote_their_own_part():
    from jswim.bench.suites import CORE
    from jswim.cli.bench import _missing

    m = parse_model_option("base_url=http://127.0.0.1:9/v1,model=m")
    jobs = runner.plan(
        [m], CORE, Path("/nonexistent"), prices_file=None, reference_url=None, baselines=False
    )
    first, second = jobs[0], jobs[1]
    first.rc = 2  # failed: its log is gone here, so its status speaks
    status = {"m": "failed: cannot reach it"}
    got = {r["part"]: r["why"] for r in _missing(jobs, [], status, {"m": first.part.name})}
    assert got[first.part.name] == "failed: cannot reach it"
    assert got[second.part.name].startswith(f"not run: m stopped at {first.part.name}")
    # A part that failed before another part stopped the model quotes its own log.
    first.log = Path(__file__)  # stands in for its log: no 'jswim: error:' line, the last line
    got = {r["part"]: r["why"] for r in _missing(jobs, [], status, {"m": second.part.name})}
    assert (
        got[first.part.name].startswith("failed: ") and "cannot reach" not in got[first.part.name]
    )


@pytest.mark.parametrize(
    "bench, board",
    [
        ("[]", None),
        ('{"suite": 5}', None),
        ("suite parts 5", None),
        ("models 5", None),
        ("status x", None),
        (None, {"rows": [{"row": "m", "kind": "llm"}], "missing": [5]}),
        (None, {"rows": 5}),
    ],
)
def test_report_and_show_of_a_damaged_bench_are_one_line_or_a_page(tmp_path, capsys, bench, board):
    from jswim.bench.suites import CORE

    out = tmp_path / "b"
    models = (parse_model_option("base_url=http://127.0.0.1:9/v1,model=m"),)
    meta, lock = runner.open_folder(out, runner.definition(CORE, models, False, False))
    lock.release()
    edits = {
        "suite parts 5": {**meta, "suite": {**meta["suite"], "parts": 5}},
        "models 5": {**meta, "models": 5},
        "status x": {**meta, "model_status": "x"},
    }
    if bench is not None:
        (out / "bench.json").write_text(json.dumps(edits[bench]) if bench in edits else bench)
    if board is not None:
        (out / "leaderboard.json").write_text(json.dumps(board))
    for cmd in (["report", str(out), "--figures", "none"], ["show", str(out)]):
        code = cli.main(cmd)
        err = capsys.readouterr().err
        assert code in (0, 2) and "Traceback" not in err
        assert code == 0 or len(err.strip().splitlines()) == 1


@pytest.mark.slow  # a bench of two child studies against a priced server (~20 s)
def test_the_models_cap_holds_over_its_parts_with_unanswered_requests(tmp_path):
    from tests.fakeserver import Fault, count_words

    cap = 0.07  # the first part finishes (about $0.04), the second stops at what is left
    n = {"seen": 0}

    def reply(body):  # every third request hangs past the client's timeout: unanswered
        n["seen"] += 1
        return Fault.delay(1.0) if n["seen"] % 3 == 0 else hash_reply(body)

    def usage(body):  # what the provider bills, answered or not
        prompt = sum(count_words(str(m.get("content", ""))) for m in body["messages"])
        return {"prompt_tokens": prompt, "completion_tokens": count_words(hash_reply(body))}

    opts = 'options = { runs = 2, q_runs = 0, steps = 8, swimmer = "purcell", direction = "+x" }'
    with FakeServer(reply=reply, usage=usage) as srv:
        path = tmp_path / "models.toml"
        path.write_text(
            f'[[models]]\nname = "m"\nbase_url = "{srv.url}"\nmodel = "fake"\n'
            f"max_cost = {cap}\ntimeout = 0.3\nconcurrency = 2\n"
            "[prices]\nfake = [10.0, 10.0]\n"  # $0.01 per 1k tokens: a call is ~$0.003
            f'[[suites.two.parts]]\nname = "a"\nstudy = "swim"\n{opts}\n'
            f'[[suites.two.parts]]\nname = "b"\nstudy = "swim"\n{opts}\n'
        )
        env = {**os.environ, "PYTHONPATH": str(ROOT)}
        cmd = [sys.executable, "-m", "jswim", "bench", str(path), "--suite", "two"]
        cmd += ["--no-reference", "--no-baselines", "--out", str(tmp_path / "b")]
        done = subprocess.run(cmd, env=env, cwd=ROOT, capture_output=True, text=True, timeout=300)
        srv.settle()
        bill = sum(
            (usage(b)["prompt_tokens"] + usage(b)["completion_tokens"]) * 0.01 / 1000
            for b in srv.requests
        )
    assert "Traceback" not in done.stderr
    assert srv.n_requests > 3 and bill <= cap  # every request arrived is billed, hung ones too
    record = json.loads((tmp_path / "b" / "bench.json").read_text())
    assert (tmp_path / "b" / "m" / "b" / "requests.jsonl").exists()  # the second part ran
    assert record["model_status"]["m"] == record["status"] == "stopped at the cost cap"


def test_a_bench_record_with_a_damaged_model_status_resumes_with_none(tmp_path):
    from jswim.bench.suites import CORE

    out = tmp_path / "b"
    models = (parse_model_option("base_url=http://127.0.0.1:9/v1,model=m"),)
    meta, lock = runner.open_folder(out, runner.definition(CORE, models, False, False))
    lock.release()
    (out / "bench.json").write_text(json.dumps({**meta, "model_status": "x"}))
    again, lock = runner.open_folder(out, runner.definition(CORE, models, False, False))
    lock.release()
    assert again["model_status"] == {}
