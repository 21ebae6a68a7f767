"""Executing a study's plans in one `StudySession`: the baselines in vectorised groups
([`baselines`][jswim.studies.baselines]), the LLM plans as per-run pipelines
([`LLMDriver`][jswim.agents.llm.LLMDriver]); each run is stored the moment it ends.

Every answered call is journaled first (``calls.jsonl``, `jswim.llm.journal.CallJournal`),
so an interrupted or capped study resumes without paying for a call twice.
"""

from __future__ import annotations

import asyncio
import dataclasses
import time
from dataclasses import dataclass, field
from typing import Any
from collections.abc import Iterable, Sequence


from jswim.agents.llm import RunResult, run_batch_async
from jswim.errors import ConfigError
from jswim.agents.variants import LLMRunSpec, variant_config
from jswim.console import eta
from jswim.llm.budget import Budget
from jswim.llm.client import ClientSettings, LLMClient
from jswim.llm.journal import CallJournal
from jswim.llm.ledger import RequestLedger
from jswim.llm.pacing import Pacer
from jswim.llm.probe import ServerInfo
from jswim.llm.sync import run_sync
from jswim.prompt import PromptTemplate
from jswim.results import as_run_rows
from jswim.studies.plans import Plan
from jswim.studies.options import StudyOptions
from jswim.studies.session import StudySession, preflight, record_session, study_totals


#: Statuses of an LLM run that are stored; one stopped by the cost cap or an interrupt is not, and
#: starts again on resume (its paid calls replayed from the journal).
STORED = ("done", "below_x_min", "llm_error")


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
        flow=p.flow,
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


#: The fields a plan's baseline group shares: one vectorised call per group.
BASELINE_GROUP = (
    "agent",
    "swimmer",
    "action_set",
    "roc_levels",
    "scene",
    "variant",
    "zeta",
    "target",
    "flow",
)


def run_baselines(session: StudySession, plans: Sequence[Plan]) -> int:
    """Run the baseline plans (Q-learning, random, PPO, controllers) in vectorised groups.

    Parameters
    ----------
    session : StudySession
        Each group's rows go into ``session.store`` the moment the group ends, and
        ``session.finished`` moves on.
    plans : sequence of Plan
        The baseline plans still to run (no ``"llm"`` agent; the ``"optimal"`` agent's go to
        `run_optimum`, after the LLM's).

    Returns
    -------
    int
        The runs this call finished.
    """
    for group in group_plans(plans, *BASELINE_GROUP).values():
        session.store.add_runs(_run_group(session, group))
    return len(plans)


def run_optimum(session: StudySession, plans: Sequence[Plan]) -> int:
    """Run the navigation cells' optimum (the ``"optimal"`` agent), the study's last runs.

    Each cell's search is seeded with every run of the cell the folder holds that reached the
    target, the LLM's included (`jswim.studies.kinds.navigate.seed_optimum`), so it is never longer
    than any of them; the cell's other rows read their ratio to it when the folder is read
    ([`jswim.results.optimum.with_cell_optimum`][jswim.results.optimum.with_cell_optimum]).

    Parameters
    ----------
    session : StudySession
        As `run_baselines`.
    plans : sequence of Plan
        The ``"optimal"`` plans still to run.

    Returns
    -------
    int
        The runs this call finished.
    """
    if not plans:
        return 0
    from jswim.studies.kinds import navigate  # lazy: start-up (navigation loads the worlds)

    navigate.clear_seeds()  # this study's runs only: not an earlier study's in this process
    navigate.seed_optimum(as_run_rows(session.store.load_runs()))
    return run_baselines(session, plans)


def _run_group(session: StudySession, group: list[Plan]) -> list[Any]:
    from jswim.studies import baselines  # lazy: start-up (the learners' modules load optax)

    rows = baselines.baseline_rows(group, session.options.horizon)
    session.finished += len(group)
    session.tick(group[0].agent)
    return rows


