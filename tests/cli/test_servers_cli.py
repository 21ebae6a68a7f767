"""`jswim swim` end to end against each misbehaving fake server, and the study-folder cases.

Every case ends in exit 0 with the right actions, or exit 2 with one line on stderr naming the
cause; never a traceback, never a failed run saved as done.
"""

from __future__ import annotations

import json
import stat
from collections import Counter

import pytest

from jswim import cli
from jswim.results import read_metadata, read_runs
from tests.fakeserver import MODES, THOUGHT, FakeServer, Fault

FAST = [
    "--steps",
    "4",
    "--runs",
    "2",
    "--q-runs",
    "2",
    "--swimmer",
    "purcell",
    "--direction",
    "+x",
    "--no-figures",
]
GOOD = [2, -1]  # what every mode's answer is
NO_OP = [1, 0]  # a failed step


def swim(url: str, out, *extra: str) -> int:
    return cli.main(
        [
            "swim",
            *FAST,
            "--out",
            str(out),
            "--base-url",
            url,
            "--model",
            "fake",
            "--api-key-env",
            "JSWIM_TEST_NO_KEY",
            *extra,
        ]
    )


def llm_rows(out):
    return [r for r in read_runs(out) if r["agent"] == "llm"]


def one_line_error(capsys) -> str:
    err = capsys.readouterr().err.strip()
    assert "Traceback" not in err
    lines = [ln for ln in err.splitlines() if ln.startswith("jswim: error:")]
    assert len(lines) == 1, err
    return lines[0]


def transcript_steps(out):
    steps = []
    for path in sorted((out / "transcripts").glob("*.jsonl")):
        steps += [r for r in map(json.loads, path.read_text().splitlines()) if r["type"] == "step"]
    return steps


@pytest.mark.parametrize(
    "name",
    [
        "plain",
        "think",
        "think-no-open-tag",
        "reasoning-field",
        "parts",
        "stream-default",
        "stream-always",
        "bare-pair",
        "negated",
    ],
)
def test_swim_reads_the_answer(name, tmp_path, capsys):
    with FakeServer(**MODES[name]) as srv:
        assert swim(srv.url, tmp_path / "o") == 0, capsys.readouterr().err
    rows = llm_rows(tmp_path / "o")
    assert len(rows) == 2 and all(r["status"] == "done" for r in rows)
    assert all(r["actions"] == [GOOD] * 4 and r["failed_steps"] == 0 for r in rows)
    steps = transcript_steps(tmp_path / "o")
    if name in ("think", "think-no-open-tag", "reasoning-field", "parts", "stream-always"):
        assert all(THOUGHT in s["attempts"][0]["reasoning"] for s in steps)  # kept, never parsed


@pytest.mark.parametrize("name", ["null-length", "empty-length", "think-length"])
def test_swim_cut_off_replies_go_to_the_follow_up(name, tmp_path, capsys):
    with FakeServer(**MODES[name]) as srv:
        assert swim(srv.url, tmp_path / "o") == 0
        bodies = srv.requests
    out = capsys.readouterr().out
    rows = llm_rows(tmp_path / "o")
    assert all(
        r["actions"] == [GOOD] * 4 and r["failed_steps"] == 0 and r["truncated"] == 4 for r in rows
    )
    assert "8 replies cut at max_tokens=10" in out  # the authors' limit for two-DOF swimmers
    # Never the same deterministic request twice in a run (no resend of an unchanged request): the
    # two runs are independent repeats from the same start, so each distinct request comes twice.
    counts = Counter(json.dumps(b, sort_keys=True) for b in bodies)
    assert len(counts) == 4 * 2 and set(counts.values()) == {2}  # 4 steps x (cut reply, follow-up)


def test_swim_never_answering_fails_steps_and_says_why(tmp_path, capsys):
    with FakeServer(**MODES["always-length"]) as srv:
        assert swim(srv.url, tmp_path / "o") == 0
    out = capsys.readouterr().out
    rows = llm_rows(tmp_path / "o")
    assert all(r["failed_steps"] == 4 and r["actions"] == [NO_OP] * 4 for r in rows)
    assert "24 replies cut at max_tokens=10" in out and "--max-tokens" in out
    meta = read_metadata(tmp_path / "o")
    assert meta["summary"]["truncated_replies"] == 2 * 4 * 3  # 3 attempts per step
    assert meta["summary"]["truncated_at"] == {"10": 24}


def test_swim_max_tokens_option_reaches_the_server(tmp_path):
    with FakeServer(**MODES["plain"]) as srv:
        assert swim(srv.url, tmp_path / "o", "--max-tokens", "4096") == 0
        assert {b["max_tokens"] for b in srv.requests} == {4096}
        assert swim(srv.url, tmp_path / "o2", "--omit-field", "max_tokens") == 0
        assert not any("max_tokens" in b for b in srv.requests[-2:])


