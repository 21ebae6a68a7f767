"""The async chat client against the fake server: retries, waits, cache, sharing, secrecy, usage."""

from __future__ import annotations

import asyncio
import email.utils
import json
import socket

import httpx
import pytest

from jswim.llm import constrain
from jswim.llm.response_cache import ResponseCache, request_key
from jswim.llm.client import ClientSettings, LLMClient, parse_retry_after, safe_url
from jswim.errors import LLMRequestError, LLMResponseError, LLMServerError
from jswim.llm.usage import PriceTable, Usage, UsageTotals
from tests.fakeserver import Fault, FakeServer

MSG = [{"role": "user", "content": "Reply with the next action as [changed DOF, ROC]"}]
REPLIES = ["[1, -1]", "[1, 0]", "[1, 1]", "[2, -1]", "[2, 0]", "[2, 1]"]
SECRET = "sk-test-DO-NOT-LEAK-1234567890"


@pytest.fixture
def server():
    with FakeServer(reply=lambda body: "[2, 1]") as srv:
        yield srv


def settings(srv: FakeServer | str, **kw) -> ClientSettings:
    base = srv.url if isinstance(srv, FakeServer) else srv
    kw = {"model": "fake", "backoff_base_s": 0.001, "backoff_max_s": 0.01, "timeout_s": 5.0, **kw}
    return ClientSettings(base_url=base, **kw)


def run(coro):
    return asyncio.run(coro)


class _RecordingAsyncio:
    """``asyncio`` as the client module sees it, with ``sleep`` recorded and not waited out.

    The client's waits (backoff, Retry-After) are its behaviour; what a loaded machine does to
    the wall clock is not. Everything else is the real asyncio.
    """

    def __init__(self) -> None:
        self.waits: list[float] = []

    def __getattr__(self, name):
        return getattr(asyncio, name)

    async def sleep(self, seconds, result=None):
        self.waits.append(float(seconds))
        await asyncio.sleep(0)
        return result


@pytest.fixture
def waits(monkeypatch):
    """The seconds each wait of the client asked for (in order); the waits themselves are skipped."""
    from jswim.llm import client as client_module

    fake = _RecordingAsyncio()
    monkeypatch.setattr(client_module, "asyncio", fake)
    return fake.waits


async def one_call(s: ClientSettings, messages=MSG, **kw):
    async with LLMClient(s) as c:
        return await c.chat(messages, **kw)


def test_plain_call(server):
    res = run(one_call(settings(server)))
    assert res.text == "[2, 1]" and res.retries == 0 and not res.cache_hit
    assert res.usage.prompt_tokens == 9 and res.usage.completion_tokens == 2
    assert server.n_requests == 1
    body = server.requests[0]
    assert body["temperature"] == 0 and body["model"] == "fake" and body["messages"] == MSG
    assert "grammar" not in body and "response_format" not in body


def test_retries_on_transient_faults(server):
    server.add_faults(
        Fault.server_error(500),
        Fault.drop(),
        Fault.malformed(),
        Fault.server_error(503),
        Fault.rate_limit(),
    )
    res = run(one_call(settings(server, max_retries=5)))
    assert res.text == "[2, 1]" and res.retries == 5
    assert server.n_requests == 6 and server.n_answered == 1


def test_retries_on_408_and_409(server):
    server.add_faults(Fault.server_error(408), Fault.server_error(409))
    assert run(one_call(settings(server))).retries == 2


def test_gives_up_with_server_error(server):
    server.add_faults(*[Fault.server_error(502)] * 10)
    with pytest.raises(LLMServerError) as err:
        run(one_call(settings(server, max_retries=3)))
    msg = str(err.value)
    assert server.url in msg and "HTTP 502" in msg and "4 attempts" in msg and "\n" not in msg
    assert server.n_requests == 4


def test_persistently_malformed_body(server):
    server.add_faults(*[Fault.malformed()] * 3)
    with pytest.raises(LLMResponseError, match="malformed"):
        run(one_call(settings(server, max_retries=2)))


