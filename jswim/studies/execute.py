"""Executing a study's LLM plans as per-run pipelines ([`LLMDriver`][jswim.agents.llm.LLMDriver]),
each stored the moment it ends (the other agents: [`baselines`][jswim.studies.baselines]).

Every answered call is journaled first (``calls.jsonl``, `jswim.llm.journal.CallJournal`),
so an interrupted or capped study resumes without paying for a call twice.
"""

from __future__ import annotations

import asyncio
import dataclasses
import time
from typing import Any
from collections.abc import Callable, Iterable, Sequence


from jswim.agents.llm import RunResult, run_batch_async
from jswim.agents.variants import LLMRunSpec, variant_config
from jswim.console import eta
from jswim.llm.backend import Backend
from jswim.llm.budget import Budget
from jswim.llm.client import ClientSettings, LLMClient
from jswim.llm.journal import CallJournal
from jswim.llm.ledger import RequestLedger
from jswim.llm.pacing import Pacer
from jswim.llm.probe import ServerInfo
from jswim.llm.sync import run_sync
from jswim.prompt import PromptTemplate
from jswim.results import StudyStore
from jswim.studies.plans import Plan
from jswim.studies.options import StudyOptions
from jswim.studies.session import preflight, record_session, add_session


#: Statuses of an LLM run that are stored; one stopped by the cost cap or an interrupt is not, and
#: starts again on resume (its paid calls replayed from the journal).
STORED = ("done", "below_x_min", "llm_error")


#: ``progress(phase, done, total, info)``: runs done of the study's runs, except in the phases
#: ``"llm"`` and ``"llm-live"``, where the work counted is LLM steps (runs are in ``info``);
#: ``info`` is a short status text.
ProgressFn = Callable[[str, int, int, str], None]


def group_plans(plans: Iterable[Plan], *keys: str) -> dict[tuple, list[Plan]]:
    """``plans`` grouped by the values of their fields ``keys``, in first-seen order."""
    out: dict[tuple, list[Plan]] = {}
    for p in plans:
        out.setdefault(tuple(getattr(p, k) for k in keys), []).append(p)
    return out


def run_spec(p: Plan) -> LLMRunSpec:
    """The LLM run a plan asks for (its swimmer, start, noise, seed, steps, memory, scene)."""
    return LLMRunSpec(
        swimmer=p.swimmer,
        direction=p.direction,
        init=p.init,
        zeta=p.zeta,
        seed=p.seed,
        n_steps=p.steps,
        n_ht=p.n_ht,
        drop=p.drop,
        run_id=p.run_id,
        roc_levels=p.roc_levels,
        scene=p.scene,
        pair_prompt=p.pair_prompt,
        target=p.target,
    )


def llm_configs(
    plans: Sequence[Plan], o: StudyOptions, template: PromptTemplate | None
) -> list[tuple[Any, list[Plan]]]:
    """The LLM plans by agent config: one driver per (variant, action set)."""
    out = []
    for (variant, action_set, temp, prompt), group in group_plans(
        plans, "variant", "action_set", "temperature", "prompt_file"
    ).items():
        tpl = PromptTemplate.from_file(prompt) if prompt else template
        cfg = variant_config(
            variant,
            action_set=action_set,
            share_identical=o.share_identical,
            x_min=o.x_min,
            max_tokens=o.max_tokens,
            **({"template": tpl} if tpl else {}),
        )
        if temp is not None:  # a sweep's temperature (each request above 0 carries its own seed)
            cfg = dataclasses.replace(cfg, temperature=temp)
        out.append((cfg, group))
    return out


