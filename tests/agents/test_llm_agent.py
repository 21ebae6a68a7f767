"""The LLM agent driving batches of swimmers against the fake server."""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from jswim.agents.llm import run_batch
from jswim.agents.variants import NO_OP, VARIANTS, LLMAgentConfig, LLMRunSpec, variant_config
from jswim.env import encode_action
from jswim.errors import ConfigError
from jswim.studies import COMPETENCE_VARIANTS, StudyOptions
from jswim.llm import ClientSettings
from jswim.errors import LLMServerError
from tests.fakeserver import Fault, FakeServer, hash_reply


def settings(srv: FakeServer, **kw) -> ClientSettings:
    # A generous timeout: on a loaded machine a jit compile can hold the event loop for seconds,
    # and a timed-out request is retried, which would change the retry counts these tests assert.
    return ClientSettings(
        base_url=srv.url,
        model="fake",
        backoff_base_s=0.001,
        backoff_max_s=0.01,
        timeout_s=120.0,
        **kw,
    )


HI = math.pi / 3


def steps_of(result) -> list[dict]:
    return [t for t in result.transcript if t["type"] == "step"]


def s5_options(prompt: str) -> list[str]:
    line = next(ln for ln in prompt.splitlines() if "Reply with the next action" in ln)
    return re.findall(r"\[\d, -?\d\]", line.split("one of", 1)[1])


def scripted(body):
    """Purcell +x: always [1, -1]. Purcell -x: junk, then [2, 1] when corrected. NG: never valid."""
    msgs = [m for m in body["messages"] if m["role"] != "system"]
    prompt = msgs[0]["content"]
    if "[6, 10]" in prompt:
        return "I would rather not say."
    if "negative x direction" in prompt:
        return "[2, 1]" if len(msgs) > 1 else "Let me think about the physics first."
    return "[1, -1]"


def test_batch_counts_retries_failures_and_clears(tmp_path):
    specs = [
        LLMRunSpec("purcell", direction=1, n_steps=6, n_ht=2),
        LLMRunSpec("purcell", direction=-1, n_steps=6, n_ht=2),
        LLMRunSpec("ng", n_steps=6),
    ]
    with FakeServer(
        reply=scripted, latency=0.02, faults=[Fault.server_error(500), Fault.rate_limit("0")]
    ) as srv:
        results = run_batch(
            specs, settings(srv), LLMAgentConfig(parse_retries=2), transcript_dir=tmp_path
        )
        n_requests, max_in_flight = srv.n_requests, srv.max_in_flight
    a, b, ng = results
    assert [r.status for r in results] == ["done"] * 3 and all(r.steps == 6 for r in results)
    # Run a: valid at once; the first move changes the shape, then [1, -1] pushes past the limit.
    assert (a.failed_steps, a.parse_retries, a.usage.calls) == (0, 0, 6)
    assert a.actions == [encode_action(1, -1)] * 6 and a.stuck == [False] + [True] * 5
    # Run b: every step needs one corrective retry.
    assert (b.failed_steps, b.parse_retries, b.usage.calls) == (0, 6, 12)
    # NG: never a valid action -> three calls per step, then the no-op.
    assert (ng.failed_steps, ng.parse_retries, ng.usage.calls) == (6, 12, 18)
    assert ng.actions == [encode_action(*NO_OP)] * 6 and ng.x == [0.0] * 6
    # The two injected faults were retried, each once.
    assert sum(r.usage.retries for r in results) == 2
    assert n_requests == 6 + 12 + 18 + 2
    # Never more than one request per run in flight (whether they overlap is a matter of timing;
    # test_pipelines checks that no run waits for another with a server that holds replies).
    assert 1 <= max_in_flight <= 3
    # No progress from step 2 -> the history is cleared at step 6 in every run (fidelity.md: from
    # step 6 with >= 6 records, the last 4 displacements below 0.01).
    assert [r.n_clears for r in results] == [1, 1, 1]

    lines = [json.loads(s) for s in (tmp_path / f"{b.run_id}.jsonl").read_text().splitlines()]
    assert [ln["type"] for ln in lines] == ["meta"] + ["step"] * 6 + ["end"]
    meta, first, end = lines[0], lines[1], lines[-1]
    assert (
        meta["n_ht"] == 2 and meta["client"]["model"] == "fake" and "negative x" in first["prompt"]
    )
    assert [att["parsed"] for att in first["attempts"]] == [None, [2, 1]]
    assert first["attempts"][0]["text"].startswith("Let me think")
    assert {"prompt_tokens", "latency_s", "cache_hit", "retries"} <= set(first["attempts"][0])
    assert [ln["cleared"] for ln in lines[1:-1]] == [False] * 5 + [True]
    assert end["status"] == "done" and end["parse_retries"] == 6
    shown = [ln.split(":")[0] for ln in lines[6]["prompt"].splitlines() if ln[:1].isdigit()]
    assert shown == ["4", "5"]  # n_ht = 2 before the clear

    row = a.as_row()
    assert (
        row["run_id"] == a.run_id
        and row["steps"] == 6
        and len(row["x"]) == 6
        and row["init"] == "11"
    )