def test_client_errors_are_not_retried(server):
    server.add_faults(Fault.server_error(400, "bad field"))
    with pytest.raises(LLMRequestError) as err:
        run(one_call(settings(server)))
    assert err.value.status == 400 and "bad field" in str(err.value)
    assert server.n_requests == 1


def test_timeout_is_retried_at_once(server, waits):
    server.add_faults(Fault.delay(30.0))
    res = run(one_call(settings(server, timeout_s=0.2)))
    # The timed-out request already waited a whole timeout: sent again with no backoff (no wait,
    # or a zero one), and answered.
    assert res.retries == 1 and server.n_requests == 2 and res.text == "[2, 1]"
    assert all(w == 0.0 for w in waits), waits


def test_retry_after_seconds_is_honoured(server, waits):
    server.add_faults(Fault.rate_limit("0.4"))
    res = run(one_call(settings(server)))
    assert res.retries == 1 and server.n_requests == 2
    assert waits == [pytest.approx(0.4)]  # the server's wait, not the (millisecond) backoff


def test_retry_after_is_capped(server, waits):
    server.add_faults(Fault.rate_limit("3600"))
    res = run(one_call(settings(server, max_retry_after_s=0.2)))
    assert res.retries == 1 and waits == [pytest.approx(0.2)]


def test_backoff_doubles_with_jitter_up_to_its_cap(server, waits):
    server.add_faults(*[Fault.server_error(503)] * 5)
    res = run(one_call(settings(server, max_retries=6, backoff_base_s=1.0, backoff_max_s=5.0)))
    assert res.retries == 5 and len(waits) == 5
    # Retry k waits min(cap, base * 2**k) scaled by a jitter in [0.5, 1].
    for k, w in enumerate(waits):
        full = min(5.0, 1.0 * 2.0**k)
        assert 0.5 * full <= w <= full, (k, w)


def test_parse_retry_after():
    now = 1_700_000_000.0
    date = email.utils.formatdate(now + 7, usegmt=True)
    assert parse_retry_after(httpx.Headers({"Retry-After": date}), now=now) == pytest.approx(7.0)
    assert parse_retry_after(httpx.Headers({"Retry-After": "2.5"})) == 2.5
    assert parse_retry_after(httpx.Headers({"retry-after-ms": "150"})) == 0.15
    assert parse_retry_after(httpx.Headers({"Retry-After": "soon"})) is None
    assert parse_retry_after(httpx.Headers({})) is None


def test_server_down_fails_fast_with_clear_error(waits):
    with socket.socket() as s:  # a port nothing listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    base = f"http://127.0.0.1:{port}/v1"
    with pytest.raises(LLMServerError) as err:
        run(one_call(settings(base, max_retries=2)))
    # Fast: two retries, each after a backoff within its (millisecond) bound, and then the error.
    assert len(waits) == 2 and all(0 <= w <= 0.01 for w in waits)
    msg = str(err.value)
    assert base in msg and "connection failed" in msg and "3 attempts" in msg


def test_disk_cache_hit_on_identical_request(server, tmp_path):
    s = settings(server, cache_dir=str(tmp_path))

    async def twice():
        async with LLMClient(s) as c:
            return await c.chat(MSG), await c.chat(MSG)

    first, second = run(twice())
    assert not first.cache_hit and second.cache_hit and second.text == first.text
    assert second.usage == first.usage
    assert server.n_requests == 1
    third = run(one_call(s))  # persistent: a new client (new run) still hits
    assert third.cache_hit and server.n_requests == 1
    run(one_call(s, messages=[{"role": "user", "content": "other"}]))
    assert server.n_requests == 2


