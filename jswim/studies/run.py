"""Running a study: build its plans, run what is not done yet, store and summarise.

Execution groups the plans (:mod:`jswim.studies.grids`): Q-learning and random-policy runs
train/roll out in one vectorised call per swimmer; LLM runs are per-run pipelines
(:class:`jswim.agents.llm.LLMDriver`), each moving on as soon as its own reply is back, and each
lands in the study folder (:class:`jswim.results.StudyStore`) the moment it ends. Every answered
call is journaled first (``calls.jsonl``, :class:`jswim.llm.journal.CallJournal`), so an
interrupted or capped study resumes without paying for a call twice. Every run, whatever its
agent, is judged by the same code, :func:`jswim.judging.gait.judge`, with the study's
:class:`jswim.judging.gait.Criterion`.

A study's identity (what a folder is compared on when resumed) is what defines its runs: the
grid's settings, the seed, the model and its sampling, the prompt template. Not in it: the
server's address (a restarted server on another port serves the same study), the concurrency,
pacing and cost cap, and how many runs or which noise levels / n_ht values the grid has (a
larger ``--runs`` or another noise level extends the folder; each run's seed comes from the
study seed and its own id, so existing runs never change).
"""

from __future__ import annotations

import asyncio
import dataclasses
import errno
import hashlib
import json
import platform
import time
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

import jax
import numpy as np

from jswim import __version__, env
from jswim.agents import fidelity
from jswim.agents.llm import RunResult, run_batch_async
from jswim.agents.variants import VARIANTS, LLMRunSpec, variant_config
from jswim.console import eta
from jswim.judging import lattice
from jswim.errors import ConfigError, JswimError, JswimWarning
from jswim.judging.gait import Criterion, GaitReport, judge
from jswim.llm.backend import Backend
from jswim.llm.budget import Budget
from jswim.llm.credentials import scrub
from jswim._io.permissions import private_files
from jswim.llm.client import ClientSettings, LLMClient
from jswim.llm.dryrun import Estimate, EstimatingClient, estimate
from jswim.llm.journal import CallJournal
from jswim.llm.pacing import Pacer
from jswim.llm.probe import ServerInfo
from jswim.llm.sampling import describe as describe_sampling
from jswim.llm.errors import LLMError
from jswim.llm.urls import is_local_host
from jswim.llm.usage import PRICES_AS_OF, UsageTotals, cap_refusal
from jswim.llm.sync import run_sync
from jswim.prompt import PromptTemplate
from jswim.scenes import Scene
from jswim.results import StudyFolderError, StudyStore, is_failed, read_runs, write_json, writing
from jswim.studies.grids import (ALL_AGENTS, AGENTS, COMPETENCE_VARIANTS, CONTINUOUS_AGENT, SPECS, SWIM_VARIANT, Plan,
                                 StudyOptions, build)
from jswim.studies import prompt_files
from jswim.studies.report import draw_figures, summarize


# -- execution ----------------------------------------------------------------------------------


