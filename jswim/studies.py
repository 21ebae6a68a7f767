"""The paper's experiments as study grids, executed in batches and stored resumably.

A study is a list of :class:`Plan` (one per run) built from :class:`StudyOptions`. Execution
groups the plans: Q-learning and random-policy runs train/roll out in one vectorised call per
swimmer, and LLM runs advance in lockstep chunks (all prompts of a round in flight at once). Each
finished chunk lands in the study folder (:class:`jswim.results.StudyStore`), so an interrupted
study resumes where it stopped. Every run, whatever its agent, is judged by the same code,
:func:`jswim.gait.judge` (three consecutive qualifying cycles within 50 steps, no later failure).

Studies (``jswim study NAME``):

``curves``   X/a against step n: LLM, Q-learning and random policy, both swimmers (Fig. 2)
``history``  the n_ht sweep, both directions, both swimmers (Fig. 3)
``noise``    mean X/a and success rate p against zeta (Fig. 4)
``ablation`` the full prompt and the prompt without each of S1..S5 (Fig. 5)
``inits``    all four initial configurations, both directions
``swim``     the main job: a few LLM runs next to Q-learning and random learners
``competence`` every protocol variant (:data:`jswim.agents.llm.VARIANTS`) next to random and
             Q-learning baselines on both allowed sets: how much of the swimming is the model's
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import platform
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Sequence

import jax
import numpy as np

from jswim import __version__, env
from jswim.errors import ConfigError
from jswim.gait import judge
from jswim.prompt import ALLOWED_MODES, SENTENCES, PromptTemplate
from jswim.results import StudyStore, read_runs
from jswim.stats import mean_interval, quartiles, wilson_interval

STUDIES = ("curves", "history", "noise", "ablation", "inits", "swim", "competence")
AGENTS = ("llm", "qlearning", "random")
DEFAULT_ZETAS = (0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0)
INIT_CHOICES = ("paper", "cycle", "random", "++", "+-", "-+", "--")

#: Protocol variant of the swim study's LLM runs; the paper studies always use "paper". Chosen
#: from the measured competence study (README): on the embedded SmolLM2-135M no variant beat the
#: random baseline (0 successes in 140 runs; the model moves D1 in >= 87% of steps under every
#: variant), so none earns the switch and the paper's protocol stays the default.
SWIM_VARIANT = "paper"

#: Variants the competence study runs by default (each next to the same baselines).
COMPETENCE_VARIANTS = ("paper", "summary", "shuffle", "shape-changing", "shape-changing+summary",
                       "shape-changing+shuffle", "shape-changing+temperature")


@dataclass(frozen=True)
class Backend:
    """Where LLM requests go.

    Attributes
    ----------
    base_url : str or None
        An OpenAI-compatible server (``.../v1``); ``None`` starts the embedded local model.
    model : str or None
        Model name for a remote server (required with ``base_url``).
    gguf : str or None
        GGUF file for the embedded server (default: the packaged SmolLM2-135M-Instruct).
    api_key_env : str
        Environment variable holding the API key (its value is never stored).
    constrain : str
        Constrained decoding: ``auto`` (grammar for llama.cpp, none otherwise), ``grammar``,
        ``json_schema`` or ``none``.
    temperature : float
        Sampling temperature (paper: 0).
    n_parallel : int
        Decoding slots of the embedded server.
    n_threads : int or None
        CPU threads of the embedded server (``None``: llama.cpp's choice, one per core). On a
        machine busy with other work, fewer threads than cores keep decoding steady.
    concurrency : int
        Requests in flight at once.
    cohorts : int
        Lockstep cohorts of a chunk of LLM runs (:func:`jswim.agents.llm.run_batch_async`); the
        results do not depend on it. More than 1 overlaps this process's per-request CPU work with
        other cohorts' waiting, which pays against a fast server with many distinct runs; 1 keeps
        identical temperature-0 requests of different runs in flight together, so they are sent once.
    cache_dir : str or None
        Response cache (temperature 0 only).
    """

    base_url: str | None = None
    model: str | None = None
    gguf: str | None = None
    api_key_env: str = "OPENAI_API_KEY"
    constrain: str = "auto"
    temperature: float = 0.0
    n_parallel: int = 4
    n_threads: int | None = None
    concurrency: int = 16
    cohorts: int = 1
    cache_dir: str | None = None

    @property
    def local(self) -> bool:
        return self.base_url is None

    def describe(self) -> dict[str, Any]:
        """What defines the backend's answers (recorded in the study's identity)."""
        if self.local:
            from jswim.llm.local import default_model_path

            path = Path(self.gguf) if self.gguf else default_model_path()
            name = path.name
        else:
            name = self.model
        return {"kind": "embedded" if self.local else "remote",
                "base_url": None if self.local else _safe_url(self.base_url),
                "model": name, "constrain": self.constrain, "temperature": self.temperature}

    def client_settings(self, base_url: str | None = None, **changes: Any):
        """:class:`jswim.llm.client.ClientSettings` for this backend."""
        from jswim.llm.client import ClientSettings
        from jswim.llm.local import LOCAL_KEY_ENV

        if self.local:
            s = ClientSettings(base_url=base_url or "", model=Path(self.gguf).name if self.gguf else "smollm2-135m",
                               api_key_env=LOCAL_KEY_ENV, server_kind="llamacpp", constrain=self.constrain,
                               temperature=self.temperature, max_concurrency=max(self.concurrency, self.n_parallel),
                               cache_dir=self.cache_dir, timeout_s=120.0)
        else:
            s = ClientSettings(base_url=self.base_url, model=self.model, api_key_env=self.api_key_env,
                               constrain=self.constrain, temperature=self.temperature,
                               max_concurrency=self.concurrency, cache_dir=self.cache_dir)
        return dataclasses.replace(s, **changes) if changes else s


def check_server(base_url: str, timeout_s: float = 5.0) -> None:
    """Raise :class:`LLMServerError` at once when nothing answers at ``base_url``.

    Any HTTP answer counts (even 401 or 404): only an unreachable host or port is an error here.
    """
    import httpx

    from jswim.llm.errors import LLMServerError

    try:
        httpx.get(base_url.rstrip("/") + "/models", timeout=timeout_s)
    except httpx.HTTPError as exc:
        raise LLMServerError(
            f"cannot reach {_safe_url(base_url)} ({type(exc).__name__}); check --base-url or start the server"
        ) from None


def _safe_url(url: str | None) -> str | None:
    from jswim.llm.client import safe_url

    return safe_url(url) if url else url


@dataclass(frozen=True)
class StudyOptions:
    """Knobs of a study; ``None`` means the study's own default."""

    swimmers: tuple[str, ...] | None = None
    directions: tuple[int, ...] | None = None
    runs: int | None = None  # LLM runs per setting
    q_runs: int | None = None  # Q-learning and random runs per setting
    steps: int = 50
    horizon: int = 50
    n_ht: int | None = None
    n_hts: tuple[int, ...] = (1, 2, 3, 4, 5, 6, 7, 8)
    zeta: float = 0.0
    zetas: tuple[float, ...] = DEFAULT_ZETAS
    init: str | None = None
    seed: int = 0
    allowed: str = "all"
    prompt_file: str | None = None
    chunk: int = 64
    agents: tuple[str, ...] = AGENTS
    variant: str | None = None  # LLM protocol variant; None: the study's (SWIM_VARIANT or "paper")
    variants: tuple[str, ...] | None = None  # competence: the variants to compare (None: all default)

    def __post_init__(self) -> None:
        if self.steps < 1 or self.steps > 10_000:
            raise ConfigError(f"--steps must be between 1 and 10000, got {self.steps}")
        for name in ("runs", "q_runs"):
            v = getattr(self, name)
            if v is not None and (v < 0 or v > 100_000):
                raise ConfigError(f"--{name.replace('_', '-')} must be between 0 and 100000, got {v}")
        if self.n_ht is not None and not 0 <= self.n_ht <= 100:
            raise ConfigError(f"--n-ht must be between 0 and 100, got {self.n_ht}")
        if self.init is not None and self.init not in INIT_CHOICES:
            raise ConfigError(f"--init must be one of {', '.join(INIT_CHOICES)}, got {self.init!r}")
        if self.allowed not in ALLOWED_MODES:
            raise ConfigError(f"--allowed must be 'all' or 'shape-changing', got {self.allowed!r}")
        bad = [z for z in (self.zeta, *self.zetas) if not (math.isfinite(z) and z >= 0)]
        if bad:
            raise ConfigError(f"noise levels must be >= 0, got {bad[0]}")
        if self.chunk < 1:
            raise ConfigError("--chunk must be >= 1")
        from jswim.agents.llm import variant_allowed

        for name in ([self.variant] if self.variant else []) + list(self.variants or ()):
            variant_allowed(name)  # raises for an unknown name

    def llm_variant(self, study: str) -> str:
        """The protocol variant of the study's LLM runs (outside the competence study)."""
        return self.variant or (SWIM_VARIANT if study == "swim" else "paper")


