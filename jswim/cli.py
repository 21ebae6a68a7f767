"""The ``jswim`` command.

``jswim swim``           the main job: LLM-driven swimmers next to Q-learning and random learners
``jswim study NAME``     one of the paper's studies (curves, history, noise, ablation, inits)
``jswim qlearn``         the Q-learning baseline's steps-to-learn distributions
``jswim ensemble``       a stroke or policy over many noisy swimmers: X/a statistics per step
``jswim gaits SWIMMER``  closed stroke cycles ranked by displacement per step
``jswim plot FOLDER``    redraw a study folder's figures
``jswim show FOLDER``    a study folder's status, settings, cost, summary table and figures (read-only)
``jswim compare F1 F2..`` studies side by side, per setting present in all (read-only)
``jswim report FOLDER``  write the folder's report.html (settings, table, figures, a run browser)
``jswim animate FOLDER`` runs of a study folder as a GIF or MP4, side by side

A user mistake ends with one line on stderr and exit status 2; Ctrl-C keeps every finished run.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import signal
import sys
import time
from pathlib import Path
from typing import Any, Iterator, Sequence

from jswim.actions import ACTION_SETS
from jswim._io.paths import path_kind  # noqa: F401  (also read from here)
from jswim.errors import ConfigError, JswimError, LLMServerError
from jswim.commands import scenes as scene_options
from jswim._io.jsonl import forget_warnings

EXIT_USAGE = 2
#: Largest count a batched command accepts (--n, --seeds, --steps, --chunk): swimmer and learner
#: indices are int32 on the device, and anything larger would fail deep inside JAX or NumPy.
MAX_COUNT = 2**31 - 1


class _Parser(argparse.ArgumentParser):
    """argparse that reports mistakes in one line with exit status 2 (its own default too)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see --help)\n")


