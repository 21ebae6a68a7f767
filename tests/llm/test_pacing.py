"""Rate-limit pacing, the cost cap and token estimates of the LLM client."""

from __future__ import annotations

import asyncio
import json
import math

import pytest

from jswim.llm import ClientSettings, LLMClient
from jswim.llm.budget import Budget, BudgetExhausted, call_bound
from jswim.llm.pacing import Pacer, parse_duration
from jswim.llm.tokens import estimate_prompt_tokens, estimate_tokens
from jswim.llm.usage import PriceTable
from tests.fakeserver import FakeServer, lognormal_latency
import itertools

MSG = [{"role": "user", "content": "Reply with [1, 1]."}]


def _settings(srv: FakeServer, **kw) -> ClientSettings:
    return ClientSettings(base_url=srv.url, model=kw.pop("model", "fake"), max_retries=0, **kw)


@pytest.mark.parametrize(
    "text, seconds",
    [
        ("1s", 1.0),
        ("6m0s", 360.0),
        ("20ms", 0.02),
        ("1h2m3s", 3723.0),
        ("0.5", 0.5),
        ("12", 12.0),
        ("2.5s", 2.5),
        (None, None),
        ("", None),
        ("soon", None),
        ("5x", None),
    ],
)
def test_parse_duration(text, seconds):
    got = parse_duration(text)
    assert got == seconds if seconds is None else math.isclose(got, seconds)


class _Clock:
    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


def _hold(p: Pacer, clock: _Clock) -> float:
    return max(0.0, p._until - clock.t)


def test_headers_hold_new_requests_until_the_provider_refills():
    clock = _Clock()
    p = Pacer(margin=4, clock=clock)
    p.observe({"x-ratelimit-remaining-requests": "10", "x-ratelimit-reset-requests": "6s"})
    assert _hold(p, clock) == 0.0  # plenty left: no wait
    # 1 left of 60 per minute, window full in 59 s -> 1 request per second refills; 3 more needed.
    p.observe(
        {
            "x-ratelimit-remaining-requests": "1",
            "x-ratelimit-limit-requests": "60",
            "x-ratelimit-reset-requests": "59s",
        }
    )
    assert math.isclose(_hold(p, clock), 3.0)
    clock.t += 10
    # Without the limit the pacer waits the whole reset time.
    p.observe({"x-ratelimit-remaining-tokens": "0", "x-ratelimit-reset-tokens": "1.5s"})
    assert math.isclose(_hold(p, clock), 1.5)
    clock.t += 10
    p.observe({"retry-after": "2"})
    assert math.isclose(_hold(p, clock), 2.0)
    clock.t += 10
    p.observe({"retry-after-ms": "250"})
    assert math.isclose(_hold(p, clock), 0.25)
    clock.t += 10
    p.observe({"retry-after": "86400"})  # a broken header cannot stall a study
    assert _hold(p, clock) == p.max_pause_s


def test_tokens_margin_scales_with_the_last_request():
    clock = _Clock()
    p = Pacer(margin=2, clock=clock)
    asyncio.run(p.wait(500))
    p.observe({"x-ratelimit-remaining-tokens": "1200", "x-ratelimit-reset-tokens": "1s"})
    assert _hold(p, clock) == 0.0  # 1200 >= 2 requests x 500 tokens
    p.observe({"x-ratelimit-remaining-tokens": "900", "x-ratelimit-reset-tokens": "1s"})
    assert math.isclose(_hold(p, clock), 1.0)


class VirtualClockLoop(asyncio.SelectorEventLoop):
    """An event loop on a virtual clock: when nothing is ready it jumps to its next timer.

    aiolimiter's buckets and the pacer's holds wait on the loop's timers, so on this loop they
    are checked to the microsecond, however loaded the machine (no wall clock involved).
    """

    def __init__(self) -> None:
        super().__init__()
        self._now = 0.0
        select = self._selector.select

        self._turns = 0

        def jump(timeout=None):
            self._turns += 1
            if (
                self._turns > 100_000
            ):  # a few hundred suffice here: a pacer that spins fails, not hangs
                raise RuntimeError("the virtual-clock loop made no progress in 100,000 turns")
            if timeout:  # idle until the next timer: advance the clock instead of sleeping
                # (by at least 0.1 us: a timer a rounding error ahead must not spin the loop)
                self._now += max(timeout, 1e-7)
            return select(0)

        self._selector.select = jump

    def time(self) -> float:
        return self._now