@dataclass(frozen=True)
class Plan:
    """One run of a study."""

    run_id: str
    agent: str
    swimmer: str
    direction: int
    init: tuple[int, ...] | str
    zeta: float
    seed: int
    steps: int
    n_ht: int | None = None
    drop: frozenset[str] = frozenset()
    allowed: str = "all"
    group: str = ""
    variant: str = "paper"  # LLM protocol variant (jswim.agents.llm.VARIANTS); "" for baselines


# -- study grids --------------------------------------------------------------------------------


def _inits(choice: str, k: int) -> tuple[int, ...] | str:
    """Initial configuration of repeat ``k`` (``cycle`` goes through the four corners)."""
    if choice == "paper":
        return (1, 1)
    if choice == "cycle":
        return env.all_inits(2)[k % 4]
    if choice == "random":
        return "random"
    return tuple(1 if ch == "+" else 0 for ch in choice)


def _init_label(init: tuple[int, ...] | str) -> str:
    return init if isinstance(init, str) else "".join("+" if v else "-" for v in init)


def build(study: str, o: StudyOptions) -> list[Plan]:
    """The runs of ``study`` for options ``o``."""
    from jswim.agents.llm import variant_allowed
    from jswim.prompt import ALLOWED_MODES

    if study not in STUDIES:
        raise ConfigError(f"unknown study {study!r}; choose one of {', '.join(STUDIES)}")
    swimmers = o.swimmers or (("purcell",) if study == "swim" else ("purcell", "ng"))
    for sw in swimmers:
        if sw not in ("purcell", "ng", "nlink", "nsphere"):
            raise ConfigError(f"unknown swimmer {sw!r}; choose purcell, ng, nlink or nsphere")
    plans: list[Plan] = []
    # Outside the competence study every LLM run uses one variant; its allowed set (if it sets
    # one) applies to the baselines too, so they are offered what the model is offered.
    variant = o.llm_variant(study)
    allowed_default = variant_allowed(variant, o.allowed)

    def add(agent: str, sw: str, direction: int, init_choice: str, k: int, zeta: float, group: str,
            n_ht: int | None = None, drop: frozenset[str] = frozenset(), variant: str = variant,
            allowed: str | None = None) -> None:
        init = _inits(init_choice, k)
        seed = o.seed * 1_000_003 + len(plans)
        allowed = allowed or (variant_allowed(variant, o.allowed) if agent == "llm" else allowed_default)
        parts = [agent, sw, "px" if direction > 0 else "mx", f"i{_init_label(init)}", f"z{zeta:g}"]
        if n_ht is not None:
            parts.append(f"h{n_ht}")
        if drop:
            parts.append("no" + "".join(sorted(drop)))
        if agent == "llm" and variant != "paper":
            parts.append(variant)
        elif agent != "llm" and allowed != o.allowed:
            parts.append(allowed)
        parts.append(f"r{k}")
        plans.append(Plan("-".join(parts), agent, sw, direction, init, float(zeta), seed, o.steps,
                          n_ht, frozenset(drop), allowed, group, variant if agent == "llm" else ""))

    def with_baselines(sw: str, direction: int, init_choice: str, zeta: float, group: str, runs: int,
                       q_runs: int, **kw: Any) -> None:
        if "llm" in o.agents:
            for k in range(runs):
                add("llm", sw, direction, init_choice, k, zeta, group, **kw)
        for agent in ("qlearning", "random"):
            if agent in o.agents:
                for k in range(q_runs):
                    add(agent, sw, direction, init_choice, k, zeta, group)

    dirs = o.directions
    if study in ("swim", "curves"):
        runs = o.runs if o.runs is not None else (4 if study == "swim" else 1)
        q_runs = o.q_runs if o.q_runs is not None else 100
        init = o.init or "paper"
        for sw in swimmers:
            for d in dirs or (1,):
                with_baselines(sw, d, init, o.zeta, "", runs, q_runs, n_ht=o.n_ht)
    elif study == "history":
        init = o.init or "paper"
        for sw in swimmers:
            for d in dirs or (1, -1):
                for h in o.n_hts:
                    for k in range(o.runs if o.runs is not None else 1):
                        add("llm", sw, d, init, k, o.zeta, f"n_ht={h}", n_ht=h)
    elif study == "noise":
        init = o.init or "cycle"
        for sw in swimmers:
            for d in dirs or (1,):
                for z in o.zetas:
                    with_baselines(sw, d, init, z, f"zeta={z:g}", o.runs if o.runs is not None else 10,
                                   o.q_runs if o.q_runs is not None else 100, n_ht=o.n_ht)
    elif study == "ablation":
        init = o.init or "cycle"
        for sw in swimmers:
            for d in dirs or (1,):
                for drop in [frozenset()] + [frozenset({s}) for s in SENTENCES]:
                    group = "full" if not drop else f"-{next(iter(drop))}"
                    for k in range(o.runs if o.runs is not None else 10):
                        add("llm", sw, d, init, k, o.zeta, group, n_ht=o.n_ht, drop=drop)
    elif study == "competence":
        runs = o.runs if o.runs is not None else 10
        q_runs = o.q_runs if o.q_runs is not None else 100
        init = o.init or "cycle"
        for sw in swimmers:
            for d in dirs or (1,):
                if "llm" in o.agents:
                    for name in o.variants or COMPETENCE_VARIANTS:
                        for k in range(runs):
                            add("llm", sw, d, init, k, o.zeta, name, n_ht=o.n_ht, variant=name)
                for agent in ("random", "qlearning"):
                    if agent in o.agents:
                        for allowed in ALLOWED_MODES:
                            for k in range(q_runs):
                                add(agent, sw, d, init, k, o.zeta, allowed, allowed=allowed)
    elif study == "inits":
        for sw in swimmers:
            for d in dirs or (1, -1):
                for init in env.all_inits(2):
                    label = _init_label(init)
                    for k in range(o.runs if o.runs is not None else 1):
                        add("llm", sw, d, label, k, o.zeta, f"init {label}", n_ht=o.n_ht)
    ids = [p.run_id for p in plans]
    assert len(set(ids)) == len(ids), "run ids must be unique"
    return plans


