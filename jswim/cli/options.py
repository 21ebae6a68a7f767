"""argv -> options, in one place: the options of ``jswim swim`` and ``jswim study NAME`` (their
parsers, `options` -> [`jswim.studies.StudyOptions`][jswim.studies.options.StudyOptions], `backend` ->
[`jswim.llm.backend.Backend`][jswim.llm.backend.Backend]), read by those commands and by ``jswim bench --dry-run``
(which prices each job's study command line in process through `study_parser`).

A study's own options (the scene studies': ``--heights``, ...) are a table in `jswim.cli.scenes`.
"""

from __future__ import annotations

import argparse
import json
import os
from typing import Any
from collections.abc import Sequence
from urllib.parse import urlsplit

from jswim._io.paths import check_file
from jswim.action_codes import ACTION_SETS
from jswim.cli import base, scenes
from jswim.errors import ConfigError
from jswim.llm.prices import load_prices
from jswim.llm.urls import is_loopback, normalize_base_url

#: One line per study, for ``jswim study NAME --help``.
STUDY_HELP = {
    "curves": "X/a against step n for the LLM, Q-learning and random policy (Fig. 2)",
    "history": "the n_ht sweep of the history length (Fig. 3)",
    "noise": "mean X/a and success rate p against the noise level zeta (Fig. 4)",
    "ablation": "the prompt without each of its sentences S1..S5, free-text replies (Fig. 5)",
    "inits": "the four initial configurations",
    "competence": "every protocol variant next to random and Q-learning baselines",
    "temperature": "the LLM runs over a grid of sampling temperatures",
    **scenes.STUDY_HELP,
    "continuous": "finer ROCs (K in 1, 2, 5, 10) for the LLM, lattice Q-learning and random policy, and the "
    "real-valued PPO baseline",
}


def add_study_commands(sub: argparse._SubParsersAction) -> list[argparse.ArgumentParser]:
    """Add ``jswim swim`` and ``jswim study NAME`` (one parser per study) to ``sub``; their parsers."""
    p = sub.add_parser(
        "swim",
        help="the main job: LLM runs next to Q-learning and random learners",
        description="Drive swimmers with the LLM for a few short runs next to Q-learning and "
        "random-policy learners; print a summary table and write a figure.",
    )
    q = sub.add_parser(
        "study",
        help="run one of the paper's studies",
        description="Run a study grid (resumable). curves: Fig. 2; history: the n_ht sweep "
        "(Fig. 3); noise: mean X/a and success vs zeta (Fig. 4); ablation: S1..S5 "
        "removed (Fig. 5); inits: the four initial configurations; competence: "
        "every protocol variant next to random and Q-learning baselines; continuous: "
        "finer ROCs (--roc-levels) for the LLM and lattice Q-learning, and a "
        "real-valued RL baseline.",
    )
    if base.outlined(p):
        return [p, q]
    from jswim.studies.specs import SPECS, STUDIES  # lazy: the grids load JAX (not for --help)

    add_run_options(p, study=False, spec=SPECS["swim"])
    names = q.add_subparsers(
        dest="name",
        metavar="NAME",
        parser_class=base.Parser,
        help="curves, history, noise, ablation, inits, competence, temperature, continuous, "
        "wall or pair",
    )
    names.required = True
    out = [p]
    for name in (s for s in STUDIES if s != "swim"):
        s = names.add_parser(
            name,
            help=STUDY_HELP.get(name, name),
            description=f"The {name} study: {STUDY_HELP.get(name, name)}. Every default below is "
            "this study's.",
        )
        add_run_options(s, study=True, spec=SPECS[name])
        scenes.register(s, name)
        out.append(s)
    return out


def study_parser() -> argparse.ArgumentParser:
    """A parser of study command lines alone (``swim ...``, ``study NAME ...``): ``jswim bench``
    reads its jobs' argv with it."""
    ap = base.Parser(prog="jswim")
    add_study_commands(ap.add_subparsers(dest="command", parser_class=base.Parser))
    return ap