def _floats(text: str) -> tuple[float, ...]:
    try:
        return tuple(float(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated numbers, got {text!r}") from None


def _ints(text: str) -> tuple[int, ...]:
    try:
        return tuple(int(v) for v in text.split(",") if v.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated integers, got {text!r}") from None


def _direction(text: str) -> tuple[int, ...]:
    table = {"+x": (1,), "-x": (-1,), "both": (1, -1), "+1": (1,), "-1": (-1,), "1": (1,)}
    if text not in table:
        raise argparse.ArgumentTypeError(f"direction must be +x, -x or both, got {text!r}")
    return table[text]


def _swimmers(text: str) -> tuple[str, ...]:
    names = ("purcell", "ng", "nlink", "nsphere")
    out = ("purcell", "ng") if text == "both" else tuple(v.strip().lower() for v in text.split(","))
    for v in out:
        if v not in names:
            raise argparse.ArgumentTypeError(f"unknown swimmer {v!r}; choose purcell, ng, both (or nlink, nsphere)")
    return out


def _dirs_text(directions: Sequence[int]) -> str:
    return "both" if set(directions) == {1, -1} else ("+x" if directions[0] > 0 else "-x")


def _add_run_options(p: argparse.ArgumentParser, *, study: bool, spec: Any) -> None:
    """The options of ``jswim swim`` and ``jswim study NAME``; each help names the defaults of the
    study (``spec``: its :class:`jswim.studies.grids.StudySpec`)."""
    if isinstance(p, _Outline):
        return
    from jswim.studies.grids import DEFAULT_ZETAS, StudyOptions

    unused = set(spec.ignores)

    def shown(field: str, text: str) -> str:  # an option the study has no use for is refused, not shown
        return argparse.SUPPRESS if field in unused else text

    g = p.add_argument_group("runs")
    g.add_argument("--swimmer", type=_swimmers, default=None, metavar="NAME",
                   help=f"purcell, ng or both (or nlink, nsphere; default {','.join(spec.swimmers)})")
    g.add_argument("--direction", type=_direction, default=None, metavar="DIR",
                   help=f"target direction: +x, -x or both (default {_dirs_text(spec.directions)})")
    g.add_argument("--steps", type=int, default=50, help="steps per run (default 50, the paper's horizon)")
    g.add_argument("--runs", type=int, default=None,
                   help=f"LLM runs per setting (default {spec.runs})")
    g.add_argument("--q-runs", type=int, default=None,
                   help=shown("q_runs", "baseline runs per setting: Q-learning, random policy, PPO where the study "
                                        f"has it (default {spec.q_runs})"))
    g.add_argument("--n-ht", type=int, default=None,
                   help=shown("n_ht", "history records in the prompt (default: per swimmer, 3 Purcell, 3/6 NG for "
                              "+x/-x, 20 four-DOF)"))
    g.add_argument("--noise", type=float, default=None, metavar="ZETA",
                   help=shown("zeta", "noise level zeta: each step's displacement becomes dX(1 + zeta Y), Y~U[-1,1] "
                              "(default 0)"))
    g.add_argument("--init", default=None, choices=("paper", "cycle", "random", "++", "+-", "-+", "--"),
                   help=shown("init", "initial configuration: paper = the authors' start per swimmer (Purcell "
                              "(pi/3, pi/3), NG (10, 6), four-sphere (6, 10, 10), four-link hinges at +2pi/9), cycle = "
                              f"repeats go through every corner, random, or a sign pair (default {spec.init})"))
    g.add_argument("--action-set", "--allowed", dest="action_set", default="all", choices=ACTION_SETS,
                   help="actions offered in S5 and by constrained decoding: all (the paper's) or only the "
                        "moves that change the shape (default all; --allowed is the old name)")
    g.add_argument("--variant", default=None, metavar="NAME[,NAME...]",
                   help="LLM protocol variant (jswim.agents.variants.VARIANTS; default: the study's, paper for the "
                        "paper's studies); the competence study takes a comma-separated list to compare")
    g.add_argument("--roc-levels", type=_ints, default=None, metavar="K",
                   help="ROC on K levels (an extension): a reply's ROC k in -K..K moves the DOF by k/K of its range, "
                        "for the LLM and the baselines alike (default 1, the paper's -1, 0, 1); the continuous study "
                        "takes a list (default 1,2,5,10)")
    g.add_argument("--seed", type=int, default=0, help="seed of the study (noise, random starts, learners)")
    g.add_argument("--prompt-file", default=None, metavar="FILE",
                   help="replace the prompt template with this file (see jswim.prompt for placeholders)")
    g.add_argument("--share-identical", action="store_true",
                   help="send identical temperature-0 requests of different runs once and share the reply (cheaper; "
                        "the runs are then copies of one run, not the paper's independent repeats)")
    g.add_argument("--x-min", type=float, default=-2.5, metavar="X",
                   help="X_min of the position encoding (X - X_min) * 1000 (default -2.5, the paper's; a position "
                        "below it is sent as a negative number and the run goes on)")
    g.add_argument("--max-tokens", type=int, default=None, metavar="N",
                   help="reply length limit (default per swimmer: 10 two DOFs, 20 four-DOF, as the authors' code; "
                        "raised where a constrained format needs more); reasoning models need thousands; "
                        "--omit-field max_tokens sends none")
    if study:
        n_hts = StudyOptions().n_hts
        g.add_argument("--zetas", type=_floats, default=None, metavar="Z1,Z2,...",
                       help=shown("zetas", f"noise grid (default {','.join(f'{z:g}' for z in DEFAULT_ZETAS)})"))
        g.add_argument("--n-hts", type=_ints, default=None, metavar="N1,N2,...",
                       help=shown("n_hts", f"history lengths (default {n_hts[0]}..{n_hts[-1]})"))
        g.add_argument("--temperatures", type=_floats, default=None, metavar="T1,T2,...",
                       help=shown("temperatures", "sampling temperatures as a grid axis of the study's LLM runs "
                                  "(each run above 0 sends its own seed); the temperature study's grid (default "
                                  "0,0.25,0.5,0.75,1); extends a folder"))
        g.add_argument("--prompt-files", default=None, metavar="A,B,...",
                       help=shown("prompt_files", "prompt templates as a grid axis of the study's LLM runs (runs "
                                  "and rows named by each file's name); extends a folder"))
    g.add_argument("--samples", type=int, default=None, metavar="N",
                   help="independent samples of each LLM run's very setting (same start; each its own run id "
                        "and seed, and at T > 0 its own request seeds), pooled into the setting's row; the "
                        "baselines' repeats are --q-runs (default 1); extends a folder")
    b = p.add_argument_group("LLM backend (default: the embedded SmolLM2-135M model, offline)")
    b.add_argument("--base-url", default=None, help="an OpenAI-compatible server, e.g. http://localhost:8080/v1")
    b.add_argument("--model", default=None, help="model name on that server (required with --base-url)")
    b.add_argument("--gguf", default=None, metavar="FILE", help="another GGUF model for the embedded server")
    b.add_argument("--api-key-env", default=None, metavar="VAR",
                   help="environment variable that holds the API key (never stored or printed); left out, "
                        "OPENAI_API_KEY is sent to api.openai.com only and no key to any other host; named but "
                        "unset or empty: an error for a remote server, a warning for this machine")
    b.add_argument("--constrain", default="auto", choices=("auto", "grammar", "json_schema", "json_object", "none"),
                   help=("constrained decoding (auto: none in this study, free text as the paper's; "
                         if spec.constrain == "none" else
                         "constrained decoding (auto: grammar for llama.cpp's and llama-cpp-python's servers and the "
                         "embedded one, json_schema for vLLM and Ollama, falling back to json_object with a schema, "
                         "then grammar, where the server rejects a form; none for OpenAI and unknown servers; ")
                   + "the paper uses none)")
    b.add_argument("--sampling", default="auto", choices=("auto", "neutral", "server"),
                   help="sampling fields sent: neutral turns off each knob the server family has (llama.cpp: "
                        "repeat_penalty 1, top_k 0, top_p 1, min_p 0, no presence/frequency penalty; vLLM alike; "
                        "nothing for OpenAI), server sends none (the server's own defaults, e.g. llama-cpp-python's "
                        "repeat_penalty 1.1); auto (default): neutral for llama.cpp-family, vLLM and Ollama servers "
                        "(the embedded one: the neutral penalties, its own defaults), none for OpenAI and unknown "
                        "servers")
    b.add_argument("--server-family", default=None,
                   choices=("llamacpp", "llama-cpp-python", "vllm", "ollama", "openai", "generic"),
                   help="what serves --base-url, instead of the preflight's guess (llama.cpp: /props answers; "
                        "llama-cpp-python, vLLM, Ollama: /v1/models owned_by me, vllm, library); sets the sampling "
                        "fields, the auto decoding form and the default concurrency")
    b.add_argument("--strict-model", action="store_true",
                   help="stop when the server's /v1/models does not list --model (default: a warning naming what "
                        "it lists; many servers run their one model under any name)")
    b.add_argument("--temperature", type=float, default=0.0, help="sampling temperature (paper: 0)")
    b.add_argument("--parallel", type=int, default=4, help="decoding slots of the embedded server (default 4)")
    b.add_argument("--threads", type=int, default=None, metavar="N",
                   help="CPU threads of the embedded server (default: one per core; fewer on a busy machine)")
    b.add_argument("--concurrency", type=int, default=None,
                   help="requests in flight at once (default: the server's slots where it says, llama.cpp's "
                        "/props total_slots; 1 for llama-cpp-python's server; else 16). A single-slot server only "
                        "queues the others, and their wait counts against --timeout")
    b.add_argument("--cohorts", type=int, default=1, metavar="K", help=argparse.SUPPRESS)  # deprecated, no effect
    b.add_argument("--rpm", type=float, default=None, metavar="N",
                   help="requests per minute to pace to (default: none of our own; the provider's "
                        "x-ratelimit-* and retry-after headers are always followed)")
    b.add_argument("--tpm", type=float, default=None, metavar="N",
                   help="tokens per minute to pace to, prompt plus max_tokens as providers count them")
    b.add_argument("--cache-dir", default=None, metavar="DIR",
                   help="persistent response cache (temperature 0; only replies that named a valid action)")
    b.add_argument("--timeout", type=float, default=None, metavar="S",
                   help="seconds to wait for each reply (default 60; 120 for the embedded model); a reply that "
                        "times out is asked for once more, then the study stops saying the server is slow")
    b.add_argument("--reasoning", default="auto", choices=("auto", "on", "off"),
                   help="reasoning models: auto (default) switches to max_completion_tokens with a budget of "
                        "4096 (--max-tokens sets it) and to the temperature the model accepts when the server's "
                        "400 asks for them; on gives that budget from the first request (open reasoning models "
                        "behind vLLM/llama.cpp); off never switches")
    b.add_argument("--reasoning-effort", default=None, choices=("minimal", "low", "medium", "high"),
                   help="send reasoning_effort with every request (OpenAI reasoning models)")
    b.add_argument("--extra-field", action="append", default=[], metavar="NAME=JSON",
                   help="send this field with every request, its value read as JSON (else as text), e.g. "
                        "top_k=1 or 'response_format={\"type\": \"text\"}'; repeatable; part of the study's identity")
    b.add_argument("--retries", type=int, default=None, metavar="N",
                   help="retries of a call after a transient failure (429, 5xx, a dropped connection, a timeout) "
                        "before the study stops, keeping every finished run (default 20; see --retry-for)")
    b.add_argument("--retry-for", type=float, default=None, metavar="S",
                   help="seconds a call keeps retrying from its first failure, with exponential backoff and jitter "
                        "(default 120: a server down for a minute does not stop the study)")
    b.add_argument("--omit-field", action="append", default=[], metavar="NAME",
                   help="never send this optional request field (seed, max_tokens, stream, ...), for servers "
                        "that reject it; repeat or comma-separate for several")
    p.add_argument("--out", default=None, metavar="FOLDER",
                   help="output folder (default jswim-out/<study>-<hash of the settings>; rerun to resume)")
    p.add_argument("--no-figures", action="store_true", help="skip the figures")
    p.add_argument("--chunk", type=int, default=None, metavar="N",
                   help="LLM runs in progress at once; each run is saved as it ends (default: --concurrency)")
    c = p.add_argument_group("cost")
    c.add_argument("--dry-run", action="store_true",
                   help="print the calls, estimated tokens and cost of the LLM runs not yet done, and exit; "
                        "no request is sent, nothing is written")
    c.add_argument("--max-cost", type=float, default=None, metavar="USD",
                   help="stop before the study's calls cost more than USD (over all its sessions; calls in "
                        "flight count as reserved); rerun with a higher cap to continue, no call paid twice")
    c.add_argument("--prices", default=None, metavar="FILE",
                   help="price table (TOML or JSON: model = [prompt, completion] USD per 1M tokens, optional "
                        "as_of date) replacing the built-in one; see jswim.llm.prices")
    c.add_argument("--price-local", action="store_true",
                   help="price a server on this machine or the LAN at the cloud list prices (a local gateway "
                        "that forwards to a paid API); by default its calls cost nothing")


#: One line per study, for ``jswim study NAME --help``.
STUDY_HELP = {
    "curves": "X/a against step n for the LLM, Q-learning and random policy (Fig. 2)",
    "history": "the n_ht sweep of the history length (Fig. 3)",
    "noise": "mean X/a and success rate p against the noise level zeta (Fig. 4)",
    "ablation": "the prompt without each of its sentences S1..S5, free-text replies (Fig. 5)",
    "inits": "the four initial configurations",
    "competence": "every protocol variant next to random and Q-learning baselines",
    "temperature": "the LLM runs over a grid of sampling temperatures",
    **scene_options.STUDY_HELP,
    "continuous": "finer ROCs (K in 1, 2, 5, 10) for the LLM, lattice Q-learning and random policy, and the "
                  "real-valued PPO baseline",
}


class _Outline(_Parser):
    """A parser that keeps only the subcommands' names and help: all ``jswim --help`` shows, built
    without the options' defaults (which import the study grids, and with them JAX: ~1.4 s)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._outlined = True  # argparse's own groups and -h/--help exist; every later option is left out

    def add_argument(self, *args: Any, **kwargs: Any) -> Any:
        return super().add_argument(*args, **kwargs) if not getattr(self, "_outlined", False) else None

    def add_argument_group(self, *args: Any, **kwargs: Any) -> Any:
        return super().add_argument_group(*args, **kwargs) if not getattr(self, "_outlined", False) else self

    def add_mutually_exclusive_group(self, *args: Any, **kwargs: Any) -> Any:
        return self

    def add_subparsers(self, **kwargs: Any) -> Any:
        return super().add_subparsers(**{**kwargs, "parser_class": _Outline})


def build_parser(outline: bool = False) -> argparse.ArgumentParser:
    """The ``jswim`` parser; ``outline`` builds only its subcommands' names (``jswim --help``)."""
    if outline:
        import collections

        DEFAULT_ZETAS, SPECS, STUDIES = (), collections.defaultdict(lambda: None), ()  # noqa: N806
    else:
        from jswim.studies.grids import DEFAULT_ZETAS, SPECS, STUDIES  # lazy: the grids load JAX

    ap = (_Outline if outline else _Parser)(prog="jswim", description="A large language model teaches model microswimmers to swim, "
                 "measured against Q-learning and a random policy.",
                 epilog="Every command takes --help. Results land in a study folder that a rerun resumes.")
    sub = ap.add_subparsers(dest="command", metavar="COMMAND", parser_class=_Outline if outline else _Parser)
    sub.required = True
    p = sub.add_parser("swim", help="the main job: LLM runs next to Q-learning and random learners",
                       description="Drive swimmers with the LLM for a few short runs next to Q-learning and "
                                   "random-policy learners; print a summary table and write a figure.")
    _add_run_options(p, study=False, spec=SPECS["swim"])
    p = sub.add_parser("study", help="run one of the paper's studies",
                       description="Run a study grid (resumable). curves: Fig. 2; history: the n_ht sweep "
                                   "(Fig. 3); noise: mean X/a and success vs zeta (Fig. 4); ablation: S1..S5 "
                                   "removed (Fig. 5); inits: the four initial configurations; competence: "
                                   "every protocol variant next to random and Q-learning baselines; continuous: "
                                   "finer ROCs (--roc-levels) for the LLM and lattice Q-learning, and a "
                                   "real-valued RL baseline.")
    sub_studies = p.add_subparsers(dest="name", metavar="NAME", parser_class=_Parser,
                                           help="curves, history, noise, ablation, inits, competence, temperature, continuous, wall or pair")
    sub_studies.required = True
    for name in (s for s in STUDIES if s != "swim"):
        q = sub_studies.add_parser(name, help=STUDY_HELP.get(name, name),
                                   description=f"The {name} study: {STUDY_HELP.get(name, name)}. Every default "
                                               "below is this study's.")
        _add_run_options(q, study=True, spec=SPECS[name])
        scene_options.register(q, name)
    p = sub.add_parser("qlearn", help="Q-learning steps-to-learn distributions",
                       description="Train many independent Q-learners on-device and summarise steps-to-learn.")
    p.add_argument("--swimmer", type=_swimmers, default=("purcell", "ng"), metavar="NAME",
                   help="purcell, ng, both, or a comma-separated list (default both)")
    p.add_argument("--direction", type=_direction, default=(1, -1), metavar="DIR",
                   help="target direction: +x, -x or both (default both)")
    p.add_argument("--seeds", type=int, default=1000, help="learners per setting (default 1000)")
    p.add_argument("--steps", type=int, default=200, help="training steps per learner (default 200)")
    p.add_argument("--noise", type=float, default=0.0, metavar="ZETA",
                   help="noise level zeta >= 0 of the environment (default 0)")
    p.add_argument("--action-set", default="both", choices=(*ACTION_SETS, "both"),
                   help="actions the learner may take: all six (the paper's), only the shape-changing moves, "
                        "or both in turn (default both)")
    p.add_argument("--learning-rate", type=float, default=None, metavar="ALPHA",
                   help="learning rate alpha in (0, 1] (default 1.0, exact for the noiseless swimmer; smaller "
                        "under noise), the start value when --lr-decay is given")
    p.add_argument("--lr-decay", type=float, default=None, metavar="FACTOR",
                   help="exponential learning-rate schedule: alpha_t = max(ALPHA * FACTOR**t, --lr-min), "
                        "FACTOR in (0, 1] (default: constant alpha)")
    p.add_argument("--lr-min", type=float, default=0.0, metavar="ALPHA_MIN",
                   help="floor of the decaying learning rate (default 0)")
    p.add_argument("--seed", type=int, default=0, help="seed of the learners (default 0)")
    p.add_argument("--chunk", type=int, default=None, metavar="N",
                   help="learners trained and judged at once (default 65536); bounds memory for --seeds 1000000")
    p.add_argument("--out", default=None, metavar="FOLDER",
                   help="also write a histogram of steps to learn (qlearn.png, .pdf) and the table (qlearn.csv) here")
    p = sub.add_parser("ensemble", help="a stroke or policy over many noisy swimmers: X/a statistics per step",
                       description="Run one stroke (default: the signature gait) or the greedy policy of a "
                                   "trained Q-learner over N noisy swimmers per noise level zeta, on every "
                                   "device, in bounded chunks; print mean, spread, quantiles of X/a per step "
                                   "and the fraction of swimmers still moving forward.")
    p.add_argument("--swimmer", default="purcell", choices=("purcell", "ng", "nlink", "nsphere"),
                   help="purcell, ng, nlink or nsphere (default purcell)")
    p.add_argument("--direction", type=_direction, default=(1,), metavar="DIR", help="+x or -x (default +x)")
    p.add_argument("--policy", default="signature", metavar="POLICY",
                   help="signature (the best closed cycle), qlearn (greedy policy of one trained Q-learner), "
                        "or moves such as '2,-1 1,-1 2,1 1,1' (DOF,ROC pairs repeated)")
    p.add_argument("--init", default=None, metavar="LEVELS",
                   help="start configuration as signs, e.g. ++, or random (default: the stroke's start; ++ "
                        "for qlearn and given moves)")
    p.add_argument("--n", type=int, default=100_000, help="swimmers per noise level (default 100000)")
    p.add_argument("--zetas", type=_floats, default=DEFAULT_ZETAS, metavar="Z1,Z2,...",
                   help="noise levels (default the paper's 0,0.5,...,3)")
    p.add_argument("--steps", type=int, default=50, help="steps per swimmer (default 50)")
    p.add_argument("--every", type=int, default=1, metavar="K", help="report every K-th step (default 1)")
    p.add_argument("--window", type=int, default=None, metavar="W",
                   help="'moving forward' means X/a grew over the last W steps (default: the stroke's period)")
    p.add_argument("--seed", type=int, default=0,
                   help="seed (default 0); each noise level's noise comes from (seed, zeta), and --policy qlearn "
                        "trains its learner with it")
    p.add_argument("--chunk", type=int, default=1 << 20, metavar="N",
                   help="swimmers simulated at once (default 1048576); bounds memory")
    p.add_argument("--rows", type=int, default=12, metavar="R", help="reported steps printed per noise level")
    p.add_argument("--out", default=None, metavar="FILE.csv|FOLDER",
                   help="also write every reported step to this CSV and a figure of mean X/a with quantile bands "
                        "beside it (FILE.png, .pdf); a folder gets ensemble.csv and ensemble.png")
    p = sub.add_parser("gaits", help="closed stroke cycles ranked by displacement per step",
                       description="Enumerate closed stroke cycles on the corners of the DOF cube, integrate "
                                   "each exactly and rank them by displacement per step.")
    p.add_argument("swimmer", choices=("purcell", "ng", "nlink", "nsphere"),
                   help="purcell, ng, nlink (N links) or nsphere (N spheres)")
    p.add_argument("--n", type=int, default=None, help="links/spheres of nlink/nsphere (default 4)")
    p.add_argument("--direction", type=_direction, default=(1,), metavar="DIR",
                   help="rank by displacement toward +x, -x or both (default +x)")
    p.add_argument("--max-len", type=int, default=None,
                   help="longest cycle (default 2**n_dof; 4 with --roc-levels above 1)")
    p.add_argument("--roc-levels", type=int, default=1, metavar="K",
                   help="search the K-level ROC lattice: one DOF per move, ROC k/K of the range, k in -K..K "
                        "(default 1: the paper's corners)")
    p.add_argument("--top", type=int, default=8, help="cycles shown (default 8)")
    p.add_argument("--out", default=None, metavar="FOLDER", help="also write a figure of the best cycles here")
    p = sub.add_parser("plot", help="redraw the figures of a study folder",
                       description="Redraw a study folder's figures into FOLDER/figures (an unfinished study's "
                                   "figures say so).")
    p.add_argument("folder", help="a study folder written by jswim swim / jswim study")
    p = sub.add_parser("show", help="a study folder: status, settings, cost, summary table, figures",
                       description="Print what a study folder holds: complete or how many runs are done, the "
                                   "model and settings, LLM usage and cost, the summary table and the figures. "
                                   "Only reads, so it works on interrupted and read-only folders.")
    p.add_argument("folder", help="a study folder written by jswim swim / jswim study")
    p = sub.add_parser("compare", help="studies side by side (e.g. two models on the same grid)",
                       description="For every setting (agent, swimmer, direction, group) present in all the "
                                   "given study folders: success rate p with its 95%% Wilson interval, mean X/a "
                                   "with a bootstrap interval, median steps to learn, tokens per step and cost, "
                                   "one row per study. Only reads.")
    p.add_argument("folders", nargs="+", metavar="FOLDER", help="two or more study folders")
    from jswim.commands import animate, bench, report, serve  # commands in their own modules register themselves

    serve.register(sub)
    report.register(sub)
    animate.register(sub)
    bench.register(sub, StudyArgv())
    return ap


class StudyArgv:
    """The front's reader of a study's argv, handed to ``jswim bench`` (which prices each job's
    command line in process) so that :mod:`jswim.commands.bench` needs no import of this module."""

    @staticmethod
    def build_parser() -> argparse.ArgumentParser:
        return build_parser()

    @staticmethod
    def options(args: argparse.Namespace, study: str) -> Any:
        return _options(args, study)

    @staticmethod
    def backend(args: argparse.Namespace) -> Any:
        return _backend(args)


# -- commands -----------------------------------------------------------------------------------


def _extra_fields(items: Sequence[str]) -> tuple[tuple[str, Any], ...]:
    import json

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
    from urllib.parse import urlsplit

    from jswim.llm.urls import normalize_base_url

    try:
        host = (urlsplit(normalize_base_url(base_url)).hostname or "").lower()
    except (ValueError, ConfigError):
        return ""
    return DEFAULT_KEY_ENV if host in OPENAI_HOSTS else ""




def _backend(args: argparse.Namespace):
    from jswim.llm.backend import Backend  # lazy: JAX and httpx load only for commands that run

    key_env = default_key_env(args.base_url) if args.api_key_env is None else args.api_key_env.strip()
    if args.api_key_env is not None and not key_env:
        raise ConfigError("--api-key-env '': name the variable that holds the key (e.g. --api-key-env "
                          "OPENAI_API_KEY), or leave --api-key-env out for a server without keys")
    if args.api_key_env is not None and args.base_url is not None and not os.environ.get(key_env):
        from jswim.llm.urls import is_loopback, normalize_base_url

        state = "is set but empty" if key_env in os.environ else "is not set"
        if not is_loopback(normalize_base_url(args.base_url)):
            raise ConfigError(f"--api-key-env {key_env}: ${key_env} {state}; export the key in it (a remote "
                              f"server would refuse every call), or leave --api-key-env out for a server without keys")
        _warn(f"--api-key-env {key_env}: ${key_env} {state}; requests to this machine's server go without a key")
    prices, as_of = None, None
    if getattr(args, "prices", None):
        from jswim.llm.prices import load_prices

        table, as_of = load_prices(args.prices)
        prices = tuple(sorted(table.items()))
    return Backend(base_url=args.base_url, model=args.model, gguf=args.gguf, api_key_env=key_env,
                   constrain=args.constrain, temperature=args.temperature, n_parallel=args.parallel,
                   n_threads=args.threads, concurrency=args.concurrency, cohorts=args.cohorts,
                   cache_dir=args.cache_dir, timeout_s=args.timeout,
                   omit_fields=tuple(f.strip() for v in args.omit_field for f in v.split(",") if f.strip()),
                   rpm=args.rpm, tpm=args.tpm, price_local=args.price_local, reasoning=args.reasoning,
                   reasoning_effort=args.reasoning_effort, prices=prices, prices_as_of=as_of,
                   extra_fields=_extra_fields(args.extra_field), sampling=args.sampling,
                   server_family=args.server_family, strict_model=args.strict_model, retries=args.retries,
                   retry_for_s=args.retry_for)


def _options(args: argparse.Namespace, study: str):
    from jswim.studies import StudyOptions  # lazy: JAX loads only for commands that run

    if args.prompt_file is not None and not Path(args.prompt_file).is_file():
        raise ConfigError(f"--prompt-file {args.prompt_file}: {path_kind(args.prompt_file, 'a file')}")
    _refuse_ignored(study, args)
    kw: dict[str, Any] = dict(
        swimmers=args.swimmer, directions=args.direction, runs=args.runs, q_runs=args.q_runs, steps=args.steps,
        n_ht=args.n_ht, zeta=0.0 if args.noise is None else args.noise, init=args.init, seed=args.seed,
        action_set=args.action_set, prompt_file=args.prompt_file, chunk=args.chunk,
        share_identical=args.share_identical, x_min=args.x_min, max_tokens=args.max_tokens,
    )
    if getattr(args, "zetas", None):
        kw["zetas"] = args.zetas
    if getattr(args, "n_hts", None):
        kw["n_hts"] = args.n_hts
    if getattr(args, "temperatures", None):
        kw["temperatures"] = args.temperatures
    if getattr(args, "samples", None) is not None:
        kw["samples"] = args.samples
    if getattr(args, "prompt_files", None):
        files = tuple(f.strip() for f in args.prompt_files.split(",") if f.strip())
        for f in files:
            if not Path(f).is_file():
                raise ConfigError(f"--prompt-files {f}: {'a folder, not a file' if Path(f).is_dir() else 'no such file'}")
            from jswim.prompt import PromptTemplate

            try:
                PromptTemplate.from_file(f)  # checked before anything runs
            except ConfigError as exc:  # named as the option the user gave
                raise ConfigError(str(exc).replace("--prompt-file ", "--prompt-files ", 1)) from None
        kw["prompt_files"] = files
    if args.roc_levels is not None:
        if study == "continuous":
            kw["roc_levels_grid"] = args.roc_levels
        elif len(args.roc_levels) != 1:
            raise ConfigError("--roc-levels takes one K here (a list only for the continuous study)")
        else:
            kw["roc_levels"] = args.roc_levels[0]
    names = tuple(v.strip() for v in (args.variant or "").split(",") if v.strip())
    if study == "competence" and names:
        kw["variants"] = names
    elif len(names) > 1:
        raise ConfigError("--variant takes one name here (a list only for the competence study)")
    elif names:
        kw["variant"] = names[0]
    kw.update(scene_options.options(args))
    return StudyOptions(**kw)


#: Study options that some studies have no use for: StudyOptions field -> command-line option.
_STUDY_OPTIONS = {"zetas": "--zetas", "n_hts": "--n-hts", "zeta": "--noise", "n_ht": "--n-ht", "q_runs": "--q-runs",
                  "init": "--init"}


def _refuse_ignored(study: str, args: argparse.Namespace) -> None:
    """An option the study would drop silently is a mistake: say so (exit 2) instead of running."""
    from jswim.studies.grids import ignored_options  # lazy: the grids load JAX

    given = [field for field, dest in (("zetas", "zetas"), ("n_hts", "n_hts"), ("zeta", "noise"), ("n_ht", "n_ht"),
                                       ("q_runs", "q_runs"), ("init", "init"))
             if getattr(args, dest, None) is not None]
    for field, why in ignored_options(study, given).items():
        raise ConfigError(f"the {study} study has no use for {_STUDY_OPTIONS[field]} ({why}); leave it out")


def _warn(message: str) -> None:
    print(f"jswim: warning: {message}", file=sys.stderr)


@contextlib.contextmanager
def _warnings_as_lines() -> Iterator[None]:
    """Inside: each :class:`~jswim.errors.JswimWarning` is one ``jswim: warning:`` line on stderr
    (others as Python shows them); the hook is restored after."""
    import warnings

    from jswim.errors import JswimWarning

    shown = warnings.showwarning

    def one_line(message, category, filename, lineno, file=None, line=None):  # noqa: ANN001 - warnings' hook
        if issubclass(category, JswimWarning):
            _warn(str(message))
        else:
            shown(message, category, filename, lineno, file, line)

    with warnings.catch_warnings():
        warnings.showwarning = one_line
        yield


#: Exit status of a study stopped by ``--max-cost`` (cleanly: rerun with a higher cap to go on).
EXIT_COST_CAP = 3


def _run(study: str, args: argparse.Namespace) -> int:
    from jswim.console import Progress  # lazy: JAX loads only for commands that run
    from jswim.studies import default_folder, run_study
    from jswim.studies.grids import short_steps_warning

    options = _options(args, study)
    backend = _backend(args)
    if args.max_cost is not None and not (math.isfinite(args.max_cost) and args.max_cost >= 0):
        raise ConfigError(f"--max-cost must be a number of dollars >= 0, got {args.max_cost}")
    out = Path(args.out) if args.out else default_folder(study, options, backend)
    try:
        out.stat()
    except FileNotFoundError:
        pass  # a new folder
    except OSError as exc:  # a name longer than the file system allows, a file on the way, ...
        raise ConfigError(f"cannot write --out {out}: {exc.strerror or type(exc).__name__}; choose another --out") from None
    if args.dry_run:
        from jswim.studies.run import estimate_study  # lazy: JAX loads only for commands that run

        est = estimate_study(study, options, backend, out, max_cost=args.max_cost)
        print("\n".join(est.lines()))
        print(json.dumps(est.as_dict(), sort_keys=True))  # the same, for scripts
        return 0
    if (text := short_steps_warning(options)) is not None:
        _warn(text)
    labels = {"llm": "LLM runs", "llm-live": "LLM runs", "qlearning": "Q-learning", "random": "random policy",
              "ppo": "continuous RL",
              "start": "start", "resume": "resume"}
    with Progress() as bar:

        def tick(phase: str, done: int, total: int, info: str = "") -> None:
            bar.update(labels.get(phase, "runs"), done, total, info,
                       unit="LLM steps" if phase.startswith("llm") else "runs")

        try:
            with _warnings_as_lines():
                result = run_study(study, options, backend, out, progress=tick, figures=not args.no_figures,
                                   max_cost=args.max_cost)
        except KeyboardInterrupt:
            bar.stop()
            from jswim._io import interrupts

            sig = interrupts.received()
            print(f"jswim: interrupted ({interrupts.name(sig)}); every finished run and answered call is kept in "
                  f"{out}. Run the same command to resume (jswim report {out}: a page of what is done).",
                  file=sys.stderr)
            return 128 + (sig or signal.SIGINT)
        except LLMServerError as exc:  # the retry budget is spent: the study stops cleanly, nothing lost
            bar.stop()
            print(f"jswim: error: {exc}. {_kept(out)}", file=sys.stderr)
            return EXIT_USAGE
        bar.update("done", len(result.rows), len(result.rows), f"{result.wall_s:.1f} s", final=True)
    _print_summary(result.summary, result.rows, f"{study}: {len(result.rows)} runs in {result.wall_s:.1f} s")
    scene_options.print_table(result.rows)
    _print_reasoning(result)
    for note in result.notes:
        print(note)
    sp = result.llm_speed
    if not sp and any(r.get("agent") == "llm" for r in result.rows):  # a resume with every LLM run done
        from jswim.llm.journal import CallJournal

        print(f"LLM calls: none this session (every LLM run was done already; nothing sent, nothing paid); the "
              f"study's calls cost ${CallJournal(result.folder).spent_usd:.4f} ({_price_note(backend)})")
    if sp.get("calls"):
        print(f"LLM calls: {sp['calls']:.0f} ({sp.get('billed_calls', 0):.0f} sent, "
              f"{sp.get('replayed_calls', 0):.0f} replayed from earlier sessions), {sp.get('tokens', 0):,.0f} tokens, "
              f"${sp.get('cost_usd', 0):.4f} this session, ${sp.get('study_cost_usd', 0):.4f} for the study "
              f"({_price_note(backend)})")
    if sp.get("requests") is not None and (sp.get("calls") or sp.get("requests")):
        from jswim.console import requests_text

        print(f"HTTP requests: {requests_text(sp)}")
    print(f"results: {result.folder}")
    if (result.folder / "report.html").is_file():
        print(f"report:  {result.folder / 'report.html'} (open it in a browser)")
    for f in result.figures:
        if f.suffix == ".png":
            print(f"figure:  {f}")
    if result.stopped == "cost cap":
        print(f"jswim: stopped at the cost cap (--max-cost {args.max_cost:g}): ${sp.get('study_cost_usd', 0):.4f} "
              f"spent; {len(result.rows)} of {result.total} runs done and kept in {result.folder}. Rerun with a "
              "higher --max-cost to continue (no call is paid twice)", file=sys.stderr)
        return EXIT_COST_CAP
    if result.failed_runs:
        n_llm = sum(r.get("agent") == "llm" for r in result.rows)
        first = result.failed_runs[0]
        print(f"jswim: error: {len(result.failed_runs)} of {n_llm} LLM runs failed ({first['run_id']}: "
              f"{first['error']}); they are recorded as failed in {result.folder}: run the same command to "
              "run them again", file=sys.stderr)
        return EXIT_USAGE
    return 0


def _print_reasoning(result: Any) -> None:
    """What a reasoning model was sent, and the replies cut off (never executed)."""
    sent = result.reasoning or {}
    for note in sent.get("notes") or ():
        print(f"reasoning model: {note}")
    if sent.get("active") and not sent.get("notes"):
        print(f"reasoning: {sent.get('token_field')}={sent.get('budget')} (--reasoning {sent.get('mode')})")
    thought = sum(r.get("reasoning_tokens") or 0 for r in result.rows if r.get("agent") == "llm")
    if thought:
        print(f"reasoning tokens: {thought:,} (priced as output)")
    if sent.get("active"):
        cut = sum(result.truncated.values())
        if cut:
            print(f"{cut} replies cut at {sent.get('token_field')}={sent.get('budget')}, {result.cut_thinking} of them "
                  "while still thinking (no answer, never executed; each went to the follow-up); raise --max-tokens")
        return
    for limit, n in sorted(result.truncated.items()):
        print(f"{n} replies cut at max_tokens={limit} (no answer; each went to the follow-up)"
              + (f", {result.cut_thinking} of them while still thinking" if result.cut_thinking else "")
              + "; a reasoning model needs room to think: --reasoning on (or a larger --max-tokens)")


def _price_note(backend: Any) -> str:
    """Where a cost line's prices come from, or why the model has none (never a silent $0)."""
    from jswim.llm.usage import PRICES_AS_OF, price_table  # lazy: httpx loads only for commands that run
    from jswim.llm.urls import is_local_host

    from jswim.console import EMBEDDED_UNPRICED, LOCAL_UNPRICED, REFERENCE_UNPRICED, cost_text
    from jswim.llm.reference import MODEL as REFERENCE_MODEL  # lazy: start-up (the reference rule loads only for a run)

    if backend is None or backend.local:
        return cost_text(None, EMBEDDED_UNPRICED)
    if backend.model == REFERENCE_MODEL:
        return cost_text(None, REFERENCE_UNPRICED)
    table, why = price_table(dict(backend.prices) if backend.prices is not None else None, backend.model,
                             local_host=is_local_host(backend.base_url), price_local=backend.price_local)
    if why:
        return cost_text(None, why)
    if table.entry(backend.model) is None and is_local_host(backend.base_url) and backend.prices is None:
        return cost_text(None, LOCAL_UNPRICED)
    if table.entry(backend.model) is None:
        return cost_text(None, f"no price for {backend.model!r} in the "
                               f"{'price table ' + backend.prices_as_of if backend.prices else 'built-in price table of ' + PRICES_AS_OF}"
                               "; --prices FILE prices it")
    return f"prices of {backend.prices_as_of or PRICES_AS_OF}" + ("" if backend.prices else " (built-in list prices)")


def _kept(out: Path) -> str:
    """What a stopped session leaves: ``The study stopped cleanly: 3 of 8 runs done and kept ...``."""
    from jswim.results import read_runs

    try:
        done, planned = len(read_runs(out)), (json.loads((out / "metadata.json").read_text()) or {}).get("n_planned")
    except (OSError, ValueError, AttributeError):
        done, planned = 0, None
    of = f" of {planned}" if isinstance(planned, int) else ""
    if not done and not (out / "calls.jsonl").exists():
        return "Nothing was done yet; run the same command once the server is back"
    return (f"The study stopped cleanly: {done}{of} runs done and kept in {out}, every answered call journaled; "
            "run the same command to resume (no call is paid twice)")


def _prices_date() -> str:
    from jswim.llm.usage import PRICES_AS_OF  # lazy: httpx loads only for commands that run

    return PRICES_AS_OF


def _print_summary(summary: Sequence[dict[str, Any]], rows: Sequence[dict[str, Any]], title: str) -> None:
    from jswim.console import print_table  # lazy: only when something ran
    from jswim.overview import SUMMARY_NOTE, order_summary, summary_table

    cols, cells = summary_table(order_summary(summary, rows))
    print_table(cols, cells, title)
    print(SUMMARY_NOTE)
    from jswim.agents.fidelity import describe_constraint

    llm = [r for r in rows if r.get("agent") == "llm"]
    if line := describe_constraint(r.get("constraint") for r in llm):
        print(line)
    if any(r.get("share_identical") for r in llm):
        print("LLM runs: --share-identical: identical requests of different runs were sent once, so runs from one "
              "start are copies of one run, not independent repeats")


def _qlearn(args: argparse.Namespace) -> int:
    from jswim.agents.qlearning import QConfig  # lazy: JAX loads only for commands that run
    from jswim.console import Progress
    from jswim.studies import qlearn

    if args.seeds < 1 or args.steps < 1:
        raise ConfigError("--seeds and --steps must be >= 1")
    if args.chunk is not None and args.chunk < 1:
        raise ConfigError(f"--chunk must be >= 1, got {args.chunk}")
    for name in ("seeds", "steps", "chunk"):
        _check_max(name, getattr(args, name))
    if not (math.isfinite(args.noise) and args.noise >= 0):
        raise ConfigError(f"--noise (zeta) must be >= 0, got {args.noise}")
    rate = _learning_rate(args)
    sets = ACTION_SETS if args.action_set == "both" else (args.action_set,)
    if args.out is not None:
        _check_out_folder(args.out)
    every: list[Any] = []
    for action_set in sets:
        t0 = time.perf_counter()
        cfg = QConfig(steps=args.steps, action_set=action_set, **({"learning_rate": rate} if rate is not None else {}))
        with Progress() as bar:
            rows = qlearn.study(cfg, swimmers=args.swimmer, directions=args.direction, zetas=(args.noise,),
                                n_seeds=args.seeds, seed=args.seed, chunk=args.chunk or qlearn.STUDY_CHUNK,
                                progress=lambda done, total: bar.update(
                                    f"Q-learners ({action_set})", done, total, _eta(t0, done, total),
                                    final=done == total, unit="learners"))
        print(qlearn.format_table(rows))
        print(f"({action_set}: {time.perf_counter() - t0:.1f} s including compilation)\n")
        every += rows
    if args.out is not None:
        from jswim.commands.figures import qlearn_outputs  # lazy: matplotlib only when asked

        for path in qlearn_outputs(every, args):
            if path.suffix != ".pdf":
                print(f"{'figure' if path.suffix == '.png' else 'table'}: {path}")
    return 0


def _check_out_folder(out: str) -> None:
    """``--out FOLDER`` of a command: an existing file there is a mistake, caught before any work."""
    if Path(out).exists() and not Path(out).is_dir():
        raise ConfigError(f"--out {out} is a file; give a folder for the figures and the table")


def _learning_rate(args: argparse.Namespace) -> Any:
    """``--learning-rate`` / ``--lr-decay`` / ``--lr-min`` as a number or an optax schedule (``None``:
    QConfig's default)."""
    alpha = args.learning_rate
    if alpha is not None and not (math.isfinite(alpha) and 0 < alpha <= 1):
        raise ConfigError(f"--learning-rate must lie in (0, 1], got {alpha}")
    if args.lr_decay is None:
        if args.lr_min:
            raise ConfigError("--lr-min is the floor of a decaying rate; give --lr-decay too")
        return alpha
    import optax  # lazy: only for a schedule

    start = 1.0 if alpha is None else alpha
    if not (math.isfinite(args.lr_decay) and 0 < args.lr_decay <= 1):
        raise ConfigError(f"--lr-decay must lie in (0, 1], got {args.lr_decay}")
    if not (math.isfinite(args.lr_min) and 0 <= args.lr_min <= start):
        raise ConfigError(f"--lr-min must lie in [0, {start:g}] (the start rate), got {args.lr_min}")
    return optax.exponential_decay(start, transition_steps=1, decay_rate=args.lr_decay,
                                   end_value=args.lr_min or None)


def _eta(t0: float, done: int, total: int) -> str:
    from jswim.console import eta

    left = eta(time.perf_counter() - t0, done / total) if total else None
    return f"ETA {left}" if left and done < total else ""


def _moves(text: str, n_dof: int) -> list[int]:
    """'2,-1 1,-1 2,1 1,1' -> action indices (validated)."""
    from jswim.env import validate_actions

    try:
        pairs = [tuple(int(v) for v in item.split(",")) for item in text.replace(";", " ").split()]
    except ValueError:
        raise ConfigError(f"--policy: expected signature, qlearn or DOF,ROC pairs like '2,-1 1,-1', got {text!r}") from None
    if not pairs or any(len(p) != 2 for p in pairs):
        raise ConfigError(f"--policy: expected DOF,ROC pairs like '2,-1 1,-1 2,1 1,1', got {text!r}")
    return [int(a) for a in validate_actions(pairs, n_dof)]


def _check_max(name: str, value: int | None) -> None:
    """One line for a count too large for the device's int32 indices (else a deep traceback)."""
    if value is not None and value > MAX_COUNT:
        raise ConfigError(f"--{name} must be at most {MAX_COUNT:,}, got {value}")


def _ensemble(args: argparse.Namespace) -> int:
    import csv

    import numpy as np

    from jswim.console import Progress
    from jswim.env import make_params
    from jswim.studies import ensemble

    for name in ("n", "steps", "every", "chunk", "rows"):
        if getattr(args, name) < 1:
            raise ConfigError(f"--{name} must be >= 1, got {getattr(args, name)}")
        _check_max(name, getattr(args, name))
    if args.every > args.steps:
        raise ConfigError(f"--every ({args.every}) must not exceed --steps ({args.steps})")
    if len(args.direction) != 1:
        raise ConfigError("--direction takes +x or -x here")
    if any(not (math.isfinite(z) and z >= 0) for z in args.zetas) or not args.zetas:
        raise ConfigError(f"--zetas must be noise levels >= 0, got {','.join(map(str, args.zetas))}")
    if args.out and Path(args.out).suffix.lower() != ".csv":
        _check_out_folder(args.out)
    elif args.out and not Path(args.out).resolve().parent.is_dir():
        raise ConfigError(f"--out {args.out}: no such folder {str(Path(args.out).parent)!r}")
    params = make_params(args.swimmer, direction=args.direction[0])
    start = None
    if args.policy == "signature":
        policy, start = ensemble.signature_policy(params)
    elif args.policy == "qlearn":
        policy = None
    else:
        policy = ensemble.stroke_policy(_moves(args.policy, params.n_dof), label=args.policy)
    init = args.init if args.init is not None else (start if start is not None else None)
    params = make_params(args.swimmer, direction=args.direction[0], init=init)
    if policy is None:
        policy = ensemble.learned_policy(params, seed=args.seed)
    t0 = time.perf_counter()
    with Progress() as bar:
        stats = ensemble.run(policy, params, n=args.n, zetas=args.zetas, steps=args.steps, every=args.every,
                             window=args.window, seed=args.seed, chunk=args.chunk,
                             progress=lambda done, total: bar.update("ensemble", done, total, _eta(t0, done, total),
                                                                     final=done == total, unit="swimmer-steps"))
    wall = time.perf_counter() - t0
    start_txt = "".join("+" if v else "-" for v in np.asarray(params.init)) if np.all(np.asarray(params.init) >= 0) \
        else "random"
    moves = " ".join(f"[{a // 3 + 1}, {a % 3 - 1}]" for a in policy.actions) if policy.kind == "stroke" else ""
    print(f"{params.model.label} swimmer, {policy.label}{' ' + moves if moves else ''}, start {start_txt}, target "
          f"{'+x' if args.direction[0] > 0 else '-x'}: {args.n:,} swimmers per noise level, {args.steps} steps")
    print(ensemble.format_table(stats, args.rows))
    total = args.n * len(args.zetas) * (args.steps // args.every * args.every)
    print(f"{total:,} swimmer-steps in {wall:.1f} s ({total / wall:,.0f}/s, compilation included); "
          f"quantiles to within the histogram bin ({max(float(s.resolution.max()) for s in stats):.2g} a at most); "
          f"forward: X/a grew over the last {args.window or policy.period} steps")
    if args.out:
        csv_path = Path(args.out) if Path(args.out).suffix.lower() == ".csv" else Path(args.out) / "ensemble.csv"
        rows = ensemble.to_rows(stats)
        try:
            csv_path.parent.mkdir(parents=True, exist_ok=True)
            with open(csv_path, "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=list(rows[0]))
                w.writeheader()
                w.writerows(rows)
        except OSError as exc:
            raise ConfigError(f"--out {args.out}: {exc.strerror or exc}") from None
        print(f"table: {csv_path}")
        from jswim.commands.figures import ensemble_figure_files  # lazy: matplotlib only when asked

        title = (f"{params.model.label} swimmer, {policy.label}{' ' + moves if moves else ''}, start {start_txt}: "
                 f"{args.n:,} swimmers per \u03b6")
        for path in ensemble_figure_files(stats, title, args.direction[0], csv_path.parent, csv_path.stem):
            if path.suffix == ".png":
                print(f"figure: {path}")
    return 0


def _gaits(args: argparse.Namespace) -> int:
    from jswim.judging import gait  # lazy: JAX loads only for commands that run
    from jswim.swimmers.models import make_model

    kw = {}
    if args.n is not None:
        if args.swimmer not in ("nlink", "nsphere"):
            raise ConfigError("--n applies to nlink and nsphere only")
        kw["n_links" if args.swimmer == "nlink" else "n_spheres"] = args.n
    model = make_model(args.swimmer, **kw)
    if args.roc_levels != 1:
        return _lattice_gaits(args, model)
    if model.n_dof > 5 and args.max_len is None:
        raise ConfigError("more than 5 DOFs: give --max-len to bound the enumeration")
    for d in args.direction:
        cycles = gait.best_cycles(model, d, args.max_len)
        print(f"{model.label} swimmer, target {'+x' if d > 0 else '-x'}: {len(cycles)} closed cycles; best first")
        print(f"{'rank':>4} {'period':>6} {'X/a per step':>13} {'X/a per cycle':>14} {'rotation':>9} simple"
              "  start  moves (DOF, ROC)")
        for i, c in enumerate(cycles[: args.top]):
            start = "".join("+" if v else "-" for v in c.start)
            moves = " ".join(f"[{dof}, {roc}]" for dof, roc in c.moves)
            print(f"{i + 1:4d} {c.period:6d} {c.per_step:+13.6f} {c.displacement:+14.6f} {c.rotation:+9.4f} "
                  f"{'yes' if c.simple else 'no':>6}  {start:5}  {moves}")
        print("simple: no shape visited twice per period; the others add detours that go back and forth")
        if args.out:
            from jswim.figures import plots  # lazy: matplotlib only when a figure is asked for

            paths = plots.save(plots.gaits_figure(model, cycles), args.out, f"gaits-{args.swimmer}-{'px' if d > 0 else 'mx'}")
            print(f"figure: {paths[0]}")
        print()
    return 0


def _lattice_gaits(args: argparse.Namespace, model: Any) -> int:
    """``jswim gaits SWIMMER --roc-levels K``: closed strokes on the K-level lattice, best first."""
    from jswim.judging import lattice  # lazy: JAX loads only for commands that run
    from jswim.actions import check_roc_levels

    k = check_roc_levels(args.roc_levels)
    if args.out:
        raise ConfigError("--out draws corner cycles only; leave it out with --roc-levels above 1")
    length = 4 if args.max_len is None else args.max_len
    for d in args.direction:
        cycles = lattice.best_lattice_cycles(model, d, k, length)
        print(f"{model.label} swimmer, target {'+x' if d > 0 else '-x'}, ROC on {k} levels (k/{k} of the range, "
              f"one DOF per move): {len(cycles)} closed strokes up to {length} moves; best first")
        print(f"{'rank':>4} {'period':>6} {'X/a per step':>13} {'X/a per cycle':>14} {'rotation':>9} simple"
              "  start  moves (DOF, ROC)")
        for i, c in enumerate(cycles[: args.top]):
            start = "(" + ", ".join(str(v) for v in c.start) + f")/{k}"
            moves = " ".join(f"[{dof}, {roc}]" for dof, roc in c.moves)
            print(f"{i + 1:4d} {c.period:6d} {c.per_step:+13.6f} {c.displacement:+14.6f} {c.rotation:+9.4f} "
                  f"{'yes' if c.simple else 'no':>6}  {start:7}  {moves}")
        print(f"start: each DOF's place on the lattice, j/{k} of its range from lo; moves that reach past a limit "
              "and runs of moves of one DOF (equal to one move) are not listed")
        print()
    return 0


def _plot(args: argparse.Namespace) -> int:
    from jswim.overview import StudyFolder  # lazy: JAX loads only for commands that run
    from jswim.results import unfinished_note
    from jswim.studies.report import draw_figures

    study = StudyFolder(args.folder)
    if not study.rows:
        raise ConfigError(f"{args.folder} has no finished runs yet")
    note = unfinished_note(study.meta.get("status"), len(study.rows), study.planned)
    try:
        paths = draw_figures(study.study, study.rows, Path(args.folder) / "figures", note=note)
    except OSError as exc:
        raise ConfigError(f"cannot write the figures into {Path(args.folder) / 'figures'} ({exc.strerror or exc}); "
                          "jswim show FOLDER reads a read-only folder") from None
    for f in paths:
        print(f"figure: {f}")
    return 0


def _show(args: argparse.Namespace) -> int:
    from jswim.console import terminal_width  # lazy: JAX loads only for commands that run
    from jswim.overview import show_text

    folder = Path(args.folder)
    if (folder / "bench.json").is_file() and not (folder / "metadata.json").exists():  # a bench's folder
        from jswim.commands import bench

        print(bench.show_text(folder, width=terminal_width()))
        return 0
    print(show_text(args.folder, width=terminal_width()))
    return 0


def _compare(args: argparse.Namespace) -> int:
    from jswim.console import terminal_width  # lazy: JAX loads only for commands that run
    from jswim.overview import compare_text

    print(compare_text(args.folders, width=terminal_width()))
    return 0


def _undecodable_token(tokens: Sequence[str]) -> str | None:
    """The option (or argument) of the first command-line token that is not UTF-8, named as the
    user typed it (``--swimmer``), never as Python holds the bytes (``'\udcff'``)."""
    for i, t in enumerate(tokens):
        try:
            t.encode("utf-8")
        except UnicodeEncodeError:
            if t.startswith("--") and "=" in t:
                return t.split("=", 1)[0]
            if i and tokens[i - 1].startswith("-") and len(tokens[i - 1]) > 1:
                return tokens[i - 1]
            return f"argument {i + 1}"
    return None


def _undecodable(args: argparse.Namespace) -> str | None:
    """The first option whose text is not UTF-8 (Python holds such bytes as lone surrogates)."""
    for name, value in vars(args).items():
        for v in value if isinstance(value, (list, tuple)) else (value,):
            if isinstance(v, str):
                try:
                    v.encode("utf-8")
                except UnicodeEncodeError:
                    return name
    return None


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``jswim`` command; returns the exit status."""
    tokens = sys.argv[1:] if argv is None else list(argv)
    if (bad := _undecodable_token(tokens)) is not None:  # before argparse, which would print '\udcff'
        print(f"jswim: error: {bad} is not valid UTF-8 text; write it in UTF-8", file=sys.stderr)
        return EXIT_USAGE
    # No command named (`jswim`, `jswim --help`): the outline parser says the same, without JAX.
    args = build_parser(outline=all(t.startswith("-") for t in tokens)).parse_args(argv)
    if (bad := _undecodable(args)) is not None:  # bytes that are not UTF-8 (e.g. $'m\xff') fail deep inside
        print(f"jswim: error: --{bad.replace('_', '-')} is not valid UTF-8 text; write it in UTF-8", file=sys.stderr)
        return EXIT_USAGE
    if args.command not in ("show", "compare"):
        from jswim import compile_cache

        compile_cache.enable()  # compiled programs kept on disk: later sessions start in seconds
    # The command only writes figure files; never open a window. Through the environment, so
    # matplotlib (~0.5 s) is imported only by commands that draw (`--no-figures` never does).
    if "matplotlib" in sys.modules:
        sys.modules["matplotlib"].use("Agg")
    else:
        os.environ["MPLBACKEND"] = "Agg"
    from jswim._io.permissions import private_files

    # Folders, figures and caches: owner only under the usual umask; every jswim warning (a
    # skipped record of a damaged folder, ...) one line, whatever the command.

    forget_warnings()
    with private_files(), _warnings_as_lines():
        return _main(args)


def _main(args: argparse.Namespace) -> int:
    try:
        if getattr(args, "command_main", None) is not None:
            return args.command_main(args)
        if args.command == "swim":
            return _run("swim", args)
        if args.command == "study":
            return _run(args.name, args)
        if args.command == "qlearn":
            return _qlearn(args)
        if args.command == "ensemble":
            return _ensemble(args)
        if args.command == "gaits":
            return _gaits(args)
        if args.command == "show":
            return _show(args)
        if args.command == "compare":
            return _compare(args)
        return _plot(args)
    except JswimError as exc:  # every user or server mistake (jswim.errors); anything else is a bug
        from jswim.llm.credentials import scrub  # no key or URL password in any message, in any form

        print(f"jswim: error: {scrub(str(exc))}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        from jswim._io import interrupts

        print(f"jswim: interrupted ({interrupts.name(interrupts.received())})", file=sys.stderr)
        return 128 + (interrupts.received() or signal.SIGINT)
    except MemoryError:
        print("jswim: error: out of memory; use fewer swimmers/learners or a smaller --chunk", file=sys.stderr)
        return EXIT_USAGE
    except RuntimeError as exc:  # JAX's device errors are RuntimeErrors; only out-of-memory is the user's
        if "RESOURCE_EXHAUSTED" not in str(exc):
            raise
        print("jswim: error: out of device memory; use fewer swimmers/learners, fewer --steps or a smaller --chunk",
              file=sys.stderr)
        return EXIT_USAGE


def _show_warning(message: Any, category: Any, filename: str, lineno: int, file: Any = None,
                  line: str | None = None) -> None:
    """Warnings as one line, ``jswim: warning: ...`` (not Python's file:line form)."""
    print(f"jswim: warning: {message}", file=sys.stderr if file is None else file)


def run() -> None:
    """Console-script wrapper: signals end a session as Ctrl-C does (:mod:`jswim._io.interrupts`)."""
    from jswim._io import interrupts

    interrupts.install()
    import warnings

    warnings.showwarning = _show_warning
    try:
        status = main()
        interrupts.quiet()  # a signal from here on (cleanup, atexit) is only noted: no traceback
        sys.stdout.flush()
    except BrokenPipeError:  # output piped into a reader that quit (`jswim show F | head`): not an error
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())  # no second error at interpreter exit
        status = 0
    except KeyboardInterrupt:  # Ctrl-C before main's own handler (imports, parser): nothing to keep yet
        interrupts.quiet()
        print(f"jswim: interrupted ({interrupts.name(interrupts.received())}) while starting; nothing was written",
              file=sys.stderr)
        status = 128 + (interrupts.received() or signal.SIGINT)
    interrupts.ignore()  # a signal during interpreter exit must not kill the process after its line
    sys.exit(status)


if __name__ == "__main__":
    run()