def test_cache_only_for_temperature_zero(server, tmp_path):
    s = settings(server, cache_dir=str(tmp_path), temperature=0.7)

    async def twice():
        async with LLMClient(s) as c:
            return await c.chat(MSG), await c.chat(MSG)

    a, b = run(twice())
    assert not a.cache_hit and not b.cache_hit and server.n_requests == 2
    assert len(ResponseCache(tmp_path)) == 0


def test_cache_key_covers_the_request():
    base = {"model": "m", "messages": MSG, "temperature": 0, "max_tokens": 8}
    keys = {
        request_key(base),
        request_key({**base, "model": "n"}),
        request_key({**base, "max_tokens": 9}),
        request_key({**base, "seed": 1}),
        request_key({**base, "grammar": constrain.gbnf(REPLIES)}),
        request_key({**base, "messages": [{"role": "user", "content": "x"}]}),
    }
    assert len(keys) == 6
    assert request_key(dict(reversed(list(base.items())))) == request_key(base)


def test_identical_concurrent_requests_are_sent_once():
    with FakeServer(reply=lambda body: "[1, 1]", latency=0.2) as srv:
        s = settings(srv)

        async def burst():
            async with LLMClient(s) as c:
                return await asyncio.gather(*[c.chat(MSG) for _ in range(10)])

        results = run(burst())
        assert srv.n_requests == 1
        assert sum(r.shared for r in results) == 9 and all(r.text == "[1, 1]" for r in results)
        totals = UsageTotals()
        for r in results:
            totals.add(r)
        assert totals.calls == 10 and totals.billed_calls == 1 and totals.shared == 9


def test_shared_failure_reaches_every_waiter():
    with FakeServer(latency=0.1, faults=[Fault.server_error(500)] * 5) as srv:
        s = settings(srv, max_retries=1)

        async def burst():
            async with LLMClient(s) as c:
                return await asyncio.gather(
                    *[c.chat(MSG) for _ in range(4)], return_exceptions=True
                )

        results = run(burst())
        assert all(isinstance(r, LLMServerError) for r in results)
        assert srv.n_requests == 2


def test_concurrency_limit_and_overlap():
    # The server holds every answer until `limit` requests have been in flight together (or 20 s
    # pass): with 8 slots all 8 calls overlap; with 2, never more than 2 are in flight. The hold
    # reads the peak, not the current count: the first answer drops the count below `limit` again,
    # and the requests still held would then wait out the client's timeout and be sent again.
    limit = {"n": 8}
    srv = FakeServer(hold=lambda body: srv.max_in_flight < limit["n"], hold_s=20.0)
    with srv:

        async def many(n):
            limit["n"] = n
            async with LLMClient(settings(srv, max_concurrency=n)) as c:
                msgs = [[{"role": "user", "content": f"q{k}"}] for k in range(8)]
                return await asyncio.gather(*[c.chat(m) for m in msgs])

        assert len(run(many(8))) == 8
        assert srv.max_in_flight == 8 and srv.n_requests == 8
        srv.reset_counts()
        assert len(run(many(2))) == 8
        assert (
            srv.max_in_flight == 2 and srv.n_requests == 8
        )  # 8: no request timed out and was sent again


def test_api_key_never_leaks(server, tmp_path, monkeypatch):
    monkeypatch.setenv("JSWIM_TEST_KEY", SECRET)
    s = settings(server, api_key_env="JSWIM_TEST_KEY", cache_dir=str(tmp_path / "cache"))
    res = run(one_call(s))
    assert server.auth_headers[-1] == f"Bearer {SECRET}"  # it is sent...
    blob = json.dumps(res.as_dict()) + repr(res) + json.dumps(s.metadata())
    assert SECRET not in blob
    for f in (tmp_path / "cache").iterdir():  # ...but never stored
        assert SECRET.encode() not in f.read_bytes()
    server.add_faults(Fault.server_error(401, f"Incorrect API key provided: {SECRET}"))
    with pytest.raises(LLMRequestError) as err:
        run(one_call(s, messages=[{"role": "user", "content": "new"}]))
    assert SECRET not in str(err.value) and "$JSWIM_TEST_KEY" in str(err.value)
    assert SECRET not in repr(LLMClient(s))


