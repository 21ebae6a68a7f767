"""Running a study: build its plans, run what is not done yet, store and summarise.

Execution groups the plans ([`jswim.studies.specs`][jswim.studies.specs]): Q-learning and random-policy runs
train/roll out in one vectorised call per swimmer (here and in [`jswim.studies.execute`][jswim.studies.execute]);
LLM runs are per-run pipelines (`jswim.studies.execute.run_llm`), each landing in the study
folder ([`jswim.results.StudyStore`][jswim.results.StudyStore]) the moment it ends, with the server's preflight and the
cost cap of [`jswim.studies.session`][jswim.studies.session]. Every run, whatever its agent, is judged by the same
code, [`jswim.judging.gait.judge`][jswim.judging.gait.judge], with the study's [`jswim.judging.gait.Criterion`][jswim.judging.gait.Criterion],
and becomes one [`jswim.results.RunRow`][jswim.results.RunRow] ([`jswim.studies.rows`][jswim.studies.rows]).

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
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any
from collections.abc import Sequence

import jax

from jswim import __version__, console, reprs
from jswim._io import callsite

if TYPE_CHECKING:
    import pandas as pd
from jswim.agents import fidelity
from jswim.agents.llm import RunResult, run_batch_async
from jswim.agents.variants import VARIANTS
from jswim.errors import ConfigError, JswimError, JswimWarning, LocalModelError
from jswim.llm.backend import Backend
from jswim.llm.credentials import scrub
from jswim._io.permissions import private_files
from jswim.llm.client import ClientSettings
from jswim.llm.dryrun import Estimate, EstimatingClient, estimate
from jswim.errors import LLMError
from jswim.llm.usage import PRICES_AS_OF, UsageTotals
from jswim.llm.sync import run_sync
from jswim.prompt import PromptTemplate
from jswim.scenes import Scene
from jswim.scenes.ranges import range_notes
from jswim.results import (
    RunRow,
    StudyFolderError,
    StudyStore,
    as_run_rows,
    is_failed,
    read_run_rows,
    read_runs,
    write_json,
    writing,
)
from jswim.studies.options import (
    ALL_AGENTS,
    AGENTS,
    COMPETENCE_VARIANTS,
    CONTINUOUS_AGENT,
    OPTIMAL_AGENT,
    SCENE_GRIDS,
    StudyOptions,
)
from jswim.studies.specs import build
from jswim.studies.study import get
from jswim.studies.kinds.navigate import with_budgets
from jswim.studies.plans import Plan
from jswim.studies import prompt_files

from jswim.studies.execute import (
    LLMOutcome,
    llm_configs,
    run_baselines,
    run_llm,
    run_optimum,
    run_spec,
)
from jswim.studies.session import (
    ProgressFn,
    StudySession,
    no_progress,
    cap_check,
    check_max_cost,
    preflight,
)
from jswim.studies.report import summarize


# -- execution ----------------------------------------------------------------------------------


@dataclass
class StudyResult:
    """What [`run_study`][jswim.studies.run.run_study] produced."""

    folder: Path
    rows: list[dict[str, Any]]
    summary: pd.DataFrame  # one row per (agent, setting); a list of dicts is turned into one
    # The figure files: empty from run_study (a study ends at its folder); the publish step
    # (jswim.report, jswim.viz.publish) draws them and the CLI and notebooks fill this in.
    figures: list[Path] = field(default_factory=list)
    wall_s: float = 0.0
    # This session's LLM calls, billed calls, wall s, calls/s, cost (empty when it ran no LLM run: a
    # resume of a finished study); the metadata summary keeps the last session that ran some.
    llm_speed: dict[str, float] = field(default_factory=dict)
    failed_runs: list[dict[str, Any]] = field(default_factory=list)  # run_id and the server's error
    truncated: dict[str, int] = field(
        default_factory=dict
    )  # max_tokens -> LLM replies cut off there
    stopped: str | None = None  # "cost cap" when --max-cost stopped the study before its end
    total: int = 0  # runs in the study's grid
    reasoning: dict[str, Any] = field(
        default_factory=dict
    )  # what a reasoning model was sent (jswim.llm.reasoning)
    cut_thinking: int = 0  # LLM replies cut while the model was still reasoning (never executed)
    notes: list[str] = field(
        default_factory=list
    )  # what was sent for sampling, decoding fallbacks, pricing

    def __post_init__(self) -> None:
        import pandas as pd  # the summary is a table: one row per (agent, setting)

        if not isinstance(self.summary, pd.DataFrame):
            self.summary = pd.DataFrame(list(self.summary))

    __repr__ = reprs.study_result_text
    _repr_html_ = reprs.study_result_html


#: Options that say how large the grid is, not what its runs are: left out of the identity, so a
#: folder grows when they grow (and a smaller value reports the runs it names).
GRID_SIZE = (
    "runs",
    "q_runs",
    "zetas",
    "n_hts",
    "temperatures",
    "prompt_files",
    "samples",
    "roc_levels_grid",
    "starts",
    *SCENE_GRIDS,
)

#: How run seeds are made (``jswim.studies.plans.run_seed``); folders made otherwise are refused.
SEEDS = "hash of the study seed and the run id"

#: The study's prompt template (written once per folder; its hash is in the identity).
PROMPT_FILE = "prompt_template.json"


def study_backend(study: str, backend: Backend | None) -> Backend | None:
    """The backend a study runs with: a study that fixes its decoding (the ablation study:
    free text, `jswim.studies.study.Study.constrain`) overrides ``constrain="auto"``; an explicit
    ``--constrain`` is kept."""
    mode = get(study).constrain
    if backend is None or mode is None or backend.constrain != "auto":
        return backend
    return dataclasses.replace(backend, constrain=mode)


def identity(study: str, o: StudyOptions, backend: Backend | None) -> dict[str, Any]:
    """Everything that defines a study's runs (compared when a folder is resumed)."""
    backend = study_backend(study, backend)
    opts = dataclasses.asdict(o)
    for name in ("chunk", *GRID_SIZE):
        opts.pop(name, None)
    spec = get(study)
    if "train_episodes" not in spec.own_options:  # others' folders keep their identity
        opts.pop("train_episodes", None)
    for name in (
        "variant",
        "variants",
    ):  # left out when unset, so older folders keep their identity
        if opts[name] is None:
            opts.pop(name)
    if opts["steps"] is None and spec.own_budgets:  # each target has its own budget
        opts["steps"] = "each target's budget"
    if opts["steps"] is None:  # the study's own horizon, written as the number it is
        opts["steps"] = spec.steps
    if opts["roc_levels"] == 1:  # the paper's ROC set: as before --roc-levels existed
        opts.pop("roc_levels")
    if opts["pair_prompt"] == "joint":  # the default: as before --pair-prompt existed
        opts.pop("pair_prompt")
    if not opts["flow"]:  # still fluid: as before --flow existed
        opts.pop("flow")
    if tuple(o.agents) == ALL_AGENTS:  # the default, written as before the continuous agent existed
        opts["agents"] = AGENTS
    if o.variant is None and spec.variant != "paper":  # a study's own default variant
        opts["variant"] = spec.variant
    template = PromptTemplate.from_file(o.prompt_file) if o.prompt_file else PromptTemplate()
    tpl = json.dumps(dataclasses.asdict(template), sort_keys=True)
    return {
        "study": study,
        "options": opts,
        "seed": o.seed,
        "seeds": SEEDS,
        "backend": backend.describe() if backend is not None and "llm" in o.agents else None,
        "prompt_template_sha256": hashlib.sha256(tpl.encode()).hexdigest()[:16],
    }


