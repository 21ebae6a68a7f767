"""Reasoning models without hand-crafted flags: `jswim swim --model gpt-5` against a server that
behaves as OpenAI's reasoning models do (tests.fakeserver.reasoning_model)."""

from __future__ import annotations

import json

import pytest

from jswim import cli
from jswim.llm.reasoning import (
    REASONING_MAX_TOKENS,
    ReasoningState,
    accepted_temperature,
    wants_completion_tokens,
)
from jswim.llm.usage import PriceTable, Usage
from jswim.results import read_metadata, read_runs
from tests.fakeserver import MODES, REASONING_TOKENS, FakeServer, reasoning_model

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
MAX_TOKENS_400 = "Unsupported parameter: 'max_tokens' is not supported with this model. Use 'max_completion_tokens' instead."
TEMPERATURE_400 = (
    "Unsupported value: 'temperature' does not support 0 with this model. Only the default (1) value "
    "is supported."
)


def swim(url, out, *extra):
    return cli.main(
        [
            "swim",
            *FAST,
            "--out",
            str(out),
            "--base-url",
            url,
            "--model",
            "gpt-5",
            "--api-key-env",
            "JSWIM_TEST_NO_KEY",
            *extra,
        ]
    )


def test_server_messages_say_what_the_model_wants():
    assert wants_completion_tokens(MAX_TOKENS_400, {"max_tokens": 10})
    assert not wants_completion_tokens(MAX_TOKENS_400, {"max_completion_tokens": 10})
    assert not wants_completion_tokens("Unsupported parameter: 'seed'", {"max_tokens": 10})
    assert accepted_temperature(TEMPERATURE_400, {"temperature": 0.0}) == 1.0
    assert accepted_temperature(TEMPERATURE_400, {"temperature": 1.0}) is None  # nothing to change
    assert accepted_temperature("temperature must be <= 2", {"temperature": 3}) is None


def test_state_amends_payloads_once_per_switch():
    st = ReasoningState()
    body = {"model": "m", "messages": [], "temperature": 0.0, "max_tokens": 10}
    assert st.apply(body) == body  # auto: plain until the server says otherwise
    assert st.adapt(MAX_TOKENS_400, body, "m") and st.adapt(
        MAX_TOKENS_400, body, "m"
    )  # two calls in flight
    assert len(st.notes) == 1
    assert st.apply(body) == {
        "model": "m",
        "messages": [],
        "temperature": 0.0,
        "max_completion_tokens": REASONING_MAX_TOKENS,
    }
    assert st.adapt(TEMPERATURE_400, body, "m") and st.apply(body)["temperature"] == 1.0
    off = ReasoningState("off")
    assert not off.adapt(MAX_TOKENS_400, body, "m") and off.apply(body) == body
    on = ReasoningState("on", budget=2000)  # an open reasoning model: max_tokens with room to think
    assert on.apply(body)["max_tokens"] == 2000 and "max_completion_tokens" not in on.apply(body)
    assert ReasoningState("on", openai=True, effort="low").apply(body) == {
        "model": "m",
        "messages": [],
        "temperature": 0.0,
        "max_completion_tokens": REASONING_MAX_TOKENS,
        "reasoning_effort": "low",
    }


def test_reasoning_tokens_are_read_and_priced_as_output():
    u = Usage.from_response(
        {
            "prompt_tokens": 100,
            "completion_tokens": 310,
            "completion_tokens_details": {"reasoning_tokens": 300},
        }
    )
    assert (u.completion_tokens, u.reasoning_tokens) == (310, 300)
    # $1 / $10 per 1M: 100 * 1 + 310 * 10 = 3200 micro-dollars
    assert PriceTable({"r": (1.0, 10.0)}).cost("r", u) == pytest.approx(3200e-6)
    apart = Usage.from_response(
        {
            "prompt_tokens": 1,
            "completion_tokens": 5,
            "completion_tokens_details": {"reasoning_tokens": 40},
        }
    )
    assert apart.completion_tokens == 45  # counted apart by the server: both billed


def test_swim_gpt5_needs_no_flags_and_records_what_was_sent(tmp_path, capsys):
    with FakeServer(**MODES["openai-reasoning"]) as srv:
        assert swim(srv.url, tmp_path / "o") == 0, capsys.readouterr().err
        answered = [
            b for b in srv.requests if "max_completion_tokens" in b and b.get("temperature") == 1
        ]
        assert len(answered) == 8  # 2 runs x 4 steps, each answered once
        assert all(b["max_completion_tokens"] == REASONING_MAX_TOKENS for b in answered)
        assert (
            srv.n_requests - len(answered) <= 2 * 2
        )  # at most one refused request per field per call in flight
    out = capsys.readouterr().out
    assert (
        "refused max_tokens" in out
        and "accepts only temperature 1" in out
        and "reasoning tokens: 2,400" in out
    )
    rows = [r for r in read_runs(tmp_path / "o") if r["agent"] == "llm"]
    assert all(r["actions"] == [[2, -1]] * 4 and r["failed_steps"] == 0 for r in rows)
    assert all(r["temperature_sent"] == 1.0 and r["temperature"] == 0.0 for r in rows)
    assert all(
        r["token_field"] == "max_completion_tokens" and r["max_tokens_sent"] == REASONING_MAX_TOKENS
        for r in rows
    )
    assert sum(r["reasoning_tokens"] for r in rows) == 8 * REASONING_TOKENS
    sent = read_metadata(tmp_path / "o")["summary"]["reasoning"]
    assert sent["token_field"] == "max_completion_tokens" and sent["temperature_sent"] == 1.0
    step = json.loads(
        (tmp_path / "o" / "transcripts" / f"{rows[0]['run_id']}.jsonl").read_text().splitlines()[1]
    )
    assert (
        step["attempts"][0]["reasoning_tokens"] == REASONING_TOKENS
        and step["attempts"][0]["temperature_sent"] == 1
    )


