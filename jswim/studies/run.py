"""Running a study: build its plans, run what is not done yet, store and summarise.

Execution groups the plans (:mod:`jswim.studies.grids`): Q-learning and random-policy runs
train/roll out in one vectorised call per swimmer, and LLM runs advance in lockstep chunks (all
prompts of a round in flight at once). Each finished chunk lands in the study folder
(:class:`jswim.results.StudyStore`), so an interrupted study resumes where it stopped. Every
run, whatever its agent, is judged by the same code, :func:`jswim.gait.judge`, with the study's
:class:`jswim.gait.Criterion`.
"""

from __future__ import annotations

import asyncio
import dataclasses
import hashlib
import json
import platform
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

import jax
import numpy as np

from jswim import __version__, env
from jswim.agents import fidelity, qlearning, random_policy
from jswim.agents.llm import run_batch_async
from jswim.agents.variants import VARIANTS, LLMRunSpec, variant_config
from jswim.console import eta
from jswim.errors import ConfigError, JswimError
from jswim.gait import Criterion, judge
from jswim.llm.backend import Backend
from jswim.llm.client import LLMClient
from jswim.llm.sync import run_sync
from jswim.prompt import PromptTemplate
from jswim.results import StudyStore, is_failed, legacy_names, read_runs
from jswim.studies.grids import COMPETENCE_VARIANTS, SPECS, SWIM_VARIANT, Plan, StudyOptions, build
from jswim.studies.report import draw_figures, summarize


# -- execution ----------------------------------------------------------------------------------


def _judge_rows(plans: Sequence[Plan], actions: np.ndarray, xs: np.ndarray, levels0: np.ndarray,
                horizon: int, extra: Sequence[dict[str, Any]] | None = None,
                pose: tuple[np.ndarray, np.ndarray] | None = None) -> list[dict[str, Any]]:
    """Rows for a batch of runs of one swimmer, judged by the shared success criterion.

    ``pose`` gives the centroid y and the orientation after each step, shape ``(runs, steps)``
    each, for the trajectories (LLM runs bring theirs in ``extra``)."""
    p0 = plans[0]
    params = env.make_params(p0.swimmer)
    params = params.replace(direction=np.array([p.direction for p in plans], float))
    rep = judge(actions, params, levels0=levels0, criterion=Criterion(horizon=horizon))
    rows = []
    for i, p in enumerate(plans):
        x = [float(v) for v in xs[i]]
        prog = np.diff(np.concatenate([[0.0], xs[i]])) * p.direction
        row = {
            "run_id": p.run_id, "agent": p.agent, "swimmer": p.swimmer, "direction": p.direction,
            "init": "".join("+" if v else "-" for v in levels0[i]), "zeta": p.zeta, "seed": p.seed,
            "n_ht": p.n_ht, "drop": ",".join(sorted(p.drop)), "action_set": p.action_set, "group": p.group,
            "variant": p.variant,
            "steps": len(x), "final_x": x[-1] if x else 0.0,
            "signed_final_x": p.direction * (x[-1] if x else 0.0),
            "success": bool(rep.success[i]), "learned": bool(rep.learned[i]),
            "steps_to_learn": int(rep.steps_to_learn[i]) if rep.learned[i] else None,
            "period": int(rep.period[i]),
            "x": x, "actions": [list(env.decode_action(int(a))) for a in actions[i]],
            "progress": [float(v) for v in prog], "status": "done",
        }
        if pose is not None:
            row["y"] = [float(v) for v in pose[0][i]]
            row["orientation"] = [float(v) for v in pose[1][i]]
        if extra is not None:
            row.update({k: v for k, v in extra[i].items() if k not in row})
            row["status"] = extra[i].get("status", "done")  # an LLM run the server failed is not done
        rows.append(row)
    return rows


def _run_baselines(plans: Sequence[Plan], horizon: int) -> list[dict[str, Any]]:
    """Q-learning or random runs of one (agent, swimmer, action set) group, vectorised."""
    p0 = plans[0]
    base = env.make_params(p0.swimmer)
    init = np.array([[-1] * base.n_dof if isinstance(p.init, str) else list(p.init) for p in plans], np.int32)
    params = qlearning.batch_params(base, len(plans), zeta=np.array([p.zeta for p in plans]),
                                    direction=np.array([p.direction for p in plans], float), init=init)
    keys = jax.vmap(jax.random.PRNGKey)(np.array([env.seed32(p.seed) for p in plans], np.uint32))
    if p0.agent == "qlearning":
        cfg = qlearning.QConfig(steps=p0.steps, action_set=p0.action_set)
        run = qlearning.train_batch(keys, params, cfg, pose=True)
    else:
        run = random_policy.run_batch(keys, params, p0.steps, p0.action_set)
    return _judge_rows(plans, np.asarray(run.actions), np.asarray(run.x), np.asarray(run.levels0), horizon,
                       pose=(np.asarray(run.y), np.asarray(run.orientation)))