def test_no_key_no_header(server, monkeypatch):
    monkeypatch.delenv("JSWIM_UNSET_KEY", raising=False)
    run(one_call(settings(server, api_key_env="JSWIM_UNSET_KEY")))
    assert server.auth_headers[-1] is None


def test_usage_and_cost(server):
    s = settings(
        server, model="gpt-4", price_local=True
    )  # the fake server stands in for a paid API

    async def calls():
        async with LLMClient(s) as c:
            return [await c.chat([{"role": "user", "content": "a b c " * k}]) for k in (1, 2, 3)]

    results = run(calls())
    totals = UsageTotals()
    for r in results:
        totals.add(r)
    assert totals.prompt_tokens == 3 + 6 + 9 and totals.completion_tokens == 6
    assert totals.cost_usd == pytest.approx((18 * 30 + 6 * 60) / 1e6)
    study = totals.merge([totals, UsageTotals()])
    assert study.calls == 6 and study.cost_usd == pytest.approx(2 * totals.cost_usd)


def priced_calls(srv: FakeServer, **kw) -> float:
    async def calls():
        async with LLMClient(settings(srv, model="gpt-4", **kw)) as c:
            got = [await c.chat([{"role": "user", "content": "a b c"}]) for _ in range(2)]
            return sum(r.cost_usd for r in got), c.unpriced

    return run(calls())


def test_a_local_server_is_not_priced_at_a_cloud_list_price(server):
    cost, why = priced_calls(server)
    assert cost == 0.0 and "--price-local" in why
    cost, why = priced_calls(server, price_local=True)  # asked: a local gateway to a paid API
    assert cost == pytest.approx(2 * (3 * 30 + 2 * 60) / 1e6) and why is None
    cost, why = priced_calls(
        server, prices={"gpt-4": (1.0, 1.0)}
    )  # the user's own table applies anywhere
    assert cost == pytest.approx(2 * 5 / 1e6) and why is None


def test_a_reply_from_another_model_is_not_priced():
    # A server that runs one model whatever name it is sent (llama-cpp-python's does).
    with FakeServer(served_model="/models/SmolLM2-135M-Instruct.Q4_1.gguf") as srv:
        cost, why = priced_calls(srv, price_local=True)
        assert cost == 0.0 and "SmolLM2" in why and "'gpt-4'" in why
    with FakeServer(
        served_model="gpt-4-0613"
    ) as srv:  # a dated snapshot of the priced model: priced
        cost, why = priced_calls(srv, price_local=True)
        assert cost > 0 and why is None


def test_a_model_the_server_does_not_list_is_not_priced(server, monkeypatch):
    cost, why = priced_calls(server, price_local=True, listed_models=("fake",))
    assert cost == 0.0 and "does not list 'gpt-4'" in why
    cost, _ = priced_calls(server, price_local=True, listed_models=("gpt-4",))
    assert cost > 0
    from tests.fakeserver import as_remote

    as_remote(monkeypatch)  # a gateway off this machine, where list prices apply: the same rule
    cost, why = priced_calls(server, listed_models=("fake",))
    assert cost == 0.0 and "does not list 'gpt-4'" in why and "--prices" in why


def test_price_table():
    prices = PriceTable()
    assert prices.lookup("gpt-4") == (30.0, 60.0)
    assert prices.lookup("gpt-4o-2024-08-06") == prices.lookup("gpt-4o")
    assert prices.lookup("gpt-4o-mini-2024-07-18") == prices.lookup("gpt-4o-mini")
    assert prices.lookup("SmolLM2-135M-Instruct.Q4_1") == (0.0, 0.0)
    assert PriceTable({"m": (1.0, 2.0)}).cost("m", Usage(1_000_000, 500_000)) == pytest.approx(2.0)
    assert (
        Usage.from_response(
            {"prompt_tokens": 5, "prompt_tokens_details": {"cached_tokens": 4}}
        ).cached_tokens
        == 4
    )
    assert Usage.from_response(None) == Usage()