def add_run_options(p: argparse.ArgumentParser, *, study: bool, spec: Any) -> None:
    """The options of ``jswim swim`` and ``jswim study NAME``; each help names the defaults of the
    study (``spec``: its [`jswim.studies.specs.StudySpec`][jswim.studies.specs.StudySpec])."""
    from jswim.studies.options import (
        DEFAULT_ZETAS,
        StudyOptions,
    )  # lazy: the grids load JAX (not for --help)

    unused = set(spec.ignores)

    def shown(
        field: str, text: str
    ) -> str:  # an option the study has no use for is refused, not shown
        return argparse.SUPPRESS if field in unused else text

    g = p.add_argument_group("runs")
    g.add_argument(
        "--swimmer",
        type=base.swimmers,
        default=None,
        metavar="NAME",
        help=f"purcell, ng or both (or nlink, nsphere; default {','.join(spec.swimmers)})",
    )
    g.add_argument(
        "--direction",
        type=base.direction,
        default=None,
        metavar="DIR",
        help=f"target direction: +x, -x or both (default {base.dirs_text(spec.directions)})",
    )
    g.add_argument(
        "--steps",
        type=int,
        default=None,
        help=(
            f"steps per run (default: {spec.steps_text})"
            if spec.steps_text
            else f"steps per run (default {spec.steps}; 50 is the paper's horizon)"
        ),
    )
    g.add_argument(
        "--runs", type=int, default=None, help=f"LLM runs per setting (default {spec.runs})"
    )
    g.add_argument(
        "--q-runs",
        type=int,
        default=None,
        help=shown(
            "q_runs",
            "baseline runs per setting: Q-learning, random policy, PPO where the study "
            f"has it (default {spec.q_runs})",
        ),
    )
    g.add_argument(
        "--n-ht",
        type=int,
        default=None,
        help=shown(
            "n_ht",
            "history records in the prompt (default: per swimmer, 3 Purcell, 3/6 NG for "
            "+x/-x, 20 four-DOF)",
        ),
    )
    g.add_argument(
        "--noise",
        type=float,
        default=None,
        metavar="ZETA",
        help=shown(
            "zeta",
            "noise level zeta: each step's displacement becomes dX(1 + zeta Y), Y~U[-1,1] "
            "(default 0)",
        ),
    )
    g.add_argument(
        "--init",
        default=None,
        choices=("paper", "cycle", "random", "++", "+-", "-+", "--"),
        help=shown(
            "init",
            "initial configuration: paper = the authors' start per swimmer (Purcell "
            "(pi/3, pi/3), NG (10, 6), four-sphere (6, 10, 10), four-link hinges at +2pi/9), cycle = "
            f"repeats go through every corner, random, or a sign pair (default {spec.init})",
        ),
    )
    g.add_argument(
        "--action-set",
        "--allowed",
        dest="action_set",
        default="all",
        choices=ACTION_SETS,
        help="actions offered in S5 and by constrained decoding: all (the paper's) or only the "
        "moves that change the shape (default all; --allowed is the old name)",
    )
    g.add_argument(
        "--variant",
        default=None,
        metavar="NAME[,NAME...]",
        help="LLM protocol variant (jswim.agents.variants.VARIANTS; default: the study's, paper for the "
        "paper's studies); the competence study takes a comma-separated list to compare",
    )
    g.add_argument(
        "--roc-levels",
        type=base.ints,
        default=None,
        metavar="K",
        help="ROC on K levels (an extension): a reply's ROC k in -K..K moves the DOF by k/K of its range, "
        "for the LLM and the baselines alike (default 1, the paper's -1, 0, 1); the continuous study "
        "takes a list (default 1,2,5,10)",
    )
    g.add_argument(
        "--seed", type=int, default=0, help="seed of the study (noise, random starts, learners)"
    )
    g.add_argument(
        "--prompt-file",
        default=None,
        metavar="FILE",
        help="replace the prompt template with this file (see jswim.prompt for placeholders)",
    )
    g.add_argument(
        "--share-identical",
        action="store_true",
        help="send identical temperature-0 requests of different runs once and share the reply (cheaper; "
        "the runs are then copies of one run, not the paper's independent repeats)",
    )
    g.add_argument(
        "--x-min",
        type=float,
        default=-2.5,
        metavar="X",
        help="X_min of the position encoding (X - X_min) * 1000 (default -2.5, the paper's; a position "
        "below it is sent as a negative number and the run goes on)",
    )
    g.add_argument(
        "--max-tokens",
        type=int,
        default=None,
        metavar="N",
        help="reply length limit (default per swimmer: 10 two DOFs, 20 four-DOF, as the authors' code; "
        "raised where a constrained format needs more); reasoning models need thousands; "
        "--omit-field max_tokens sends none",
    )
    if study:
        n_hts = StudyOptions().n_hts
        g.add_argument(
            "--zetas",
            type=base.floats,
            default=None,
            metavar="Z1,Z2,...",
            help=shown(
                "zetas", f"noise grid (default {','.join(f'{z:g}' for z in DEFAULT_ZETAS)})"
            ),
        )
        g.add_argument(
            "--n-hts",
            type=base.ints,
            default=None,
            metavar="N1,N2,...",
            help=shown("n_hts", f"history lengths (default {n_hts[0]}..{n_hts[-1]})"),
        )
        g.add_argument(
            "--temperatures",
            type=base.floats,
            default=None,
            metavar="T1,T2,...",
            help=shown(
                "temperatures",
                "sampling temperatures as a grid axis of the study's LLM runs "
                "(each run above 0 sends its own seed); the temperature study's grid (default "
                "0,0.25,0.5,0.75,1); extends a folder",
            ),
        )
        g.add_argument(
            "--prompt-files",
            default=None,
            metavar="A,B,...",
            help=shown(
                "prompt_files",
                "prompt templates as a grid axis of the study's LLM runs (runs "
                "and rows named by each file's name); extends a folder",
            ),
        )
    g.add_argument(
        "--samples",
        type=int,
        default=None,
        metavar="N",
        help="independent samples of each LLM run's very setting (same start; each its own run id "
        "and seed, and at T > 0 its own request seeds), pooled into the setting's row; the "
        "baselines' repeats are --q-runs (default 1); extends a folder",
    )
    b = p.add_argument_group("LLM backend (default: the embedded SmolLM2-135M model, offline)")
    b.add_argument(
        "--base-url",
        default=None,
        help="an OpenAI-compatible server, e.g. http://localhost:8080/v1",
    )
    b.add_argument(
        "--model", default=None, help="model name on that server (required with --base-url)"
    )
    b.add_argument(
        "--gguf", default=None, metavar="FILE", help="another GGUF model for the embedded server"
    )
    b.add_argument(
        "--api-key-env",
        default=None,
        metavar="VAR",
        help="environment variable that holds the API key (never stored or printed); left out, "
        "OPENAI_API_KEY is sent to api.openai.com only and no key to any other host; named but "
        "unset or empty: an error for a remote server, a warning for this machine",
    )
    b.add_argument(
        "--constrain",
        default="auto",
        choices=("auto", "grammar", "json_schema", "json_object", "none"),
        help=(
            "constrained decoding (auto: none in this study, free text as the paper's; "
            if spec.constrain == "none"
            else "constrained decoding (auto: grammar for llama.cpp's and llama-cpp-python's servers and the "
            "embedded one, json_schema for vLLM and Ollama, falling back to json_object with a schema, "
            "then grammar, where the server rejects a form; none for OpenAI and unknown servers; "
        )
        + "the paper uses none)",
    )
    b.add_argument(
        "--sampling",
        default="auto",
        choices=("auto", "neutral", "server"),
        help="sampling fields sent: neutral turns off each knob the server family has (llama.cpp: "
        "repeat_penalty 1, top_k 0, top_p 1, min_p 0, no presence/frequency penalty; vLLM alike; "
        "nothing for OpenAI), server sends none (the server's own defaults, e.g. llama-cpp-python's "
        "repeat_penalty 1.1); auto (default): neutral for llama.cpp-family, vLLM and Ollama servers "
        "(the embedded one: the neutral penalties, its own defaults), none for OpenAI and unknown "
        "servers",
    )
    b.add_argument(
        "--server-family",
        default=None,
        choices=("llamacpp", "llama-cpp-python", "vllm", "ollama", "openai", "generic"),
        help="what serves --base-url, instead of the preflight's guess (llama.cpp: /props answers; "
        "llama-cpp-python, vLLM, Ollama: /v1/models owned_by me, vllm, library); sets the sampling "
        "fields, the auto decoding form and the default concurrency",
    )
    b.add_argument(
        "--strict-model",
        action="store_true",
        help="stop when the server's /v1/models does not list --model (default: a warning naming what "
        "it lists; many servers run their one model under any name)",
    )
    b.add_argument("--temperature", type=float, default=0.0, help="sampling temperature (paper: 0)")
    b.add_argument(
        "--parallel", type=int, default=4, help="decoding slots of the embedded server (default 4)"
    )
    b.add_argument(
        "--threads",
        type=int,
        default=None,
        metavar="N",
        help="CPU threads of the embedded server (default: one per core; fewer on a busy machine)",
    )
    b.add_argument(
        "--concurrency",
        type=int,
        default=None,
        help="requests in flight at once (default: the server's slots where it says, llama.cpp's "
        "/props total_slots; 1 for llama-cpp-python's server; else 16). A single-slot server only "
        "queues the others, and their wait counts against --timeout",
    )
    b.add_argument(
        "--cohorts", type=int, default=1, metavar="K", help=argparse.SUPPRESS
    )  # deprecated, no effect
    b.add_argument(
        "--rpm",
        type=float,
        default=None,
        metavar="N",
        help="requests per minute to pace to (default: none of our own; the provider's "
        "x-ratelimit-* and retry-after headers are always followed)",
    )
    b.add_argument(
        "--tpm",
        type=float,
        default=None,
        metavar="N",
        help="tokens per minute to pace to, prompt plus max_tokens as providers count them",
    )
    b.add_argument(
        "--cache-dir",
        default=None,
        metavar="DIR",
        help="persistent response cache (temperature 0; only replies that named a valid action)",
    )
    b.add_argument(
        "--timeout",
        type=float,
        default=None,
        metavar="S",
        help="seconds to wait for each reply (default 60; 120 for the embedded model); a reply that "
        "times out is asked for once more, then the study stops saying the server is slow",
    )
    b.add_argument(
        "--reasoning",
        default="auto",
        choices=("auto", "on", "off"),
        help="reasoning models: auto (default) switches to max_completion_tokens with a budget of "
        "4096 (--max-tokens sets it) and to the temperature the model accepts when the server's "
        "400 asks for them; on gives that budget from the first request (open reasoning models "
        "behind vLLM/llama.cpp); off never switches",
    )
    b.add_argument(
        "--reasoning-effort",
        default=None,
        choices=("minimal", "low", "medium", "high"),
        help="send reasoning_effort with every request (OpenAI reasoning models)",
    )
    b.add_argument(
        "--extra-field",
        action="append",
        default=[],
        metavar="NAME=JSON",
        help="send this field with every request, its value read as JSON (else as text), e.g. "
        'top_k=1 or \'response_format={"type": "text"}\'; repeatable; part of the study\'s identity',
    )
    b.add_argument(
        "--retries",
        type=int,
        default=None,
        metavar="N",
        help="retries of a call after a transient failure (429, 5xx, a dropped connection, a timeout) "
        "before the study stops, keeping every finished run (default 20; see --retry-for)",
    )
    b.add_argument(
        "--retry-for",
        type=float,
        default=None,
        metavar="S",
        help="seconds a call keeps retrying from its first failure, with exponential backoff and jitter "
        "(default 120: a server down for a minute does not stop the study)",
    )
    b.add_argument(
        "--omit-field",
        action="append",
        default=[],
        metavar="NAME",
        help="never send this optional request field (seed, max_tokens, stream, ...), for servers "
        "that reject it; repeat or comma-separate for several",
    )
    p.add_argument(
        "--out",
        default=None,
        metavar="FOLDER",
        help="output folder (default jswim-out/<study>-<hash of the settings>; rerun to resume)",
    )
    p.add_argument(
        "--no-figures",
        action="store_true",
        help="skip the publish step: no figures and no report.html (jswim plot / jswim report FOLDER draw them later)",
    )
    p.add_argument(
        "--chunk",
        type=int,
        default=None,
        metavar="N",
        help="LLM runs in progress at once; each run is saved as it ends (default: --concurrency)",
    )
    c = p.add_argument_group("cost")
    c.add_argument(
        "--dry-run",
        action="store_true",
        help="print the calls, estimated tokens and cost of the LLM runs not yet done, and exit; "
        "no request is sent, nothing is written",
    )
    c.add_argument(
        "--max-cost",
        type=float,
        default=None,
        metavar="USD",
        help="stop before the study's calls cost more than USD (over all its sessions; calls in "
        "flight count as reserved); rerun with a higher cap to continue, no call paid twice",
    )
    c.add_argument(
        "--prices",
        default=None,
        metavar="FILE",
        help="price table (TOML or JSON: model = [prompt, completion] USD per 1M tokens, optional "
        "as_of date) replacing the built-in one; see jswim.llm.prices",
    )
    c.add_argument(
        "--price-local",
        action="store_true",
        help="price a server on this machine or the LAN at the cloud list prices (a local gateway "
        "that forwards to a paid API); by default its calls cost nothing",
    )