@dataclass
class LLMOutcome:
    """What one session's LLM runs came to ([`run_llm`][jswim.studies.execute.run_llm]).

    Attributes
    ----------
    finished : int
        LLM runs this session stored.
    capped : bool
        The cost cap stopped the session before every plan ran.
    speed : dict
        This session's calls (made, billed, replayed from the journal), wall time (s), calls/s,
        tokens, cost (USD), requests, retries, faults and unanswered requests.
    sent : dict
        What a reasoning model was sent (`jswim.llm.reasoning.ReasoningState.describe`); empty
        for other models.
    notes : list of str
        What was sent for sampling, the decoding fallbacks, why calls were not priced.
    """

    finished: int = 0
    capped: bool = False
    speed: dict[str, Any] = field(default_factory=dict)
    sent: dict[str, Any] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)


def run_llm(session: StudySession, plans: Sequence[Plan]) -> LLMOutcome:
    """Run the LLM plans as per-run pipelines, each stored the moment it ends.

    At most ``options.chunk`` runs (default: the concurrency) are in progress at once, across all
    the study's agent configs; a run that ends is stored at once and the next one starts, so runs
    finish, and are saved, one by one. Every answered call is journaled first, so a capped or
    interrupted session resumes without paying a call twice.

    Parameters
    ----------
    session : StudySession
        The study's store, options, backend (required), template, progress and cost cap;
        ``session.finished`` moves on with each stored run.
    plans : sequence of Plan
        The LLM plans still to run.

    Returns
    -------
    LLMOutcome
        Runs stored, whether the cap stopped the session, its speed, what was sent, notes.

    Raises
    ------
    ConfigError
        No backend, or a cost cap the calls could not reach.
    LLMError
        The server cannot be used (refused, unreachable, no such model).
    """
    return _LLMSession(session, plans).run()