def test_in_memory_transcript_and_history_window():
    with FakeServer(reply=hash_reply) as srv:
        (res,) = run_batch([LLMRunSpec(n_steps=5, n_ht=2, zeta=0.3, seed=7)], settings(srv))
    steps = [t for t in res.transcript if t["type"] == "step"]
    assert len(steps) == 5
    # The prompt of step 4 shows records 2 and 3 (n_ht = 2), unless a clear intervened.
    shown = [ln.split(":")[0] for ln in steps[3]["prompt"].splitlines() if ln[:1].isdigit()]
    assert shown == ["2", "3"]
    assert steps[3]["x_before"] == pytest.approx(steps[2]["x_after"])


def test_runs_are_reproducible_and_independent_of_the_batch():
    one = LLMRunSpec(n_steps=8, zeta=1.0, seed=3)
    with FakeServer(reply=hash_reply) as srv:
        (alone,) = run_batch([one], settings(srv))
        batch = run_batch(
            [LLMRunSpec(n_steps=8, zeta=1.0, seed=s) for s in (1, 2, 3)], settings(srv)
        )
    assert np.allclose(alone.x, batch[2].x) and alone.actions == batch[2].actions
    assert not np.allclose(batch[0].x, batch[1].x)


def test_results_do_not_depend_on_concurrency_or_the_deprecated_cohorts():
    # Each run is its own pipeline: one request at a time or six, the same actions and positions.
    # ``cohorts=`` (lockstep groups, gone) is still accepted and must change nothing.
    specs = [LLMRunSpec(n_steps=6, zeta=0.5, seed=s) for s in range(5)] + [
        LLMRunSpec("ng", n_steps=4)
    ]
    with FakeServer(reply=hash_reply, latency=0.01) as srv:
        serial = run_batch(specs, settings(srv, max_concurrency=1))
        serial_peak = srv.max_in_flight
        srv.reset_counts()
        wide = run_batch(specs, settings(srv, max_concurrency=6), cohorts=3)
    assert serial_peak == 1  # the client kept to one request in flight
    assert [r.run_id for r in serial] == [r.run_id for r in wide]
    for a, b in zip(serial, wide):
        assert a.actions == b.actions and np.allclose(a.x, b.x) and a.status == b.status == "done"
    assert (
        len({tuple(r.actions) for r in serial}) > 1
    )  # the runs differ, so the match is not trivial


@pytest.mark.parametrize("direction", [1, -1])
def test_progress_is_each_step_s_displacement_toward_the_target(direction):
    # progress (the clearing rule's input and the summary's numbers) must be direction * dX, as
    # read off the positions before and after each step (noise on, both swimmers, both targets).
    specs = [
        LLMRunSpec(sw, direction=direction, zeta=0.5, seed=s, n_steps=6)
        for sw in ("purcell", "ng")
        for s in (1, 2)
    ]
    with FakeServer(reply=hash_reply) as srv:
        results = run_batch(specs, settings(srv))
    moved = 0
    for res in results:
        for st in steps_of(res):
            dx = st["x_after"] - st["x_before"]
            assert st["progress"] == pytest.approx(direction * dx, abs=1e-9)
            moved += abs(dx) > 1e-6
        np.testing.assert_allclose(res.progress, direction * np.diff([0.0, *res.x]), atol=1e-9)
    assert moved > 6  # most steps moved the body, so the sign is really tested


def test_position_below_x_min_never_ends_the_run():
    # fidelity.md: a value below X_min is sent as a negative number; runs are never stopped for it.
    with FakeServer(reply=lambda body: "[1, -1]") as srv:  # from (+, +) this moves toward -x
        with pytest.warns(UserWarning, match="x_min"):
            (res,) = run_batch([LLMRunSpec(n_steps=5)], settings(srv), LLMAgentConfig(x_min=-0.001))
        second = srv.requests[1]["messages"][-1]["content"]
    assert res.status == "done" and res.steps == 5 and res.below_x_min == 1
    assert res.x[0] < -0.001 and res.as_row()["below_x_min"] == 1
    assert re.search(r"X 1 -> -\d+, stuck no", second)  # (X - X_min) * 1000 < 0, sent as it is


