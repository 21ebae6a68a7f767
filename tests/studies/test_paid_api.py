"""Studies against a priced server: dry run, cost cap, resume without re-billing, identity, seeds."""

from __future__ import annotations

import functools
import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from jswim.cli import main
from jswim.llm.usage import DEFAULT_PRICES
from jswim.results import read_runs
from tests.fakeserver import FakeServer, hash_reply

ROOT = Path(__file__).resolve().parents[2]
# A test dependency (pyproject's `test` extra): missing, this module must fail, not skip.
import bpe_openai  # noqa: E402


@functools.cache
def _o200k_encoding():
    # loaded on first use, not at import: every pytest-xdist worker collects (imports) this module
    return bpe_openai.get_encoding("o200k_base")


def o200k(text: str) -> int:
    """The server's token count: the real tokenizer of gpt-4o (independent of jswim's estimate)."""
    return len(_o200k_encoding().encode(text))


#: What the stand-in for a paid API lists at /v1/models (a model it does not list is not priced).
LISTED = ("gpt-4", "gpt-4o", "gpt-4o-mini")


def priced_server(**kw) -> FakeServer:
    return FakeServer(reply=hash_reply, tokens=o200k, **{"models": LISTED, **kw})


def billed_usd(srv: FakeServer, model: str) -> float:
    """What the server's own usage numbers cost at the price table's rates (every request it answered)."""
    p_in, p_out = DEFAULT_PRICES[model]
    total = 0.0
    for body in srv.requests:
        prompt = sum(o200k(str(m.get("content", ""))) for m in body["messages"])
        total += (prompt * p_in + o200k(hash_reply(body)) * p_out) / 1e6
    return total


def ledger(folder: Path) -> list[dict]:
    """The study's call journal (``calls.jsonl``), one dict per answered call."""
    path = folder / "calls.jsonl"
    return [json.loads(ln) for ln in path.read_text().splitlines()] if path.exists() else []


def swim(
    url: str, out: Path, *extra: str, model: str = "gpt-4o", runs: int = 3, steps: int = 12
) -> list[str]:
    return [
        "swim",
        "--base-url",
        url,
        "--model",
        model,
        "--runs",
        str(runs),
        "--q-runs",
        "0",
        "--steps",
        str(steps),
        "--noise",
        "0.5",
        "--no-figures",
        "--out",
        str(out),
        "--price-local",
        *extra,
    ]


def test_dry_run_sends_nothing_and_estimates_the_real_tokens(tmp_path, capsys):
    out = tmp_path / "study"
    with priced_server() as srv:
        assert main(swim(srv.url, out, "--dry-run")) == 0
        printed = capsys.readouterr().out
        assert srv.n_requests == 0
        assert not (out / "runs.jsonl").exists()
        est = json.loads(printed.strip().splitlines()[-1])  # the machine-readable last line
        assert est["calls"] == 3 * 12
        assert main(swim(srv.url, out)) == 0
        rows = read_runs(out)
        sent = srv.settle()
        real_prompt = sum(
            o200k(str(m.get("content", ""))) for body in srv.requests for m in body["messages"]
        )
        real_cost = billed_usd(srv, "gpt-4o")
    assert "2025-04" in printed and "$" in printed
    assert sum(r["calls"] for r in rows) == est["calls"]
    # per call (runs that send identical requests may share one: the server then sees fewer)
    assert abs((est["prompt_tokens"] / est["calls"]) / (real_prompt / sent) - 1) < 0.2
    assert abs((est["cost_usd"] / est["calls"]) / (real_cost / sent) - 1) < 0.2