# -- execution ----------------------------------------------------------------------------------


def _judge_rows(plans: Sequence[Plan], actions: np.ndarray, xs: np.ndarray, levels0: np.ndarray,
                horizon: int, extra: Sequence[dict[str, Any]] | None = None) -> list[dict[str, Any]]:
    """Rows for a batch of runs of one swimmer, judged by the shared success criterion."""
    p0 = plans[0]
    params = env.make_params(p0.swimmer)
    params = params.replace(direction=np.array([p.direction for p in plans], float))
    rep = judge(actions, params, levels0=levels0, horizon=horizon)
    rows = []
    for i, p in enumerate(plans):
        x = [float(v) for v in xs[i]]
        prog = np.diff(np.concatenate([[0.0], xs[i]])) * p.direction
        row = {
            "run_id": p.run_id, "agent": p.agent, "swimmer": p.swimmer, "direction": p.direction,
            "init": "".join("+" if v else "-" for v in levels0[i]), "zeta": p.zeta, "seed": p.seed,
            "n_ht": p.n_ht, "drop": ",".join(sorted(p.drop)), "allowed": p.allowed, "group": p.group,
            "variant": p.variant,
            "steps": len(x), "final_x": x[-1] if x else 0.0,
            "signed_final_x": p.direction * (x[-1] if x else 0.0),
            "success": bool(rep.success[i]), "learned": bool(rep.learned[i]),
            "steps_to_learn": int(rep.steps_to_learn[i]) if rep.learned[i] else None,
            "period": int(rep.period[i]),
            "x": x, "actions": [list(env.decode_action(int(a))) for a in actions[i]],
            "progress": [float(v) for v in prog], "status": "done",
        }
        if extra is not None:
            row.update({k: v for k, v in extra[i].items() if k not in row})
        rows.append(row)
    return rows


