"""--max-cost holds whatever the server reports: replies that cannot be priced, bodies that are no
chat completion, bills above the reservation, a ledger edited by hand, a journal that cannot be
written, replies that never end or are huge. Every cap case is checked against the fake server's
own request count and its own usage numbers, never against jswim's."""

from __future__ import annotations

import asyncio
import json
import math
from pathlib import Path

import pytest

from jswim import cli
from jswim.errors import LLMServerError
from jswim.llm.budget import Budget
from jswim.llm.client import KEEP_BASE, KEEP_PER_TOKEN, ClientSettings, LLMClient
from jswim.llm.pacing import Pacer
from jswim.llm.tokens import estimate_prompt_tokens
from tests.fakeserver import FakeServer, Fault, count_words, hash_reply

#: USD per token, prompt and completion: $0.001 (a call of a few hundred tokens costs cents).
PER_TOKEN = 0.001


def prices_file(tmp_path: Path) -> Path:
    p = tmp_path / "prices.json"
    p.write_text(json.dumps({"fake": [PER_TOKEN * 1e6, PER_TOKEN * 1e6]}))
    return p


def swim(url: str, out: Path, prices: Path, cap: float, *extra: str) -> list[str]:
    return [
        "swim",
        "--base-url",
        url,
        "--model",
        "fake",
        "--runs",
        "2",
        "--steps",
        "8",
        "--q-runs",
        "0",
        "--swimmer",
        "purcell",
        "--direction",
        "+x",
        "--no-figures",
        "--concurrency",
        "1",
        "--max-tokens",
        "10",
        "--prices",
        str(prices),
        "--max-cost",
        repr(cap),
        "--out",
        str(out),
        *extra,
    ]


def bound(body: dict) -> float:
    """jswim's reservation for one request, from what the server received."""
    return (estimate_prompt_tokens(body["messages"]) + body.get("max_tokens", 0)) * PER_TOKEN


def billed(srv: FakeServer, usage) -> float:
    """What the server's own usage numbers bill for every request it received."""
    total = 0.0
    for body in srv.requests:
        u = usage(body)
        total += (u["prompt_tokens"] + u["completion_tokens"]) * PER_TOKEN
    return total


def honest(body: dict) -> dict:
    prompt = sum(count_words(str(m.get("content", ""))) for m in body["messages"])
    return {"prompt_tokens": prompt, "completion_tokens": count_words(hash_reply(body))}


@pytest.fixture(scope="module")
def with_usage(tmp_path_factory) -> tuple[int, float]:
    """Requests sent, and the cap, when the server reports honest usage."""
    tmp = tmp_path_factory.mktemp("honest")
    with FakeServer(reply=hash_reply, usage=honest) as srv:
        cap = 4.5 * _first_bound(tmp)
        srv.reset_counts()
        code = cli.main(swim(srv.url, tmp / "F", prices_file(tmp), cap))
        assert code == 3
        return srv.settle(), cap


def _first_bound(tmp: Path) -> float:
    """The reservation of the study's first request (a dry run sends nothing)."""
    with FakeServer(reply=hash_reply) as probe:
        cli.main(
            swim(probe.url, tmp / "probe", prices_file(tmp), 1e9, "--runs", "1", "--steps", "1")
        )
        return bound(probe.requests[0])


@pytest.mark.parametrize(
    "usage",
    [
        None,  # no usage object at all
        {"prompt_tokens": -5, "completion_tokens": -1, "total_tokens": -6},
        {"prompt_tokens": math.nan, "completion_tokens": math.nan},
        {"prompt_tokens": "n/a", "completion_tokens": 3},
        {"prompt_tokens": 0, "completion_tokens": 0},
    ],
    ids=["missing", "negative", "nan", "text", "zero"],
)
def test_a_reply_that_cannot_be_priced_is_priced_at_its_reservation(
    tmp_path, capsys, usage, with_usage
):
    sent_honest, cap = with_usage
    with FakeServer(reply=hash_reply, usage=lambda body: usage) as srv:
        code = cli.main(swim(srv.url, tmp_path / "F", prices_file(tmp_path), cap))
        sent = srv.settle()
        reservations = sum(bound(b) for b in srv.requests)
    err = capsys.readouterr().err
    assert code == 3, err
    assert "cost cap" in err
    # Priced at the reservation, the cap stops no later than with honest counts (never all 16).
    assert 1 <= sent <= sent_honest < 16
    assert reservations <= cap