@pytest.mark.parametrize("concurrency", [1, 2])
def test_server_down_raises_and_closes_transcripts(tmp_path, concurrency):
    with FakeServer(faults=[None] * 2 + [Fault.server_error(503)] * 50) as srv:
        with pytest.raises(LLMServerError, match="503"):
            run_batch(
                [LLMRunSpec(n_steps=5, seed=s) for s in (0, 1)],
                settings(srv, max_retries=2, max_concurrency=concurrency),
                LLMAgentConfig(share_identical=False),
                transcript_dir=tmp_path,
            )
    for f in tmp_path.iterdir():
        lines = [json.loads(s) for s in f.read_text().splitlines()]
        assert (
            lines[-1]["type"] == "end"
            and lines[-1]["status"] == "aborted"
            and lines[-1]["steps"] == 1
        )


def test_shape_changing_set_reaches_the_grammar():
    with FakeServer(reply=lambda body: "[1, -1]") as srv:
        run_batch(
            [LLMRunSpec(n_steps=2)],
            settings(srv, server_kind="llamacpp"),
            LLMAgentConfig(action_set="shape-changing"),
        )
        grammars = [r["grammar"] for r in srv.requests]
    assert grammars[0] == 'root ::= "[1, -1]" | "[2, -1]"'  # from (+, +)
    assert grammars[1] == 'root ::= "[1, 1]" | "[2, -1]"'  # after D1 went to lo


def test_runs_are_independent_unless_sharing_is_asked_for(tmp_path):
    specs = [LLMRunSpec(n_steps=3, run_id=f"r{k}") for k in range(4)]  # same task, no noise
    # Default (the paper's independent repeats): every run makes its own calls.
    with FakeServer(reply=hash_reply, latency=0.05) as srv:
        results = run_batch(specs, settings(srv, cache_dir=str(tmp_path)))
        assert srv.n_requests == 12
        assert sum(r.usage.shared + r.usage.cache_hits for r in results) == 0
        # A rerun (resume) is answered from each run's own cached calls ...
        srv.reset_counts()
        again = run_batch(specs, settings(srv, cache_dir=str(tmp_path)))
        assert srv.n_requests == 0 and sum(r.usage.cache_hits for r in again) == 12
        # ... but a new run is never answered with another run's reply.
        run_batch([LLMRunSpec(n_steps=3, run_id="r9")], settings(srv, cache_dir=str(tmp_path)))
        assert srv.n_requests == 3
    assert all(r.as_row()["share_identical"] is False for r in results)
    # Sharing on (a cost saving): one request per round, the four runs are copies. This rests on
    # the event loop's order, not on timing: the four identical requests are made in the same loop
    # turn, before any reply can be read, so it holds with a server that answers at once.
    with FakeServer(reply=hash_reply, latency=0.0) as srv:
        shared = run_batch(specs, settings(srv), LLMAgentConfig(share_identical=True))
        assert srv.n_requests == 3
    assert all(r.x == shared[0].x for r in shared)
    assert (
        sum(r.usage.shared for r in shared) == 9 and shared[0].as_row()["share_identical"] is True
    )


def test_duplicate_run_ids_are_rejected():
    from jswim.errors import ConfigError

    with pytest.raises(ConfigError, match="duplicate"):
        run_batch([LLMRunSpec(), LLMRunSpec()], ClientSettings(base_url="http://127.0.0.1:9/v1"))


def test_blocking_call_works_inside_a_running_event_loop():
    # Jupyter runs an event loop in the main thread; run_batch must not fail there.
    import asyncio

    spec = LLMRunSpec(n_steps=4, seed=5)
    with FakeServer(reply=hash_reply) as srv:
        (outside,) = run_batch([spec], settings(srv))

        async def inside():
            return run_batch([spec], settings(srv))

        (within,) = asyncio.run(inside())
    assert within.actions == outside.actions and np.allclose(within.x, outside.x)


# -- protocol variants ---------------------------------------------------------------------------


def test_summary_variant_shows_the_run_s_own_observed_means():
    with FakeServer(reply=hash_reply) as srv:
        (res,) = run_batch(
            [LLMRunSpec(n_steps=12, zeta=0.5, seed=3)], settings(srv), variant_config("summary")
        )
    steps = steps_of(res)
    stats: dict[tuple, list[float]] = {}
    for k, st in enumerate(steps):
        dofs = (HI, HI) if k == 0 else tuple(steps[k - 1]["dofs_after"])
        here = tuple(f"{v:.3f}" for v in dofs)
        line = next(ln for ln in st["prompt"].splitlines() if ln.startswith("Observed so far"))
        for a in st["options"]:
            seen = stats.get((here, tuple(a)))
            if seen is None:
                assert f"[{a[0]}, {a[1]}] not tried yet" in line
            else:
                mean = sum(seen) / len(seen)
                amount = round(abs(mean) * 1000)
                if amount:
                    way = "toward" if mean > 0 else "away from"
                    assert (
                        f"[{a[0]}, {a[1]}] moved X {amount} {way} +x on average in {len(seen)}"
                        in line
                    )
                else:
                    assert f"[{a[0]}, {a[1]}] left X unchanged in {len(seen)}" in line
        # What the step moved toward +x, from the positions (not the progress the driver computed).
        stats.setdefault((here, tuple(st["action"])), []).append(st["x_after"] - st["x_before"])
    assert any(len(v) > 1 for v in stats.values())  # the test saw repeated pairs