def _run_baselines(plans: Sequence[Plan], horizon: int) -> list[dict[str, Any]]:
    """Q-learning or random runs of one (agent, swimmer, allowed) group, vectorised."""
    from jswim.agents import qlearning, random_policy

    p0 = plans[0]
    base = env.make_params(p0.swimmer)
    init = np.array([[-1] * base.n_dof if isinstance(p.init, str) else list(p.init) for p in plans], np.int32)
    params = qlearning.batch_params(base, len(plans), zeta=np.array([p.zeta for p in plans]),
                                    direction=np.array([p.direction for p in plans], float), init=init)
    keys = jax.vmap(jax.random.PRNGKey)(np.array([p.seed for p in plans], np.uint32))
    if p0.agent == "qlearning":
        cfg = qlearning.QConfig(steps=p0.steps, action_set=p0.allowed)
        run = qlearning.train_batch(keys, params, cfg)
    else:
        run = random_policy.run_batch(keys, params, p0.steps, p0.allowed)
    return _judge_rows(plans, np.asarray(run.actions), np.asarray(run.x), np.asarray(run.levels0), horizon)


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


def identity(study: str, o: StudyOptions, backend: Backend | None) -> dict[str, Any]:
    """Everything that defines a study's runs (compared when a folder is resumed)."""
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
    """``jswim-out/<study>-<hash>``: the same settings reuse (and resume) the same folder."""
    digest = hashlib.sha256(json.dumps(identity(study, o, backend), sort_keys=True, default=str).encode())
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
    plans = build(study, options)
    ident = identity(study, options, backend)
    if study == "competence":  # the variants' switches define the runs too
        from jswim.agents.llm import VARIANTS

        ident["variants"] = {v: VARIANTS[v] for v in options.variants or COMPETENCE_VARIANTS}
    folder = Path(out) if out is not None else default_folder(study, options, backend)
    template = PromptTemplate.from_file(options.prompt_file) if options.prompt_file else None
    store = StudyStore(folder, study, ident, extra={
        "jswim_version": __version__, "jax_version": jax.__version__, "python": platform.python_version(),
        "prompt_template": dataclasses.asdict(template or PromptTemplate()),
        "success_criterion": "3 consecutive qualifying cycles within the horizon, no later failure (jswim.gait.judge)",
        "horizon": options.horizon,
        "llm_variants": list(options.variants or COMPETENCE_VARIANTS) if study == "competence"
        else [options.llm_variant(study)],
    })
    done = store.done_ids()
    todo = [p for p in plans if p.run_id not in done]
    if backend is not None and not backend.local and any(p.agent == "llm" for p in todo):
        check_server(backend.base_url)  # fail before the baselines, not after
    total = len(plans)
    finished = total - len(todo)
    tick = progress or (lambda phase, d, t, info="": None)
    tick("resume" if finished else "start", finished, total, f"{finished} runs already done" if finished else "")

    for (agent, _sw, _allowed), group in _groups([p for p in todo if p.agent != "llm"], "agent", "swimmer", "allowed").items():
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
    store.finalize("complete", {"groups": summary, **({"llm_speed": speed} if speed else {})})
    figs = draw_figures(study, rows, folder / "figures") if figures else []
    return StudyResult(folder, rows, summary, figs, time.perf_counter() - t0, speed)