def run_llm(
    plans: Sequence[Plan],
    o: StudyOptions,
    backend: Backend,
    store: StudyStore,
    template: PromptTemplate | None,
    tick: ProgressFn,
    finished: int,
    total: int,
    speed: dict[str, float],
    max_cost: float | None,
    sent: dict[str, Any] | None = None,
    info: ServerInfo | None = None,
    notes: list[str] | None = None,
) -> tuple[int, bool]:
    """Run the LLM plans as per-run pipelines; returns (runs finished, stopped by the cost cap).

    At most ``o.chunk`` runs (default: the concurrency) are in progress at once, across all the
    study's agent configs; a run that ends is stored at once and the next one starts, so runs
    finish, and are saved, one by one. ``speed`` (filled in) gets this session's calls (made,
    billed, replayed from the journal), wall time, tokens and cost; ``sent`` what a reasoning
    model was sent (`jswim.llm.reasoning.ReasoningState.describe`).
    """
    by_id = {p.run_id: p for p in plans}
    steps_total = sum(p.steps for p in plans)
    steps_done = 0
    t_start = time.perf_counter()
    totals = {"calls": 0, "billed_calls": 0, "replayed_calls": 0}
    journal = CallJournal(store.folder)
    calls_before = journal.n_calls
    # The ledger (requests.jsonl), not metadata.json, says what was spent and what earlier
    # sessions sent without an answer (the server may have billed those: still under the cap).
    ledger = RequestLedger(store.folder, journal)
    budget = Budget(max_cost, spent_usd=journal.spent_usd, ledger=ledger)
    spent_before = budget.spent_usd
    live: list[LLMClient] = []  # the open client, for its running counts

    def report(phase: str = "llm") -> None:
        elapsed = time.perf_counter() - t_start
        rate = steps_done / max(elapsed, 1e-9)
        info = f"runs {finished}/{total} · {rate:.1f} steps/s"
        left = eta(elapsed, steps_done / steps_total if steps_total else 0.0)
        if left is not None and steps_done < steps_total:
            info += f" · ETA {left}"
        if live:
            c = live[0].counts
            info += (
                f" · {c.in_flight} in flight · {c.tokens / 1000:.1f}k tok · ${budget.spent_usd:.4f}"
            )
            if max_cost is not None:
                info += f" of ${max_cost:g}"
            if c.cache_hits or c.shared:
                info += f" · {c.cache_hits} cached · {c.shared} shared"
        # The LLM steps are the work (a baseline run takes milliseconds, an LLM step a request):
        # the bar counts them, so it never reads 99% before the first LLM step.
        tick(phase, steps_done, steps_total, info)

    def on_step(n: int) -> None:
        nonlocal steps_done
        steps_done += n

    def on_done(r: RunResult) -> None:
        nonlocal finished
        totals["calls"] += r.usage.calls
        totals["billed_calls"] += r.usage.billed_calls - r.replayed_calls
        totals["replayed_calls"] += r.replayed_calls
        if r.status in STORED:
            from jswim.studies import (
                baselines,
            )  # lazy: start-up (the learners' modules load JAX and optax)

            store.add_runs([baselines.llm_row(by_id[r.run_id], r, o.horizon)])
            journal.forget(r.run_id)
            finished += 1
            report()

    async def keep_reporting() -> None:
        while True:  # a slow model takes seconds per call: show the requests in flight meanwhile
            await asyncio.sleep(0.5)
            report("llm-live")

    async def go(settings: ClientSettings, info: ServerInfo) -> None:
        pacer = Pacer(backend.rpm, backend.tpm, margin=settings.max_concurrency)
        async with LLMClient(settings, pacer=pacer, budget=budget) as client:
            live.append(client)
            record_session(store, backend, info, client, notes if notes is not None else [])
            window = asyncio.Semaphore(o.chunk or settings.max_concurrency)
            reporter = asyncio.ensure_future(keep_reporting())
            try:
                await asyncio.gather(
                    *[
                        run_batch_async(
                            [run_spec(p) for p in group],
                            client,
                            cfg,
                            store.folder / "transcripts",
                            window=window,
                            journal=journal,
                            on_step=on_step,
                            on_done=on_done,
                        )
                        for cfg, group in llm_configs(plans, o, template)
                    ]
                )
            finally:
                reporter.cancel()
                await asyncio.gather(reporter, return_exceptions=True)
                if notes is not None:  # fallbacks and pricing are known once calls were answered
                    notes.clear()
                record_session(store, backend, info, client, notes if notes is not None else [])

    # --max-tokens is also the reasoning budget, once reasoning is on (jswim.llm.reasoning).
    room = {"reasoning_max_tokens": o.max_tokens} if o.max_tokens is not None else {}
    try:
        if backend.local:
            with backend.server() as srv:
                info = preflight(store, backend, srv)
                t_start = time.perf_counter()  # the model's loading time is not LLM work
                run_sync(go(backend.client_settings(srv, info, **room), info))
        else:
            info = info or preflight(store, backend, max_cost=max_cost)
            run_sync(go(backend.client_settings(info=info, **room), info))
    finally:
        journal.close()
        ledger.close()
        if journal.n_calls > calls_before:
            store.changed = True  # calls were paid for: the folder's status must say how it ended
        if (
            live
            and sent is not None
            and (live[0].reasoning.active or live[0].reasoning.notes or live[0].reasoning.effort)
        ):
            sent.update(live[0].reasoning.describe())
        wall = time.perf_counter() - t_start
        c = live[0].counts if live else None
        speed.update(
            totals,
            wall_s=wall,
            calls_per_s=totals["calls"] / wall if wall > 0 else 0.0,
            billed_calls_per_s=totals["billed_calls"] / wall if wall > 0 else 0.0,
            tokens=c.tokens if c else 0,
            cost_usd=budget.spent_usd - spent_before,
            study_cost_usd=budget.spent_usd,
            requests=c.requests if c else 0,
            retries=c.retries if c else 0,
            faults=dict(sorted(c.faults.items())) if c else {},
            unanswered=c.unanswered if c else 0,
            unanswered_usd=c.unanswered_usd if c else 0.0,
        )
        store.meta["llm_totals"] = add_session(store.meta.get("llm_totals"), speed, journal.n_calls)
    return finished, budget.exhausted
