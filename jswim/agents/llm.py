"""The LLM agent: prompt -> chat client -> parse -> env step, for a batch of independent runs.

Each run is its own pipeline: render the prompt, call the model (one [`jswim.llm.LLMClient`][jswim.llm.client.LLMClient]
for all runs bounds the calls in flight and paces them), parse, step, record, and on to the next
step as soon as its own reply is back. There is no round and no barrier: real APIs have
heavy-tailed latency, and a barrier would make every step cost the slowest of all the runs' calls.
Stepping is shared without holding anyone back: the runs of one world keep one batched state, and
the actions handed in during one turn of the event loop are stepped in one jitted call at the next
turn (replies that land together, step together; a run never waits for another run's reply;
[`jswim.agents.step_batcher`][jswim.agents.step_batcher]).

Any world serves ([`jswim.env.base.Environment`][jswim.env.base.Environment]; ``worlds=``, default
[`jswim.agents.world_view.world`][jswim.agents.world_view.world]); what the prompt shows beyond the paper's lone swimmer comes
from the world and its observation ([`jswim.agents.world_view.view`][jswim.agents.world_view.view]). The protocol itself
(prompt in, action or follow-up out) is pure and lives in [`jswim.agents.protocol`][jswim.agents.protocol]; the run
spec, the agent settings and the named variants in [`jswim.agents.variants`][jswim.agents.variants]; the history and
its clearing rule in [`jswim.agents.memory`][jswim.agents.memory]. This module does the I/O: requests, env steps,
transcripts.

A reply without a valid action is retried ``parse_retries`` times with a short corrective follow-up
message (a new request, so temperature-0 caching does not replay the bad reply); if it still fails,
the step executes the no-op ``[1, 0]`` and counts as a failed step. The executed step, failed or
not, enters the history shown to the model. Randomness: run ``i``'s start and noise come from
``PRNGKey(seed_i)`` alone ([`jswim.agents.step_batcher`][jswim.agents.step_batcher]), whoever shares its batch.
"""

from __future__ import annotations

import asyncio
import dataclasses
import json
import math
import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO
from collections.abc import Callable, Iterable, Sequence

import numpy as np

from jswim import reprs
from jswim.judging import lattice
from jswim.agents import fidelity, pair_prompt, protocol, world_view
from jswim.agents.step_batcher import StepGroup, group_key
from jswim.agents.defaults import default_max_tokens, default_n_ht
from jswim.agents.memory import History, MoveStats, shape_key
from jswim.agents.variants import NO_OP, LLMAgentConfig, LLMRunSpec
from jswim.errors import (
    ConfigError,
    LLMError,
    LLMServerError,
    LLMSetupError,
    PositionBelowMinimumError,
)
from jswim.llm import constrain
from jswim.llm.budget import BudgetExhausted
from jswim.llm.client import ChatResult, ClientSettings, LLMClient
from jswim.llm.journal import CallJournal, call_key
from jswim.llm.local import LocalServer
from jswim.llm.sync import run_sync
from jswim.llm.usage import UsageTotals
from jswim.prompt import Action, HistoryRecord, PromptConfig, SwimmerText, nav_template


#: Shown once (Python's default warning filter) when a position falls below x_min.
BELOW_X_MIN_WARNING = (
    "a swimmer's X fell below x_min = {x_min:g}: the prompt shows that position as a negative "
    "number, as the authors' code does, and the run goes on (the step is recorded in "
    "below_x_min; a lower --x-min keeps positions positive)"
)