def _run_llm(plans: Sequence[Plan], o: StudyOptions, backend: Backend, store: StudyStore,
             template: PromptTemplate | None, tick: ProgressFn, finished: int, total: int,
             speed: dict[str, float] | None = None) -> int:
    """Run the LLM plans, one lockstep batch per (variant, allowed) group and chunk.

    ``speed`` (filled in) gets the calls made, the calls the server answered, the wall time and
    calls per second of this session's LLM work.
    """
    import asyncio

    from jswim.agents.llm import LLMRunSpec, run_batch_async, variant_config
    from jswim.llm.client import LLMClient
    from jswim.llm.sync import run_sync

    def spec(p: Plan) -> LLMRunSpec:
        return LLMRunSpec(swimmer=p.swimmer, direction=p.direction, init=p.init, zeta=p.zeta, seed=p.seed,
                          n_steps=p.steps, n_ht=p.n_ht, drop=p.drop, run_id=p.run_id)

    steps_total = sum(p.steps for p in plans)
    steps_done = 0
    t_start = time.perf_counter()
    calls = {"calls": 0, "billed_calls": 0}

    live: list[LLMClient] = []  # the open client, for its running counts

    def report(phase: str = "llm") -> None:
        rate = steps_done / max(time.perf_counter() - t_start, 1e-9)
        info = f"steps {steps_done}/{steps_total} {rate:.1f}/s"
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
        for (variant, allowed), group in _groups(plans, "variant", "allowed").items():
            cfg = variant_config(variant, allowed=allowed, **({"template": template} if template else {}))
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
            from jswim.llm.local import LocalServer

            with LocalServer(backend.gguf, n_parallel=backend.n_parallel, n_threads=backend.n_threads) as srv:
                t_start = time.perf_counter()  # the model's loading time is not LLM work
                return run_sync(go(backend.client_settings(srv.client_settings().base_url)))
        return run_sync(go(backend.client_settings()))
    finally:
        if speed is not None:
            wall = time.perf_counter() - t_start
            speed.update(calls, wall_s=wall, calls_per_s=calls["calls"] / wall if wall > 0 else 0.0,
                         billed_calls_per_s=calls["billed_calls"] / wall if wall > 0 else 0.0)