def default_folder(
    study: str, o: StudyOptions, backend: Backend | None, root: str = "jswim-out"
) -> Path:
    """``jswim-out/<study>-<hash of the identity>``: the same settings reuse (and resume, or
    extend) the same folder."""
    ident = identity(study, o, backend)
    digest = hashlib.sha256(json.dumps(ident, sort_keys=True, default=str).encode())
    return Path(root) / f"{study}-{digest.hexdigest()[:8]}"


@private_files()  # the folder and the cache: owner only under the usual umask (jswim._io.permissions)
def run_study(
    study: str,
    options: StudyOptions = StudyOptions(),
    backend: Backend | None = Backend(),
    out: str | Path | None = None,
    progress: ProgressFn | bool | None = None,
    max_cost: float | None = None,
) -> StudyResult:
    """Run (or resume, or extend) a study and write its folder; draw nothing.

    A study ends at its folder: its figures and ``report.html`` are the publish step after it,
    ``jswim.report(folder)`` (`jswim.viz.publish.report`), which ``jswim study`` and ``jswim swim``
    call unless ``--no-figures``.

    Parameters
    ----------
    study : str
        One of `jswim.studies.names()`.
    options : StudyOptions
        Grid and agent knobs.
    backend : Backend or None
        LLM server (default: the embedded model); needed only when the study has LLM runs.
    out : path, optional
        Study folder (default [`default_folder`][jswim.studies.run.default_folder]). Finished runs found there are kept.
    progress : bool or callable, optional
        ``None`` (default): one updating display in a Jupyter notebook, a bar on a terminal,
        nothing elsewhere; ``True``: also dated lines on stderr where there is no terminal;
        ``False``: nothing (`study_progress`). A callable
        ``progress(phase, done, total, info)`` (`ProgressFn`): after each finished batch of
        baseline runs (runs done of all), and after each finished LLM run (phase ``"llm"``) and
        every 0.5 s while LLM requests are out (phase ``"llm-live"``), counting LLM steps done of
        all the session's LLM steps, with runs, requests in flight, tokens and cost in ``info``.
    max_cost : float, optional
        Cap in USD on what the study's calls cost, over all its sessions (the call journal's
        total). Calls reserve their cost bound before they go out; at the cap no new call is
        made, runs in flight finish their call, finished runs are kept, the folder's status reads
        ``stopped at the cost cap`` and `StudyResult.stopped` is ``"cost cap"``. The same
        call with a higher cap goes on from there, paying no call twice.

    Returns
    -------
    StudyResult
        The folder, its rows (one dict per run, every run the grid names that the folder
        holds), the summary table, this session's LLM speed and failures, and ``stopped`` when
        the cost cap ended it. ``figures`` is empty: the folder is the study's end, and the
        publish step ([`jswim.report`][jswim.viz.publish.report]) draws from it.

    Raises
    ------
    ConfigError
        For a cap that is not a finite number of dollars >= 0 (`check_max_cost`) or an LLM
        study without a backend.
    """
    max_cost = check_max_cost(max_cost)
    t0 = time.perf_counter()
    backend = study_backend(study, backend)
    plans = with_budgets(build(study, options))
    if not plans:
        raise ConfigError(
            f"these settings give the {study} study no runs at all (--runs 0 and --q-runs 0?); "
            "nothing to do"
        )
    if backend is not None and backend.local and any(p.agent == "llm" for p in plans):
        _check_embedded_model(study, backend)  # before the baselines, not after them
    ident = identity(study, options, backend)
    if get(study).variants_grid:  # the variants' switches define the runs too
        ident["variants"] = {v: VARIANTS[v] for v in options.variants or COMPETENCE_VARIANTS}
    folder = Path(out) if out is not None else default_folder(study, options, backend)
    template = PromptTemplate.from_file(options.prompt_file) if options.prompt_file else None
    prompts = prompt_files.check(
        folder, options
    )  # an edited prompt file never resumes into old runs
    # What the folder records is what it holds: this session's grid and every earlier one.
    record = FolderRecord(study, options, backend, plans, prompts)
    store = StudyStore(
        folder,
        study,
        ident,
        extra=record,
    )
    try:
        for note in store.repairs:
            callsite.warn_user(FolderRepaired(f"{folder}: {note}"))
        store.meta.pop("prompt_template", None)  # folders before prompt_template.json had it here
        tpl_path = folder / PROMPT_FILE
        if (
            not tpl_path.exists()
        ):  # the identity holds its hash: a resumed folder has this very template
            with writing(folder):
                write_json(tpl_path, dataclasses.asdict(template or PromptTemplate()))
        with console.study_progress(progress) as tick:
            return _run_in(
                store,
                study,
                plans,
                options,
                backend,
                folder,
                template,
                tick,
                t0,
                max_cost,
                held=record.plans,
            )
    except KeyboardInterrupt:
        _record_status(store, "interrupted")  # finished runs are kept; the same command resumes
        raise
    except JswimError as exc:
        # A session that stops before changing anything (a refused cap, a server that is not there)
        # leaves the folder's status as it was; otherwise it says stopped, and why.
        if not store.restore_status():
            _record_status(
                store, "stopped", error=scrub(str(exc))
            )  # never a key, however the message got it
        raise
    except OSError as exc:  # a full disk or an I/O error outside the store's own writes
        raise _folder_error(store, exc) from None
    finally:
        store.close()  # the folder's lock: the next session may start