def _extra_fields(items: Sequence[str]) -> tuple[tuple[str, Any], ...]:
    out = []
    for item in items:
        name, sep, text = item.partition("=")
        if not sep or not name.strip():
            raise ConfigError(f"--extra-field expects NAME=VALUE, got {item!r}")
        try:
            value = json.loads(text)
        except ValueError:
            value = text
        out.append((name.strip(), value))
    return tuple(out)


#: The variable read for the key when --api-key-env is left out, and the only hosts it is sent to.
DEFAULT_KEY_ENV, OPENAI_HOSTS = "OPENAI_API_KEY", ("api.openai.com",)


def default_key_env(base_url: str | None) -> str:
    """The key variable of a backend whose ``--api-key-env`` was left out: ``OPENAI_API_KEY`` for
    OpenAI's own API, else none (``""``): a key nobody named never goes to another host (a
    gateway, a local server), whatever the environment holds."""
    if base_url is None:
        return DEFAULT_KEY_ENV  # the embedded model: its own key (jswim.llm.local), this one is never read
    try:
        host = (urlsplit(normalize_base_url(base_url)).hostname or "").lower()
    except (ValueError, ConfigError):
        return ""
    return DEFAULT_KEY_ENV if host in OPENAI_HOSTS else ""


def backend(args: argparse.Namespace) -> Any:
    """The [`jswim.llm.backend.Backend`][jswim.llm.backend.Backend] of a study's command line (validated there)."""
    from jswim.llm.backend import Backend  # lazy: JAX and httpx load only for commands that run

    key_env = (
        default_key_env(args.base_url) if args.api_key_env is None else args.api_key_env.strip()
    )
    if args.api_key_env is not None and not key_env:
        raise ConfigError(
            "--api-key-env '': name the variable that holds the key (e.g. --api-key-env "
            "OPENAI_API_KEY), or leave --api-key-env out for a server without keys"
        )
    if args.api_key_env is not None and args.base_url is not None and not os.environ.get(key_env):
        state = "is set but empty" if key_env in os.environ else "is not set"
        if not is_loopback(normalize_base_url(args.base_url)):
            raise ConfigError(
                f"--api-key-env {key_env}: ${key_env} {state}; export the key in it (a remote "
                f"server would refuse every call), or leave --api-key-env out for a server without keys"
            )
        base.warn(
            f"--api-key-env {key_env}: ${key_env} {state}; requests to this machine's server go without a key"
        )
    prices, as_of = None, None
    if getattr(args, "prices", None):
        table, as_of = load_prices(args.prices)
        prices = tuple(sorted(table.items()))
    return Backend(
        base_url=args.base_url,
        model=args.model,
        gguf=args.gguf,
        api_key_env=key_env,
        constrain=args.constrain,
        temperature=args.temperature,
        n_parallel=args.parallel,
        n_threads=args.threads,
        concurrency=args.concurrency,
        cohorts=args.cohorts,
        cache_dir=args.cache_dir,
        timeout_s=args.timeout,
        omit_fields=tuple(f.strip() for v in args.omit_field for f in v.split(",") if f.strip()),
        rpm=args.rpm,
        tpm=args.tpm,
        price_local=args.price_local,
        reasoning=args.reasoning,
        reasoning_effort=args.reasoning_effort,
        prices=prices,
        prices_as_of=as_of,
        extra_fields=_extra_fields(args.extra_field),
        sampling=args.sampling,
        server_family=args.server_family,
        strict_model=args.strict_model,
        retries=args.retries,
        retry_for_s=args.retry_for,
    )