@dataclass
class RunResult:
    """Outcome of one run (per-step lists hold the state after each executed step)."""

    run_id: str
    spec: LLMRunSpec
    n_ht: int
    rocs: tuple[int, ...]
    status: str = "running"  # "done", "below_x_min" or "llm_error"
    error: str | None = None
    levels0: list[int] = field(default_factory=list)
    x: list[float] = field(default_factory=list)
    y: list[float] = field(default_factory=list)  # centroid y
    orientation: list[float] = field(default_factory=list)  # rad, of the reference link
    actions: list[int] = field(default_factory=list)  # env action indices
    progress: list[float] = field(default_factory=list)
    stuck: list[bool] = field(default_factory=list)
    failed_steps: int = 0
    parse_retries: int = 0
    truncated: int = 0  # replies the server cut off at max_tokens (no answer)
    cut_thinking: int = (
        0  # of those, replies cut while the model was still reasoning (never executed)
    )
    n_clears: int = 0
    usage: UsageTotals = field(default_factory=UsageTotals)
    tokens_seen: int = 0  # prompt + reply tokens of every call, shared or cached ones included
    replayed_calls: int = (
        0  # calls answered from the study's call journal (paid in an earlier session)
    )
    transcript: list[dict[str, Any]] | None = None  # in memory when no transcript folder is given
    knobs: dict[str, Any] = field(
        default_factory=dict
    )  # the variant switches (LLMAgentConfig.knobs)
    below_x_min: int | None = (
        None  # first step whose X fell below x_min (sent as a negative number)
    )
    # Worlds beyond the paper's lone swimmer (several swimmers, a wall: ``per_swimmer``): per step,
    # each swimmer's displacement, height (the observation's ``height``), tilt, and any contact.
    per_swimmer: bool = False
    xs: list[list[float]] = field(default_factory=list)
    heights: list[list[float]] = field(default_factory=list)
    tilts: list[list[float]] = field(default_factory=list)
    contact: list[bool] = field(default_factory=list)
    # A navigation task (spec.target): whether the target was reached, and the current target's
    # (x, y) after each step (a moving target's track, a path's waypoint in turn).
    reached: bool | None = None
    targets: list[list[float]] = field(default_factory=list)

    @property
    def steps(self) -> int:
        return len(self.x)

    def __repr__(self) -> str:
        return reprs.run_result_text(self)

    def _repr_html_(self) -> str:
        return reprs.run_result_html(self)

    def as_row(self) -> dict[str, Any]:
        """A flat record for [`jswim.results.StudyStore.add_runs`][jswim.results.StudyStore.add_runs]."""
        s = self.spec
        u = self.usage
        return {
            "run_id": self.run_id,
            "agent": "llm",
            "swimmer": s.swimmer,
            "direction": s.direction,
            "init": "".join(map(str, self.levels0)),
            "zeta": s.zeta,
            "seed": s.seed,
            "n_ht": self.n_ht,
            "drop": ",".join(sorted(s.drop)),
            "status": self.status,
            "error": self.error,
            "steps": self.steps,
            "final_x": self.x[-1] if self.x else 0.0,
            "failed_steps": self.failed_steps,
            "parse_retries": self.parse_retries,
            "truncated": self.truncated,
            "cut_thinking": self.cut_thinking,
            "reasoning_tokens": u.reasoning_tokens,
            "http_retries": u.retries,
            "n_clears": self.n_clears,
            "calls": u.calls,
            "billed_calls": u.billed_calls,
            "cache_hits": u.cache_hits,
            "prompt_tokens": u.prompt_tokens,
            "completion_tokens": u.completion_tokens,
            "cached_tokens": u.cached_tokens,
            "cost_usd": u.cost_usd,
            "tokens_seen": self.tokens_seen,
            "replayed_calls": self.replayed_calls,
            "roc_levels": s.roc_levels,
            "levels0": self.levels0,
            "x": self.x,
            "y": self.y,
            "orientation": self.orientation,
            "actions": self.actions,
            "progress": self.progress,
            "stuck": self.stuck,
            "below_x_min": self.below_x_min,
            **self.knobs,
            **(
                {"target": s.target, "reached": self.reached, "targets": self.targets}
                if s.target
                else {}
            ),
            **(
                {
                    "scene": s.scene,
                    "xs": self.xs,
                    "heights": self.heights,
                    "tilts": self.tilts,
                    "contact": self.contact,
                }
                if self.per_swimmer
                else {}
            ),
        }