@pytest.mark.parametrize(
    "name, extra, fix, words",
    [
        (
            "reject-grammar",
            ["--constrain", "grammar"],
            ["--constrain", "none"],
            ["supplied: grammar", "--constrain none"],
        ),
        (
            "reject-seed",
            ["--temperature", "0.7"],
            ["--omit-field", "seed"],
            ["'seed' is not supported", "--omit-field seed"],
        ),
        (
            "reject-max-tokens",
            ["--reasoning", "off"],
            ["--omit-field", "max_tokens"],
            ["max_completion_tokens", "--omit-field max_tokens"],
        ),
    ],
)
def test_swim_rejected_field_is_one_line_then_the_option_works(
    name, extra, fix, words, tmp_path, capsys
):
    with FakeServer(**MODES[name]) as srv:
        assert swim(srv.url, tmp_path / "o", *extra) == 2
        line = one_line_error(capsys)
        assert all(w in line for w in words), line
        assert not llm_rows(tmp_path / "o")  # nothing saved as done
        meta = read_metadata(tmp_path / "o")
        assert meta["status"] == "stopped" and words[0] in meta["error"]
        assert swim(srv.url, tmp_path / "o2", *extra, *fix) == 0
    assert all(
        r["status"] == "done" and r["actions"] == [GOOD] * 4 for r in llm_rows(tmp_path / "o2")
    )


def test_swim_context_400_fails_the_run_and_resume_reruns_it(tmp_path, capsys):
    with FakeServer(**MODES["context-400"]) as srv:
        assert swim(srv.url, tmp_path / "o") == 2
        line = one_line_error(capsys)
        assert "2 of 2 LLM runs failed" in line and "maximum context length" in line
        rows = llm_rows(tmp_path / "o")
        assert all(
            r["status"] == "llm_error" and "maximum context length" in r["error"] for r in rows
        )
        assert read_metadata(tmp_path / "o")["status"] == "incomplete"
        srv.reply = MODES["plain"]["reply"]  # a healthy server (or a larger context)
        assert swim(srv.url, tmp_path / "o") == 0
    rows = llm_rows(tmp_path / "o")
    assert len(rows) == 2 and all(r["status"] == "done" and len(r["x"]) == 4 for r in rows)
    assert read_metadata(tmp_path / "o")["status"] == "complete"


def test_swim_error_at_the_first_request_fails_the_runs_in_one_line(tmp_path, capsys):
    # A per-run rejection (HTTP 422) before any step: runs with no steps are recorded as failed.
    reject = lambda body: Fault("status", 422, message="Unprocessable Entity: messages.0.content")
    with FakeServer(reply=reject) as srv:
        assert swim(srv.url, tmp_path / "o") == 2
        line = one_line_error(capsys)
        assert "2 of 2 LLM runs failed" in line and "HTTP 422" in line, line
        rows = llm_rows(tmp_path / "o")
        assert len(rows) == 2 and all(r["status"] == "llm_error" and r["steps"] == 0 for r in rows)
        assert read_metadata(tmp_path / "o")["status"] == "incomplete"
        srv.reply = MODES["plain"]["reply"]
        assert swim(srv.url, tmp_path / "o") == 0
    assert all(
        r["status"] == "done" and r["actions"] == [GOOD] * 4 for r in llm_rows(tmp_path / "o")
    )


def test_swim_cold_server(tmp_path, capsys):
    # Timeouts are transient faults: within the retry budget a server that wakes up is waited for,
    with FakeServer(**{**MODES["cold"], "cold_start": 2.0}) as srv:
        assert swim(srv.url, tmp_path / "o0", "--timeout", "0.4") == 0
        assert "transient faults: timeout x" in capsys.readouterr().out
    # and past it the study stops saying the server is slow.
    with FakeServer(**{**MODES["cold"], "cold_start": 2.0}) as srv:
        assert swim(srv.url, tmp_path / "o", "--timeout", "0.4", "--retries", "1") == 2
        line = one_line_error(capsys)
        assert "slow" in line and "--timeout" in line and "--retries 1" in line
        assert srv.n_requests <= 2 * 2  # each run's request tried at most twice
    with FakeServer(**MODES["cold"]) as srv:
        assert swim(srv.url, tmp_path / "o2", "--timeout", "10") == 0


@pytest.mark.parametrize(
    "shape",
    ["127.0.0.1:{port}", "http://127.0.0.1:{port}", "http://127.0.0.1:{port}/v1/chat/completions"],
)
def test_swim_base_url_shapes(shape, tmp_path):
    with FakeServer(**MODES["plain"]) as srv:
        assert swim(shape.format(port=srv.port), tmp_path / "o") == 0


def test_swim_wrong_base_url_names_the_url_tried(tmp_path, capsys):
    with FakeServer(**MODES["plain"]) as srv:
        assert swim(f"http://127.0.0.1:{srv.port}/api", tmp_path / "o") == 2
        line = one_line_error(capsys)
    assert f"127.0.0.1:{srv.port}/api" in line and "/v1" in line


