"""argv -> options, in one place: the options of ``jswim swim`` and ``jswim study NAME`` (their
parsers, `options` -> [`jswim.studies.StudyOptions`][jswim.studies.options.StudyOptions], `backend` ->
[`jswim.llm.backend.Backend`][jswim.llm.backend.Backend]), read by those commands and by ``jswim bench --dry-run``
(which prices each job's study command line in process through `study_parser`).

Each option is defined once: the run options in `jswim.studies.flags.FLAGS` (its flags, help,
type and the `StudyOptions` field it sets), a study's own options (the scene studies'
``--heights``, ...) with the study (`jswim.studies.study.Study.flags`); this module only reads them.
"""

from __future__ import annotations

import argparse
import json
import os
from typing import Any
from collections.abc import Sequence
from urllib.parse import urlsplit

from jswim._io.paths import check_file
from jswim.cli import base
from jswim.studies.flags import FLAGS, Flag
from jswim.errors import ConfigError
from jswim.llm.prices import load_prices
from jswim.llm.urls import is_loopback, normalize_base_url


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
        help="run a study: the paper's figures and their extensions",
        description="Run a study grid into its folder (resumable: finished runs are kept), then "
        "draw its figures and report page from the folder. The paper's figures are curves "
        "(Fig. 2), history (the n_ht sweep, Fig. 3), noise (Fig. 4) and ablation (Fig. 5); the "
        "others extend them. Each NAME below says what it measures; `jswim study NAME --help` "
        "gives its options and defaults.",
    )
    if base.outlined(p):
        return [p, q]
    from jswim.studies.study import get, names  # lazy: the study kinds load JAX (not for --help)

    studies = [get(n) for n in names()]
    main = next(st for st in studies if st.command == "swim")
    add_run_options(p, study=False, spec=main)
    p.set_defaults(name=main.name)
    nested = [st for st in studies if st.command == "study"]
    sub_names = q.add_subparsers(
        dest="name",
        metavar="NAME",
        parser_class=base.Parser,
        help=", ".join(st.name for st in nested),
    )
    sub_names.required = True
    out = [p]
    for st in nested:
        s = sub_names.add_parser(
            st.name,
            help=st.help,
            description=f"The {st.name} study: {st.help}. Every default below is this study's.",
        )
        add_run_options(s, study=True, spec=st)
        add_own_options(s, st)
        out.append(s)
    return out


def help_text(flag: Flag, spec: Any) -> str:
    """``flag``'s help for the study of ``spec``: the study's own wording where it has one,
    hidden (``argparse.SUPPRESS``) where the study has no use for the option."""
    if flag.field is not None and flag.field in spec.ignores:
        return argparse.SUPPRESS  # the study refuses it (options): not offered
    own = spec.option_help.get(flag.names[0])
    if own is not None:
        return own
    return flag.help(spec) if callable(flag.help) else flag.help


def add_run_options(p: argparse.ArgumentParser, *, study: bool, spec: Any) -> None:
    """Add `jswim.studies.flags.FLAGS` to ``p``, each help naming the defaults of ``spec``'s study.

    Parameters
    ----------
    p : argparse.ArgumentParser
        The parser of ``jswim swim`` or of ``jswim study NAME``.
    study : bool
        ``jswim study NAME`` (adds the grid axes, ``Flag.study_only``).
    spec : Study
        The study's defaults ([`jswim.studies.study.Study`][jswim.studies.study.Study]).
    """
    groups: dict[str, Any] = {}
    for flag in FLAGS:
        if flag.study_only and not study:
            continue
        if flag.group not in groups:
            groups[flag.group] = p.add_argument_group(flag.group) if flag.group else p
        kwargs = dict(flag.kwargs)
        if kwargs.get("action") != "store_true":  # store_true's own default (False) stays
            kwargs.setdefault("default", None)
        groups[flag.group].add_argument(*flag.names, help=help_text(flag, spec), **kwargs)