def _range_notes(plans: Sequence[Plan]) -> list[str]:
    """Each stated-range rule some plan's scene breaks (`jswim.scenes.ranges.range_notes`), once."""
    notes: dict[str, None] = {}
    for swimmer, scene in {(p.swimmer, p.scene) for p in plans if p.scene}:
        notes.update(dict.fromkeys(range_notes(swimmer, Scene.from_dict(json.loads(scene)))))
    return list(notes)


class FolderRecord:
    """What a session records of its folder in ``metadata.json`` (``StudyStore(extra=...)``):
    `_folder_metadata` of every run the folder holds or plans, never only this session's grid.

    A grid-size option (`GRID_SIZE`: ``--flows``, ``--distances``, ``--zetas``, ``--runs``, ...)
    may be smaller on a resume than in the folder: the session runs what it names, and the
    record keeps the union. ``grids`` lists each distinct grid a session ran; ``grid`` holds,
    per option, the union of their values (a list's values in order, sorted where each list
    was; the largest count); ``n_planned``, ``group_order`` and the rest are those of the runs
    of every grid (by run id: no grid crossed with another).

    Attributes
    ----------
    plans : list of Plan
        The runs of every grid the folder records, this session's first as given (set when
        the store calls it).
    """

    def __init__(
        self,
        study: str,
        options: StudyOptions,
        backend: Backend | None,
        plans: Sequence[Plan],
        prompts: dict[str, Any],
    ) -> None:
        self.study, self.options, self.backend, self.prompts = study, options, backend, prompts
        self.plans: list[Plan] = list(plans)

    def __call__(self, before: dict[str, Any] | None) -> dict[str, Any]:
        now = _plain({k: getattr(self.options, k) for k in GRID_SIZE})
        grids = [g for g in _grids(before) if g != now] + [now]
        ids = {p.run_id for p in self.plans}
        kept = []
        for g in grids[:-1]:
            built = _grid_plans(self.study, self.options, g)
            if built is None:  # a hand edit: it names no run, and is not carried on
                continue
            kept.append(g)
            for p in built:
                if p.run_id not in ids:
                    ids.add(p.run_id)
                    self.plans.append(p)
        grids = kept + [now]
        meta = _folder_metadata(self.study, self.options, self.backend, self.plans, self.prompts)
        meta["grid"] = _union(grids, self.study)
        meta["grids"] = grids
        return meta