def _groups(plans: Iterable[Plan], *keys: str) -> dict[tuple, list[Plan]]:
    out: dict[tuple, list[Plan]] = {}
    for p in plans:
        out.setdefault(tuple(getattr(p, k) for k in keys), []).append(p)
    return out


@dataclass
class StudyResult:
    """What :func:`run_study` produced."""

    folder: Path
    rows: list[dict[str, Any]]
    summary: list[dict[str, Any]]
    figures: list[Path] = field(default_factory=list)
    wall_s: float = 0.0
    llm_speed: dict[str, float] = field(default_factory=dict)  # calls, billed calls, wall s, calls/s
    failed_runs: list[dict[str, Any]] = field(default_factory=list)  # run_id and the server's error
    truncated: dict[str, int] = field(default_factory=dict)  # max_tokens -> LLM replies cut off there


def study_backend(study: str, backend: Backend | None) -> Backend | None:
    """The backend a study runs with: a study that fixes its decoding (the ablation study:
    free text, :attr:`StudySpec.constrain`) overrides ``constrain="auto"``; an explicit
    ``--constrain`` is kept."""
    mode = SPECS[study].constrain if study in SPECS else None
    if backend is None or mode is None or backend.constrain != "auto":
        return backend
    return dataclasses.replace(backend, constrain=mode)


def identity(study: str, o: StudyOptions, backend: Backend | None) -> dict[str, Any]:
    """Everything that defines a study's runs (compared when a folder is resumed)."""
    backend = study_backend(study, backend)
    opts = dataclasses.asdict(o)
    opts.pop("chunk")
    for name in ("variant", "variants"):  # left out when unset, so older folders keep their identity
        if opts[name] is None:
            opts.pop(name)
    if study == "swim" and o.variant is None and SWIM_VARIANT != "paper":
        opts["variant"] = SWIM_VARIANT
    template = PromptTemplate.from_file(o.prompt_file) if o.prompt_file else PromptTemplate()
    tpl = json.dumps(dataclasses.asdict(template), sort_keys=True)
    return {
        "study": study, "options": opts, "seed": o.seed,
        "backend": backend.describe() if backend is not None and "llm" in o.agents else None,
        "prompt_template_sha256": hashlib.sha256(tpl.encode()).hexdigest()[:16],
    }


def default_folder(study: str, o: StudyOptions, backend: Backend | None, root: str = "jswim-out") -> Path:
    """``jswim-out/<study>-<hash>``: the same settings reuse (and resume) the same folder.

    The hash is taken over the identity with its fields under their earlier names
    (:func:`jswim.results.legacy_names`), so folders made before the rename are found again."""
    ident = legacy_names(identity(study, o, backend))
    digest = hashlib.sha256(json.dumps(ident, sort_keys=True, default=str).encode())
    return Path(root) / f"{study}-{digest.hexdigest()[:8]}"


#: ``progress(phase, runs_done, runs_total, info)``; ``info`` is a short status text.
ProgressFn = Callable[[str, int, int, str], None]


