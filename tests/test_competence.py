"""Protocol variants (summary, shuffle, temperature, allowed set) and the competence study."""

from __future__ import annotations

import json
import math
import re
from collections import Counter

import jax
import numpy as np
import pytest

from jswim import cli, env, gait
from jswim.agents import random_policy
from jswim.agents.llm import VARIANTS, LLMAgentConfig, LLMRunSpec, run_batch, variant_config
from jswim.errors import ConfigError
from jswim.llm import ClientSettings
from jswim.prompt import (
    CACHE_LAYOUT,
    Action,
    HistoryRecord,
    MoveStats,
    PromptConfig,
    SwimmerText,
    render_prompt,
    render_summary,
    shape_key,
)
from jswim.results import read_metadata, read_runs
from jswim.studies import COMPETENCE_VARIANTS, Backend, StudyOptions, build, run_study, summarize
from tests.fakeserver import FakeServer, hash_reply

LO, HI = -math.pi / 3, math.pi / 3
PURCELL = SwimmerText(2, LO, HI, dof_decimals=3)


def settings(srv: FakeServer, **kw) -> ClientSettings:
    return ClientSettings(base_url=srv.url, model="fake", backoff_base_s=0.001, timeout_s=5.0, **kw)


def steps_of(result) -> list[dict]:
    return [t for t in result.transcript if t["type"] == "step"]


def s5_options(prompt: str) -> list[str]:
    line = next(ln for ln in prompt.splitlines() if "Reply with the next action" in ln)
    return re.findall(r"\[\d, -?\d\]", line.split("one of", 1)[1])


# -- prompt layer -------------------------------------------------------------------------------


def test_summary_sentence_reports_observed_means_without_negative_numbers():
    stats = MoveStats()
    here = shape_key(PURCELL, (HI, HI))
    stats.add(here, Action(1, -1), 0.0123)
    stats.add(here, Action(1, -1), 0.0097)  # mean 0.011 -> 11 thousandths
    stats.add(here, Action(2, -1), -0.0052)
    stats.add(shape_key(PURCELL, (LO, HI)), Action(2, -1), 0.5)  # another shape: not reported here
    options = [Action(2, -1), Action(1, -1), Action(1, 0)]
    stats.add(here, Action(1, 0), 0.0)
    text = render_summary(PURCELL, stats, (HI, HI), options, +1)
    assert text.startswith("Observed so far from the current shape (D1, D2) = (1.047, 1.047):")
    assert "[2, -1] moved X 5 away from +x on average in 1 try" in text
    assert "[1, -1] moved X 11 toward +x on average in 2 tries" in text
    assert "[1, 0] left X unchanged in 1 try" in text
    assert text.index("[2, -1]") < text.index("[1, -1]") < text.index("[1, 0]")  # the options' order
    assert "-5" not in text and "500" not in text
    # Progress is recorded in the target direction and named after it; untried pairs are said so.
    text = render_summary(PURCELL, stats, (HI, HI), [Action(1, -1), Action(1, 1)], -1)
    assert "[1, -1] moved X 11 toward -x" in text and "[1, 1] not tried yet" in text


def test_per_step_text_goes_last_and_the_paper_prompt_is_unchanged():
    rec = HistoryRecord(1, (HI, HI), (LO, HI), Action(1, -1), 0.0, 0.01)
    paper = render_prompt(PURCELL, PromptConfig(), 1, [rec], (LO, HI))
    assert PromptConfig().layout == CACHE_LAYOUT and paper.index("Reply with") < paper.index("1: (")
    for cfg in (PromptConfig(allowed="shape-changing"), PromptConfig(shuffle=True), PromptConfig(summary=True)):
        text = render_prompt(PURCELL, cfg, 1, [rec], (LO, HI), summary="Observed so far: x." if cfg.summary else "")
        lines = text.splitlines()
        assert lines[-1].startswith("Reply with the next action"), text  # S5 last: per-step text
        if cfg.summary:
            assert lines[-2] == "Observed so far: x." and lines[-3].startswith("1: (")
    # A hand-made layout is used as given; without a {summary} slot the sentence precedes S3.
    from jswim.prompt import PAPER_LAYOUT, PromptTemplate

    cfg = PromptConfig(summary=True, template=PromptTemplate(layout=PAPER_LAYOUT))
    text = render_prompt(PURCELL, cfg, 1, [rec], (LO, HI), summary="Observed so far: x.")
    assert text.index("Observed so far") < text.index("Latest records") < text.index("Reply with")