def test_max_cost_stops_below_the_cap_and_a_higher_cap_finishes_without_rebilling(tmp_path, capsys):
    out = tmp_path / "study"
    runs, steps, conc = 4, 10, 2
    with priced_server(latency=0.01) as srv:
        # gpt-4 at $30/$60 per 1M: ~$0.01 per call here, so $0.05 buys a few calls of the 40.
        code = main(
            swim(
                srv.url,
                out,
                "--max-cost",
                "0.05",
                "--concurrency",
                str(conc),
                model="gpt-4",
                runs=runs,
                steps=steps,
            )
        )
        err = capsys.readouterr().err
        assert code == 3, err
        assert "cost cap" in err and "--max-cost" in err
        first = srv.n_requests
        spent = billed_usd(srv, "gpt-4")
        one_call = max(billed_usd_one(b) for b in srv.requests)
        assert 0 < first < runs * steps
        assert spent <= 0.05 + conc * one_call
        meta = json.loads((out / "metadata.json").read_text())
        assert meta["status"] == "stopped at the cost cap"
        assert len(read_runs(out)) < runs
        assert (
            main(
                swim(
                    srv.url,
                    out,
                    "--max-cost",
                    "10",
                    "--concurrency",
                    str(conc),
                    model="gpt-4",
                    runs=runs,
                    steps=steps,
                )
            )
            == 0
        )
        rows = read_runs(out)
    assert len(rows) == runs and all(r["status"] == "done" and r["steps"] == steps for r in rows)
    # every call the runs paid for reached the server exactly once over both sessions
    # (billed_calls: calls not answered by another run's identical request in flight)
    assert sum(r["calls"] for r in rows) == runs * steps
    assert srv.n_requests == sum(r["billed_calls"] for r in rows)


def billed_usd_one(body) -> float:
    p_in, p_out = DEFAULT_PRICES["gpt-4"]
    prompt = sum(o200k(str(m.get("content", ""))) for m in body["messages"])
    return (prompt * p_in + o200k(hash_reply(body)) * p_out) / 1e6


def test_interrupt_and_resume_bill_each_call_once(tmp_path):
    out = tmp_path / "study"
    runs, steps = 3, 12
    interrupted = threading.Event()
    # The server answers 10 calls, then holds every answer until Ctrl-C was sent: the study cannot
    # finish before the interrupt however slow this (loaded) machine is.
    srv = priced_server(
        latency=0.05,
        hold=lambda body: srv.n_answered >= 10 and not interrupted.is_set(),
        hold_s=300.0,
    )
    with srv:
        cmd = [sys.executable, "-m", "jswim.cli", *swim(srv.url, out, runs=runs, steps=steps)]
        # the same precision as this test process (conftest: float64), so both sessions step alike
        env = {**os.environ, "PYTHONPATH": str(ROOT), "JAX_ENABLE_X64": "1"}
        proc = subprocess.Popen(
            cmd, cwd=ROOT, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True
        )
        while srv.n_answered < 10 and proc.poll() is None:
            time.sleep(0.02)
        while (
            srv.n_requests - srv.n_answered < 1 and proc.poll() is None
        ):  # the next call is being held
            time.sleep(0.02)
        proc.send_signal(signal.SIGINT)  # Ctrl-C in the middle of the runs
        interrupted.set()
        _, err = proc.communicate(timeout=60)
        assert proc.returncode == 130, err
        before = srv.n_requests
        assert 10 <= before < runs * steps
        assert len(read_runs(out)) < runs
        kept = len(
            (out / "calls.jsonl").read_text().splitlines()
        )  # the answers the client received
        assert kept >= 3
        assert main(swim(srv.url, out, runs=runs, steps=steps)) == 0
        rows = read_runs(out)
    assert len(rows) == runs and sum(r["calls"] for r in rows) == runs * steps
    # Every answer received before Ctrl-C is replayed, none is asked again ...
    assert sum(r["replayed_calls"] for r in rows) == kept
    # ... so the server answered each paid call once, plus at most the calls in flight at the
    # interrupt (one per run), whose answers the interrupted process never read.
    extra = srv.n_answered - sum(r["billed_calls"] for r in rows)
    assert 0 <= extra <= runs


def test_the_address_is_not_the_identity_but_the_model_is(tmp_path, capsys):
    out = tmp_path / "study"
    with priced_server() as a:
        assert main(swim(a.url, out, runs=2, steps=12)) == 0
    with priced_server() as b:  # a restarted server on another port: same study, resumed
        assert main(swim(b.url, out, runs=2, steps=12)) == 0
        assert b.n_requests == 0
        capsys.readouterr()
        assert main(swim(b.url, out, runs=2, steps=12, model="gpt-4o-mini")) == 2
        err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "model" in err and "'gpt-4o-mini'" in err and "'gpt-4o'" in err