@pytest.mark.parametrize("seed", ["4295", "-1", str(2**70)])
def test_swim_any_integer_seed(seed, tmp_path, capsys):
    with FakeServer(**MODES["plain"]) as srv:
        assert swim(srv.url, tmp_path / "o", "--seed", seed) == 0, capsys.readouterr().err
    assert len(read_runs(tmp_path / "o")) == 6


def test_swim_cache_keeps_only_valid_replies(tmp_path):
    cache = str(tmp_path / "cache")
    with FakeServer(reply=lambda b: "I am not sure.") as srv:
        assert swim(srv.url, tmp_path / "o", "--cache-dir", cache) == 0
    with FakeServer(**MODES["plain"]) as srv:
        assert swim(srv.url, tmp_path / "o2", "--cache-dir", cache) == 0
        assert srv.n_requests > 0  # nothing of the failed run was replayed
    assert all(r["actions"] == [GOOD] * 4 for r in llm_rows(tmp_path / "o2"))


# -- study folders --------------------------------------------------------------------------


def test_unwritable_out_is_one_line(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    with FakeServer(**MODES["plain"]) as srv:
        assert swim(srv.url, tmp_path / "file" / "o") == 2
    assert "cannot write" in one_line_error(capsys)
    assert cli.main(["gaits", "purcell", "--out", str(tmp_path / "file" / "g")]) == 2
    assert "cannot write" in one_line_error(capsys)


def test_plot_into_unwritable_figures_is_one_line(tmp_path, capsys):
    with FakeServer(**MODES["plain"]) as srv:
        assert swim(srv.url, tmp_path / "o") == 0
    (tmp_path / "o" / "figures").write_text("not a folder")
    capsys.readouterr()
    assert cli.main(["plot", str(tmp_path / "o")]) == 2
    assert "cannot write" in one_line_error(capsys)


def test_folder_files_are_strict_json_with_one_mode(tmp_path):
    with FakeServer(**MODES["plain"]) as srv:
        assert swim(srv.url, tmp_path / "o") == 0
    text = (tmp_path / "o" / "metadata.json").read_text()
    json.loads(text, parse_constant=lambda c: pytest.fail(f"metadata.json has {c}"))
    modes = {stat.S_IMODE(p.stat().st_mode) for p in (tmp_path / "o").rglob("*") if p.is_file()}
    assert len(modes) == 1, modes


def test_ctrl_c_marks_the_folder_interrupted(tmp_path, capsys, monkeypatch):
    calls = {"n": 0}

    def reply(body):
        calls["n"] += 1
        return "[2, -1]"

    from jswim.llm import client as client_module

    real_chat = client_module.LLMClient.chat

    async def chat(self, *a, **kw):
        if calls["n"] >= 3:
            raise KeyboardInterrupt
        return await real_chat(self, *a, **kw)

    monkeypatch.setattr(client_module.LLMClient, "chat", chat)
    with FakeServer(reply=reply) as srv:
        assert swim(srv.url, tmp_path / "o") == 130
    assert read_metadata(tmp_path / "o")["status"] == "interrupted"
    assert "resume" in capsys.readouterr().err


def test_bad_gguf_fails_before_the_baselines(tmp_path, capsys):
    fake = tmp_path / "model.gguf"
    fake.write_text("not a model")
    rc = cli.main(["swim", *FAST, "--out", str(tmp_path / "o"), "--gguf", str(fake)])
    assert rc == 2 and "GGUF" in one_line_error(capsys)
    # Refused before any run: not one baseline row written (the folder may or may not exist).
    assert not (tmp_path / "o" / "runs.jsonl").exists()


@pytest.mark.parametrize(
    "text, words",
    [
        ("Go {direction}. {S5}\n{S3}\n{bogus}", ["{bogus}"]),
        ("Go {direction}. Answer with one of {allowed}.", ["history", "{S3}"]),
        ("Go {direction}.\n{history}", ["allowed", "{S5}"]),
    ],
)
def test_bad_prompt_file_fails_before_the_baselines(text, words, tmp_path, capsys):
    path = tmp_path / "prompt.txt"
    path.write_text(text)
    with FakeServer(**MODES["plain"]) as srv:
        rc = swim(srv.url, tmp_path / "o", "--prompt-file", str(path))
        assert srv.n_requests == 0
    line = one_line_error(capsys)
    assert rc == 2 and all(w in line for w in words), line
    assert not (tmp_path / "o" / "runs.jsonl").exists()


@pytest.mark.parametrize("kind, words", [("binary", ["UTF-8"]), ("folder", ["folder"])])
def test_unreadable_prompt_file_is_one_line(kind, words, tmp_path, capsys):
    path = tmp_path / "prompt.txt"
    if kind == "binary":
        path.write_bytes(b"\xff\xfe\x00 {history} {allowed}")
    else:
        path.mkdir()
    with FakeServer(**MODES["plain"]) as srv:
        rc = swim(srv.url, tmp_path / "o", "--prompt-file", str(path))
        assert srv.n_requests == 0
    line = one_line_error(capsys)
    assert rc == 2 and all(w in line for w in words), line