def _plain(value: Any) -> Any:
    """``value`` as JSON holds it (tuples as lists)."""
    return json.loads(json.dumps(value))


def _grids(before: dict[str, Any] | None) -> list[dict[str, Any]]:
    """The grids a folder's metadata records (``grids``, today's form:
    `jswim.results.migrate.migrate_metadata`; none for a new folder)."""
    return [_plain(g) for g in (before or {}).get("grids") or ()]


def _grid_plans(study: str, options: StudyOptions, grid: dict[str, Any]) -> list[Plan] | None:
    """The runs ``options`` name with an earlier session's ``grid`` (its values as lists);
    ``None`` where the recorded grid is no grid these options take (a hand edit)."""
    given = {k: tuple(v) if isinstance(v, list) else v for k, v in grid.items() if k in GRID_SIZE}
    try:
        return build(study, dataclasses.replace(options, **given))
    except (ConfigError, TypeError, ValueError):
        return None


def _union(grids: Sequence[dict[str, Any]], study: str) -> dict[str, Any]:
    """Per grid option, what the folder holds over ``grids``: the values of its lists in order
    of first appearance (sorted where every list was), the largest count (``None``, the study's
    own, read as its number where a count is also given)."""
    spec = get(study)
    own = {"runs": spec.runs, "q_runs": spec.q_runs}
    out: dict[str, Any] = {}
    for k in dict.fromkeys(k for g in grids for k in g):
        values = [g.get(k) for g in grids if k in g]
        lists = [v for v in values if isinstance(v, list)]
        counts = [v for v in values if isinstance(v, int) and not isinstance(v, bool)]
        if lists:
            merged = list(dict.fromkeys(_key(x) for v in lists for x in v))
            items = {_key(x): x for v in reversed(lists) for x in v}
            union = [items[x] for x in merged]
            if all(v == sorted(v, key=_order) for v in lists):
                union.sort(key=_order)
            out[k] = union
        elif counts:
            out[k] = max(counts + [own[k] for v in values if v is None and k in own])
        else:
            out[k] = values[-1]
    return out


