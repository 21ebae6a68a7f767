"""The options of ``jswim swim`` and ``jswim study NAME``, each defined once, as a table.

Each option is one `Flag`: its names, its argparse keywords, its group, its help (text or a
function of the study's [`Study`][jswim.studies.study.Study], so that every default the help
names is that study's), the [`StudyOptions`][jswim.studies.options.StudyOptions] field it sets
(``Flag.field``) and whether a bench suite part may set it (``Flag.part``). Every other view of
the options is read from this table: the parsers (`jswim.cli.options.add_run_options`), argv ->
`StudyOptions` and the refusals of an option a study has no use for
(`jswim.cli.options.options`), the keys of a bench suite's options
(`jswim.bench.suites.part_options`). A study's own options (the scene studies' ``--heights``,
...) are declared with the study (`jswim.studies.study.Study.flags`).
"""

from __future__ import annotations

import argparse
import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

from jswim._io.paths import check_file
from jswim.action_codes import ACTION_SETS
from jswim.errors import ConfigError

#: The groups of the options, in the order ``--help`` lists them (``""``: the parser's own).
RUNS, BACKEND, OUTPUT, COST = (
    "runs",
    "LLM backend (default: the embedded SmolLM2-135M model, offline)",
    "",
    "cost",
)


@dataclass(frozen=True)
class Flag:
    """One command-line option of a study.

    Attributes
    ----------
    names : tuple of str
        Its flags (the first is the one shown; the others are old names).
    help : str or callable
        Its help, or a function of the study's `Study` that returns it.
    group : str
        The help group it is listed in (`RUNS`, `BACKEND`, `OUTPUT`, `COST`).
    field : str or None
        The `StudyOptions` field it sets, its value passed on when given (``None``: read apart,
        or not a study option). A study whose ``Study.ignores`` names the field refuses the
        option and does not show it.
    convert : callable or None
        The field's value from the given one, checking it (where argparse's ``type`` would word
        an error otherwise, or too early).
    study_only : bool
        Only ``jswim study NAME`` has it (the grid axes), not ``jswim swim``.
    part : bool
        A bench suite part may set it, under `dest` (a models file's ``options`` key).
    llm : bool
        It chooses an LLM: a study without LLM runs refuses it.
    kwargs : mapping
        The rest of ``ArgumentParser.add_argument``'s keywords (``default=None`` unless given).
    """

    names: tuple[str, ...]
    help: str | Callable[[Any], str]
    group: str = RUNS
    field: str | None = None
    convert: Callable[[Any], Any] | None = None
    study_only: bool = False
    part: bool = False
    llm: bool = False
    kwargs: Mapping[str, Any] = dataclasses.field(default_factory=dict)

    @property
    def dest(self) -> str:
        """Its argparse ``dest``, as argparse names it (``--q-runs`` -> ``q_runs``)."""
        return self.kwargs.get("dest") or self.names[0].lstrip("-").replace("-", "_")


_META = ("group", "field", "convert", "study_only", "part", "llm")


def _flag(*names: str, help: str | Callable[[Any], str], **kw: Any) -> Flag:
    """A `Flag` from ``add_argument``-like keywords (`Flag`'s own attributes aside)."""
    meta = {k: kw.pop(k) for k in _META if k in kw}
    return Flag(names, help, kwargs=kw, **meta)


#: The swimmers ``--swimmer`` takes (``both``: purcell and ng).
SWIMMERS = ("purcell", "ng", "nlink", "nsphere")


def _listed(text: str, kind: type, what: str) -> tuple[Any, ...]:
    """``A,B,...`` as ``kind`` values; an empty item (``3,,6``, ``3,``) is refused, not dropped."""
    items = [v.strip() for v in text.split(",")]
    if not text.strip() or not all(items):
        raise argparse.ArgumentTypeError(
            f"expected comma-separated {what} without empty items, got {text!r}"
        )
    try:
        return tuple(kind(v) for v in items)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated {what}, got {text!r}") from None


