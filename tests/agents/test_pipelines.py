"""Per-run pipelines: no run waits for another run's reply; the call journal replays paid calls."""

from __future__ import annotations

import asyncio

import numpy as np

from jswim.agents.llm import LLMAgentConfig, LLMDriver, LLMRunSpec, run_batch
from jswim.llm import ClientSettings, LLMClient
from jswim.llm.journal import CallJournal
from tests.fakeserver import FakeServer, hash_reply

INDEPENDENT = LLMAgentConfig(share_identical=False)


def _settings(srv: FakeServer, **kw) -> ClientSettings:
    return ClientSettings(base_url=srv.url, model="fake", **kw)


def test_a_slow_run_holds_no_other_run_back():
    # The server answers run "+x" only once run "-x" has sent all four of its calls. As per-run
    # pipelines, "-x" finishes first and "+x" then goes on; in lockstep rounds "-x" would wait for
    # "+x"'s first reply and the server would give up holding it (hold_s) with "-x" at one call.
    def fast_calls(srv):
        return sum("negative x" in b["messages"][-1]["content"] for b in list(srv.requests))

    specs = [
        LLMRunSpec(direction=1, seed=1, n_steps=4),
        LLMRunSpec(direction=-1, seed=2, n_steps=4),
    ]
    srv = FakeServer(
        reply=hash_reply,
        hold_s=20.0,
        hold=lambda body: "positive x" in body["messages"][-1]["content"] and fast_calls(srv) < 4,
    )
    with srv:
        done = []

        async def go():
            async with LLMClient(_settings(srv)) as c:
                return await LLMDriver(
                    specs, c, INDEPENDENT, on_done=lambda r: done.append(r.spec.direction)
                ).run()

        results = asyncio.run(go())
        order = [
            "+x" if "positive x" in b["messages"][-1]["content"] else "-x" for b in srv.requests
        ]
    assert [r.steps for r in results] == [4, 4]
    assert done == [-1, 1]
    # "+x" sent its first call, then nothing until "-x" had sent all of its four.
    assert order.index("+x", order.index("+x") + 1) > max(
        i for i, o in enumerate(order) if o == "-x"
    )


def test_results_do_not_depend_on_which_runs_step_together():
    specs = [
        LLMRunSpec(swimmer=sw, zeta=1.0, seed=s, n_steps=6, init="random")
        for sw in ("purcell", "ng")
        for s in (3, 4, 5)
    ]
    with FakeServer(reply=hash_reply) as srv:
        together = run_batch(specs, _settings(srv), INDEPENDENT)
        alone = [run_batch([s], _settings(srv), INDEPENDENT)[0] for s in specs]
    for a, b in zip(together, alone):
        assert a.levels0 == b.levels0
        np.testing.assert_array_equal(a.x, b.x)
        assert a.actions == b.actions
        # Each step's progress is its displacement toward the target (the positions say so).
        np.testing.assert_allclose(a.progress, a.spec.direction * np.diff([0.0, *a.x]), atol=1e-9)
    assert any(abs(p) > 1e-3 for r in together for p in r.progress)


def test_window_bounds_runs_in_progress():
    specs = [LLMRunSpec(seed=s, zeta=0.5, n_steps=3) for s in range(6)]
    with FakeServer(reply=hash_reply, latency=0.01) as srv:

        async def go():
            async with LLMClient(_settings(srv, max_concurrency=16)) as c:
                return await LLMDriver(specs, c, INDEPENDENT, window=2).run()

        results = asyncio.run(go())
        most = srv.max_in_flight
    assert all(r.status == "done" and r.steps == 3 for r in results)
    assert most <= 2


def test_journal_replays_a_runs_own_paid_calls(tmp_path):
    specs = [LLMRunSpec(seed=s, zeta=0.5, n_steps=5) for s in range(3)]

    async def go(srv, journal):
        async with LLMClient(_settings(srv)) as c:
            return await LLMDriver(specs, c, INDEPENDENT, journal=journal).run()

    with FakeServer(reply=hash_reply) as srv:
        j = CallJournal(tmp_path)
        first = asyncio.run(go(srv, j))
        j.close()
        paid = srv.n_requests
        j2 = CallJournal(tmp_path)
        assert j2.n_calls == paid == 15
        again = asyncio.run(go(srv, j2))
        j2.close()
        assert srv.n_requests == paid  # nothing sent twice
    for a, b in zip(first, again):
        assert a.x == b.x and a.actions == b.actions
        assert b.replayed_calls == 5 and b.usage.calls == 5
        assert b.usage.prompt_tokens == a.usage.prompt_tokens  # the run's totals keep what it paid


def test_journal_stops_replaying_where_a_run_diverges(tmp_path):
    spec = LLMRunSpec(seed=1, zeta=0.5, n_steps=4)

    async def go(srv, journal, steps):
        async with LLMClient(_settings(srv)) as c:
            s = LLMRunSpec(seed=1, zeta=0.5, n_steps=steps)
            return await LLMDriver([s], c, INDEPENDENT, journal=journal).run()

    with FakeServer(reply=hash_reply) as srv:
        j = CallJournal(tmp_path)
        asyncio.run(go(srv, j, 2))  # an interrupted run: 2 of its calls were paid
        j.close()
        srv.reset_counts()
        j = CallJournal(tmp_path)
        res = asyncio.run(go(srv, j, spec.n_steps))[0]
        j.close()
        assert res.replayed_calls == 2 and srv.n_requests == 2
    # A different run never gets these answers.
    with FakeServer(reply=hash_reply) as srv:
        j = CallJournal(tmp_path)

        async def other():
            async with LLMClient(_settings(srv)) as c:
                return await LLMDriver(
                    [LLMRunSpec(seed=2, zeta=0.5, n_steps=2)], c, INDEPENDENT, journal=j
                ).run()

        r = asyncio.run(other())[0]
        j.close()
        assert r.replayed_calls == 0 and srv.n_requests == 2