def add_own_options(parser: argparse.ArgumentParser, study: Any) -> None:
    """Add ``study``'s own options (`jswim.studies.study.Study.flags`) to its parser, as a group."""
    if not study.flags:
        return
    group = parser.add_argument_group(f"{study.name} options")
    for flag, kw in study.flags:
        group.add_argument(flag, default=None, **kw)


def _own_options(args: argparse.Namespace) -> dict[str, Any]:
    """The StudyOptions keywords of the study's own options given (`add_own_options`)."""
    from jswim.studies.specs import own_options  # lazy: as in add_study_commands

    return {d: getattr(args, d) for d in own_options() if getattr(args, d, None) is not None}


def study_parser() -> argparse.ArgumentParser:
    """A parser of study command lines alone (``swim ...``, ``study NAME ...``): ``jswim bench``
    reads its jobs' argv with it."""
    ap = base.Parser(prog="jswim")
    add_study_commands(ap.add_subparsers(dest="command", parser_class=base.Parser))
    return ap


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


def options(args: argparse.Namespace, study: str) -> Any:
    """The [`jswim.studies.StudyOptions`][jswim.studies.options.StudyOptions] of a study's command line (validated there)."""
    from jswim.studies import StudyOptions  # lazy: JAX loads only for commands that run

    if args.prompt_file is not None:
        check_file(args.prompt_file, "--prompt-file")
    _refuse_ignored(study, args)
    kw: dict[str, Any] = {}
    for flag in FLAGS:  # each option that names its field: passed on when given
        value = getattr(args, flag.dest, None)
        if flag.field is not None and value is not None:
            kw[flag.field] = value if flag.convert is None else flag.convert(value)
    from jswim.studies.study import get, names as study_names  # lazy: as in add_study_commands

    spec = get(study)
    if args.roc_levels is not None:
        k = args.roc_levels[0]
        if "roc_levels_grid" not in spec.ignores:
            kw["roc_levels_grid"] = args.roc_levels
        elif len(args.roc_levels) != 1:
            grids = [n for n in study_names() if "roc_levels_grid" not in get(n).ignores]
            raise ConfigError(f"--roc-levels takes one K here (a list only for {_studies(grids)})")
        elif k < spec.min_roc_levels:
            m = spec.min_roc_levels
            raise ConfigError(
                f"--roc-levels {k}: the {study} study steers on K >= {m} levels "
                f"({spec.roc_levels_why}); leave it out for K = {m}, or give {m} or more"
            )
        else:
            kw["roc_levels"] = k
    names = tuple(v.strip() for v in (args.variant or "").split(",") if v.strip())
    if spec.variants_grid and names:
        kw["variants"] = names
    elif len(names) > 1:
        grids = [n for n in study_names() if get(n).variants_grid]
        raise ConfigError(f"--variant takes one name here (a list only for {_studies(grids)})")
    elif names:
        kw["variant"] = names[0]
    kw.update(_own_options(args))
    return StudyOptions(**kw)


def _studies(names: Sequence[str]) -> str:
    return " and ".join(f"the {n} study" for n in names)


def _refuse_ignored(study: str, args: argparse.Namespace) -> None:
    """An option the study would drop silently is a mistake: say so (exit 2) instead of running."""
    from jswim.studies.specs import IGNORED, ignored_options  # lazy: the grids load JAX

    given = {f.field: f for f in FLAGS if f.field and getattr(args, f.dest, None) is not None}
    # in IGNORED's order: a grid axis (--zetas) is named before the one value it sweeps (--noise)
    for field, why in ignored_options(study, [k for k in IGNORED if k in given]).items():
        raise ConfigError(
            f"the {study} study has no use for {given[field].names[0]} ({why}); leave it out"
        )
    llm = [f.names[0] for f in FLAGS if f.llm and getattr(args, f.dest, None) is not None]
    for _, why in ignored_options(study, ["runs"] if llm else []).items():
        raise ConfigError(f"the {study} study has no use for {llm[0]} ({why}); leave it out")