@pytest.mark.slow  # ~4 s: the client's backoff between the bad bodies
def test_bodies_that_are_no_chat_completion_are_spent_and_stop_at_the_cap(tmp_path, capsys):
    prices = prices_file(tmp_path)
    cap = 3.5 * _first_bound(tmp_path)
    with FakeServer(reply=lambda body: Fault.malformed()) as srv:
        code = cli.main(swim(srv.url, tmp_path / "F", prices, cap, "--retries", "10"))
        sent = srv.settle()
        reservations = sum(bound(b) for b in srv.requests)
    err = capsys.readouterr().err
    assert code == 3, err
    assert "cost cap" in err
    assert 1 <= sent <= 3 and reservations <= cap
    meta = json.loads((tmp_path / "F" / "metadata.json").read_text())
    assert meta["status"] == "stopped at the cost cap"


@pytest.mark.parametrize(
    "scale",
    [
        # a prompt counted 1.8 times jswim's estimate
        lambda u, body: {**u, "prompt_tokens": int(1.8 * estimate_prompt_tokens(body["messages"]))},
        lambda u, body: {**u, "completion_tokens": 500},  # 500 tokens for max_tokens 10
    ],
    ids=["prompt x1.8", "completion 500 for 10"],
)
def test_bills_above_the_reservation_pass_the_cap_by_at_most_one_calls_excess(
    tmp_path, capsys, scale
):
    prices = prices_file(tmp_path)
    cap = 4.5 * _first_bound(tmp_path)

    def usage(body):
        return scale(honest(body), body)

    with FakeServer(reply=hash_reply, usage=usage) as srv:
        code = cli.main(swim(srv.url, tmp_path / "F", prices, cap))
        sent = srv.settle()
        total = billed(srv, usage)
        excess = max(
            (usage(b)["prompt_tokens"] + usage(b)["completion_tokens"]) * PER_TOKEN - bound(b)
            for b in srv.requests
        )
    assert code == 3, capsys.readouterr().err
    assert excess > 0 and sent >= 1
    # docs/paid-apis.md (What the cap guarantees): with one request in flight, the cap is passed
    # by at most that one request's excess over its reservation (at least its unscaled bound).
    assert total <= cap + excess + 1e-12


def test_the_ratio_learned_in_one_session_holds_in_the_next(tmp_path):
    prices = prices_file(tmp_path)
    cap = 4.5 * _first_bound(tmp_path)

    def usage(body):
        return {**honest(body), "completion_tokens": 500}

    with FakeServer(reply=hash_reply, usage=usage) as srv:
        cli.main(swim(srv.url, tmp_path / "F", prices, cap))
        first_total = billed(srv, usage)
        srv.reset_counts()
        higher = 2 * first_total
        assert cli.main(swim(srv.url, tmp_path / "F", prices, higher)) == 3
        second = billed(srv, usage)
    # No first-call excess this time: the ledger already knew the ratio.
    assert first_total + second <= higher + 1e-12


@pytest.mark.parametrize("value", [-1, "NaN", 0, None, "text"])
def test_the_folders_totals_are_no_ledger(tmp_path, capsys, value):
    prices = prices_file(tmp_path)
    cap = 3.5 * _first_bound(tmp_path)
    out = tmp_path / "F"
    with FakeServer(reply=hangs_for_all(), hold_s=0.5) as srv:  # every request times out
        code = cli.main(swim(srv.url, out, prices, cap, "--timeout", "0.2", "--retries", "20"))
        assert code == 3, capsys.readouterr().err
        first = srv.settle()
        meta_path = out / "metadata.json"
        meta = json.loads(meta_path.read_text())
        meta["llm_totals"]["unanswered_usd"] = math.nan if value == "NaN" else value
        meta_path.write_text(json.dumps(meta))
        srv.reset_counts()
        cli.main(swim(srv.url, out, prices, cap, "--timeout", "0.2", "--retries", "20"))
        assert srv.settle() == 0  # the ledger still counts every unanswered request
    assert 1 <= first <= 3


def hangs_for_all():
    def reply(body):
        return Fault.delay(2.0)

    return reply