def test_more_runs_extend_a_folder_and_keep_the_existing_ones(tmp_path):
    out = tmp_path / "study"
    with priced_server() as srv:
        assert main(swim(srv.url, out, runs=2, steps=12)) == 0
        before = {r["run_id"]: r for r in read_runs(out)}
        srv.reset_counts()
        assert main(swim(srv.url, out, runs=3, steps=12)) == 0
        after = {r["run_id"]: r for r in read_runs(out)}
        assert srv.n_requests == 12  # only the new run's steps
    assert set(before) < set(after) and len(after) == 3
    for rid, row in before.items():
        assert after[rid]["x"] == row["x"] and after[rid]["seed"] == row["seed"]


def test_seeds_follow_the_run_not_its_place_in_the_grid():
    from jswim.studies.options import StudyOptions
    from jswim.studies.specs import build

    small = {
        p.run_id: p.seed for p in build("noise", StudyOptions(zetas=(0.0, 1.0), runs=2, q_runs=2))
    }
    large = {
        p.run_id: p.seed
        for p in build("noise", StudyOptions(zetas=(0.0, 0.5, 1.0), runs=3, q_runs=2))
    }
    assert small.items() <= large.items()  # adding a level and a repeat changes no existing run
    swim_ids = {p.run_id: p.seed for p in build("swim", StudyOptions(runs=2))}
    curves = {p.run_id: p.seed for p in build("curves", StudyOptions(runs=2))}
    shared = set(swim_ids) & set(curves)
    assert shared and all(swim_ids[i] == curves[i] for i in shared)  # same run id, same seed
    other = {
        p.run_id: p.seed
        for p in build("noise", StudyOptions(zetas=(0.0, 1.0), runs=2, q_runs=2, seed=1))
    }
    assert all(other[i] != small[i] for i in small)  # the study seed still matters
    assert len(set(large.values())) == len(large)


# -- money promises: each number checked against one computed here, independently ---------------

#: gpt-4's list prices, written out (not read from jswim's table): USD per 1M tokens.
GPT4_IN, GPT4_OUT = 30.0, 60.0


def test_the_cap_holds_over_three_sessions_and_a_higher_cap_bills_each_call_once(tmp_path, capsys):
    out = tmp_path / "study"
    runs, steps, conc = 4, 10, 2
    with priced_server(latency=0.01) as srv:

        def session(cap: str) -> int:
            return main(
                swim(
                    srv.url,
                    out,
                    "--max-cost",
                    cap,
                    "--concurrency",
                    str(conc),
                    model="gpt-4",
                    runs=runs,
                    steps=steps,
                )
            )

        one_call = 0.0

        def check_under(cap: float) -> None:
            nonlocal one_call
            one_call = max([one_call] + [billed_usd_one(b) for b in srv.requests])
            assert billed_usd(srv, "gpt-4") <= cap + conc * one_call

        # Session 1: stopped at the cap.
        assert session("0.05") == 3
        first = srv.n_requests
        assert 0 < first < runs * steps
        check_under(0.05)
        paid = sum(r["cost_usd"] for r in ledger(out))
        assert paid == pytest.approx(billed_usd(srv, "gpt-4"), rel=1e-9)
        # Session 2, the same cap: the spend of session 1 counts, so nothing at all is sent.
        assert session("0.05") == 3
        assert srv.n_requests == first
        assert sum(r["cost_usd"] for r in ledger(out)) == pytest.approx(paid, rel=1e-12)
        # Session 3, a little more: some more calls, the study still under the new cap.
        assert session("0.12") == 3
        second = srv.n_requests
        assert second > first
        check_under(0.12)
        # Session 4, enough: the study finishes.
        assert session("10") == 0
        rows = read_runs(out)
        meta = json.loads((out / "metadata.json").read_text())
        total = billed_usd(srv, "gpt-4")
        calls = ledger(out)
    capsys.readouterr()
    assert len(rows) == runs and all(r["status"] == "done" and r["steps"] == steps for r in rows)
    # Each call reached the server once over the four sessions, and was journaled once.
    assert srv.n_requests == len(calls) == runs * steps
    assert len({(c["run"], c["n"]) for c in calls}) == len(calls)
    # The ledger, the metadata and the runs' rows all say what the server billed.
    assert sum(c["cost_usd"] for c in calls) == pytest.approx(total, rel=1e-9)
    assert meta["summary"]["llm_speed"]["study_cost_usd"] == pytest.approx(total, rel=1e-9)
    assert sum(r["cost_usd"] for r in rows) == pytest.approx(total, rel=1e-9)