@dataclass
class _Run:
    """Mutable per-run state of the driver."""

    result: RunResult
    text: SwimmerText
    prompt: PromptConfig
    history: History
    dofs: np.ndarray
    x: float = 0.0
    active: bool = True
    sink: TextIO | None = None
    stats: MoveStats = field(default_factory=MoveStats)
    max_tokens: int | None = None
    deviations: list[str] = field(
        default_factory=list
    )  # from the paper's protocol (agents.fidelity)
    meta: dict[str, Any] = field(default_factory=dict)  # the transcript's first record
    n_calls: int = 0  # calls made so far (their index in the call journal)
    begun: bool = False
    closed: bool = False
    seen: dict[str, Any] | None = (
        None  # per_swimmer: each swimmer's position, height, tilt before the next step
    )
    convs: list[pair_prompt.Conversation] = field(
        default_factory=list
    )  # --pair-prompt each: one per swimmer
    # A navigation task: the centre's y, the heading, the current target and its waypoint number.
    y: float = 0.0
    heading: float = 0.0
    target: tuple[float, float] | None = None
    waypoint: int = 1
    waypoints: tuple[tuple[float, float], ...] = ()
    flow: tuple[float, float] | None = None  # in a flow: the local flow (lab frame) now

    def log(self, record: dict[str, Any]) -> None:
        if self.sink is not None:
            self.sink.write(json.dumps(record, default=_jsonable) + "\n")
        elif self.result.transcript is not None:
            self.result.transcript.append(record)


def _waypoint(run: _Run) -> int:
    """Which waypoint of a path the current target is (1-based; 1 for a point or a moving
    target): the path's point nearest the target the world reports."""
    if len(run.waypoints) < 2 or run.target is None:
        return 1
    d = [math.dist(p, run.target) for p in run.waypoints]
    return int(np.argmin(d)) + 1


def _jsonable(obj: Any) -> Any:
    if isinstance(obj, (frozenset, set)):
        return sorted(obj)
    if isinstance(obj, np.generic):
        return obj.item()
    return str(obj)