def _key(x: Any) -> str:
    """A grid value's identity in a union (``0`` and ``0.0`` are one flow speed)."""
    return repr(float(x)) if isinstance(x, (int, float)) and not isinstance(x, bool) else repr(x)


def _order(x: Any) -> tuple:
    """Numbers by value, before any text (a sort that never compares a number with a text)."""
    if isinstance(x, (int, float)) and not isinstance(x, bool):
        return (0, float(x), "")
    return (1, 0.0, str(x))


def _folder_metadata(
    study: str,
    options: StudyOptions,
    backend: Backend | None,
    plans: Sequence[Plan],
    prompts: dict[str, Any],
) -> dict[str, Any]:
    """What a study's ``metadata.json`` records beside its identity: versions, the success rule,
    the grid and its order, the fidelity deviations and extensions, the server and prices."""
    return {
        **prompts,  # each prompt file's name and the hash of its bytes (jswim.studies.prompt_files)
        "jswim_version": __version__,
        "jax_version": jax.__version__,
        "python": platform.python_version(),
        # The template itself is in prompt_template.json, written once (below), not in every
        # rewrite of metadata.json at each status change.
        "prompt_template_file": PROMPT_FILE,
        # The rule this study's runs are judged by (a navigation run: its target reached).
        "success_criterion": get(study).success(plans, options.horizon, options.steps),
        "horizon": options.horizon,
        "llm_variants": list(options.variants or COMPETENCE_VARIANTS)
        if get(study).variants_grid
        else [options.variant or get(study).variant],
        "n_planned": len(plans),  # so that a reader can tell an unfinished study (jswim show)
        # The grid's order of its groups (n_ht 1, 2, ..., 10): readers show them so, not as runs finished.
        "group_order": list(dict.fromkeys(p.group for p in plans)),
        # What differs from the paper's protocol in every LLM run (each transcript lists its own too),
        # and the extensions some runs use (finer or real-valued ROCs).
        "fidelity_deviations": list(fidelity.ALWAYS)
        + fidelity.study_extensions({p.roc_levels for p in plans})
        + _scene_extensions(plans)
        + ([fidelity.NAVIGATION] if any(p.target for p in plans) else [])
        + ([fidelity.FLOW] if any(p.flow for p in plans) else []),
        "roc_levels": sorted({p.roc_levels for p in plans}),
        # The physics models its scenes use outside their stated range (jswim.scenes.ranges),
        # as the runs warned of them once and as the page lists them.
        "model_range_notes": _range_notes(plans),
        "grid": {k: getattr(options, k) for k in GRID_SIZE},
        "server": backend.address() if backend is not None else None,
        "prices_as_of": (
            backend.prices_as_of if backend is not None and backend.prices_as_of else PRICES_AS_OF
        ),
    }