def test_a_journal_that_cannot_be_written_sends_nothing(tmp_path, capsys):
    prices = prices_file(tmp_path)
    out = tmp_path / "F"
    with FakeServer(reply=hash_reply) as srv:
        assert cli.main(swim(srv.url, out, prices, 1e9, "--runs", "1", "--steps", "2")) == 0
        (out / "calls.jsonl").unlink()
        (out / "calls.jsonl").symlink_to(tmp_path / "gone" / "calls.jsonl")  # dangling
        srv.reset_counts()
        for _ in range(3):
            code = cli.main(swim(srv.url, out, prices, 1e9, "--runs", "3", "--steps", "2"))
            err = capsys.readouterr().err
            assert code == 2 and "calls.jsonl" in err and "nothing was sent" in err
            assert "Traceback" not in err
        assert srv.n_requests == 0


def test_a_ledger_that_cannot_be_written_sends_nothing(tmp_path, capsys):
    prices = prices_file(tmp_path)
    out = tmp_path / "F"
    with FakeServer(reply=hash_reply) as srv:
        assert cli.main(swim(srv.url, out, prices, 1e9, "--runs", "1", "--steps", "2")) == 0
        (out / "requests.jsonl").unlink()
        (out / "requests.jsonl").mkdir()  # no file can be appended there
        srv.reset_counts()
        code = cli.main(swim(srv.url, out, prices, 1e9, "--runs", "3", "--steps", "2"))
        err = capsys.readouterr().err
        assert code == 2 and "requests.jsonl" in err and "Traceback" not in err
        assert srv.n_requests == 0


def test_a_ledger_line_that_cannot_be_written_stops_that_request(tmp_path, monkeypatch):
    import jswim.llm.ledger as ledger_module
    from jswim.errors import StudyFolderError
    from jswim.llm.ledger import RequestLedger

    ledger = RequestLedger(tmp_path)

    def full_disk(*a, **kw):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(ledger_module, "open", full_disk, raising=False)

    async def go(url):
        s = settings(url, prices={"fake": (1e6, 1e6)})
        async with LLMClient(s, budget=Budget(1e9, ledger=ledger)) as c:
            await c.chat([{"role": "user", "content": "x"}])

    with FakeServer(reply=hash_reply) as srv:
        with pytest.raises(StudyFolderError, match="nothing was sent"):
            asyncio.run(go(srv.url))
        assert srv.n_requests == 0


def settings(url: str, **kw) -> ClientSettings:
    return ClientSettings(base_url=url, model="fake", **{"backoff_base_s": 0.01, **kw})


def test_a_reply_that_never_ends_is_cut_at_the_attempts_wall_time():
    async def go(url):
        async with LLMClient(settings(url, timeout_s=0.3, retry_for_s=0.6, max_retries=10)) as c:
            await c.chat([{"role": "user", "content": "x"}])

    # The stream sends a piece every 0.05 s (well within --timeout between bytes) and stops
    # after 30 s at the latest, so a client without a bound on the whole attempt fails below.
    with FakeServer(reply=lambda body: Fault.endless(0.05), hold_s=30.0) as srv:
        with pytest.raises(LLMServerError, match="no whole answer within 0.6 s") as err:
            asyncio.run(go(srv.url))
        sent = srv.n_requests
    assert 1 <= sent <= 2 and "kept coming" in str(err.value)


def test_an_endless_reply_counts_as_unanswered_against_the_cap():
    async def go(url, budget):
        s = settings(url, timeout_s=0.2, retry_for_s=0.3, prices={"fake": (1e6, 1e6)})
        async with LLMClient(s, budget=budget) as c:
            await c.chat([{"role": "user", "content": "x"}])

    budget = Budget(1e9)
    with FakeServer(reply=lambda body: Fault.endless(0.05)) as srv:
        with pytest.raises(LLMServerError):
            asyncio.run(go(srv.url, budget))
        assert budget.unanswered_usd > 0 and budget.reserved_usd == 0