def floats(text: str) -> tuple[float, ...]:
    """An argparse ``type``: ``"0,0.5"`` -> ``(0.0, 0.5)``."""
    return _listed(text, float, "numbers")


def ints(text: str) -> tuple[int, ...]:
    """An argparse ``type``: ``"3,6"`` -> ``(3, 6)``."""
    return _listed(text, int, "integers")


def direction(text: str) -> tuple[int, ...]:
    """An argparse ``type``: ``+x``, ``-x`` or ``both`` -> the target directions."""
    table = {"+x": (1,), "-x": (-1,), "both": (1, -1), "+1": (1,), "-1": (-1,), "1": (1,)}
    if text not in table:
        raise argparse.ArgumentTypeError(f"direction must be +x, -x or both, got {text!r}")
    return table[text]


def swimmers(text: str) -> tuple[str, ...]:
    """An argparse ``type``: ``purcell,ng`` or ``both`` -> the swimmers (`SWIMMERS`)."""
    out = ("purcell", "ng") if text == "both" else tuple(v.strip().lower() for v in text.split(","))
    for v in out:
        if v not in SWIMMERS:
            raise argparse.ArgumentTypeError(
                f"unknown swimmer {v!r}; choose purcell, ng, both (or nlink, nsphere)"
            )
    return out


def dirs_text(directions: Sequence[int]) -> str:
    """Target directions as ``--direction`` takes them (``(1, -1)`` -> ``both``)."""
    return "both" if set(directions) == {1, -1} else ("+x" if directions[0] > 0 else "-x")


def prompt_file_list(text: str) -> tuple[str, ...]:
    """``--prompt-files A,B``: each a readable template, checked before anything runs."""
    from jswim.prompt import PromptTemplate  # lazy: the prompt text is read only for a run

    files = tuple(f.strip() for f in text.split(",") if f.strip())
    for f in files:
        check_file(f, "--prompt-files")
        try:
            PromptTemplate.from_file(f)
        except ConfigError as exc:  # named as the option the user gave
            raise ConfigError(str(exc).replace("--prompt-file ", "--prompt-files ", 1)) from None
    return files


def _steps_help(spec: Any) -> str:
    if spec.steps_text:
        return f"steps per run (default: {spec.steps_text})"
    return f"steps per run (default {spec.steps}; 50 is the paper's horizon)"


def _zetas_help(spec: Any) -> str:
    from jswim.studies.options import DEFAULT_ZETAS  # lazy: the grids load JAX (not for --help)

    return f"noise grid (default {','.join(f'{z:g}' for z in DEFAULT_ZETAS)})"


def _n_hts_help(spec: Any) -> str:
    from jswim.studies.options import StudyOptions  # lazy: the grids load JAX (not for --help)

    n_hts = StudyOptions().n_hts
    return f"history lengths (default {n_hts[0]}..{n_hts[-1]})"


def _constrain_help(spec: Any) -> str:
    if spec.constrain == "none":
        head = "constrained decoding (auto: none in this study, free text as the paper's; "
    else:
        head = (
            "constrained decoding (auto: grammar for llama.cpp's and llama-cpp-python's servers "
            "and the embedded one, json_schema for vLLM and Ollama, falling back to json_object "
            "with a schema, then grammar, where the server rejects a form; none for OpenAI and "
            "unknown servers; "
        )
    return head + "the paper uses none)"