# -- the agent against the fake server ----------------------------------------------------------


def test_summary_variant_shows_the_run_s_own_observed_means():
    with FakeServer(reply=hash_reply) as srv:
        (res,) = run_batch([LLMRunSpec(n_steps=12, zeta=0.5, seed=3)], settings(srv), variant_config("summary"))
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
                    assert f"[{a[0]}, {a[1]}] moved X {amount} {way} +x on average in {len(seen)}" in line
                else:
                    assert f"[{a[0]}, {a[1]}] left X unchanged in {len(seen)}" in line
        stats.setdefault((here, tuple(st["action"])), []).append(st["progress"])  # noisy, as observed
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
        tuple(tuple(int(v) for v in re.findall(r"-?\d", o)) for o in order) for order in orders]
    assert orders == [tuple(s5_options(st["prompt"])) for st in steps_of(b)]  # seeded by run and step
    assert all(tuple(s5_options(st["prompt"])) == canonical for st in steps_of(plain))
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
    assert all(len(set(s)) == 5 for s in seeds) and not set(seeds[0]) & set(seeds[1])  # per step, per run
    assert sorted(b["seed"] for b in bodies) == sorted(seeds[0] + seeds[1])
    assert sorted(b["seed"] for b in bodies_again) == sorted(b["seed"] for b in bodies)  # reproducible
    assert {r.as_row()["temperature"] for r in first} == {0.7}
    # At temperature 0 no seed is sent and identical requests are shared.
    with FakeServer(reply=lambda body: "[1, 1]") as srv:
        zero = run_batch(specs, settings(srv), variant_config("paper"))
        assert all("seed" not in b for b in srv.requests) and srv.n_requests == 5
    assert sum(r.usage.shared for r in zero) == 5


def test_variant_is_recorded_in_rows_and_transcripts():
    with FakeServer(reply=hash_reply) as srv:
        (res,) = run_batch([LLMRunSpec(n_steps=3)], settings(srv), variant_config("shape-changing+summary"))
    row = res.as_row()
    assert (row["variant"], row["allowed"], row["summary"], row["shuffle"], row["temperature"]) == (
        "shape-changing+summary", "shape-changing", True, False, 0.0)
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


# -- study grid and baselines ------------------------------------------------------------------


def test_competence_grid():
    plans = build("competence", StudyOptions())
    llm = [p for p in plans if p.agent == "llm"]
    counts = Counter((p.swimmer, p.variant) for p in llm)
    assert counts == {(sw, v): 10 for sw in ("purcell", "ng") for v in COMPETENCE_VARIANTS}
    assert all(p.steps == 50 and p.direction == 1 and p.group == p.variant for p in llm)
    assert all(p.allowed == VARIANTS[p.variant].get("allowed", "all") for p in llm)
    # Starts go through the four corners.
    inits = [p.init for p in llm if p.swimmer == "ng" and p.variant == "paper"]
    assert inits[:4] == list(env.all_inits(2)) and inits[4] == inits[0]
    base = Counter((p.agent, p.swimmer, p.allowed, p.group) for p in plans if p.agent != "llm")
    assert base == {(a, sw, s, s): 100 for a in ("random", "qlearning") for sw in ("purcell", "ng")
                    for s in ("all", "shape-changing")}
    assert len({p.seed for p in plans}) == len(plans) and len({p.run_id for p in plans}) == len(plans)
    picked = build("competence", StudyOptions(variants=("shuffle",), runs=3, q_runs=0))
    assert [p.variant for p in picked] == ["shuffle"] * 6
    # Elsewhere a variant applies to every LLM run, and its allowed set to the baselines.
    swim = build("swim", StudyOptions(variant="shape-changing+shuffle", q_runs=2))
    assert {(p.agent, p.allowed, p.variant) for p in swim} == {
        ("llm", "shape-changing", "shape-changing+shuffle"), ("qlearning", "shape-changing", ""),
        ("random", "shape-changing", "")}
    assert {p.variant for p in build("ablation", StudyOptions(runs=1))} == {"paper"}
    assert StudyOptions().llm_variant("ablation") == "paper"


