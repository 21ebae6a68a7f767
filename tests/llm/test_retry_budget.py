"""Flaky servers: transient failures never end a study while the server comes back within the
retry budget (--retries / --retry-for); a spent budget stops the study cleanly, keeping every
finished run; requests, retries and faults are counted as the server counts them."""

from __future__ import annotations

import asyncio
import json
import time

import pytest

from jswim import cli
from jswim.errors import LLMServerError
from jswim.llm.client import ClientSettings, LLMClient
from jswim.results import read_metadata, read_runs
from tests.fakeserver import FakeServer, Fault, hash_reply

MSG = [{"role": "user", "content": "Say [1, 1]"}]


def settings(url: str, **kw) -> ClientSettings:
    return ClientSettings(
        base_url=url,
        model="fake",
        **{"backoff_base_s": 0.02, "backoff_max_s": 0.1, "timeout_s": 5.0, **kw},
    )


async def one_call(s: ClientSettings):
    async with LLMClient(s) as c:
        res = await c.chat(MSG)
        return res, c.counts


def down_for(seconds: float):
    """A server that answers 503 (and drops every third connection) until ``seconds`` after its
    first request, then answers normally: an outage it comes back from."""
    state = {"t0": None, "n": 0}

    def reply(body):
        state["t0"] = state["t0"] or time.monotonic()
        state["n"] += 1
        if time.monotonic() - state["t0"] < seconds:
            return Fault.drop() if state["n"] % 3 == 0 else Fault.server_error(503, "overloaded")
        return "[1, 1]"

    return reply


def test_an_outage_shorter_than_the_budget_is_ridden_out():
    with FakeServer(reply=down_for(0.6)) as srv:
        res, counts = asyncio.run(one_call(settings(srv.url, retry_for_s=30.0)))
        assert res.text == "[1, 1]" and res.retries >= 3
        assert counts.requests == srv.n_requests and counts.retries == srv.n_requests - 1
        assert (
            counts.faults.get("5xx", 0) + counts.faults.get("connection", 0) == srv.n_requests - 1
        )
        assert counts.faults.get("connection", 0) >= 1


def test_the_default_budget_rides_out_a_minute():
    # With the default backoff (0.5 s doubling to 30 s, jitter in [0.5, 1]) the shortest sum of
    # waits of the default 20 retries exceeds a minute, and --retry-for 120 s allows it.
    s = ClientSettings(base_url="http://127.0.0.1:1/v1", model="m")
    shortest = sum(
        min(s.backoff_max_s, s.backoff_base_s * 2.0**k) * 0.5 for k in range(s.max_retries)
    )
    assert shortest > 60 and s.retry_for_s >= 60


def test_a_spent_retry_count_is_one_line_naming_the_budget():
    with FakeServer(reply=lambda body: Fault.server_error(500)) as srv:
        with pytest.raises(LLMServerError) as err:
            asyncio.run(one_call(settings(srv.url, max_retries=3)))
        assert srv.n_requests == 4  # the first attempt and 3 retries
    msg = str(err.value)
    assert "\n" not in msg and "gave up after 4 attempts" in msg and "--retries 3" in msg


def test_a_spent_retry_time_stops_retrying():
    with FakeServer(reply=lambda body: Fault.rate_limit(None)) as srv:
        with pytest.raises(LLMServerError, match="--retry-for 0.3"):
            asyncio.run(one_call(settings(srv.url, max_retries=10_000, retry_for_s=0.3)))
        assert 2 <= srv.n_requests < 10_000


FAST = [
    "--steps",
    "12",
    "--runs",
    "2",
    "--q-runs",
    "0",
    "--swimmer",
    "purcell",
    "--direction",
    "+x",
    "--no-figures",
    "--model",
    "fake",
]


def test_a_flaky_server_never_ends_the_study_and_every_request_is_counted(tmp_path, capsys):
    faults = [
        Fault.rate_limit("0"),
        Fault.server_error(502),
        None,
        Fault.drop(),
        None,
        None,
        None,
    ] * 8
    with FakeServer(reply=hash_reply, faults=faults) as srv:
        assert cli.main(["swim", *FAST, "--base-url", srv.url, "--out", str(tmp_path / "F")]) == 0
        out = capsys.readouterr().out
        sent = srv.settle()
    line = next(ln for ln in out.splitlines() if ln.startswith("HTTP requests:"))
    assert line.startswith(f"HTTP requests: {sent} sent (")  # ours match the server's count
    assert "429 x" in line and "5xx x" in line and "connection x" in line
    totals = read_metadata(tmp_path / "F")["llm_totals"]
    assert (
        totals["requests"] == sent
        and totals["retries"] == sent - 24
        and sum(totals["faults"].values()) == sent - 24
    )
    assert cli.main(["show", str(tmp_path / "F")]) == 0
    shown = capsys.readouterr().out
    assert (
        f"HTTP requests: {sent} sent ({sent - 24} retries" in shown and "24 answered calls" in shown
    )