#: StudyOptions field <- argparse dest, each passed on when given (a study's own options: scenes.OPTIONS).
PASSED = {
    "swimmers": "swimmer",
    "directions": "direction",
    "runs": "runs",
    "q_runs": "q_runs",
    "steps": "steps",
    "n_ht": "n_ht",
    "init": "init",
    "seed": "seed",
    "action_set": "action_set",
    "prompt_file": "prompt_file",
    "chunk": "chunk",
    "share_identical": "share_identical",
    "x_min": "x_min",
    "max_tokens": "max_tokens",
}
#: Grid axes of ``jswim study``, passed on when given and not empty.
GRIDS = {"zetas": "zetas", "n_hts": "n_hts", "temperatures": "temperatures"}
#: Options some studies have no use for (refused there): StudyOptions field -> (dest, option).
IGNORABLE = {
    "zetas": ("zetas", "--zetas"),
    "n_hts": ("n_hts", "--n-hts"),
    "zeta": ("noise", "--noise"),
    "n_ht": ("n_ht", "--n-ht"),
    "q_runs": ("q_runs", "--q-runs"),
    "init": ("init", "--init"),
    "runs": ("runs", "--runs"),
    "directions": ("direction", "--direction"),
}

#: The options that choose an LLM, refused by a study without LLM runs.
LLM_OPTIONS = {"base_url": "--base-url", "model": "--model", "gguf": "--gguf"}