_RUN_FLAGS = [
    _flag(
        "--swimmer",
        field="swimmers",
        part=True,
        type=swimmers,
        metavar="NAME",
        help=lambda s: f"purcell, ng or both (or nlink, nsphere; default {','.join(s.swimmers)})",
    ),
    _flag(
        "--direction",
        part=True,
        field="directions",
        type=direction,
        metavar="DIR",
        help=lambda s: f"target direction: +x, -x or both (default {dirs_text(s.directions)})",
    ),
    _flag("--steps", field="steps", part=True, type=int, help=_steps_help),
    _flag(
        "--runs",
        part=True,
        field="runs",
        type=int,
        help=lambda s: f"LLM runs per setting (default {s.runs})",
    ),
    _flag(
        "--q-runs",
        part=True,
        field="q_runs",
        type=int,
        help=lambda s: (
            "baseline runs per setting: Q-learning, random policy, PPO where the study "
            f"has it (default {s.q_runs})"
        ),
    ),
    _flag(
        "--n-ht",
        part=True,
        field="n_ht",
        type=int,
        help="history records in the prompt (default: per swimmer, 3 Purcell, 3/6 NG for +x/-x, "
        "20 four-DOF)",
    ),
    _flag(
        "--noise",
        part=True,
        field="zeta",
        type=float,
        metavar="ZETA",
        help="noise level zeta: each step's displacement becomes dX(1 + zeta Y), Y~U[-1,1] "
        "(default 0)",
    ),
    _flag(
        "--init",
        part=True,
        field="init",
        choices=("paper", "cycle", "random", "++", "+-", "-+", "--"),
        help=lambda s: (
            "initial configuration: paper = the authors' start per swimmer (Purcell "
            "(pi/3, pi/3), NG (10, 6), four-sphere (6, 10, 10), four-link hinges at +2pi/9), cycle = "
            f"repeats go through every corner, random, or a sign pair (default {s.init})"
        ),
    ),
    _flag(
        "--action-set",
        "--allowed",
        field="action_set",
        part=True,
        dest="action_set",
        default="all",
        choices=ACTION_SETS,
        help="actions offered in S5 and by constrained decoding: all (the paper's) or only the "
        "moves that change the shape (default all; --allowed is the old name)",
    ),
    _flag(
        "--variant",
        part=True,
        metavar="NAME[,NAME...]",
        help="LLM protocol variant (jswim.agents.variants.VARIANTS; default: the study's, paper "
        "for the paper's studies); the competence study takes a comma-separated list to compare",
    ),
    _flag(
        "--roc-levels",
        type=ints,
        metavar="K",
        help="ROC on K levels (an extension): a reply's ROC k in -K..K moves the DOF by k/K of its "
        "range, for the LLM and the baselines alike (default 1, the paper's -1, 0, 1)",
    ),
    _flag(
        "--seed",
        field="seed",
        part=True,
        type=int,
        default=0,
        help="seed of the study (noise, random starts, learners)",
    ),
    _flag(
        "--prompt-file",
        field="prompt_file",
        part=True,
        metavar="FILE",
        help="replace the prompt template with this file (see jswim.prompt for placeholders)",
    ),
    _flag(
        "--share-identical",
        field="share_identical",
        action="store_true",
        help="send identical temperature-0 requests of different runs once and share the reply "
        "(cheaper; the runs are then copies of one run, not the paper's independent repeats)",
    ),
    _flag(
        "--x-min",
        field="x_min",
        part=True,
        type=float,
        default=-2.5,
        metavar="X",
        help="X_min of the position encoding (X - X_min) * 1000 (default -2.5, the paper's; a "
        "position below it is sent as a negative number and the run goes on)",
    ),
    _flag(
        "--max-tokens",
        field="max_tokens",
        type=int,
        metavar="N",
        help="reply length limit (default per swimmer: 10 two DOFs, 20 four-DOF, as the authors' "
        "code; raised where a constrained format needs more); reasoning models need thousands; "
        "--omit-field max_tokens sends none",
    ),
    _flag(
        "--zetas",
        part=True,
        field="zetas",
        study_only=True,
        type=floats,
        metavar="Z1,Z2,...",
        help=_zetas_help,
    ),
    _flag(
        "--n-hts",
        part=True,
        field="n_hts",
        study_only=True,
        type=ints,
        metavar="N1,N2,...",
        help=_n_hts_help,
    ),
    _flag(
        "--temperatures",
        part=True,
        field="temperatures",
        study_only=True,
        type=floats,
        metavar="T1,T2,...",
        help="sampling temperatures as a grid axis of the study's LLM runs (each run above 0 "
        "sends its own seed); the temperature study's grid (default 0,0.25,0.5,0.75,1); extends "
        "a folder",
    ),
    _flag(
        "--prompt-files",
        convert=prompt_file_list,
        part=True,
        field="prompt_files",
        study_only=True,
        metavar="A,B,...",
        help="prompt templates as a grid axis of the study's LLM runs (runs and rows named by "
        "each file's name); extends a folder",
    ),
    _flag(
        "--samples",
        field="samples",
        part=True,
        type=int,
        metavar="N",
        help="independent samples of each LLM run's very setting (same start; each its own run id "
        "and seed, and at T > 0 its own request seeds), pooled into the setting's row; the "
        "baselines' repeats are --q-runs (default 1); extends a folder",
    ),
]