def test_a_spent_budget_stops_cleanly_and_the_same_command_resumes(tmp_path, capsys):
    state = {"down": False, "n": 0}

    def reply(body):  # 5 calls answered, then down for longer than the budget
        state["n"] += 1
        return Fault.server_error(503) if state["down"] and state["n"] > 5 else hash_reply(body)

    args = ["swim", *FAST, "--out", str(tmp_path / "F"), "--retries", "2", "--retry-for", "5"]
    with FakeServer(reply=reply) as srv:
        state["down"] = True
        rc = cli.main([*args, "--base-url", srv.url])
        err = capsys.readouterr().err
        last = err.strip().splitlines()[-1]
        assert rc == 2 and "Traceback" not in err
        assert "gave up" in last and "kept in" in last and "run the same command to resume" in last
        assert read_metadata(tmp_path / "F")["status"] == "stopped"
        answered = len((tmp_path / "F" / "calls.jsonl").read_text().splitlines())
        assert answered == 5
        state["down"] = False
        sent = srv.settle()
        assert cli.main([*args, "--base-url", srv.url]) == 0
        assert srv.n_requests - sent == 24 - answered  # the 5 answered calls are not paid again
    rows = read_runs(tmp_path / "F")
    assert len(rows) == 2 and all(r["status"] == "done" for r in rows)
    assert json.loads((tmp_path / "F" / "metadata.json").read_text())["llm_totals"]["sessions"] == 2


# -- timeouts: transient like the rest, and a request that got no answer may have been billed --


def test_a_server_that_hangs_then_recovers_is_ridden_out_and_every_timeout_counted():
    from tests.fakeserver import hangs_for

    with FakeServer(reply=hangs_for(0.8)) as srv:
        res, counts = asyncio.run(
            one_call(settings(srv.url, timeout_s=0.2, max_retries=20, retry_for_s=30.0))
        )
        assert res.text in ("[1, -1]", "[2, -1]", "[1, 1]", "[2, 1]")
        assert res.retries >= 3 and counts.requests == srv.n_requests == res.retries + 1
    assert counts.faults == {"timeout": res.retries}
    assert counts.unanswered == res.retries  # each was read whole by the server and never answered


def test_timeouts_spend_the_retry_time_from_when_the_first_attempt_went_out():
    from tests.fakeserver import hangs_for

    with FakeServer(reply=hangs_for(60.0)) as srv:
        t0 = time.monotonic()
        with pytest.raises(LLMServerError, match="slow.*--retry-for 0.5") as err:
            asyncio.run(
                one_call(settings(srv.url, timeout_s=0.2, max_retries=10_000, retry_for_s=0.5))
            )
        took = time.monotonic() - t0
    # 0.2 s timeouts sent back to back: the 0.5 s budget (counted from the first send) allows 3
    # (a loaded machine may fit fewer), never the 10,000 retries the count would.
    assert 2 <= srv.n_requests <= 4 and took < 5
    assert "no answer within 0.2 s" in str(err.value)


def test_a_request_that_got_no_answer_counts_against_the_cost_cap():
    from jswim.llm.budget import Budget, BudgetExhausted
    from tests.fakeserver import hangs_for

    prices = {"fake": (1_000_000.0, 1_000_000.0)}  # $1 per token: a call's bound is some dollars

    async def run(url: str, budget: Budget):
        async with LLMClient(settings(url, timeout_s=0.2, prices=prices), budget=budget) as c:
            return await c.chat(MSG), c.counts

    with FakeServer(reply=hangs_for(0.1)) as srv:  # the first request hangs, the retry is answered
        budget = Budget(cap_usd=1e6)
        res, counts = asyncio.run(run(srv.url, budget))
        bound = counts.unanswered_usd
        assert counts.unanswered == 1 and res.retries == 1 and bound > 1
        assert budget.unanswered_usd == pytest.approx(bound)  # kept against the cap, not released
        assert budget.spent_usd == pytest.approx(res.cost_usd) and budget.reserved_usd == 0
    with FakeServer(
        reply=hangs_for(60.0)
    ) as srv:  # room for one request: the unanswered one fills it
        budget = Budget(cap_usd=1.5 * bound)
        with pytest.raises(BudgetExhausted, match="got no answer"):
            asyncio.run(run(srv.url, budget))
        assert (
            srv.n_requests == 1
            and budget.spent_usd == 0
            and budget.unanswered_usd == pytest.approx(bound)
        )


def test_the_summary_and_show_say_how_many_requests_got_no_answer(tmp_path, capsys):
    from tests.fakeserver import hangs_for

    args = ["swim", *FAST, "--runs", "1", "--timeout", "0.3", "--out", str(tmp_path / "F")]
    with FakeServer(reply=hangs_for(1.0)) as srv:
        assert cli.main([*args, "--base-url", srv.url]) == 0
        out = capsys.readouterr().out
        sent = srv.settle()
    line = next(ln for ln in out.splitlines() if ln.startswith("HTTP requests:"))
    totals = read_metadata(tmp_path / "F")["llm_totals"]
    timeouts = totals["faults"]["timeout"]
    assert totals["requests"] == sent and timeouts >= 2 and totals["unanswered"] == timeouts
    assert line.startswith(
        f"HTTP requests: {sent} sent ({timeouts} retries; transient faults: timeout x{timeouts}"
    )
    assert f"{timeouts} got no answer" in line and "may have been billed" in line
    assert cli.main(["show", str(tmp_path / "F")]) == 0
    assert f"{timeouts} got no answer" in capsys.readouterr().out