def test_a_huge_reply_is_kept_to_what_max_tokens_allows(tmp_path):
    huge = "[1, 1] " + "x" * 1_000_000

    async def go(url):
        async with LLMClient(settings(url, max_tokens=10)) as c:
            return await c.chat([{"role": "user", "content": "x"}])

    with FakeServer(reply=lambda body: huge) as srv:
        res = asyncio.run(go(srv.url))
    limit = KEEP_BASE + KEEP_PER_TOKEN * 10
    assert res.text.startswith("[1, 1]") and limit < len(res.text) < limit + 80
    assert "characters not kept" in res.text and len(res.raw) < limit + 80


def test_a_huge_reply_does_not_fill_the_folder(tmp_path, capsys):
    huge = "[1, 1] " + "x" * 1_000_000
    out = tmp_path / "F"
    with FakeServer(reply=lambda body: huge) as srv:
        cli.main(swim(srv.url, out, prices_file(tmp_path), 1e9))
        assert srv.n_requests >= 8
    size = sum(p.stat().st_size for p in out.rglob("*") if p.is_file())
    assert size < 2_000_000  # 16 calls of 1 MB each were 49 MB


def test_retry_after_waits_no_longer_than_the_retry_time(monkeypatch):
    import jswim.llm.client as client_module
    import jswim.llm.pacing as pacing_module

    waits: list[float] = []
    real_sleep = asyncio.sleep
    now = [0.0]  # the pacer's clock, moved by the waits it asks for

    async def sleep(seconds, *a, **kw):  # the waits the client and the pacer ask for, recorded
        waits.append(seconds)
        now[0] += seconds
        await real_sleep(0)

    monkeypatch.setattr(client_module.asyncio, "sleep", sleep)
    monkeypatch.setattr(pacing_module.asyncio, "sleep", sleep)

    async def go(url):
        s = settings(url, retry_for_s=6.0, max_retries=3)
        async with LLMClient(s, pacer=Pacer(None, None, clock=lambda: now[0])) as c:
            await c.chat([{"role": "user", "content": "x"}])

    with FakeServer(reply=lambda body: Fault.rate_limit("3600")) as srv:
        with pytest.raises(LLMServerError, match="429"):
            asyncio.run(go(srv.url))
    assert srv.n_requests >= 2 and waits and max(waits) <= 6.0  # was 60 s under --retry-for 6


def test_a_body_over_the_size_limit_is_spent_at_its_reservation(monkeypatch):
    import jswim.llm.client as client_module
    from jswim.errors import LLMResponseError

    monkeypatch.setattr(client_module, "MAX_BODY_BYTES", 64 << 10)  # 64 KiB for the test

    async def go(url, budget):
        s = settings(url, max_retries=1, prices={"fake": (1e6, 1e6)}, max_tokens=10)
        async with LLMClient(s, budget=budget) as c:
            await c.chat([{"role": "user", "content": "x"}])

    budget = Budget(1e9)
    with FakeServer(reply=lambda body: "[1, 1] " + "x" * (128 << 10)) as srv:
        with pytest.raises(LLMResponseError, match="larger than"):
            asyncio.run(go(srv.url, budget))
        sent = srv.n_requests
        one = bound(srv.requests[0]) / PER_TOKEN  # $1 per token here
    assert sent == 2 and budget.spent_usd == pytest.approx(2 * one) and budget.reserved_usd == 0


def test_a_steady_overbilling_ratio_is_learned_from_the_first_replies_in_flight(tmp_path, capsys):
    """Four requests in flight, a server billing exactly three times every reservation: only the
    first four can pass their reservations; every later one is reserved at the ratio they showed,
    so a cap reached after them holds exactly."""
    prices = prices_file(tmp_path)
    ratio = 3

    def usage(body):
        prompt = estimate_prompt_tokens(body["messages"])
        return {"prompt_tokens": ratio * prompt, "completion_tokens": ratio * body["max_tokens"]}

    cap = 14 * ratio * _first_bound(tmp_path)
    args = swim("", tmp_path / "F", prices, cap, "--concurrency", "4", "--runs", "4")
    with FakeServer(reply=hash_reply, usage=usage) as srv:
        args[2] = srv.url
        assert cli.main(args) == 3, capsys.readouterr().err
        sent = srv.settle()
        total = billed(srv, usage)
        first_wave = sum(bound(b) for b in srv.requests[:4])
    assert sent > 4 and total > first_wave  # the first replies were billed above their bounds
    assert total <= cap * (1 + 1e-9)  # ... and the cap, reached later, holds exactly