class LLMDriver:
    """Runs a batch of [`LLMRunSpec`][jswim.agents.variants.LLMRunSpec] against one client (use [`run_batch`][jswim.agents.llm.run_batch]).

    Each run is its own pipeline (prompt, call, parse, step, record) and moves on as soon as its
    own reply is back; the client bounds the calls in flight. ``window`` bounds the runs in
    progress at once (a number, or a semaphore shared by several drivers); further runs start
    as earlier ones finish, so runs end, and are saved, in order. ``journal`` answers a resumed
    run's calls that were already paid for (`jswim.llm.journal.CallJournal`) and records
    new ones. ``on_step(n)`` is called after every step; ``on_done(result)`` when a run ends
    (status ``done``, ``below_x_min``, ``llm_error`` or ``budget``: stopped by the cost cap).
    ``worlds(spec) -> (env, params)`` builds each run's world (default
    [`jswim.agents.world_view.world`][jswim.agents.world_view.world]); any [`jswim.env.base.Environment`][jswim.env.base.Environment] serves.
    """

    def __init__(
        self,
        specs: Sequence[LLMRunSpec],
        client: LLMClient,
        config: LLMAgentConfig = LLMAgentConfig(),
        transcript_dir: str | Path | None = None,
        *,
        window: int | asyncio.Semaphore | None = None,
        journal: CallJournal | None = None,
        on_step: Callable[[int], None] | None = None,
        on_done: Callable[[RunResult], None] | None = None,
        transcripts: bool = True,
        cohorts: int
        | None = None,  # deprecated: runs no longer move in lockstep; accepted, ignored
        worlds: Callable[[LLMRunSpec], tuple[Any, Any]] = world_view.world,
    ) -> None:
        if not specs:
            raise ConfigError("no runs given")
        self.client = client
        self.config = config
        self.transcript_dir = Path(transcript_dir) if transcript_dir is not None else None
        self.transcripts = transcripts
        self.journal = journal
        self.on_step = on_step
        self.on_done = on_done
        self.window = window
        ids = [s.label() for s in specs]
        dupes = sorted({i for i in ids if ids.count(i) > 1})
        if dupes:
            raise ConfigError(
                f"duplicate run ids {dupes[:3]}; give the runs distinct seeds or run_id"
            )
        built = [worlds(s) for s in specs]
        by_world: dict[Any, list[int]] = {}
        for i, (w, p) in enumerate(built):  # one batched state per world (and params structure)
            by_world.setdefault(group_key(w, p), []).append(i)
        self.runs: list[_Run] = [None] * len(specs)  # type: ignore[list-item]
        self._where: dict[int, tuple[StepGroup, int]] = {}
        self.groups = []
        for idx in by_world.values():
            w = built[idx[0]][0]
            models = [world_view.model(specs[i], w) for i in idx]
            g = StepGroup(
                idx,
                w,
                [built[i][1] for i in idx],
                [specs[i].seed for i in idx],
                lattice.encode(*NO_OP, w.roc_levels),
                models[0].lo,
                models[0].hi,
            )
            self.groups.append(g)
            for j, i in enumerate(idx):
                self._where[i] = (g, j)
                self.runs[i] = self._make_run(specs[i], ids[i], models[j], g, j)

    def _make_run(
        self, spec: LLMRunSpec, run_id: str, model: Any, group: StepGroup, pos: int
    ) -> _Run:
        n_ht, base, prompt = protocol.setup(spec, model, self.config)
        cfg = self.config
        env, start = group.env, {k: v[pos] for k, v in group.start.items()}
        view = world_view.view(env, group.x0[pos], start["heights"])  # None: the paper's prompt
        text, template = world_view.text(base, prompt.template, env.n_dof, view)
        prompt = dataclasses.replace(prompt, template=template)
        nav = world_view.nav_view(spec)  # None: the paper's task along +x or -x
        if nav is not None:
            text = dataclasses.replace(text, nav=nav)
            prompt = dataclasses.replace(
                prompt,
                template=nav_template(prompt.template, flow=nav.flow),
                x_min=world_view.nav_x_min(spec, prompt.x_min),
            )
        levels0 = [int(v) for v in group.levels0[pos]]
        result = RunResult(
            run_id,
            spec,
            n_ht,
            text.rocs,
            levels0=levels0,
            per_swimmer=view is not None,
            transcript=None if self.transcript_dir or not self.transcripts else [],
            knobs=cfg.knobs(self.client.settings.temperature),
        )
        run = _Run(
            result,
            text,
            prompt,
            History(protocol.clearing_rule(cfg, model)),
            np.array(start["dofs"], np.float64),
        )
        if nav is not None:
            run.y, run.heading = float(start["y"]), float(start["orientation"])
            run.flow = tuple(float(v) for v in start["flow"]) if nav.flow else None
            run.waypoints = tuple(tuple(p) for p in json.loads(spec.target).get("points") or ())
            run.target = tuple(float(v) for v in start["target"])
            run.waypoint = _waypoint(run)
            result.reached = False
        settings = self.client.settings
        constraint = constrain.resolve_mode(settings.constrain, settings.server_kind)
        run.max_tokens = protocol.max_tokens(cfg, model, constraint)
        result.knobs.update(constraint=constraint, max_tokens=run.max_tokens)
        run.deviations = fidelity.deviations(
            cfg,
            temperature=cfg.sampling_temperature(settings.temperature),
            constraint=constraint,
            max_tokens=run.max_tokens,
            default_max_tokens=default_max_tokens(model),
            n_ht=n_ht,
            default_n_ht=default_n_ht(model, spec.direction),
            roc_levels=spec.roc_levels,
        )
        world_meta, deviation = world_view.notes(spec)
        run.deviations += [deviation] if deviation else []
        if nav is not None:
            run.deviations.append(fidelity.navigation_deviation(spec.target))
            if spec.flow:
                run.deviations.append(fidelity.flow_deviation(spec.flow))
        if env.n_swimmers > 1:
            result.knobs["pair_prompt"] = spec.pair_prompt
        if spec.pair_prompt == "each":  # one conversation per swimmer (jswim.agents.pair_prompt)
            run.convs = pair_prompt.conversations(spec, model, cfg, run.dofs, view)
        if view is not None:
            run.seen = {k: tuple(float(v) for v in start[k]) for k in ("xs", "heights", "tilts")}
        run.meta = {
            "type": "meta",
            "run_id": run_id,
            # a run without a target (the paper's task) keeps the transcript it always had
            "spec": {
                k: v
                for k, v in dataclasses.asdict(spec).items()
                if k not in ("target", "flow") or v
            },
            "n_ht": n_ht,
            "rocs": list(text.rocs),
            "levels0": result.levels0,
            "agent": cfg.metadata(),
            "client": self._client_meta(run.max_tokens),
            "deviations": run.deviations,
            **world_meta,
            **({"pair_prompt": spec.pair_prompt} if "pair_prompt" in result.knobs else {}),
            **(pair_prompt.metadata(run.convs) if run.convs else {}),
        }
        return run

    def _client_meta(self, max_tokens: int | None) -> dict[str, Any]:
        """The client's settings as this run's requests carry them: ``max_tokens`` is the run's
        own limit (per swimmer), not the client's default, and ``None`` when the field is omitted."""
        meta = self.client.settings.metadata()
        meta["max_tokens"] = None if "max_tokens" in meta.get("omit_fields", ()) else max_tokens
        return meta

    def _begin(self, run: _Run) -> None:
        """Open the run's transcript when the run starts (not before: thousands may wait)."""
        if self.transcript_dir is not None and self.transcripts:
            self.transcript_dir.mkdir(parents=True, exist_ok=True)
            run.sink = open(
                self.transcript_dir / f"{run.result.run_id}.jsonl", "w", encoding="utf-8"
            )
        run.begun = True
        run.log(run.meta)

    async def _call(self, run: _Run, messages: list[dict[str, str]], **kw: Any) -> ChatResult:
        """One call of ``run``: replayed from the journal when already paid for, else sent (and recorded)."""
        journal = self.journal
        if journal is None:
            return self._note_form(run, await self.client.chat(messages, **kw))
        temperature = kw.get("temperature")
        if temperature is None:
            temperature = self.client.settings.temperature
        params = {
            k: v for k, v in kw.items() if not callable(v)
        }  # cache_if: how to cache, not what is asked
        key = call_key(
            messages, **{**params, "temperature": temperature, "model": self.client.settings.model}
        )
        n = run.n_calls
        run.n_calls += 1
        res = journal.replay(run.result.run_id, n, key)
        if res is not None:
            run.result.replayed_calls += 1
            return res
        res = self._note_form(run, await self.client.chat(messages, **kw))
        journal.record(run.result.run_id, n, key, res)
        return res

    def _note_sent(self, run: _Run, res: ChatResult) -> None:
        """Record in the run's row what a reasoning model was sent instead of what was asked."""
        if res.temperature_sent is not None and res.temperature_sent != run.result.knobs.get(
            "temperature"
        ):
            run.result.knobs["temperature_sent"] = res.temperature_sent
        state = getattr(self.client, "reasoning", None)
        if state is not None and state.active:
            run.result.knobs.update(token_field=state.token_field, max_tokens_sent=state.budget)

    @staticmethod
    def _note_form(run: _Run, res: ChatResult) -> ChatResult:
        """Record the constrained-decoding form a reply came with (``--constrain auto`` may have
        fallen back to another form than the one the run started with)."""
        if res.constraint != "none" and run.result.knobs.get("constraint") != res.constraint:
            run.result.knobs["constraint"] = res.constraint
        return res

    # -- one decision ------------------------------------------------------------------------

    async def _decide(self, run: _Run) -> tuple[Action, bool, dict[str, Any]]:
        cfg = self.config
        spec = run.result.spec
        step = run.result.steps + 1
        # Who decides: the run's one conversation, or (--pair-prompt each) the swimmer whose turn it is.
        conv = run.convs[pair_prompt.turn(step, len(run.convs))] if run.convs else None
        mind = conv if conv is not None else run
        req = protocol.request(
            cfg,
            mind.text,
            mind.prompt,
            direction=spec.direction,
            seed=spec.seed,
            step=step,
            records=mind.history.records,
            dofs=mind.dofs,
            x=mind.x,
            stats=mind.stats,
            target=run.target,
            waypoint=run.waypoint,
        )
        temperature = cfg.sampling_temperature(self.client.settings.temperature)
        messages = req.messages
        attempts = []
        action = None
        for k in range(cfg.parse_retries + 1):
            seed = protocol.sample_seed(spec.seed, step, k, temperature)
            # Not sharing: the cache key carries the run, step and attempt, so only this very
            # call's earlier reply (a resume) can answer it, never another run's. Only replies
            # that name a valid action go in the disk cache: a failure is never replayed.
            scope = None if cfg.share_identical else f"{run.result.run_id}/{step}/{k}"
            res = await self._call(
                run,
                messages,
                replies=req.replies,
                temperature=cfg.temperature,
                seed=seed,
                max_tokens=run.max_tokens,
                cache_scope=scope,
                cache_if=lambda r: protocol.valid_reply(req, r.text),
            )
            run.result.usage.add(res)
            run.result.tokens_seen += res.usage.total_tokens
            run.result.truncated += res.truncated
            run.result.cut_thinking += res.cut_while_thinking
            self._note_sent(run, res)
            reply = protocol.read_reply(req, messages, res.text, k, cfg, truncated=res.truncated)
            action = reply.action
            attempts.append(
                {**res.as_dict(), "seed": seed, "parsed": list(action) if action else None}
            )
            if action is not None or reply.follow_up is None:
                break
            run.result.parse_retries += 1
            messages = reply.follow_up
        failed = action is None
        log = {
            "prompt": req.prompt,
            "attempts": attempts,
            "options": [list(a) for a in req.options],
        }
        action = NO_OP if failed else action
        if conv is not None:  # the swimmer's own [d, ROC] as the joint action
            log.update(swimmer=conv.swimmer + 1, own_action=list(action))
            action = pair_prompt.to_joint(conv.swimmer, action)
        return action, failed, log

    # -- the loop ----------------------------------------------------------------------------

    async def run(self) -> list[RunResult]:
        """Advance every run to its end; returns the results in input order.

        Raises
        ------
        LLMServerError
            The server stayed down (transcripts so far are written and closed first).
        """
        window = self.window
        if window is None or isinstance(window, int):
            window = asyncio.Semaphore(window or len(self.runs))
        tasks = [asyncio.ensure_future(self._pipeline(i, window)) for i in range(len(self.runs))]
        try:
            done, pending = await asyncio.wait(tasks, return_when=asyncio.FIRST_EXCEPTION)
            for t in pending:  # the server is down (or a bug): stop the other runs too
                t.cancel()
            await asyncio.gather(*pending, return_exceptions=True)
            # Read every finished task's exception (an unread one is logged at exit), raise the first.
            errors = [
                t.exception() for t in done if not t.cancelled() and t.exception() is not None
            ]
            if errors:
                raise errors[0]
        finally:
            for t in tasks:
                t.cancel()
            for run in self.runs:
                if run.active:
                    run.result.status = "aborted"
                self._close(run)
        return [r.result for r in self.runs]

    async def _pipeline(self, i: int, window: asyncio.Semaphore) -> None:
        run = self.runs[i]
        group, pos = self._where[i]
        async with window:
            self._begin(run)
            while run.active:
                try:
                    decision = await self._decide(run)
                except BudgetExhausted as exc:
                    self._finish(run, "budget", str(exc))
                    break
                except (LLMServerError, LLMSetupError):
                    # Down, or set up so that no request can succeed (URL, key, a rejected field): stop all.
                    raise
                except LLMError as exc:
                    self._finish(run, "llm_error", str(exc))
                    break
                except PositionBelowMinimumError as exc:  # can only come from a bad x_min
                    self._finish(run, "below_x_min", str(exc))
                    break
                # The reply's integer ROC k is the environment's code for ROC k/K (jswim.judging.lattice).
                index = lattice.encode(*decision[0], group.env.roc_levels)
                out = await group.submit(pos, index)
                self._record(run, decision, index, out)
                if self.on_step is not None:
                    self.on_step(1)
            self._close(run)
        if self.on_done is not None:
            self.on_done(run.result)

    def _record(
        self,
        run: _Run,
        decision: tuple[Action, bool, dict[str, Any]],
        index: int,
        out: dict[str, Any],
    ) -> None:
        action, failed, log = decision
        res = run.result
        x_before, x_after = run.x, float(out["x"])
        scene = {}
        if (
            run.seen is not None
        ):  # a world beyond the paper's: positions, heights and tilts of each swimmer
            now = {k: tuple(float(v) for v in out[k]) for k in ("xs", "heights", "tilts")}
            scene = {
                f"{k}_{w}": run.seen[k] if w == "before" else now[k]
                for k in ("xs", "heights", "tilts")
                for w in ("before", "after")
            }
            run.seen = now
            res.xs.append(list(now["xs"]))
            res.heights.append(list(now["heights"]))
            res.tilts.append(list(now["tilts"]))
            res.contact.append(bool(out["contact"]))
        nav = {}
        if run.target is not None:  # a navigation task: y and heading, the target's next place
            y_after, heading_after = float(out["y"]), float(out["orientation"])
            nav = {
                "y_before": run.y,
                "y_after": y_after,
                "heading_before": run.heading,
                "heading_after": heading_after,
                "flow": run.flow,
            }
            run.y, run.heading = y_after, heading_after
            if run.flow is not None:  # the flow where the swimmer now is: the next record's
                run.flow = tuple(float(v) for v in out["flow"])
            run.target = tuple(float(v) for v in out["target"])
            run.waypoint = _waypoint(run)
            res.targets.append(list(run.target))
            res.reached = bool(out["reached"])
        rec = HistoryRecord(
            res.steps + 1,
            tuple(run.dofs),
            tuple(float(v) for v in out["dofs"]),
            action,
            x_before,
            x_after,
            bool(out["stuck"]),
            **scene,
            **nav,
        )
        if run.convs:  # each swimmer's own record, progress and clearing (jswim.agents.pair_prompt)
            cleared = pair_prompt.record(run.convs, rec, res.spec.direction)
            n_clears = sum(c.history.n_clears for c in run.convs)
        else:
            run.stats.add(shape_key(run.text, rec.dofs_before), action, float(out["progress"]))
            cleared = run.history.add(rec, float(out["progress"]))
            n_clears = run.history.n_clears
        run.dofs = np.asarray(out["dofs"], np.float64)
        run.x = x_after
        res.x.append(x_after)
        res.y.append(float(out["y"]))
        res.orientation.append(float(out["orientation"]))
        res.actions.append(int(index))
        res.progress.append(float(out["progress"]))
        res.stuck.append(bool(out["stuck"]))
        res.failed_steps += failed
        res.n_clears = n_clears
        run.log(
            {
                "type": "step",
                "step": rec.step,
                **log,
                "action": list(action),
                "failed": failed,
                "x_before": x_before,
                "x_after": x_after,
                "progress": float(out["progress"]),
                "stuck": rec.stuck,
                "dofs_after": list(rec.dofs_after),
                "cleared": cleared,
                "n_clears": n_clears,
                **(
                    {
                        "y_after": rec.y_after,
                        "heading_after": rec.heading_after,
                        "target": list(run.target),
                        "reached": res.reached,
                    }
                    if nav
                    else {}
                ),
                **(
                    {
                        "xs_after": list(rec.xs_after),
                        "heights_after": list(rec.heights_after),
                        "tilts_after": list(rec.tilts_after),
                        "contact": bool(out["contact"]),
                    }
                    if scene
                    else {}
                ),
            }
        )
        if x_after < run.prompt.x_min and res.below_x_min is None:
            # Sent as a negative number, as the authors' code does; the run goes on.
            res.below_x_min = res.steps
            warnings.warn(BELOW_X_MIN_WARNING.format(x_min=run.prompt.x_min), stacklevel=2)
        if res.steps >= res.spec.n_steps or bool(out.get("ended", False)):
            self._finish(run, "done")

    def _finish(self, run: _Run, status: str, error: str | None = None) -> None:
        run.active = False
        run.result.status = status
        run.result.error = error

    def _close(self, run: _Run) -> None:
        if run.closed or not run.begun:
            return
        run.closed = True
        res = run.result
        run.log(
            {
                "type": "end",
                "status": res.status,
                "error": res.error,
                "steps": res.steps,
                "failed_steps": res.failed_steps,
                "parse_retries": res.parse_retries,
                "n_clears": res.n_clears,
                "usage": res.usage.as_dict(),
            }
        )
        if run.sink is not None:
            # On disk before the run's record reaches runs.jsonl (fsynced too): a finished run's
            # transcript is never torn by a crash after it.
            run.sink.flush()
            os.fsync(run.sink.fileno())
            run.sink.close()
            run.sink = None