def test_dry_run_cost_and_worst_case_match_the_hand_computed_prices(tmp_path, capsys):
    out = tmp_path / "study"
    runs, steps = 2, 12
    with priced_server() as srv:
        assert main(swim(srv.url, out, "--dry-run", model="gpt-4", runs=runs, steps=steps)) == 0
        assert srv.n_requests == 0
    printed = capsys.readouterr().out
    est = json.loads(printed.strip().splitlines()[-1])
    calls, prompt, completion = est["calls"], est["prompt_tokens"], est["completion_tokens"]
    assert calls == runs * steps
    assert (est["price_in"], est["price_out"]) == (GPT4_IN, GPT4_OUT)
    # Purcell's replies are limited to 10 tokens (the authors' code); a bare action is a few tokens.
    assert est["max_tokens"] == "10"
    assert 2 * calls <= completion <= 10 * calls
    assert 50 * calls < prompt < 1000 * calls  # a prompt is a few hundred tokens
    cost = (prompt * GPT4_IN + completion * GPT4_OUT) / 1_000_000
    worst = (prompt * GPT4_IN + calls * 10 * GPT4_OUT) / 1_000_000
    assert est["cost_usd"] == pytest.approx(cost, rel=1e-12)
    assert est["cost_max_usd"] == pytest.approx(worst, rel=1e-12)
    assert worst > cost
    assert f"cost: ${cost:.2f} at $30 / $60 per 1M tokens" in printed
    assert f"at most ${worst:.2f} if every reply ran to max_tokens=10" in printed


def test_a_cap_below_one_call_sends_nothing(tmp_path, capsys):
    # One gpt-4 call here costs ~$0.01 at worst (a few hundred prompt tokens, 10 of completion).
    out = tmp_path / "study"
    with priced_server() as srv:
        assert main(swim(srv.url, out, "--max-cost", "0.001", model="gpt-4", runs=2, steps=12)) == 3
        assert srv.n_requests == 0
    assert "cost cap" in capsys.readouterr().err
    assert ledger(out) == []


def test_the_journal_sums_what_every_session_paid(tmp_path):
    from jswim.llm.client import ChatResult
    from jswim.llm.journal import CallJournal
    from jswim.llm.usage import Usage

    def answer(cost: float, **kw) -> ChatResult:
        return ChatResult(
            text="[1, 1]",
            usage=Usage(100, 5),
            latency_s=0.0,
            cache_hit=kw.get("cache_hit", False),
            shared=kw.get("shared", False),
            retries=0,
            cost_usd=cost,
            constraint="none",
            finish_reason="stop",
            raw="[1, 1]",
        )

    costs = [[0.25, 0.125], [0.5], [0.0625, 1.0]]
    for k, session in enumerate(costs):
        j = CallJournal(tmp_path)
        assert j.spent_usd == sum(sum(c) for c in costs[:k])  # exact in binary: powers of two
        for n, c in enumerate(session):
            j.record(f"run{k}", n, f"key{n}", answer(c))
        j.record(
            f"run{k}", len(session), "cached", answer(4.0, cache_hit=True)
        )  # not billed: no cost
        j.close()
    assert CallJournal(tmp_path).spent_usd == 1.9375
    assert CallJournal(tmp_path).replay("run2", 1, "key1").cost_usd == 1.0