def test_grammar_sent_to_llamacpp_backends(server):
    run(one_call(settings(server, server_kind="llamacpp"), replies=REPLIES))
    assert server.requests[-1]["grammar"] == (
        'root ::= "[1, -1]" | "[1, 0]" | "[1, 1]" | "[2, -1]" | "[2, 0]" | "[2, 1]"'
    )
    run(one_call(settings(server, server_kind="openai"), replies=REPLIES))
    assert "grammar" not in server.requests[-1]  # auto = none elsewhere
    res = run(one_call(settings(server, constrain="none", server_kind="llamacpp"), replies=REPLIES))
    assert "grammar" not in server.requests[-1] and res.constraint == "none"


def test_json_schema_mode():
    with FakeServer(reply=lambda body: '{"action": "[1, 0]"}') as srv:
        res = run(one_call(settings(srv, constrain="json_schema"), replies=REPLIES))
        fmt = srv.requests[-1]["response_format"]
        assert fmt["type"] == "json_schema"
        assert fmt["json_schema"]["schema"]["properties"]["action"]["enum"] == REPLIES
        assert (
            res.text == "[1, 0]"
            and res.raw == '{"action": "[1, 0]"}'
            and res.constraint == "json_schema"
        )


def test_constraint_helpers():
    assert constrain.gbnf(['say "hi"']) == 'root ::= "say \\"hi\\""'
    assert constrain.resolve_mode("auto", "llamacpp") == "grammar"
    assert constrain.resolve_mode("auto", "generic") == "none"
    assert constrain.resolve_mode("grammar", "openai", has_replies=False) == "none"
    assert constrain.reply_text("json_schema", "not json") == "not json"
    with pytest.raises(ValueError):
        constrain.resolve_mode("magic", "generic")


def test_safe_url():
    assert safe_url("https://user:pw@example.com:8443/v1/?token=x") == "https://example.com:8443/v1"


def test_cancelled_owner_does_not_hang_sharers():
    with FakeServer(latency=0.5) as srv:

        async def scenario():
            async with LLMClient(settings(srv)) as c:
                owner = asyncio.ensure_future(c.chat(MSG))
                await asyncio.sleep(0.05)
                sharer = asyncio.ensure_future(c.chat(MSG))
                await asyncio.sleep(0.05)
                owner.cancel()
                return await asyncio.wait_for(
                    asyncio.gather(owner, sharer, return_exceptions=True), 2.0
                )

        owner, sharer = run(scenario())
        assert isinstance(owner, asyncio.CancelledError)
        assert isinstance(sharer, LLMServerError) and "cancelled" in str(sharer)


# -- transports ---------------------------------------------------------------------------------


def test_loopback_http_gets_the_asyncio_transport():
    from jswim.llm.transport import LoopbackTransport

    def transport(s):
        return LLMClient(s)._http_client()._transport

    assert isinstance(transport(settings("http://127.0.0.1:8080/v1")), LoopbackTransport)
    assert isinstance(transport(settings("http://localhost:8080/v1")), LoopbackTransport)
    assert not isinstance(
        transport(settings("http://127.0.0.1:8080/v1", fast_transport=False)), LoopbackTransport
    )
    assert not isinstance(transport(settings("https://api.openai.com/v1")), LoopbackTransport)
    assert not isinstance(transport(settings("http://10.1.2.3:8000/v1")), LoopbackTransport)


@pytest.mark.parametrize("fast", [True, False], ids=["asyncio", "httpx-default"])
def test_both_transports_recover_from_the_same_faults(server, fast):
    server.add_faults(
        Fault.server_error(500),
        Fault.drop(),
        Fault.malformed(),
        Fault.delay(3.0),
        Fault.rate_limit(),
    )
    res = run(one_call(settings(server, max_retries=5, timeout_s=0.5, fast_transport=fast)))
    assert res.text == "[2, 1]" and res.retries == 5 and server.n_answered == 1