def options(args: argparse.Namespace, study: str) -> Any:
    """The [`jswim.studies.StudyOptions`][jswim.studies.options.StudyOptions] of a study's command line (validated there)."""
    from jswim.studies import StudyOptions  # lazy: JAX loads only for commands that run

    if args.prompt_file is not None:
        check_file(args.prompt_file, "--prompt-file")
    _refuse_ignored(study, args)
    kw: dict[str, Any] = {field: getattr(args, dest) for field, dest in PASSED.items()}
    kw["zeta"] = 0.0 if args.noise is None else args.noise
    kw.update(
        {field: getattr(args, dest) for field, dest in GRIDS.items() if getattr(args, dest, None)}
    )
    if getattr(args, "samples", None) is not None:
        kw["samples"] = args.samples
    if getattr(args, "prompt_files", None):
        kw["prompt_files"] = _prompt_files(args.prompt_files)
    if args.roc_levels is not None:
        if study == "continuous":
            kw["roc_levels_grid"] = args.roc_levels
        elif len(args.roc_levels) != 1:
            raise ConfigError(
                "--roc-levels takes one K here (a list only for the continuous study)"
            )
        elif study == "navigate" and args.roc_levels[0] < 2:
            raise ConfigError(
                f"--roc-levels {args.roc_levels[0]}: the navigate study steers on K >= 2 levels (the corner "
                "world, K = 1, cannot turn); leave it out for K = 2, or give 2 or more"
            )
        else:
            kw["roc_levels"] = args.roc_levels[0]
    names = tuple(v.strip() for v in (args.variant or "").split(",") if v.strip())
    if study == "competence" and names:
        kw["variants"] = names
    elif len(names) > 1:
        raise ConfigError("--variant takes one name here (a list only for the competence study)")
    elif names:
        kw["variant"] = names[0]
    kw.update(scenes.options(args))
    return StudyOptions(**kw)