def virtual_run(main):
    loop = VirtualClockLoop()
    try:
        return loop.run_until_complete(main(loop))
    finally:
        loop.close()


def test_rpm_60_spaces_requests_one_second_apart_with_no_burst():
    async def go(loop):
        pacer = Pacer(rpm=60, clock=loop.time)

        async def one(i):
            await pacer.wait(100)
            return loop.time()

        return sorted(await asyncio.gather(*[one(i) for i in range(6)]))

    released = virtual_run(go)
    assert released[0] == pytest.approx(0.0, abs=1e-9)  # the first at once
    gaps = [b - a for a, b in itertools.pairwise(released)]
    assert gaps == pytest.approx([1.0] * 5, abs=1e-5)  # then one per second: no burst of the bucket


def test_tpm_spends_its_ten_seconds_of_tokens_then_paces():
    async def go(loop):
        pacer = Pacer(tpm=6000, clock=loop.time)  # 100 tokens/s, a 1000-token bucket (10 s worth)
        out = []
        for _ in range(4):
            await pacer.wait(500)
            out.append(loop.time())
        return out

    t = virtual_run(go)
    assert t[:2] == pytest.approx([0.0, 0.0], abs=1e-9)  # 1000 tokens at once
    assert [b - a for a, b in itertools.pairwise(t[1:])] == pytest.approx(
        [5.0, 5.0], abs=1e-5
    )  # then 500 per 5 s


def test_retry_after_on_a_success_holds_every_next_request():
    async def go(loop):
        pacer = Pacer(clock=loop.time)
        await pacer.wait(10)
        pacer.observe({"retry-after-ms": "400"})  # on an answer that succeeded
        await asyncio.gather(pacer.wait(10), pacer.wait(10))
        return loop.time(), pacer.paused_s

    now, paused = virtual_run(go)
    assert now == pytest.approx(0.4, abs=1e-5) and paused >= 0.4 - 1e-5


def test_paced_client_sends_every_request():
    # End to end through the client (no timing asserted: the spacing is checked above).
    async def go(url: str) -> None:
        async with LLMClient(
            ClientSettings(base_url=url, model="fake", max_concurrency=8),
            pacer=Pacer(rpm=600, tpm=10**6),
        ) as c:
            await asyncio.gather(
                *[c.chat([{"role": "user", "content": f"call {i}"}]) for i in range(5)]
            )

    with FakeServer() as srv:
        asyncio.run(go(srv.url))
    assert srv.n_requests == 5


def test_budget_refuses_past_the_cap_and_stays_closed():
    b = Budget(1.0, spent_usd=0.25)
    r1 = b.reserve(0.5)
    with pytest.raises(BudgetExhausted, match="higher --max-cost"):
        b.reserve(0.5)  # 0.25 + 0.5 + 0.5 > 1
    b.settle(r1, 0.1)  # the call cost less than reserved ...
    assert math.isclose(b.spent_usd, 0.35) and b.reserved_usd == 0.0
    with pytest.raises(BudgetExhausted):
        b.reserve(0.01)  # ... but the stop is final: no new call after the first refusal
    unlimited = Budget(None)
    unlimited.settle(unlimited.reserve(1e9), 5.0)
    assert unlimited.spent_usd == 5.0 and unlimited.remaining_usd is None
    with pytest.raises(ValueError):
        Budget(-1.0)


def test_call_bound_prices_prompt_and_max_tokens():
    prices = PriceTable({"m": (2.0, 10.0)})
    payload = {"messages": MSG, "max_tokens": 10}
    assert math.isclose(
        call_bound(payload, prices, "m"), (estimate_prompt_tokens(MSG) * 2.0 + 10 * 10.0) / 1e6
    )
    assert call_bound(payload, prices, "free-model") == 0.0