def test_the_journal_answers_only_the_very_request_it_recorded(tmp_path):
    from jswim.llm.client import ChatResult
    from jswim.llm.journal import CallJournal
    from jswim.llm.usage import Usage

    res = ChatResult(
        text="[2, -1]",
        usage=Usage(300, 6),
        latency_s=0.0,
        cache_hit=False,
        shared=False,
        retries=0,
        cost_usd=0.01,
        constraint="none",
        finish_reason="stop",
        raw="[2, -1]",
    )
    j = CallJournal(tmp_path)
    j.record("run-a", 0, "request-0", res)
    j.record("run-a", 1, "request-1", res)
    j.close()
    j = CallJournal(tmp_path)
    assert j.replay("run-b", 0, "request-0") is None  # another run's call: never
    assert (
        j.replay("run-a", 0, "another request") is None
    )  # the same place, a different request: sent
    j = CallJournal(tmp_path)
    assert (
        j.replay("run-a", 0, "request-0").text == "[2, -1]"
    )  # the very request: answered, not paid again
    assert j.replay("run-a", 1, "request-0") is None  # the right request at the wrong index


def test_reasoning_tokens_are_billed_at_the_completion_price(tmp_path, capsys):
    # A reasoning model (gpt-5-like: max_completion_tokens, temperature 1) thinks 300 tokens per
    # answer; they count as completion tokens, so each answered call costs, at gpt-4o's $2.5/$10:
    # prompt words * 2.5 + (300 + 2 answer words) * 10, per 1M (the fake server counts words).
    from tests.fakeserver import MODES, REASONING_TOKENS, count_words

    out = tmp_path / "study"
    # The server lists the model it is asked for: an unlisted model is never priced.
    with FakeServer(**MODES["openai-reasoning"], models=("gpt-4o",)) as srv:
        assert main(swim(srv.url, out, model="gpt-4o", runs=2, steps=4)) == 0, (
            capsys.readouterr().err
        )
        answered = [
            b for b in srv.requests if "max_completion_tokens" in b and b.get("temperature") == 1
        ]
    capsys.readouterr()
    assert len(answered) == 2 * 4
    expected = (
        sum(
            sum(count_words(str(m.get("content", ""))) for m in b["messages"]) * 2.5
            + (REASONING_TOKENS + count_words("[2, -1]")) * 10.0
            for b in answered
        )
        / 1_000_000
    )
    calls = ledger(out)
    assert len(calls) == len(answered)
    assert sum(c["cost_usd"] for c in calls) == pytest.approx(expected, rel=1e-9)
    assert expected > 8 * REASONING_TOKENS * 10.0 / 1_000_000  # the thinking is most of the bill
    rows = [r for r in read_runs(out) if r["agent"] == "llm"]
    assert sum(r["cost_usd"] for r in rows) == pytest.approx(expected, rel=1e-9)


# -- a cap that cannot lapse: calls the price rule would not price -------------------------------

from tests.fakeserver import GATEWAY_MODELS, as_remote  # noqa: E402


def status(folder: Path) -> str | None:
    meta = folder / "metadata.json"
    return json.loads(meta.read_text()).get("status") if meta.exists() else None


def test_a_cap_on_a_model_the_server_does_not_list_is_refused_and_prices_file_makes_it_hold(
    tmp_path, capsys
):
    # The case: --price-local, a server listing other names, --max-cost 0.05, 8 x 20 calls.
    # It sent all 160 requests at $0 while its dry run printed $1.23; now both apply one rule.
    out = tmp_path / "study"
    with priced_server(models=GATEWAY_MODELS, latency=0.005) as srv:
        args = swim(
            srv.url,
            out,
            "--max-cost",
            "0.05",
            "--concurrency",
            "2",
            model="gpt-4",
            runs=8,
            steps=20,
        )
        assert main([*args, "--dry-run"]) == 0
        dry = capsys.readouterr().out
        est = json.loads(dry.strip().splitlines()[-1])
        assert (
            srv.n_preflight > 0 and srv.n_requests == 0
        )  # the dry run asked /v1/models, sent no chat
        assert est["cost_usd"] == 0 and "does not list 'gpt-4'" in est["unpriced"]
        assert "--prices" in est["cap_refusal"] and "--max-cost: the run would send nothing" in dry
        assert main(args) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert srv.n_requests == 0 and len(err) == 1
        assert "--max-cost 0.05 cannot hold" in err[0] and "--prices" in err[0]
        prices = tmp_path / "prices.toml"
        prices.write_text('as_of = "test"\n[prices]\n"gpt-4" = [30.0, 60.0]\n')
        assert main([*args, "--prices", str(prices), "--dry-run"]) == 0
        est = json.loads(capsys.readouterr().out.strip().splitlines()[-1])
        assert est["price_in"] == GPT4_IN and est["cost_usd"] > 0.5 and est["cap_refusal"] is None
        code = main([*args, "--prices", str(prices)])
        err = capsys.readouterr().err
        sent = srv.settle()
        one_call = max(billed_usd_one(b) for b in srv.requests)
        spent = billed_usd(srv, "gpt-4")
    assert code == 3, err
    assert 0 < sent < 160
    assert spent <= 0.05 + 2 * one_call
    assert status(out) == "stopped at the cost cap"