def run_study(
    study: str,
    options: StudyOptions = StudyOptions(),
    backend: Backend | None = Backend(),
    out: str | Path | None = None,
    progress: ProgressFn | None = None,
    figures: bool = True,
) -> StudyResult:
    """Run (or resume) a study and write its folder.

    Parameters
    ----------
    study : str
        One of :data:`STUDIES`.
    options : StudyOptions
        Grid and agent knobs.
    backend : Backend or None
        LLM server (default: the embedded model); needed only when the study has LLM runs.
    out : path, optional
        Study folder (default :func:`default_folder`). Finished runs found there are kept.
    progress : callable, optional
        ``progress(phase, done, total, info)`` (:data:`ProgressFn`): after each finished batch of
        runs and each LLM round (phase ``"llm"``), and every 0.5 s while LLM requests are out
        (phase ``"llm-live"``: steps done, requests in flight, tokens, cache hits, shared calls).
    figures : bool
        Also draw the study's figures into ``out/figures``.
    """
    t0 = time.perf_counter()
    backend = study_backend(study, backend)
    plans = build(study, options)
    if not plans:
        raise ConfigError(f"these settings give the {study} study no runs at all (--runs 0 and --q-runs 0?); "
                          "nothing to do")
    ident = identity(study, options, backend)
    if study == "competence":  # the variants' switches define the runs too
        ident["variants"] = {v: VARIANTS[v] for v in options.variants or COMPETENCE_VARIANTS}
    folder = Path(out) if out is not None else default_folder(study, options, backend)
    template = PromptTemplate.from_file(options.prompt_file) if options.prompt_file else None
    store = StudyStore(folder, study, ident, extra={
        "jswim_version": __version__, "jax_version": jax.__version__, "python": platform.python_version(),
        "prompt_template": dataclasses.asdict(template or PromptTemplate()),
        "success_criterion": Criterion(horizon=options.horizon).describe(),
        "horizon": options.horizon,
        "llm_variants": list(options.variants or COMPETENCE_VARIANTS) if study == "competence"
        else [options.llm_variant(study)],
        "n_planned": len(plans),  # so that a reader can tell an unfinished study (jswim show)
        # What differs from the paper's protocol in every LLM run (each transcript lists its own too).
        "fidelity_deviations": list(fidelity.ALWAYS),
    })
    try:
        return _run_in(store, study, plans, options, backend, folder, template, progress, figures, t0)
    except KeyboardInterrupt:
        store.set_status("interrupted")  # finished runs are kept; the same command resumes
        raise
    except JswimError as exc:
        store.set_status("stopped", error=str(exc))
        raise


def _run_in(store: StudyStore, study: str, plans: Sequence[Plan], options: StudyOptions, backend: Backend | None,
            folder: Path, template: PromptTemplate | None, progress: ProgressFn | None, figures: bool,
            t0: float) -> StudyResult:
    done = store.done_ids()
    todo = [p for p in plans if p.run_id not in done]
    if backend is not None and any(p.agent == "llm" for p in todo):
        backend.check()  # fail before the baselines, not after
    total = len(plans)
    finished = total - len(todo)
    tick = progress or (lambda phase, d, t, info="": None)
    tick("resume" if finished else "start", finished, total, f"{finished} runs already done" if finished else "")

    for (agent, _sw, _allowed), group in _groups([p for p in todo if p.agent != "llm"], "agent", "swimmer", "action_set").items():
        store.add_runs(_run_baselines(group, options.horizon))
        finished += len(group)
        tick(agent, finished, total, "")

    llm_plans = [p for p in todo if p.agent == "llm"]
    speed: dict[str, float] = {}
    if llm_plans:
        if backend is None:
            raise ConfigError("this study has LLM runs; give a backend")
        finished = _run_llm(llm_plans, options, backend, store, template, tick, finished, total, speed)

    rows = read_runs(folder)
    summary = summarize(rows)
    # LLM speed of the session that ran LLM runs (a resume with none to run keeps the earlier one).
    speed = speed or dict((store.meta.get("summary") or {}).get("llm_speed") or {})
    constraint = sorted({r["constraint"] for r in rows if r.get("agent") == "llm" and r.get("constraint")})
    failed = [{"run_id": r["run_id"], "error": r.get("error")} for r in rows if is_failed(r)]
    llm = [r for r in rows if r.get("agent") == "llm"]
    cut: dict[str, int] = {}  # max_tokens -> replies cut off there (the limit is per swimmer)
    for r in llm:
        if r.get("truncated"):
            cut[str(r.get("max_tokens"))] = cut.get(str(r.get("max_tokens")), 0) + r["truncated"]
    replies = {"truncated_replies": sum(cut.values()), "truncated_at": cut} if llm else {}
    store.finalize("incomplete" if failed else "complete",
                   {"groups": summary, "failed_runs": failed, **replies, **({"llm_speed": speed} if speed else {}),
                    **({"constrained_decoding": constraint} if constraint else {})})
    figs = draw_figures(study, rows, folder / "figures") if figures else []
    return StudyResult(folder, rows, summary, figs, time.perf_counter() - t0, speed, failed,
                       dict(replies.get("truncated_at", {})))