@pytest.mark.parametrize("fast", [True, False], ids=["asyncio", "httpx-default"])
def test_both_transports_keep_the_connection_alive(server, fast):
    async def calls():
        async with LLMClient(settings(server, max_concurrency=1, fast_transport=fast)) as c:
            return [(await c.chat(MSG, use_cache=False)).text for _ in range(5)]

    assert run(calls()) == ["[2, 1]"] * 5
    assert server.n_requests == 5 and server.n_connections == 1


@pytest.mark.parametrize("fast", [True, False], ids=["asyncio", "httpx-default"])
def test_both_transports_report_a_dead_server(fast):
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    with pytest.raises(LLMServerError, match="connection failed"):
        run(one_call(settings(f"http://127.0.0.1:{port}/v1", max_retries=1, fast_transport=fast)))


def test_usage_totals_bill_only_what_reached_the_server():
    from jswim.llm.client import ChatResult

    def result(**kw):
        base = dict(
            text="[1, 1]",
            usage=Usage(100, 5),
            latency_s=0.0,
            cache_hit=False,
            shared=False,
            retries=0,
            cost_usd=0.25,
            constraint="none",
            finish_reason="stop",
            raw="[1, 1]",
        )
        return ChatResult(**{**base, **kw})

    t = UsageTotals()
    t.add(result())
    t.add(result(cache_hit=True))  # from the disk cache: counted, not billed
    t.add(result(shared=True, retries=2))  # waited on an identical request in flight: not billed
    assert (t.calls, t.billed_calls, t.cache_hits, t.shared, t.retries) == (3, 1, 1, 1, 2)
    assert (t.prompt_tokens, t.completion_tokens, t.cost_usd) == (100, 5, 0.25)


# -- redirects -----------------------------------------------------------------------------------


@pytest.mark.parametrize("status", [307, 308])
def test_a_same_host_redirect_is_followed_with_the_key_and_the_body(status, monkeypatch):
    monkeypatch.setenv("JSWIM_TEST_KEY", SECRET)
    with FakeServer(
        reply=lambda body: "[2, 1]",
        redirects={"/v1/chat/completions": (status, "/v2/chat/completions")},
    ) as srv:
        res = run(one_call(settings(srv, api_key_env="JSWIM_TEST_KEY")))
        assert res.text == "[2, 1]"
        assert srv.redirected == [f"Bearer {SECRET}"] and srv.auth_headers == [f"Bearer {SECRET}"]
        assert srv.requests[0]["messages"] == MSG  # the body went again, whole


def test_a_redirect_loop_stops_at_the_limit():
    from jswim.llm.client import MAX_REDIRECTS
    from jswim.errors import LLMSetupError

    with FakeServer(redirects={"/v1/chat/completions": (307, "/v1/chat/completions")}) as srv:
        with pytest.raises(LLMSetupError, match=f"more than {MAX_REDIRECTS} redirects"):
            run(one_call(settings(srv)))
        assert len(srv.redirected) == MAX_REDIRECTS + 1 and srv.n_requests == 0


def test_a_redirect_to_another_host_is_refused_and_the_key_never_goes_there(monkeypatch):
    from jswim.errors import LLMSetupError

    monkeypatch.setenv("JSWIM_TEST_KEY", SECRET)
    with FakeServer() as other:
        # Same machine, another port: another host as far as the key is concerned.
        with FakeServer(
            redirects={"/v1/chat/completions": (308, other.url + "/chat/completions")}
        ) as srv:
            with pytest.raises(LLMSetupError, match="another host") as err:
                run(one_call(settings(srv, api_key_env="JSWIM_TEST_KEY")))
        assert other.n_requests == 0 and other.auth_headers == []
    assert SECRET not in str(err.value)