_BACKEND_FLAGS = [
    _flag(
        "--base-url", llm=True, help="an OpenAI-compatible server, e.g. http://localhost:8080/v1"
    ),
    _flag("--model", llm=True, help="model name on that server (required with --base-url)"),
    _flag("--gguf", llm=True, metavar="FILE", help="another GGUF model for the embedded server"),
    _flag(
        "--api-key-env",
        metavar="VAR",
        help="environment variable that holds the API key (never stored or printed); left out, "
        "OPENAI_API_KEY is sent to api.openai.com only and no key to any other host; named but "
        "unset or empty: an error for a remote server, a warning for this machine",
    ),
    _flag(
        "--constrain",
        default="auto",
        choices=("auto", "grammar", "json_schema", "json_object", "none"),
        help=_constrain_help,
    ),
    _flag(
        "--sampling",
        default="auto",
        choices=("auto", "neutral", "server"),
        help="sampling fields sent: neutral turns off each knob the server family has (llama.cpp: "
        "repeat_penalty 1, top_k 0, top_p 1, min_p 0, no presence/frequency penalty; vLLM alike; "
        "nothing for OpenAI), server sends none (the server's own defaults, e.g. "
        "llama-cpp-python's repeat_penalty 1.1); auto (default): neutral for llama.cpp-family, "
        "vLLM and Ollama servers (the embedded one: the neutral penalties, its own defaults), "
        "none for OpenAI and unknown servers",
    ),
    _flag(
        "--server-family",
        choices=("llamacpp", "llama-cpp-python", "vllm", "ollama", "openai", "generic"),
        help="what serves --base-url, instead of the preflight's guess (llama.cpp: /props answers; "
        "llama-cpp-python, vLLM, Ollama: /v1/models owned_by me, vllm, library); sets the "
        "sampling fields, the auto decoding form and the default concurrency",
    ),
    _flag(
        "--strict-model",
        action="store_true",
        help="stop when the server's /v1/models does not list --model (default: a warning naming "
        "what it lists; many servers run their one model under any name)",
    ),
    _flag("--temperature", type=float, default=0.0, help="sampling temperature (paper: 0)"),
    _flag(
        "--parallel", type=int, default=4, help="decoding slots of the embedded server (default 4)"
    ),
    _flag(
        "--threads",
        type=int,
        metavar="N",
        help="CPU threads of the embedded server (default: one per core; fewer on a busy machine)",
    ),
    _flag(
        "--concurrency",
        type=int,
        help="requests in flight at once (default: the server's slots where it says, llama.cpp's "
        "/props total_slots; 1 for llama-cpp-python's server; else 16). A single-slot server "
        "only queues the others, and their wait counts against --timeout",
    ),
    # deprecated, no effect; kept so that old command lines (and bench files) still parse
    _flag("--cohorts", type=int, default=1, metavar="K", help=argparse.SUPPRESS),
    _flag(
        "--rpm",
        type=float,
        metavar="N",
        help="requests per minute to pace to (default: none of our own; the provider's "
        "x-ratelimit-* and retry-after headers are always followed)",
    ),
    _flag(
        "--tpm",
        type=float,
        metavar="N",
        help="tokens per minute to pace to, prompt plus max_tokens as providers count them",
    ),
    _flag(
        "--cache-dir",
        metavar="DIR",
        help="persistent response cache (temperature 0; only replies that named a valid action)",
    ),
    _flag(
        "--timeout",
        type=float,
        metavar="S",
        help="seconds to wait for each reply (default 60; 120 for the embedded model); a reply "
        "that times out is asked for once more, then the study stops saying the server is slow",
    ),
    _flag(
        "--reasoning",
        default="auto",
        choices=("auto", "on", "off"),
        help="reasoning models: auto (default) switches to max_completion_tokens with a budget of "
        "4096 (--max-tokens sets it) and to the temperature the model accepts when the server's "
        "400 asks for them; on gives that budget from the first request (open reasoning models "
        "behind vLLM/llama.cpp); off never switches",
    ),
    _flag(
        "--reasoning-effort",
        choices=("minimal", "low", "medium", "high"),
        help="send reasoning_effort with every request (OpenAI reasoning models)",
    ),
    _flag(
        "--extra-field",
        action="append",
        default=[],
        metavar="NAME=JSON",
        help="send this field with every request, its value read as JSON (else as text), e.g. "
        'top_k=1 or \'response_format={"type": "text"}\'; repeatable; part of the study\'s '
        "identity",
    ),
    _flag(
        "--retries",
        type=int,
        metavar="N",
        help="retries of a call after a transient failure (429, 5xx, a dropped connection, a "
        "timeout) before the study stops, keeping every finished run (default 20; see "
        "--retry-for)",
    ),
    _flag(
        "--retry-for",
        type=float,
        metavar="S",
        help="seconds a call keeps retrying from its first failure, with exponential backoff and "
        "jitter (default 120: a server down for a minute does not stop the study)",
    ),
    _flag(
        "--omit-field",
        action="append",
        default=[],
        metavar="NAME",
        help="never send this optional request field (seed, max_tokens, stream, ...), for servers "
        "that reject it; repeat or comma-separate for several",
    ),
]