def _judge_rows(plans: Sequence[Plan], actions: np.ndarray, xs: np.ndarray, levels0: np.ndarray,
                horizon: int, extra: Sequence[dict[str, Any]] | None = None,
                pose: tuple[np.ndarray, np.ndarray] | None = None, report: GaitReport | None = None,
                moves: Sequence[list[list[float]]] | None = None) -> list[dict[str, Any]]:
    """Rows for a batch of runs of one swimmer and ROC lattice, judged by the shared success criterion.

    ``levels0`` holds the starts' lattice positions (levels on the paper's K = 1). ``pose``
    gives the centroid y and the orientation after each step, shape ``(runs, steps)`` each, for
    the trajectories (LLM runs bring theirs in ``extra``). The real-valued agent brings its own
    ``report`` (:func:`jswim.agents.ppo.evaluate`) and ``moves`` (``[dof, roc]`` per step)."""
    p0 = plans[0]
    k = p0.roc_levels
    params = env.make_params(p0.swimmer)
    params = params.replace(direction=np.array([p.direction for p in plans], float))
    rep = report if report is not None else judge(actions, params, levels0=levels0,
                                                 criterion=Criterion(horizon=horizon), roc_levels=k)
    rows = []
    for i, p in enumerate(plans):
        x = [float(v) for v in xs[i]]
        prog = np.diff(np.concatenate([[0.0], xs[i]])) * p.direction
        row = {
            "run_id": p.run_id, "agent": p.agent, "swimmer": p.swimmer, "direction": p.direction,
            "init": "".join("+" if v > 0 else "-" for v in levels0[i]), "zeta": p.zeta, "seed": p.seed,
            "n_ht": p.n_ht, "drop": ",".join(sorted(p.drop)), "action_set": p.action_set, "group": p.group,
            "variant": p.variant,
            "steps": len(x), "final_x": x[-1] if x else 0.0,
            "signed_final_x": p.direction * (x[-1] if x else 0.0),
            "success": bool(rep.success[i]), "learned": bool(rep.learned[i]),
            "steps_to_learn": int(rep.steps_to_learn[i]) if rep.learned[i] else None,
            "period": int(rep.period[i]),
            "roc_levels": k, "sample": p.sample,
            "x": x, "actions": moves[i] if moves is not None else [list(lattice.decode(int(a), max(k, 1)))
                                                                  for a in actions[i]],
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
    """Q-learning, random or continuous-RL runs of one (agent, swimmer, action set, ROC lattice)
    group, vectorised."""
    p0 = plans[0]
    if p0.scene:  # walls, pairs, Purcell above a wall (issues 19, 34): the stroke and the baselines on the scene
        from jswim.studies import scenes  # lazy: start-up (the scene baselines' module, for scene studies only)

        return scenes.run_baselines(plans, horizon)
    if p0.agent == CONTINUOUS_AGENT:
        return _run_continuous(plans, horizon)
    from jswim.agents import qlearning, random_policy  # lazy: optax and their jits, for baselines only

    base = env.make_params(p0.swimmer, **_lattice(p0.roc_levels))
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


def _lattice(roc_levels: int) -> dict[str, int]:
    """``make_params`` keywords of a ROC lattice (none for the paper's K = 1)."""
    return {} if roc_levels == 1 else {"roc_levels": roc_levels}


def _run_continuous(plans: Sequence[Plan], horizon: int) -> list[dict[str, Any]]:
    """The real-valued RL baseline (:mod:`jswim.agents.ppo`) for one swimmer, judged on shapes
    (:func:`jswim.agents.ppo.evaluate`: :func:`jswim.judging.shape_judge.judge_shapes` on displacements
    replayed exactly, without noise)."""
    from jswim.agents import ppo, qlearning

    p0 = plans[0]
    base = env.make_params(p0.swimmer)
    init = np.array([[-1] * base.n_dof if isinstance(p.init, str) else list(p.init) for p in plans], np.int32)
    params = qlearning.batch_params(base, len(plans), zeta=np.array([p.zeta for p in plans]),
                                    direction=np.array([p.direction for p in plans], float), init=init)
    keys = jax.vmap(jax.random.PRNGKey)(np.array([env.seed32(p.seed) for p in plans], np.uint32))
    run = ppo.train_batch(keys, params, ppo.PPOConfig(steps=p0.steps))
    rocs, dofs0 = np.asarray(run.actions, np.float64), np.asarray(run.dofs0, np.float64)
    rep = ppo.evaluate(run, params, criterion=Criterion(horizon=horizon))
    dof = np.asarray(run.dof, np.int64)
    moves = [[[int(d), float(rocs[i, t, d - 1])] for t, d in enumerate(dof[i])] for i in range(len(plans))]
    span = base.model.hi - base.model.lo
    corners = np.rint((dofs0 - base.model.lo) / span).astype(np.int64)  # the starts are corners
    return _judge_rows(plans, np.zeros(dof.shape, np.int64), np.asarray(run.x), corners, horizon,
                       pose=(np.asarray(run.y), np.asarray(run.orientation)), report=rep, moves=moves)


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
    # This session's LLM calls, billed calls, wall s, calls/s, cost (empty when it ran no LLM run: a
    # resume of a finished study); the metadata summary keeps the last session that ran some.
    llm_speed: dict[str, float] = field(default_factory=dict)
    failed_runs: list[dict[str, Any]] = field(default_factory=list)  # run_id and the server's error
    truncated: dict[str, int] = field(default_factory=dict)  # max_tokens -> LLM replies cut off there
    stopped: str | None = None  # "cost cap" when --max-cost stopped the study before its end
    total: int = 0  # runs in the study's grid
    reasoning: dict[str, Any] = field(default_factory=dict)  # what a reasoning model was sent (jswim.llm.reasoning)
    cut_thinking: int = 0  # LLM replies cut while the model was still reasoning (never executed)
    notes: list[str] = field(default_factory=list)  # what was sent for sampling, decoding fallbacks, pricing


#: Options that say how large the grid is, not what its runs are: left out of the identity, so a
#: folder grows when they grow (and a smaller value reports the runs it names).
GRID_SIZE = ("runs", "q_runs", "zetas", "n_hts", "temperatures", "prompt_files", "samples", "roc_levels_grid",
             "heights", "separations", "phases", "school_sizes", "formations")

#: How run seeds are made (``jswim.studies.grids.run_seed``); folders made otherwise are refused.
SEEDS = "hash of the study seed and the run id"

#: The study's prompt template (written once per folder; its hash is in the identity).
PROMPT_FILE = "prompt_template.json"

#: Statuses of an LLM run that are stored; one stopped by the cost cap or an interrupt is not, and
#: starts again on resume (its paid calls replayed from the journal).
STORED = ("done", "below_x_min", "llm_error")


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
    for name in ("chunk", *GRID_SIZE):
        opts.pop(name, None)
    for name in ("variant", "variants"):  # left out when unset, so older folders keep their identity
        if opts[name] is None:
            opts.pop(name)
    if opts["roc_levels"] == 1:  # the paper's ROC set: as before --roc-levels existed
        opts.pop("roc_levels")
    if opts["pair_prompt"] == "joint":  # the default: as before --pair-prompt existed
        opts.pop("pair_prompt")
    if tuple(o.agents) == ALL_AGENTS:  # the default, written as before the continuous agent existed
        opts["agents"] = AGENTS
    if study == "swim" and o.variant is None and SWIM_VARIANT != "paper":
        opts["variant"] = SWIM_VARIANT
    template = PromptTemplate.from_file(o.prompt_file) if o.prompt_file else PromptTemplate()
    tpl = json.dumps(dataclasses.asdict(template), sort_keys=True)
    return {
        "study": study, "options": opts, "seed": o.seed, "seeds": SEEDS,
        "backend": backend.describe() if backend is not None and "llm" in o.agents else None,
        "prompt_template_sha256": hashlib.sha256(tpl.encode()).hexdigest()[:16],
    }


def default_folder(study: str, o: StudyOptions, backend: Backend | None, root: str = "jswim-out") -> Path:
    """``jswim-out/<study>-<hash of the identity>``: the same settings reuse (and resume, or
    extend) the same folder."""
    ident = identity(study, o, backend)
    digest = hashlib.sha256(json.dumps(ident, sort_keys=True, default=str).encode())
    return Path(root) / f"{study}-{digest.hexdigest()[:8]}"


#: ``progress(phase, done, total, info)``: runs done of the study's runs, except in the phases
#: ``"llm"`` and ``"llm-live"``, where the work counted is LLM steps (runs are in ``info``);
#: ``info`` is a short status text.
ProgressFn = Callable[[str, int, int, str], None]


@private_files()  # the folder and the cache: owner only under the usual umask (jswim._io.permissions)
def run_study(
    study: str,
    options: StudyOptions = StudyOptions(),
    backend: Backend | None = Backend(),
    out: str | Path | None = None,
    progress: ProgressFn | None = None,
    figures: bool = True,
    max_cost: float | None = None,
) -> StudyResult:
    """Run (or resume, or extend) a study and write its folder.

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
        baseline runs (runs done of all), and after each finished LLM run (phase ``"llm"``) and
        every 0.5 s while LLM requests are out (phase ``"llm-live"``), counting LLM steps done of
        all the session's LLM steps, with runs, requests in flight, tokens and cost in ``info``.
    figures : bool
        Also draw the study's figures into ``out/figures``.
    max_cost : float, optional
        Cap in USD on what the study's calls cost, over all its sessions (the call journal's
        total). Calls reserve their cost bound before they go out; at the cap no new call is
        made, runs in flight finish their call, finished runs are kept, the folder's status reads
        ``stopped at the cost cap`` and :attr:`StudyResult.stopped` is ``"cost cap"``. The same
        call with a higher cap goes on from there, paying no call twice.

    Raises
    ------
    ConfigError
        For a negative cap or an LLM study without a backend.
    """
    if max_cost is not None and not (max_cost >= 0):
        raise ConfigError(f"--max-cost must be a number of dollars >= 0, got {max_cost}")
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
    prompts = prompt_files.check(folder, options)  # an edited prompt file never resumes into old runs
    store = StudyStore(folder, study, ident, extra={
        **prompts,  # each prompt file's name and the hash of its bytes (jswim.studies.prompt_files)
        "jswim_version": __version__, "jax_version": jax.__version__, "python": platform.python_version(),
        # The template itself is in prompt_template.json, written once (below), not in every
        # rewrite of metadata.json at each status change.
        "prompt_template_file": PROMPT_FILE,
        "success_criterion": Criterion(horizon=options.horizon).describe(),
        "horizon": options.horizon,
        "llm_variants": list(options.variants or COMPETENCE_VARIANTS) if study == "competence"
        else [options.llm_variant(study)],
        "n_planned": len(plans),  # so that a reader can tell an unfinished study (jswim show)
        # The grid's order of its groups (n_ht 1, 2, ..., 10): readers show them so, not as runs finished.
        "group_order": list(dict.fromkeys(p.group for p in plans)),
        # What differs from the paper's protocol in every LLM run (each transcript lists its own too),
        # and the extensions some runs use (finer or real-valued ROCs).
        "fidelity_deviations": list(fidelity.ALWAYS) + fidelity.study_extensions({p.roc_levels for p in plans})
        + _scene_extensions(plans),
        "roc_levels": sorted({p.roc_levels for p in plans}),
        "grid": {k: getattr(options, k) for k in GRID_SIZE},
        "server": backend.address() if backend is not None else None,
        "prices_as_of": (backend.prices_as_of if backend is not None and backend.prices_as_of else PRICES_AS_OF),
    })
    try:
        for note in store.repairs:
            warnings.warn(FolderRepaired(f"{folder}: {note}"), stacklevel=2)
        store.meta.pop("prompt_template", None)  # folders before prompt_template.json had it here
        tpl_path = folder / PROMPT_FILE
        if not tpl_path.exists():  # the identity holds its hash: a resumed folder has this very template
            with writing(folder):
                write_json(tpl_path, dataclasses.asdict(template or PromptTemplate()))
        return _run_in(store, study, plans, options, backend, folder, template, progress, figures, t0, max_cost)
    except KeyboardInterrupt:
        _record_status(store, "interrupted")  # finished runs are kept; the same command resumes
        raise
    except JswimError as exc:
        # A session that stops before changing anything (a refused cap, a server that is not there)
        # leaves the folder's status as it was; otherwise it says stopped, and why.
        if not store.restore_status():
            _record_status(store, "stopped", error=scrub(str(exc)))  # never a key, however the message got it
        raise
    except OSError as exc:  # a full disk or an I/O error outside the store's own writes
        msg = f"cannot write {exc.filename or folder}: {exc.strerror or exc}"
        if not store.restore_status():
            _record_status(store, "stopped", error=msg)
        if exc.errno in (errno.ENOSPC, errno.EDQUOT):
            hint = "make room and run the same command to resume"
        elif exc.errno in (errno.EEXIST, errno.ENOTDIR, errno.EISDIR):
            hint = "a file or folder is in the way of one jswim writes: move it away and run the same command"
        else:
            hint = "fix that and run the same command to resume"
        raise StudyFolderError(f"{msg}; every finished run and answered call is kept in {folder}: {hint}") from None
    finally:
        store.close()  # the folder's lock: the next session may start


def _scene_extensions(plans: Sequence[Plan]) -> list[str]:
    """The fidelity lines of the scenes a study's runs use (none in the paper's studies)."""
    scenes = sorted({(p.scene, p.pair_prompt) for p in plans if p.scene})
    if not scenes:
        return []
    ppo = any(p.scene and p.agent == CONTINUOUS_AGENT for p in plans)
    return fidelity.scene_extensions([(Scene.from_dict(json.loads(s)), pair) for s, pair in scenes], ppo=ppo)


class FolderRepaired(JswimWarning):
    """Opening a study folder repaired it (a torn journal line cut, a temporary file removed)."""


def _record_status(store: StudyStore, status: str, **fields: Any) -> None:
    """``store.set_status`` where the folder still takes it (a full disk may refuse even that)."""
    try:
        store.set_status(status, **fields)
    except (OSError, StudyFolderError):
        pass


def _run_in(store: StudyStore, study: str, plans: Sequence[Plan], options: StudyOptions, backend: Backend | None,
            folder: Path, template: PromptTemplate | None, progress: ProgressFn | None, figures: bool,
            t0: float, max_cost: float | None = None) -> StudyResult:
    done = store.done_ids()
    todo = [p for p in plans if p.run_id not in done]
    info: ServerInfo | None = None
    if backend is not None and not backend.local and any(p.agent == "llm" for p in todo):
        info = _preflight(store, backend, max_cost=max_cost)  # fail before the baselines, not after
    total = len(plans)
    finished = total - len(todo)
    tick = progress or (lambda phase, d, t, info="": None)
    tick("resume" if finished else "start", finished, total, f"{finished} runs already done" if finished else "")

    for (agent, *_), group in _groups([p for p in todo if p.agent != "llm"], "agent", "swimmer", "action_set",
                                      "roc_levels", "scene", "variant", "zeta").items():
        store.add_runs(_run_baselines(group, options.horizon))
        finished += len(group)
        tick(agent, finished, total, "")

    llm_plans = [p for p in todo if p.agent == "llm"]
    speed: dict[str, float] = {}
    sent: dict[str, Any] = {}
    notes: list[str] = []
    capped = False
    if llm_plans:
        if backend is None:
            raise ConfigError("this study has LLM runs; give a backend")
        finished, capped = _run_llm(llm_plans, options, backend, store, template, tick, finished, total, speed,
                                    max_cost, sent, info, notes)

    # The study is the runs its grid names now (a folder may hold more, from a larger --runs).
    names = {p.run_id: i for i, p in enumerate(plans)}
    rows = sorted((r for r in read_runs(folder) if r["run_id"] in names), key=lambda r: names[r["run_id"]])
    summary = summarize(rows)
    scene_table = _scene_table(rows)
    # LLM speed of the session that ran LLM runs (a resume with none to run keeps the earlier one).
    session_speed = dict(speed)
    speed = speed or dict((store.meta.get("summary") or {}).get("llm_speed") or {})
    constraint = sorted({r["constraint"] for r in rows if r.get("agent") == "llm" and r.get("constraint")})
    failed = [{"run_id": r["run_id"], "error": r.get("error")} for r in rows if is_failed(r)]
    llm = [r for r in rows if r.get("agent") == "llm"]
    cut: dict[str, int] = {}  # max_tokens -> replies cut off there (the limit is per swimmer)
    for r in llm:
        if r.get("truncated"):
            cut[str(r.get("max_tokens"))] = cut.get(str(r.get("max_tokens")), 0) + r["truncated"]
    replies = {"truncated_replies": sum(cut.values()), "truncated_at": cut} if llm else {}
    cut_thinking = sum(r.get("cut_thinking") or 0 for r in llm)
    if llm:
        replies["cut_while_thinking"] = cut_thinking
        replies["reasoning_tokens"] = sum(r.get("reasoning_tokens") or 0 for r in llm)
    # What a reasoning model was sent (this session's, else the one that ran LLM runs).
    sent = sent or dict((store.meta.get("summary") or {}).get("reasoning") or {})
    status = "stopped at the cost cap" if capped else "incomplete" if failed else "complete"
    store.finalize(status,
                   {"groups": summary, **scene_table, "failed_runs": failed, **replies, **({"llm_speed": speed} if speed else {}),
                    **({"reasoning": sent} if sent else {}),
                    **({"constrained_decoding": constraint} if constraint else {})})
    figs = draw_figures(study, rows, folder / "figures") if figures else []
    _write_report(folder, figures)
    return StudyResult(folder, rows, summary, figs, time.perf_counter() - t0, session_speed, failed,
                       dict(replies.get("truncated_at", {})), "cost cap" if capped else None, total, sent,
                       cut_thinking, notes)


def _scene_table(rows: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """``{"scenes": table}`` of a study with scene runs (:func:`jswim.studies.scenes.scene_summary`), else ``{}``."""
    if not any(r.get("scene") for r in rows):
        return {}
    from jswim.studies import scenes

    return {"scenes": scenes.scene_summary([r for r in rows if not is_failed(r)])}


def cap_check(backend: Backend, info: ServerInfo | None, max_cost: float | None) -> None:
    """Refuse a cost cap the study's calls could not reach (:func:`jswim.llm.usage.cap_refusal`),
    by the pricing rule of the run and of its dry run alike: the server's listed models
    (``info``), the host, ``--price-local`` and ``--prices``.

    Raises
    ------
    ConfigError
        One line naming ``--prices``, before any request is sent.
    """
    if backend.local or max_cost is None:
        return
    s = backend.client_settings(info=info)
    why = cap_refusal(s.prices, s.model, max_cost, local_host=is_local_host(s.base_url), listed=s.listed_models,
                      price_local=s.price_local)
    if why is not None:
        raise ConfigError(why)


def _preflight(store: StudyStore, backend: Backend, server: Any = None, max_cost: float | None = None) -> ServerInfo:
    """The server's preflight (:meth:`Backend.preflight`), recorded in the study's metadata
    (``llm_server``); its warnings go out as :class:`~jswim.errors.JswimWarning`. A cost cap the
    calls could not reach is refused here (:func:`cap_check`), before the status says running."""
    info = backend.preflight(server)
    cap_check(backend, info, max_cost)
    store.set_status("running", llm_server=info.metadata())
    for text in info.warnings:
        warnings.warn(text, JswimWarning, stacklevel=3)
    return info


def _record_session(store: StudyStore, backend: Backend, info: ServerInfo, client: LLMClient,
                    notes: list[str]) -> None:
    """What the session sent and what the server made of it: the sampling fields (with the
    server's reported defaults, from the preflight), the decoding form ``auto`` settled on, and
    why calls were not priced; into the metadata's ``llm_server`` and the printed ``notes``."""
    s = client.settings
    record = dict(store.meta.get("llm_server") or info.metadata())
    record.update(sampling={"preset": backend.sampling, "sent": dict(s.sampling)},
                  max_concurrency=s.max_concurrency)
    notes.append(describe_sampling(backend.sampling, backend.family(info), s.sampling))
    if client.fallbacks:
        record["constrain_fallbacks"] = list(client.fallbacks)
        for f in client.fallbacks:
            notes.append(f"constrained decoding: the server rejected {f['rejected']} ({f['server']}); "
                         f"--constrain auto moved on to {f['next']}")
    if client.unpriced:
        record["unpriced"] = client.unpriced
        notes.append(f"cost: {client.unpriced}")
    store.set_status(store.meta.get("status", "running"), llm_server=record)


def _write_report(folder: Path, figures: bool) -> None:
    """``report.html`` of the finished session (:mod:`jswim.viz.page`), with the figures just drawn.

    The runs are safe on disk by now: a page that cannot be written is a warning, not a lost study."""
    from jswim.viz.page import write_report  # lazy: the page's code loads only at the end

    try:
        write_report(folder, figures="files" if figures else "none")
    except Exception as exc:  # noqa: BLE001 - the study's results are written; say why the page is not
        warnings.warn(f"report.html not written ({type(exc).__name__}: {exc}); jswim report {folder} retries",
                      stacklevel=2)


def _spec(p: Plan) -> LLMRunSpec:
    return LLMRunSpec(swimmer=p.swimmer, direction=p.direction, init=p.init, zeta=p.zeta, seed=p.seed,
                      n_steps=p.steps, n_ht=p.n_ht, drop=p.drop, run_id=p.run_id, roc_levels=p.roc_levels,
                      scene=p.scene, pair_prompt=p.pair_prompt)


def _configs(plans: Sequence[Plan], o: StudyOptions,
             template: PromptTemplate | None) -> list[tuple[Any, list[Plan]]]:
    """The LLM plans by agent config: one driver per (variant, action set)."""
    out = []
    for (variant, action_set, temp, prompt), group in _groups(plans, "variant", "action_set", "temperature",
                                                              "prompt_file").items():
        tpl = PromptTemplate.from_file(prompt) if prompt else template
        cfg = variant_config(variant, action_set=action_set, share_identical=o.share_identical, x_min=o.x_min,
                             max_tokens=o.max_tokens, **({"template": tpl} if tpl else {}))
        if temp is not None:  # a sweep's temperature (each request above 0 carries its own seed)
            cfg = dataclasses.replace(cfg, temperature=temp)
        out.append((cfg, group))
    return out


def _row(plan: Plan, r: RunResult, horizon: int) -> dict[str, Any]:
    """The judged result row of one finished LLM run."""
    acts = np.array([r.actions], np.int64).reshape(1, len(r.actions))
    xs = np.array([r.x], float).reshape(1, len(r.x))
    if plan.scene:  # a scene run: judged per swimmer, with the scene's columns (jswim.studies.scenes)
        from jswim.studies import scenes

        extra = {k: v for k, v in r.as_row().items() if k not in ("x", "actions", "progress", "levels0")}
        return scenes.llm_row(plan, r, horizon, extra)
    extra = {k: v for k, v in r.as_row().items() if k not in ("x", "actions", "progress", "stuck", "levels0")}
    # The judge reads the start as lattice positions: a corner level times K.
    return _judge_rows([plan], acts, xs, np.array([r.levels0], np.int64) * plan.roc_levels, horizon, [extra])[0]


def _run_llm(plans: Sequence[Plan], o: StudyOptions, backend: Backend, store: StudyStore,
             template: PromptTemplate | None, tick: ProgressFn, finished: int, total: int,
             speed: dict[str, float], max_cost: float | None, sent: dict[str, Any] | None = None,
             info: ServerInfo | None = None, notes: list[str] | None = None) -> tuple[int, bool]:
    """Run the LLM plans as per-run pipelines; returns (runs finished, stopped by the cost cap).

    At most ``o.chunk`` runs (default: the concurrency) are in progress at once, across all the
    study's agent configs; a run that ends is stored at once and the next one starts, so runs
    finish, and are saved, one by one. ``speed`` (filled in) gets this session's calls (made,
    billed, replayed from the journal), wall time, tokens and cost; ``sent`` what a reasoning
    model was sent (:meth:`jswim.llm.reasoning.ReasoningState.describe`).
    """
    by_id = {p.run_id: p for p in plans}
    steps_total = sum(p.steps for p in plans)
    steps_done = 0
    t_start = time.perf_counter()
    totals = {"calls": 0, "billed_calls": 0, "replayed_calls": 0}
    journal = CallJournal(store.folder)
    spent_before = journal.spent_usd
    calls_before = journal.n_calls
    # Earlier sessions' requests that got no answer may have been billed: still under the cap.
    unanswered_before = float((store.meta.get("llm_totals") or {}).get("unanswered_usd") or 0.0)
    budget = Budget(max_cost, spent_usd=spent_before, unanswered_usd=unanswered_before)
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
            info += f" · {c.in_flight} in flight · {c.tokens / 1000:.1f}k tok · ${budget.spent_usd:.4f}"
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
            store.add_runs([_row(by_id[r.run_id], r, o.horizon)])
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
            _record_session(store, backend, info, client, notes if notes is not None else [])
            window = asyncio.Semaphore(o.chunk or settings.max_concurrency)
            reporter = asyncio.ensure_future(keep_reporting())
            try:
                await asyncio.gather(*[
                    run_batch_async([_spec(p) for p in group], client, cfg, store.folder / "transcripts",
                                    window=window, journal=journal, on_step=on_step, on_done=on_done)
                    for cfg, group in _configs(plans, o, template)
                ])
            finally:
                reporter.cancel()
                await asyncio.gather(reporter, return_exceptions=True)
                if notes is not None:  # fallbacks and pricing are known once calls were answered
                    notes.clear()
                _record_session(store, backend, info, client, notes if notes is not None else [])

    # --max-tokens is also the reasoning budget, once reasoning is on (jswim.llm.reasoning).
    room = {"reasoning_max_tokens": o.max_tokens} if o.max_tokens is not None else {}
    try:
        if backend.local:
            with backend.server() as srv:
                info = _preflight(store, backend, srv)
                t_start = time.perf_counter()  # the model's loading time is not LLM work
                run_sync(go(backend.client_settings(srv, info, **room), info))
        else:
            info = info or _preflight(store, backend, max_cost=max_cost)
            run_sync(go(backend.client_settings(info=info, **room), info))
    finally:
        journal.close()
        if journal.n_calls > calls_before:
            store.changed = True  # calls were paid for: the folder's status must say how it ended
        if live and sent is not None and (live[0].reasoning.active or live[0].reasoning.notes
                                          or live[0].reasoning.effort):
            sent.update(live[0].reasoning.describe())
        wall = time.perf_counter() - t_start
        c = live[0].counts if live else None
        speed.update(totals, wall_s=wall, calls_per_s=totals["calls"] / wall if wall > 0 else 0.0,
                     billed_calls_per_s=totals["billed_calls"] / wall if wall > 0 else 0.0,
                     tokens=c.tokens if c else 0, cost_usd=budget.spent_usd - spent_before,
                     study_cost_usd=budget.spent_usd, requests=c.requests if c else 0,
                     retries=c.retries if c else 0, faults=dict(sorted(c.faults.items())) if c else {},
                     unanswered=c.unanswered if c else 0, unanswered_usd=c.unanswered_usd if c else 0.0)
        store.meta["llm_totals"] = add_session(store.meta.get("llm_totals"), speed, journal.n_calls)
    return finished, budget.exhausted


def add_session(totals: dict[str, Any] | None, speed: dict[str, Any], answered_calls: int) -> dict[str, Any]:
    """The study's LLM totals over all its sessions, with one more session's ``speed``.

    ``answered_calls`` is the call journal's count (every answered call of the study, all
    sessions, finished runs or not), so calls per second divide the study's calls by the study's
    LLM wall time, never one session's by another's. ``requests`` are HTTP requests sent (what
    the server counts: first attempts and retries), ``faults`` transient failures by kind,
    ``unanswered`` requests sent whole that got no answer (the server may have billed them; at most
    ``unanswered_usd``).
    """
    t = dict(totals or {})
    t["sessions"] = int(t.get("sessions", 0)) + 1
    for k in ("wall_s", "requests", "retries", "billed_calls", "replayed_calls", "tokens", "unanswered",
              "unanswered_usd"):
        t[k] = (t.get(k) or 0) + (speed.get(k) or 0)
    faults = dict(t.get("faults") or {})
    for k, n in (speed.get("faults") or {}).items():
        faults[k] = faults.get(k, 0) + n
    t["faults"] = dict(sorted(faults.items()))
    t["answered_calls"] = answered_calls
    t["calls_per_s"] = answered_calls / t["wall_s"] if t["wall_s"] > 0 else 0.0
    return t


def estimate_study(
    study: str, options: StudyOptions = StudyOptions(), backend: Backend | None = Backend(),
    out: str | Path | None = None, max_cost: float | None = None,
) -> Estimate:
    """What the study's LLM runs not yet done would cost (``--dry-run``); no chat request is sent.

    The runs go through the real driver against :class:`jswim.llm.dryrun.EstimatingClient`, so
    the prompts are rendered from real swimmer states; the study folder is read (to skip the
    runs it has) but never written. A remote server is asked its ``/v1/models`` (free), so the
    dry run prices the calls by the very rule the run will (a model the server does not list is
    not priced at a list price); when it cannot be asked, the estimate says so. With
    ``max_cost``, :attr:`Estimate.cap_refusal` is the line the run would refuse with, if any.
    """
    if backend is None:
        raise ConfigError("a dry run needs a backend (the model to price)")
    backend = study_backend(study, backend)
    plans = [p for p in build(study, options) if p.agent == "llm"]
    folder = Path(out) if out is not None else default_folder(study, options, backend)
    prompt_files.check(folder, options)  # the same refusal as the study itself
    done = {r["run_id"] for r in read_runs(folder)}
    plans = [p for p in plans if p.run_id not in done]
    template = PromptTemplate.from_file(options.prompt_file) if options.prompt_file else None
    if backend.local:  # no server is started: the settings only name the model and the limits
        settings = ClientSettings(base_url="http://127.0.0.1/v1", model=backend.describe()["model"],
                                  temperature=backend.temperature)
    info, unasked = None, None
    if not backend.local:
        try:
            info = backend.preflight(timeout_s=min(backend.timeout_s or 5.0, 5.0))
        except (LLMError, ConfigError) as exc:  # no server (yet), no key: price as if it lists the model
            unasked = f"could not ask the server which models it lists ({scrub(str(exc)).split(';')[0]})"
    if not backend.local:  # --max-tokens is also the reasoning budget, as in the study itself
        settings = backend.client_settings(info=info, **({"reasoning_max_tokens": options.max_tokens}
                                                          if options.max_tokens is not None else {}))
    refusal = None
    if max_cost is not None and not backend.local:
        try:
            cap_check(backend, info, max_cost)
        except ConfigError as exc:
            refusal = str(exc)
    client = EstimatingClient(settings)
    results: list[RunResult] = []

    async def go() -> None:
        window = asyncio.Semaphore(max(len(plans), 1))  # no waiting: every run steps at once
        for cfg, group in _configs(plans, options, template):
            results.extend(await run_batch_async([_spec(p) for p in group], client, cfg, window=window,
                                                 transcripts=False))

    if plans:
        run_sync(go())
    u = UsageTotals().merge(r.usage for r in results)
    est = estimate(client, u.calls, u.prompt_tokens, u.completion_tokens)
    est = dataclasses.replace(est, cap_refusal=refusal, models_unasked=unasked)
    return dataclasses.replace(est, prices_as_of=backend.prices_as_of) if backend.prices_as_of else est