def test_a_cap_on_calls_a_local_server_would_not_price_is_refused_before_any_request(
    tmp_path, capsys
):
    out = tmp_path / "study"
    with priced_server() as srv:
        args = [
            a
            for a in swim(srv.url, out, "--max-cost", "0.05", model="gpt-4")
            if a != "--price-local"
        ]
        assert main([*args, "--dry-run"]) == 0
        dry = capsys.readouterr().out
        assert main(args) == 2
        err = capsys.readouterr().err
        assert srv.n_requests == 0
    line = dry.strip().splitlines()[-1]
    assert json.loads(line)["cap_refusal"] and "--max-cost: the run would send nothing" in dry
    assert len(err.strip().splitlines()) == 1 and "--prices" in err and "--price-local" in err
    assert status(out) != "running"


def test_a_remote_gateway_listing_other_names_refuses_the_cap_and_prices_file_makes_it_hold(
    tmp_path, capsys, monkeypatch
):
    as_remote(monkeypatch)
    out = tmp_path / "study"
    with priced_server(models=GATEWAY_MODELS, latency=0.005) as srv:
        args = [
            a
            for a in swim(
                srv.url,
                out,
                "--max-cost",
                "0.05",
                "--concurrency",
                "2",
                model="gpt-4",
                runs=4,
                steps=12,
            )
            if a != "--price-local"
        ]
        # The dry run asks /v1/models (free) and applies the run's rule: not priced, the cap refused.
        assert main([*args, "--dry-run"]) == 0
        dry = capsys.readouterr().out
        est = json.loads(dry.strip().splitlines()[-1])
        assert est["cost_usd"] == 0 and "does not list 'gpt-4'" in est["unpriced"]
        assert "--prices" in est["cap_refusal"]
        assert main(args) == 2
        err = capsys.readouterr().err
        assert srv.n_requests == 0 and len(err.strip().splitlines()) == 1
        assert "--max-cost 0.05 cannot hold" in err and "--prices" in err
        prices = tmp_path / "prices.toml"
        prices.write_text('as_of = "test"\n[prices]\n"gpt-4" = [30.0, 60.0]\n')
        assert main([*args, "--prices", str(prices)]) == 3
        assert 0 < srv.settle() < 48
        assert billed_usd(srv, "gpt-4") <= 0.05 + 2 * max(billed_usd_one(b) for b in srv.requests)


def test_a_reply_naming_another_model_is_priced_under_a_cap(tmp_path, capsys, monkeypatch):
    # A gateway that lists gpt-4 but answers "openai/gpt-4-0613": uncapped that call costs $0 (and
    # says why); under --max-cost it is priced as requested, so the cap still stops the study.
    as_remote(monkeypatch)
    out = tmp_path / "study"
    with priced_server(served_model="openai/gpt-4-0613", latency=0.005) as srv:
        args = [
            a
            for a in swim(
                srv.url,
                out,
                "--max-cost",
                "0.05",
                "--concurrency",
                "2",
                model="gpt-4",
                runs=4,
                steps=12,
            )
            if a != "--price-local"
        ]
        assert main(args) == 3
        assert 0 < srv.settle() < 48
    assert "priced at gpt-4's price anyway" in capsys.readouterr().out
    assert sum(rec["cost_usd"] for rec in ledger(out)) > 0.04