def _folder_error(store: StudyStore, exc: OSError) -> StudyFolderError:
    """The one-line error of a study stopped by an I/O error (a full disk, a file in the way),
    its status recorded where the session had changed the folder."""
    folder = store.folder
    msg = f"cannot write {exc.filename or folder}: {exc.strerror or exc}"
    if not store.restore_status():
        _record_status(store, "stopped", error=msg)
    if exc.errno in (errno.ENOSPC, errno.EDQUOT):
        hint = "make room and run the same command to resume"
    elif exc.errno in (errno.EEXIST, errno.ENOTDIR, errno.EISDIR):
        hint = "a file or folder is in the way of one jswim writes: move it away and run the same command"
    else:
        hint = "fix that and run the same command to resume"
    return StudyFolderError(
        f"{msg}; every finished run and answered call is kept in {folder}: {hint}"
    )


def _check_embedded_model(study: str, backend: Backend) -> None:
    """Refuse an LLM study on the embedded model when that model cannot start, naming the ways on.

    Raises
    ------
    LocalModelError
        The model's package or its native library is missing; nothing was run or written.
    """
    try:
        backend.server().check()
    except LocalModelError as exc:
        raise LocalModelError(
            f"{exc}. The {study} study's LLM runs need a model: install it, or point the study at "
            "a server (Backend(base_url=...); `jswim serve reference` starts a rule-based one on "
            "this machine), or run the baselines only (StudyOptions(runs=0)); nothing was run"
        ) from None


def _scene_extensions(plans: Sequence[Plan]) -> list[str]:
    """The fidelity lines of the scenes a study's runs use (none in the paper's studies)."""
    scenes = sorted({(p.scene, p.pair_prompt) for p in plans if p.scene})
    if not scenes:
        return []
    ppo = any(p.scene and p.agent == CONTINUOUS_AGENT for p in plans)
    return fidelity.scene_extensions(
        [(Scene.from_dict(json.loads(s)), pair) for s, pair in scenes], ppo=ppo
    )


class FolderRepaired(JswimWarning):
    """Opening a study folder repaired it (a torn journal line cut, a temporary file removed)."""


def _record_status(store: StudyStore, status: str, **fields: Any) -> None:
    """``store.set_status`` where the folder still takes it (a full disk may refuse even that)."""
    try:
        store.set_status(status, **fields)
    except (OSError, StudyFolderError):
        pass