async def run_batch_async(
    specs: Sequence[LLMRunSpec],
    client: LLMClient,
    config: LLMAgentConfig = LLMAgentConfig(),
    transcript_dir: str | Path | None = None,
    **options: Any,
) -> list[RunResult]:
    """Run a batch with an open client; ``options`` go to [`LLMDriver`][jswim.agents.llm.LLMDriver] (window, journal,
    on_step, on_done, transcripts)."""
    return await LLMDriver(specs, client, config, transcript_dir, **options).run()


def run_batch(
    specs: Iterable[LLMRunSpec],
    settings: ClientSettings | None = None,
    config: LLMAgentConfig = LLMAgentConfig(),
    transcript_dir: str | Path | None = None,
    cohorts: int | None = None,
    worlds: Callable[[LLMRunSpec], tuple[Any, Any]] = world_view.world,
    **local_options: Any,
) -> list[RunResult]:
    """Run a batch of LLM runs to completion (blocking).

    Parameters
    ----------
    specs : iterable of LLMRunSpec
        The runs.
    settings : ClientSettings, optional
        Server to use; ``None`` starts the embedded local model for the duration of the call
        (``local_options`` go to `jswim.llm.local.LocalServer`).
    config : LLMAgentConfig
        Agent settings shared by the runs.
    transcript_dir : str or Path, optional
        Folder for one ``<run_id>.jsonl`` transcript per run; ``None`` keeps transcripts in
        memory (``RunResult.transcript``).
    cohorts : int, optional
        Deprecated and ignored: runs no longer advance in lockstep rounds.
    worlds : callable, optional
        ``worlds(spec) -> (env, params)``: each run's world ([`LLMDriver`][jswim.agents.llm.LLMDriver]).
    """
    specs = list(specs)

    async def go(s: ClientSettings) -> list[RunResult]:
        async with LLMClient(s) as client:
            return await run_batch_async(specs, client, config, transcript_dir, worlds=worlds)

    if settings is not None:
        return run_sync(go(settings))
    with LocalServer(**local_options) as srv:
        return run_sync(go(srv.client_settings()))