def test_client_stops_at_the_cap_before_sending():
    prices = {"priced": (1000.0, 1000.0)}  # $0.001 per token: a few calls reach the cap

    async def go(url: str) -> tuple[int, Budget]:
        settings = ClientSettings(base_url=url, model="priced", prices=prices, max_tokens=5)
        bound = call_bound({"messages": MSG, "max_tokens": 5}, PriceTable(prices), "priced")
        budget = Budget(3.5 * bound)
        ok = 0
        async with LLMClient(settings, budget=budget) as c:
            for _ in range(10):
                try:
                    await c.chat(MSG, use_cache=False)
                except BudgetExhausted:
                    break
                ok += 1
            assert math.isclose(c.counts.cost_usd, budget.spent_usd)
        return ok, budget, bound

    with FakeServer() as srv:
        ok, budget, bound = asyncio.run(go(srv.url))
        sent = srv.settle()
    assert 3 <= ok == sent < 10  # refused before sending: the server saw only the paid calls
    assert budget.exhausted and budget.reserved_usd == 0.0
    assert 0 < budget.spent_usd <= budget.cap_usd < budget.spent_usd + bound


def test_failed_attempts_release_their_reservation():
    from tests.fakeserver import Fault

    async def go(url: str) -> Budget:
        budget = Budget(1.0)
        async with LLMClient(
            ClientSettings(base_url=url, model="gpt-4o", max_retries=0), budget=budget
        ) as c:
            with pytest.raises(Exception):
                await c.chat(MSG)
        return budget

    with FakeServer(faults=[Fault.server_error()]) as srv:
        budget = asyncio.run(go(srv.url))
    assert budget.reserved_usd == 0.0 and budget.spent_usd == 0.0


def test_lognormal_latency_is_fixed_by_the_request_and_heavy_tailed():
    f = lognormal_latency(0.5, 0.8, seed=1)
    body = {"messages": [{"role": "user", "content": "step 3"}]}
    assert f(body) == f(json.loads(json.dumps(body)))
    draws = sorted(f({"messages": [{"role": "user", "content": f"p{i}"}]}) for i in range(4000))
    median = draws[len(draws) // 2]
    assert 0.45 < median < 0.55
    # log-normal: mean = median * exp(sigma^2 / 2) = 0.689; the 97.7% quantile = median * e^(2 sigma)
    assert 0.64 < sum(draws) / len(draws) < 0.74
    assert 2.2 < draws[int(0.977 * len(draws))] < 2.7
    assert f(body) != lognormal_latency(0.5, 0.8, seed=2)(body)


# -- token estimates ---------------------------------------------------------------------------


def test_estimate_counts_pieces():
    assert estimate_tokens("") == 0
    # 3-digit chunks: a 7-digit number is 3 pieces, a word with its space is one
    assert estimate_tokens("1234567") == round(3 * 1.06)
    assert estimate_tokens("the cat sat") == round(3 * 1.06)
    assert estimate_prompt_tokens([{"role": "user", "content": ""}]) == 3 + 4


def _protocol_prompts() -> list[str]:
    from jswim.agents.llm import LLMRunSpec, run_batch
    from jswim.llm import ClientSettings as CS
    from tests.fakeserver import hash_reply

    prompts = []
    with FakeServer(reply=hash_reply) as srv:
        specs = [
            LLMRunSpec(swimmer=sw, zeta=0.5, seed=k, n_steps=12, direction=d)
            for sw in ("purcell", "ng")
            for k in range(2)
            for d in (1, -1)
        ]
        for r in run_batch(specs, CS(base_url=srv.url, model="fake")):
            prompts += [rec["prompt"] for rec in r.transcript if rec.get("type") == "step"]
    return prompts


def test_estimate_within_10_percent_of_openai_tokenizers():
    bpe = pytest.importorskip("bpe_openai")
    prompts = _protocol_prompts()
    assert len(prompts) >= 50
    for name in ("o200k_base", "cl100k_base"):
        enc = bpe.get_encoding(name)
        est = sum(estimate_tokens(p) for p in prompts)
        true = sum(len(enc.encode(p)) for p in prompts)
        assert abs(est / true - 1) < 0.05, (name, est / true)
        worst = max(abs(estimate_tokens(p) / len(enc.encode(p)) - 1) for p in prompts)
        assert worst < 0.10, (name, worst)