def _run_in(
    store: StudyStore,
    study: str,
    plans: Sequence[Plan],
    options: StudyOptions,
    backend: Backend | None,
    folder: Path,
    template: PromptTemplate | None,
    progress: ProgressFn | None,
    t0: float,
    max_cost: float | None = None,
    held: Sequence[Plan] = (),
) -> StudyResult:
    done = store.done_ids()
    todo = [p for p in plans if p.run_id not in done]
    session = StudySession(
        store,
        options,
        backend,
        template,
        total=len(plans),
        finished=len(plans) - len(todo),
        progress=progress or no_progress,
        max_cost=max_cost,
    )
    if backend is not None and not backend.local and any(p.agent == "llm" for p in todo):
        # fail before the baselines, not after
        session.server = preflight(store, backend, max_cost=max_cost)
    finished = session.finished
    session.tick(
        "resume" if finished else "start", info=f"{finished} runs already done" if finished else ""
    )
    # a navigation cell's optimum goes last: every other run of the cell seeds its search
    run_baselines(session, [p for p in todo if p.agent not in ("llm", OPTIMAL_AGENT)])
    llm_plans = [p for p in todo if p.agent == "llm"]
    outcome = run_llm(session, llm_plans) if llm_plans else LLMOutcome()
    run_optimum(session, [p for p in todo if p.agent == OPTIMAL_AGENT])
    speed, sent, notes, capped, total = (
        outcome.speed,
        outcome.sent,
        outcome.notes,
        outcome.capped,
        session.total,
    )

    # The study is the runs its grid names now (a folder may hold more, from a larger --runs);
    # the folder's record sums up every run it holds of the grids it records (FolderRecord).
    names = {p.run_id: i for i, p in enumerate(plans)}
    stored = read_runs(folder)
    rows = sorted((r for r in stored if r["run_id"] in names), key=lambda r: names[r["run_id"]])
    typed = as_run_rows(rows)  # StudyResult.rows stay the dicts of read_runs (users index them)
    summary = summarize(typed)
    everything = {p.run_id: i for i, p in enumerate([*plans, *held])}
    if len(everything) > len(names):
        kept = sorted(
            (r for r in stored if r["run_id"] in everything),
            key=lambda r: everything[r["run_id"]],
        )
        kept_typed = as_run_rows(kept)
        folder_summary = summarize(kept_typed)
    else:
        kept_typed, folder_summary = typed, summary
    scene_table = {**_scene_table(kept_typed), **_nav_table(kept_typed)}
    # LLM speed of the session that ran LLM runs (a resume with none to run keeps the earlier one).
    session_speed = dict(speed)
    speed = speed or dict((store.meta.get("summary") or {}).get("llm_speed") or {})
    llm = [r for r in typed if r.agent == "llm"]
    held_llm = [r for r in kept_typed if r.agent == "llm"]
    constraint = sorted({r.constraint for r in held_llm if r.constraint})
    failed = [{"run_id": r.run_id, "error": r.error} for r in typed if is_failed(r)]
    held_failed = [{"run_id": r.run_id, "error": r.error} for r in kept_typed if is_failed(r)]
    replies, cut_thinking = _reply_tallies(llm)
    held_replies = replies if kept_typed is typed else _reply_tallies(held_llm)[0]
    # What a reasoning model was sent (this session's, else the one that ran LLM runs).
    sent = sent or dict((store.meta.get("summary") or {}).get("reasoning") or {})
    status = "stopped at the cost cap" if capped else "incomplete" if held_failed else "complete"
    store.finalize(
        status,
        {
            "groups": folder_summary,
            **scene_table,
            "failed_runs": held_failed,
            **held_replies,
            **({"llm_speed": speed} if speed else {}),
            **({"reasoning": sent} if sent else {}),
            **({"constrained_decoding": constraint} if constraint else {}),
        },
    )
    return StudyResult(
        folder=folder,
        rows=rows,
        summary=summary,
        figures=[],
        wall_s=time.perf_counter() - t0,
        llm_speed=session_speed,
        failed_runs=failed,
        truncated=dict(replies.get("truncated_at", {})),
        stopped="cost cap" if capped else None,
        total=total,
        reasoning=sent,
        cut_thinking=cut_thinking,
        notes=notes,
    )


def _reply_tallies(llm: Sequence[RunRow]) -> tuple[dict[str, Any], int]:
    """The LLM rows' reply tallies for the folder's summary (replies cut at ``max_tokens``, per
    limit; cut while thinking; reasoning tokens), and the count cut while thinking."""
    if not llm:
        return {}, 0
    cut: dict[str, int] = {}  # max_tokens -> replies cut off there (the limit is per swimmer)
    for r in llm:
        if r.truncated:
            cut[str(r.max_tokens)] = cut.get(str(r.max_tokens), 0) + r.truncated
    cut_thinking = sum(r.cut_thinking or 0 for r in llm)
    replies = {
        "truncated_replies": sum(cut.values()),
        "truncated_at": cut,
        "cut_while_thinking": cut_thinking,
        "reasoning_tokens": sum(r.reasoning_tokens or 0 for r in llm),
    }
    return replies, cut_thinking