def test_shuffle_changes_the_order_not_the_set_and_replays():
    spec = LLMRunSpec(n_steps=10, seed=11)
    cfg = variant_config("shuffle")
    with FakeServer(reply=hash_reply) as srv:
        (a,) = run_batch([spec], settings(srv), cfg)
        (b,) = run_batch([spec], settings(srv), cfg)
        bodies = list(srv.requests)
        (plain,) = run_batch([spec], settings(srv), LLMAgentConfig())
    orders = [tuple(s5_options(st["prompt"])) for st in steps_of(a)]
    canonical = ("[1, -1]", "[1, 0]", "[1, 1]", "[2, -1]", "[2, 0]", "[2, 1]")
    assert all(sorted(o) == sorted(canonical) for o in orders)
    assert len(set(orders)) > 3 and orders != [canonical] * len(orders)
    assert [tuple(map(tuple, st["options"])) for st in steps_of(a)] == [
        tuple(tuple(int(v) for v in re.findall(r"-?\d", o)) for o in order) for order in orders
    ]
    assert orders == [
        tuple(s5_options(st["prompt"])) for st in steps_of(b)
    ]  # seeded by run and step
    assert all(
        "the changed DOF 1 or 2 and the ROC -1, 0 or 1." in st["prompt"] for st in steps_of(plain)
    )
    # The grammar is not shuffled: only the text is.
    grammars = {body.get("grammar") for body in bodies}
    assert len(grammars) == 1


def test_temperature_requests_carry_per_run_seeds_and_are_never_cached(tmp_path):
    specs = [LLMRunSpec(n_steps=5, seed=1), LLMRunSpec(n_steps=5, seed=2)]
    cfg = variant_config("temperature")
    with FakeServer(reply=lambda body: "[1, 1]") as srv:
        first = run_batch(specs, settings(srv, cache_dir=str(tmp_path)), cfg)
        bodies = list(srv.requests)
        srv.reset_counts()
        again = run_batch(specs, settings(srv, cache_dir=str(tmp_path)), cfg)
        assert srv.n_requests == 10  # everything asked again: nothing came from the cache
        bodies_again = list(srv.requests)
    assert all(body["temperature"] == 0.7 for body in bodies)
    assert sum(r.usage.cache_hits + r.usage.shared for r in first + again) == 0
    seeds = [[at["seed"] for st in steps_of(r) for at in st["attempts"]] for r in first]
    assert all(len(set(s)) == 5 for s in seeds) and not set(seeds[0]) & set(
        seeds[1]
    )  # per step, per run
    assert sorted(b["seed"] for b in bodies) == sorted(seeds[0] + seeds[1])
    assert sorted(b["seed"] for b in bodies_again) == sorted(
        b["seed"] for b in bodies
    )  # reproducible
    assert {r.as_row()["temperature"] for r in first} == {0.7}
    # At temperature 0 no seed is sent, and identical requests of the two runs are still sent apart.
    with FakeServer(reply=lambda body: "[1, 1]") as srv:
        zero = run_batch(specs, settings(srv), variant_config("paper"))
        assert all("seed" not in b for b in srv.requests) and srv.n_requests == 10
    assert sum(r.usage.shared for r in zero) == 0


def test_variant_is_recorded_in_rows_and_transcripts():
    with FakeServer(reply=hash_reply) as srv:
        (res,) = run_batch(
            [LLMRunSpec(n_steps=3)], settings(srv), variant_config("shape-changing+summary")
        )
    row = res.as_row()
    assert (
        row["variant"],
        row["action_set"],
        row["summary"],
        row["shuffle"],
        row["temperature"],
    ) == ("shape-changing+summary", "shape-changing", True, False, 0.0)
    assert row["tokens_seen"] > 0
    meta = res.transcript[0]
    assert meta["agent"]["variant"] == "shape-changing+summary" and meta["agent"]["summary"] is True
    # Two options per step for a two-DOF swimmer: never fewer, so the model always chooses.
    assert all(len(st["options"]) == 2 for st in steps_of(res))


def test_variant_registry_is_checked():
    with pytest.raises(ConfigError, match="unknown variant"):
        variant_config("oracle")
    with pytest.raises(ConfigError, match="unknown variant"):
        StudyOptions(variant="oracle")
    with pytest.raises(ConfigError, match="temperature"):
        LLMAgentConfig(temperature=3.0)
    assert set(COMPETENCE_VARIANTS) <= set(VARIANTS) and VARIANTS["paper"] == {}