def test_random_baseline_honours_the_allowed_set():
    params = env.make_params("purcell", init=(1, 1))
    keys = jax.random.split(jax.random.PRNGKey(0), 64)
    model = params.model
    for allowed in ("shape-changing", "all"):
        run = random_policy.run_batch(keys, params, 40, allowed)
        acts = np.asarray(run.actions)
        rp = gait.replay(acts.T, model, np.asarray(run.levels0))
        rocs = np.vectorize(lambda a: env.decode_action(int(a))[1])(acts)
        if allowed == "shape-changing":
            assert rp.moved.all() and (rocs != 0).all()  # only moves that change the shape
        else:
            assert not rp.moved.all() and (rocs == 0).any()  # the full set includes no-ops
        # Uniform over what is offered: both DOFs are moved often.
        dofs = np.vectorize(lambda a: env.decode_action(int(a))[0])(acts)
        assert 0.35 < (dofs == 1).mean() < 0.65


def test_competence_study_end_to_end(tmp_path, capsys):
    out = tmp_path / "competence"
    with FakeServer(reply=hash_reply, latency=0.002) as srv:
        rc = cli.main(["study", "competence", "--swimmer", "purcell", "--runs", "2", "--q-runs", "4",
                       "--steps", "8", "--variant", "paper,shape-changing+shuffle", "--out", str(out),
                       "--base-url", srv.url, "--model", "fake", "--api-key-env", "JSWIM_TEST_NO_KEY"])
    assert rc == 0
    rows = read_runs(out)
    assert Counter((r["agent"], r["group"]) for r in rows) == {
        ("llm", "paper"): 2, ("llm", "shape-changing+shuffle"): 2, ("random", "all"): 4,
        ("random", "shape-changing"): 4, ("qlearning", "all"): 4, ("qlearning", "shape-changing"): 4}
    llm = [r for r in rows if r["agent"] == "llm"]
    assert {(r["variant"], r["allowed"], r["shuffle"]) for r in llm} == {
        ("paper", "all", False), ("shape-changing+shuffle", "shape-changing", True)}
    meta = read_metadata(out)
    assert meta["identity"]["variants"]["shape-changing+shuffle"] == {"allowed": "shape-changing", "shuffle": True}
    assert meta["llm_variants"] == ["paper", "shape-changing+shuffle"]
    summary = {(s["agent"], s["group"]): s for s in summarize(rows)}
    s = summary[("llm", "shape-changing+shuffle")]
    mine = [r for r in llm if r["group"] == "shape-changing+shuffle"]
    assert s["n"] == 2 and s["distinct"] == 2 and s["tokens_per_step"] > 0
    assert s["failed_steps"] == sum(r["failed_steps"] for r in mine)  # the fake picks outside the set
    assert (out / "figures" / "competence.png").is_file()
    # The random baseline on the shape-changing set never wastes a step.
    for r in rows:
        if r["agent"] == "random" and r["allowed"] == "shape-changing":
            assert all(roc != 0 for _, roc in r["actions"])
    spec = json.loads((out / "metadata.json").read_text())
    assert spec["status"] == "complete"


def test_study_reports_llm_calls_per_second(tmp_path):
    with FakeServer(reply=hash_reply) as srv:
        res = run_study("competence", StudyOptions(swimmers=("ng",), runs=1, q_runs=0, steps=4,
                                                    variants=("paper",)),
                        Backend(base_url=srv.url, model="fake", api_key_env="JSWIM_TEST_NO_KEY"),
                        tmp_path / "c", figures=False)
    sp = res.llm_speed
    assert sp["calls"] == 4 and sp["billed_calls"] == 4 and sp["calls_per_s"] > 0


def test_swim_takes_a_variant_and_records_it(tmp_path):
    out = tmp_path / "swim"
    with FakeServer(reply=hash_reply) as srv:
        rc = cli.main(["swim", "--variant", "shuffle", "--runs", "1", "--q-runs", "2", "--steps", "4",
                       "--no-figures", "--out", str(out), "--base-url", srv.url, "--model", "fake",
                       "--api-key-env", "JSWIM_TEST_NO_KEY"])
        assert rc == 0
        assert cli.main(["swim", "--variant", "a,b", "--out", str(tmp_path / "x"), "--base-url", srv.url,
                         "--model", "fake"]) == 2
    (llm,) = [r for r in read_runs(out) if r["agent"] == "llm"]
    assert (llm["variant"], llm["shuffle"]) == ("shuffle", True)
    meta = read_metadata(out)
    assert meta["llm_variants"] == ["shuffle"] and meta["identity"]["options"]["variant"] == "shuffle"