class _LLMSession:
    """The running counts of one session's LLM runs and the callbacks that move them."""

    def __init__(self, session: StudySession, plans: Sequence[Plan]) -> None:
        if session.backend is None:
            raise ConfigError("this study has LLM runs; give a backend")
        self.s, self.plans = session, plans
        self.by_id = {p.run_id: p for p in plans}
        self.steps_total = sum(p.steps for p in plans)
        self.steps_done = 0
        self.t_start = time.perf_counter()
        self.totals = {"calls": 0, "billed_calls": 0, "replayed_calls": 0}
        self.journal = CallJournal(session.store.folder)
        self.calls_before = self.journal.n_calls
        # The ledger (requests.jsonl), not metadata.json, says what was spent and what earlier
        # sessions sent without an answer (the server may have billed those: still under the cap).
        self.ledger = RequestLedger(session.store.folder, self.journal)
        self.budget = Budget(session.max_cost, spent_usd=self.journal.spent_usd, ledger=self.ledger)
        self.spent_before = self.budget.spent_usd
        self.client: LLMClient | None = None  # the open client, for its running counts
        self.out = LLMOutcome()

    def report(self, phase: str = "llm") -> None:
        """Tick the session's progress: LLM steps done, runs, speed, requests, tokens, cost."""
        elapsed = time.perf_counter() - self.t_start
        done, total = self.steps_done, self.steps_total
        info = f"runs {self.s.finished}/{self.s.total} · {done / max(elapsed, 1e-9):.1f} steps/s"
        left = eta(elapsed, done / total if total else 0.0)
        if left is not None and done < total:
            info += f" · ETA {left}"
        if self.client is not None:
            c = self.client.counts
            info += f" · {c.in_flight} in flight · {c.tokens / 1000:.1f}k tok · ${self.budget.spent_usd:.4f}"
            if self.s.max_cost is not None:
                info += f" of ${self.s.max_cost:g}"
            if c.cache_hits or c.shared:
                info += f" · {c.cache_hits} cached · {c.shared} shared"
        # The LLM steps are the work (a baseline run takes milliseconds, an LLM step a request):
        # the bar counts them, so it never reads 99% before the first LLM step.
        self.s.tick(phase, done, info, total=total)

    def on_step(self, n: int) -> None:
        self.steps_done += n

    def on_done(self, r: RunResult) -> None:
        """Count a run's calls; store it (and forget its journal lines) when it is one to keep."""
        self.totals["calls"] += r.usage.calls
        self.totals["billed_calls"] += r.usage.billed_calls - r.replayed_calls
        self.totals["replayed_calls"] += r.replayed_calls
        if r.status in STORED:
            from jswim.studies import baselines  # lazy: start-up (the learners load JAX, optax)

            self.s.store.add_runs(
                [baselines.llm_row(self.by_id[r.run_id], r, self.s.options.horizon)]
            )
            self.journal.forget(r.run_id)
            self.s.finished += 1
            self.out.finished += 1
            self.report()

    async def keep_reporting(self) -> None:
        while True:  # a slow model takes seconds per call: show the requests in flight meanwhile
            await asyncio.sleep(0.5)
            self.report("llm-live")

    async def go(self, settings: ClientSettings, info: ServerInfo) -> None:
        """Every plan through one client, at most ``chunk`` runs at once."""
        s, backend = self.s, self.s.backend
        # The session is written down before its first request: a kill -9 later still leaves it
        # counted (its requests, its time to its last line). A folder an older jswim began keeps
        # what its metadata said of the sessions before.
        named = any(c.number for c in self.ledger.sessions)
        self.ledger.begin_session(None if named else s.store.meta.get("llm_totals"))
        pacer = Pacer(backend.rpm, backend.tpm, margin=settings.max_concurrency)
        async with LLMClient(settings, pacer=pacer, budget=self.budget) as client:
            self.client = client
            record_session(s.store, backend, info, client, self.out.notes)
            window = asyncio.Semaphore(s.options.chunk or settings.max_concurrency)
            reporter = asyncio.ensure_future(self.keep_reporting())
            try:
                await asyncio.gather(
                    *[
                        run_batch_async(
                            [run_spec(p) for p in group],
                            client,
                            cfg,
                            s.store.folder / "transcripts",
                            window=window,
                            journal=self.journal,
                            on_step=self.on_step,
                            on_done=self.on_done,
                        )
                        for cfg, group in llm_configs(self.plans, s.options, s.template)
                    ]
                )
            finally:
                reporter.cancel()
                await asyncio.gather(reporter, return_exceptions=True)
                self.out.notes.clear()  # fallbacks and pricing are known once calls were answered
                record_session(s.store, backend, info, client, self.out.notes)

    def run(self) -> LLMOutcome:
        """Start the server or preflight it, run every plan, and settle the session's accounts."""
        s, backend = self.s, self.s.backend
        # --max-tokens is also the reasoning budget, once reasoning is on (jswim.llm.reasoning).
        mt = s.options.max_tokens
        room = {"reasoning_max_tokens": mt} if mt is not None else {}
        try:
            if backend.local:
                with backend.server() as srv:
                    info = preflight(s.store, backend, srv)
                    self.t_start = time.perf_counter()  # the model's loading time is not LLM work
                    run_sync(self.go(backend.client_settings(srv, info, **room), info))
            else:
                info = s.server or preflight(s.store, backend, max_cost=s.max_cost)
                run_sync(self.go(backend.client_settings(info=info, **room), info))
        finally:
            self.settle()
        self.out.capped = self.budget.exhausted
        return self.out

    def settle(self) -> None:
        """Close the journal and ledger; this session's speed and what it sent, into the metadata."""
        self.journal.close()
        self.ledger.end_session()
        self.ledger.close()
        if self.journal.n_calls > self.calls_before:
            self.s.store.changed = (
                True  # calls were paid for: the folder's status must say how it ended
            )
        r = self.client.reasoning if self.client is not None else None
        if r is not None and (r.active or r.notes or r.effort):
            self.out.sent.update(r.describe())
        self.out.speed.update(self.speed())
        meta = self.s.store.meta
        meta["llm_totals"] = study_totals(self.ledger, self.journal.n_calls)

    def speed(self) -> dict[str, Any]:
        """This session's calls, wall time, rates, tokens, cost and the client's fault counts."""
        wall = time.perf_counter() - self.t_start
        c, t = (self.client.counts if self.client is not None else None), self.totals
        return {
            **t,
            "wall_s": wall,
            "calls_per_s": t["calls"] / wall if wall > 0 else 0.0,
            "billed_calls_per_s": t["billed_calls"] / wall if wall > 0 else 0.0,
            "tokens": c.tokens if c else 0,
            "cost_usd": self.budget.spent_usd - self.spent_before,
            "study_cost_usd": self.budget.spent_usd,
            "requests": c.requests if c else 0,
            "retries": c.retries if c else 0,
            "faults": dict(sorted(c.faults.items())) if c else {},
            "unanswered": c.unanswered if c else 0,
            "unanswered_usd": c.unanswered_usd if c else 0.0,
        }