def _prompt_files(text: str) -> tuple[str, ...]:
    """``--prompt-files A,B``: each a readable template, checked before anything runs."""
    from jswim.prompt import (
        PromptTemplate,
    )  # lazy: start-up (the prompt text is read only for a run)

    files = tuple(f.strip() for f in text.split(",") if f.strip())
    for f in files:
        check_file(f, "--prompt-files")
        try:
            PromptTemplate.from_file(f)
        except ConfigError as exc:  # named as the option the user gave
            raise ConfigError(str(exc).replace("--prompt-file ", "--prompt-files ", 1)) from None
    return files


def _refuse_ignored(study: str, args: argparse.Namespace) -> None:
    """An option the study would drop silently is a mistake: say so (exit 2) instead of running."""
    from jswim.studies.specs import ignored_options  # lazy: the grids load JAX

    given = [
        field for field, (dest, _) in IGNORABLE.items() if getattr(args, dest, None) is not None
    ]
    for field, why in ignored_options(study, given).items():
        raise ConfigError(
            f"the {study} study has no use for {IGNORABLE[field][1]} ({why}); leave it out"
        )
    llm = [flag for dest, flag in LLM_OPTIONS.items() if getattr(args, dest, None) is not None]
    for _, why in ignored_options(study, ["runs"] if llm else []).items():
        raise ConfigError(f"the {study} study has no use for {llm[0]} ({why}); leave it out")