def _scene_table(rows: Sequence[RunRow]) -> dict[str, Any]:
    """``{"scenes": table}`` of a study with scene runs (`jswim.studies.scene_studies.scene_summary`), else ``{}``."""
    if not any(r.scene for r in rows):
        return {}
    from jswim.studies import (
        scene_studies,
    )  # lazy: start-up (the scene module, for scene studies only)

    return {"scenes": scene_studies.scene_summary([r for r in rows if not is_failed(r)])}


def _nav_table(rows: Sequence[RunRow]) -> dict[str, Any]:
    """``{"navigation": table}`` of a study with navigation runs
    (`jswim.studies.kinds.navigate.nav_summary`), else ``{}``."""
    if not any(r.target for r in rows):
        return {}
    from jswim.studies.kinds import navigate  # lazy: the navigation study's module

    return {"navigation": navigate.nav_summary(rows)}


def estimate_study(
    study: str,
    options: StudyOptions = StudyOptions(),
    backend: Backend | None = Backend(),
    out: str | Path | None = None,
    max_cost: float | None = None,
) -> Estimate:
    """What the study's LLM runs not yet done would cost (``--dry-run``); no chat request is sent.

    The runs go through the real driver against `jswim.llm.dryrun.EstimatingClient`, so
    the prompts are rendered from real swimmer states; the study folder is read (to skip the
    runs it has) but never written. A remote server is asked its ``/v1/models`` (free), so the
    dry run prices the calls by the very rule the run will (a model the server does not list is
    not priced at a list price); when it cannot be asked, the estimate says so. With
    ``max_cost``, `Estimate.cap_refusal` is the line the run would refuse with, if any.
    """
    if backend is None:
        raise ConfigError("a dry run needs a backend (the model to price)")
    backend = study_backend(study, backend)
    plans = with_budgets([p for p in build(study, options) if p.agent == "llm"])
    folder = Path(out) if out is not None else default_folder(study, options, backend)
    prompt_files.check(folder, options)  # the same refusal as the study itself
    done = {r.run_id for r in read_run_rows(folder)}
    plans = [p for p in plans if p.run_id not in done]
    template = PromptTemplate.from_file(options.prompt_file) if options.prompt_file else None
    if backend.local:  # no server is started: the settings only name the model and the limits
        settings = ClientSettings(
            base_url="http://127.0.0.1/v1",
            model=backend.describe()["model"],
            temperature=backend.temperature,
        )
    info, unasked = None, None
    if not backend.local:
        try:
            info = backend.preflight(timeout_s=min(backend.timeout_s or 5.0, 5.0))
        except (
            LLMError,
            ConfigError,
        ) as exc:  # no server (yet), no key: price as if it lists the model
            unasked = (
                f"could not ask the server which models it lists ({scrub(str(exc)).split(';')[0]})"
            )
    if not backend.local:  # --max-tokens is also the reasoning budget, as in the study itself
        settings = backend.client_settings(
            info=info,
            **(
                {"reasoning_max_tokens": options.max_tokens}
                if options.max_tokens is not None
                else {}
            ),
        )
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
        for cfg, group in llm_configs(plans, options, template):
            results.extend(
                await run_batch_async(
                    [run_spec(p) for p in group], client, cfg, window=window, transcripts=False
                )
            )

    if plans:
        run_sync(go())
    u = UsageTotals().merge(r.usage for r in results)
    est = estimate(client, u.calls, u.prompt_tokens, u.completion_tokens)
    est = dataclasses.replace(est, cap_refusal=refusal, models_unasked=unasked)
    return (
        dataclasses.replace(est, prices_as_of=backend.prices_as_of) if backend.prices_as_of else est
    )