def test_swim_reply_cut_while_thinking_is_counted_not_executed(tmp_path, capsys):
    with FakeServer(reply=reasoning_model(think=500)) as srv:  # thinks past a 100-token budget
        assert swim(srv.url, tmp_path / "o", "--max-tokens", "100") == 0, capsys.readouterr().err
        assert {b.get("max_completion_tokens") for b in srv.requests if "max_tokens" not in b} == {
            100
        }
    out = capsys.readouterr().out
    rows = [r for r in read_runs(tmp_path / "o") if r["agent"] == "llm"]
    assert all(
        r["actions"] == [[1, 0]] * 4 and r["failed_steps"] == 4 for r in rows
    )  # the no-op, counted failed
    assert (
        sum(r["cut_thinking"] for r in rows) == 2 * 4 * 3
    )  # 3 attempts per step, each cut while thinking
    assert "24 replies cut at max_completion_tokens=100, 24 of them while still thinking" in out


def test_swim_reasoning_off_stops_in_one_line_naming_the_flag(tmp_path, capsys):
    with FakeServer(**MODES["openai-reasoning"]) as srv:
        assert swim(srv.url, tmp_path / "o", "--reasoning", "off") == 2
    err = capsys.readouterr().err
    errors = [ln for ln in err.splitlines() if ln.startswith("jswim: error:")]
    assert "Traceback" not in err and len(errors) == 1 and "--reasoning auto" in errors[0]


def test_open_reasoning_model_gets_room_with_reasoning_on(tmp_path, capsys):
    with FakeServer(**MODES["think"]) as srv:  # <think> blocks, accepts max_tokens
        assert swim(srv.url, tmp_path / "o", "--reasoning", "on") == 0, capsys.readouterr().err
        assert {b["max_tokens"] for b in srv.requests} == {REASONING_MAX_TOKENS}
    assert "reasoning: max_tokens=4096 (--reasoning on)" in capsys.readouterr().out


def _dry(tmp_path, capsys, model, *extra):
    prices = tmp_path / "prices.toml"
    prices.write_text(
        'as_of = "2026-11"\n"gpt-5" = [1.25, 10.0]\n"gpt-4o" = [2.5, 10.0]\n"qwq-32b" = [1.0, 2.0]\n'
    )
    capsys.readouterr()
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
                str(tmp_path / "o"),
                "--base-url",
                "https://api.openai.com/v1",
                "--model",
                model,
                "--prices",
                str(prices),
                "--dry-run",
                *extra,
            ]
        )
        == 0
    )
    out = capsys.readouterr().out
    return out, json.loads(out.strip().splitlines()[-1])


def test_dry_run_counts_a_reasoning_models_thinking_and_its_worst_case(tmp_path, capsys):
    plain_text, plain = _dry(tmp_path, capsys, "gpt-4o")
    assert (
        plain["reasoning_tokens"] == 0
        and plain["reasoning_budget"] is None
        and "reasoning:" not in plain_text
    )
    text, est = _dry(
        tmp_path, capsys, "gpt-5"
    )  # auto: OpenAI's reasoning model by name gets the budget
    calls = est["calls"]
    assert calls == 6 and est["prompt_tokens"] == plain["prompt_tokens"]  # the same prompts
    assert est["reasoning_budget"] == REASONING_MAX_TOKENS and est["reasoning_share"] == 0.25
    assert est["reasoning_tokens"] == calls * 1024  # a quarter of 4096 per call
    assert (
        est["completion_tokens"] == plain["completion_tokens"] + calls * 1024
    )  # thinking is output
    assert est["cost_usd"] == pytest.approx(
        (est["prompt_tokens"] * 1.25 + est["completion_tokens"] * 10.0) / 1e6
    )
    assert est["cost_max_usd"] == pytest.approx(
        (est["prompt_tokens"] * 1.25 + calls * 4096 * 10.0) / 1e6
    )
    assert (
        "6,144 of the completion tokens are thinking" in text
        and "reasoning tokens included" in text
    )
    assert (
        "used its whole reasoning budget (4096 tokens)" in text
        and "thinking is counted only" not in text
    )
    # --max-tokens is the budget; the effort sets the share; off sends the plain max_tokens.
    _, est = _dry(tmp_path, capsys, "gpt-5", "--max-tokens", "2000")
    assert est["reasoning_budget"] == 2000 and est["reasoning_tokens"] == calls * 500
    _, est = _dry(tmp_path, capsys, "gpt-5", "--reasoning-effort", "high")
    assert est["reasoning_tokens"] == calls * 2048
    _, est = _dry(tmp_path, capsys, "gpt-5", "--reasoning", "off")
    assert est["reasoning_tokens"] == 0 and est["cost_max_usd"] < 0.01
    # An open reasoning model: on gives the budget; auto would cut it while thinking, and says so.
    _, est = _dry(tmp_path, capsys, "qwq-32b", "--reasoning", "on")
    assert est["reasoning_tokens"] == calls * 1024
    text, est = _dry(tmp_path, capsys, "qwq-32b")
    assert est["reasoning_tokens"] == 0 and "give --reasoning on" in text


def test_show_says_what_a_reasoning_model_was_sent(tmp_path, capsys):
    with FakeServer(**MODES["openai-reasoning"]) as srv:
        assert swim(srv.url, tmp_path / "o") == 0
    capsys.readouterr()
    assert cli.main(["show", str(tmp_path / "o")]) == 0
    model = next(ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("model:"))
    assert "temperature 0 asked, 1 sent" in model and "max_completion_tokens=4096" in model