# -- summaries and figures ----------------------------------------------------------------------


def summarize(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per (agent, swimmer, direction, group): success rate with 95% Wilson CI, mean X/a in the
    target direction with a bootstrap CI, steps-to-learn quartiles, tokens per step.

    ``tokens_per_step`` counts what the model read and wrote per decision (shared and cached calls
    included) where rows record it. ``distinct`` is the number of different runs (start and
    actions): at temperature 0 without noise, runs from the same start are identical copies, so
    the intervals of such groups rest on fewer independent runs than ``n``."""
    out = []
    keys = ("agent", "swimmer", "direction", "group")
    grouped: dict[tuple, list[dict]] = {}
    for r in rows:
        grouped.setdefault(tuple(r.get(k) for k in keys), []).append(r)
    for key, g in sorted(grouped.items(), key=lambda kv: tuple(str(v) for v in kv[0])):
        k = sum(bool(r["success"]) for r in g)
        lo, hi = wilson_interval(k, len(g))
        m, mlo, mhi = mean_interval([r["signed_final_x"] for r in g])
        stl = [r["steps_to_learn"] for r in g if r.get("steps_to_learn") is not None]
        q = quartiles(stl)
        steps = sum(r["steps"] for r in g) or 1
        tokens = sum(r["tokens_seen"] if r.get("tokens_seen") is not None
                     else (r.get("prompt_tokens") or 0) + (r.get("completion_tokens") or 0) for r in g)
        distinct = len({(r.get("init"), json.dumps(r.get("actions"))) for r in g})
        out.append({
            **dict(zip(keys, key)), "n": len(g), "distinct": distinct,
            "success_rate": k / len(g), "success_lo": lo, "success_hi": hi,
            "mean_x": m, "mean_x_lo": mlo, "mean_x_hi": mhi,
            "steps_to_learn_q25": q[0], "steps_to_learn_median": q[1], "steps_to_learn_q75": q[2],
            "learned": len(stl), "tokens_per_step": tokens / steps if tokens else None,
            "failed_steps": sum(r.get("failed_steps") or 0 for r in g),
            "parse_retries": sum(r.get("parse_retries") or 0 for r in g),
            "cost_usd": sum(r.get("cost_usd") or 0.0 for r in g),
        })
    return out


def draw_figures(study: str, rows: Sequence[dict[str, Any]], folder: str | Path) -> list[Path]:
    """The study's figures as PNG and PDF in ``folder``."""
    from jswim import plots
    from jswim.swimmers.models import make_model

    if not rows:
        return []
    models = {sw: make_model(sw) for sw in {r["swimmer"] for r in rows}}
    paths: list[Path] = []
    if study in ("curves", "swim"):
        cycles = {}
        for sw in models:
            ok = [r for r in rows if r["swimmer"] == sw and r["success"]]
            ok.sort(key=lambda r: ({"llm": 0, "qlearning": 1}.get(r["agent"], 2), r["steps_to_learn"]))
            if ok:
                r = ok[0]
                s = r["steps_to_learn"]
                acts = [tuple(a) for a in r["actions"]][s: s + r["period"]]
                levels = [1 if ch == "+" else 0 for ch in r["init"]]
                for dof, roc in [tuple(a) for a in r["actions"]][:s]:
                    if roc:
                        levels[dof - 1] = 1 if roc > 0 else 0
                cycles[sw] = (levels, acts, r["agent"])
        paths += plots.save(plots.curves_figure(rows, models, cycles), folder, study)
    elif study == "history":
        paths += plots.save(plots.history_figure(rows), folder, "history")
    elif study == "noise":
        paths += plots.save(plots.noise_figure(rows), folder, "noise")
    elif study == "ablation":
        order = ["full"] + [f"-{s}" for s in SENTENCES]
        paths += plots.save(plots.bars_figure(rows, "group", order, "(sentence removed)"), folder, "ablation")
    elif study == "inits":
        paths += plots.save(plots.bars_figure(rows, "group", None, "(initial configuration)"), folder, "inits")
    elif study == "competence":
        # One entry per LLM variant, then one per baseline (agent, allowed set).
        entries = [{**r, "entry": r["group"] if r["agent"] == "llm" else f"{r['agent']} ({r['group']})"} for r in rows]
        from jswim.agents.llm import VARIANTS

        order = [v for v in VARIANTS if any(e["entry"] == v for e in entries)]
        order += sorted({e["entry"] for e in entries} - set(order))
        paths += plots.save(plots.competence_figure(entries, order), folder, "competence")
    return paths