_OUTPUT_FLAGS = [
    _flag(
        "--out",
        metavar="FOLDER",
        help="output folder (default jswim-out/<study>-<hash of the settings>; rerun to resume)",
    ),
    _flag(
        "--no-figures",
        action="store_true",
        help="skip the publish step: no figures and no report.html (jswim plot / jswim report "
        "FOLDER draw them later)",
    ),
    _flag(
        "--chunk",
        field="chunk",
        type=int,
        metavar="N",
        help="LLM runs in progress at once; each run is saved as it ends (default: --concurrency)",
    ),
]

_COST_FLAGS = [
    _flag(
        "--dry-run",
        action="store_true",
        help="print the calls, estimated tokens and cost of the LLM runs not yet done, and exit; "
        "no request is sent, nothing is written",
    ),
    _flag(
        "--max-cost",
        type=float,
        metavar="USD",
        help="stop before the study's calls cost more than USD (over all its sessions; calls in "
        "flight count as reserved); rerun with a higher cap to continue, no call paid twice",
    ),
    _flag(
        "--prices",
        metavar="FILE",
        help="price table (TOML or JSON: model = [prompt, completion] USD per 1M tokens, optional "
        "as_of date) replacing the built-in one; see jswim.llm.prices",
    ),
    _flag(
        "--price-local",
        action="store_true",
        help="price a server on this machine or the LAN at the cloud list prices (a local gateway "
        "that forwards to a paid API); by default its calls cost nothing",
    ),
]


def _in(group: str, flags: list[Flag]) -> list[Flag]:
    return [dataclasses.replace(f, group=group) for f in flags]


#: Every option of ``jswim swim`` and ``jswim study NAME``, in ``--help`` order.
FLAGS: tuple[Flag, ...] = (
    *_RUN_FLAGS,
    *_in(BACKEND, _BACKEND_FLAGS),
    *_in(OUTPUT, _OUTPUT_FLAGS),
    *_in(COST, _COST_FLAGS),
)