def _run_llm(plans: Sequence[Plan], o: StudyOptions, backend: Backend, store: StudyStore,
             template: PromptTemplate | None, tick: ProgressFn, finished: int, total: int,
             speed: dict[str, float] | None = None) -> int:
    """Run the LLM plans, one lockstep batch per (variant, action set) group and chunk.

    ``speed`` (filled in) gets the calls made, the calls the server answered, the wall time and
    calls per second of this session's LLM work.
    """
    def spec(p: Plan) -> LLMRunSpec:
        return LLMRunSpec(swimmer=p.swimmer, direction=p.direction, init=p.init, zeta=p.zeta, seed=p.seed,
                          n_steps=p.steps, n_ht=p.n_ht, drop=p.drop, run_id=p.run_id)

    steps_total = sum(p.steps for p in plans)
    steps_done = 0
    t_start = time.perf_counter()
    calls = {"calls": 0, "billed_calls": 0}

    live: list[LLMClient] = []  # the open client, for its running counts

    def report(phase: str = "llm") -> None:
        elapsed = time.perf_counter() - t_start
        rate = steps_done / max(elapsed, 1e-9)
        info = f"steps {steps_done}/{steps_total} {rate:.1f}/s"
        left = eta(elapsed, steps_done / steps_total if steps_total else 0.0)
        if left is not None and steps_done < steps_total:
            info += f" · ETA {left}"
        if live:
            c = live[0].counts
            info += f" · {c.in_flight} in flight · {c.tokens / 1000:.1f}k tok · {c.cache_hits} cached · {c.shared} shared"
        tick(phase, finished, total, info)

    def on_round(n: int) -> None:
        nonlocal steps_done
        steps_done += n
        report()

    async def keep_reporting() -> None:
        # Rounds of a slow model take seconds; show the requests in flight meanwhile.
        while True:
            await asyncio.sleep(0.5)
            report("llm-live")

    async def go(settings: Any) -> int:
        async with LLMClient(settings) as client:
            live.append(client)
            reporter = asyncio.ensure_future(keep_reporting())
            try:
                await _llm_chunks(client)
            finally:
                reporter.cancel()
                await asyncio.gather(reporter, return_exceptions=True)
        return finished

    async def _llm_chunks(client: Any) -> None:
        nonlocal finished
        for (variant, action_set), group in _groups(plans, "variant", "action_set").items():
            cfg = variant_config(variant, action_set=action_set, share_identical=o.share_identical, x_min=o.x_min,
                                 max_tokens=o.max_tokens, **({"template": template} if template else {}))
            for i in range(0, len(group), o.chunk):
                chunk = group[i: i + o.chunk]
                results = await run_batch_async([spec(p) for p in chunk], client, cfg,
                                                transcript_dir=store.folder / "transcripts", on_round=on_round,
                                                cohorts=min(backend.cohorts, len(chunk)))
                for r in results:
                    calls["calls"] += r.usage.calls
                    calls["billed_calls"] += r.usage.billed_calls
                rows = []
                by_swimmer = _groups(chunk, "swimmer")
                res_by_id = {r.run_id: r for r in results}
                for (_sw,), members in by_swimmer.items():
                    res = [res_by_id[p.run_id] for p in members]
                    steps = max(len(r.x) for r in res)
                    acts = np.array([r.actions + [1] * (steps - len(r.actions)) for r in res], np.int64)
                    xs = np.array([r.x + [r.x[-1] if r.x else 0.0] * (steps - len(r.x)) for r in res])
                    lv = np.array([r.levels0 for r in res], np.int64)
                    extra = [{k: v for k, v in r.as_row().items()
                              if k not in ("x", "actions", "progress", "stuck", "levels0")} for r in res]
                    rows += _judge_rows(members, acts, xs, lv, o.horizon, extra)
                store.add_runs(rows)
                finished += len(chunk)
                report()

    try:
        if backend.local:
            with backend.server() as srv:
                t_start = time.perf_counter()  # the model's loading time is not LLM work
                return run_sync(go(backend.client_settings(srv)))
        return run_sync(go(backend.client_settings()))
    finally:
        if speed is not None:
            wall = time.perf_counter() - t_start
            speed.update(calls, wall_s=wall, calls_per_s=calls["calls"] / wall if wall > 0 else 0.0,
                         billed_calls_per_s=calls["billed_calls"] / wall if wall > 0 else 0.0)
