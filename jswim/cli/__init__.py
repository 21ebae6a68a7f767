"""The ``jswim`` command: one module per command (``register(sub)`` adds its parser, ``main(args)``
runs it), argv -> options of the studies in `jswim.cli.options`, shared parts in
`jswim.cli.base`. Every command, in one table: docs/getting-started.md. A user mistake ends
with one line on stderr and exit status 2; a command that reads folders (``reads_folder``:
show, compare, plot, report, animate) and had to skip a record or field of one shows the rest,
says each in one line and exits 2 too. Ctrl-C keeps every finished run.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import warnings
from typing import Any
from collections.abc import Sequence

from jswim import compile_cache
from jswim._io import interrupts
from jswim._io.jsonl import SkippedRecord, forget_warnings
from jswim._io.permissions import private_files
from jswim.cli import animate, bench, ensemble, folders, gaits, qlearn, report, serve, study
from jswim.cli.base import EXIT_USAGE, Outline, Parser, warnings_as_lines
from jswim.errors import JswimError

__all__ = ["build_parser", "main", "run"]
from jswim.llm.credentials import scrub

#: The commands in the order ``jswim --help`` lists them.
COMMANDS = (study, qlearn, ensemble, gaits, folders, serve, report, animate, bench)


def build_parser(outline: bool = False) -> argparse.ArgumentParser:
    """The ``jswim`` parser; ``outline`` builds only its subcommands' names (``jswim --help``)."""
    ap = (Outline if outline else Parser)(
        prog="jswim",
        description="A large language model teaches model microswimmers to swim, measured against "
        "Q-learning and a random policy.",
        epilog="Every command takes --help. Results land in a study folder that a rerun resumes.",
    )
    sub = ap.add_subparsers(
        dest="command", metavar="COMMAND", parser_class=Outline if outline else Parser
    )
    sub.required = True
    for command in COMMANDS:
        command.register(sub)
    return ap


def _undecodable_token(tokens: Sequence[str]) -> str | None:
    """The option (or argument) of the first command-line token that is not UTF-8, named as the
    user typed it (``--swimmer``), never as Python holds the bytes (``'\udcff'``)."""
    for i, t in enumerate(tokens):
        if not _utf8(t):
            if t.startswith("--") and "=" in t:
                return t.split("=", 1)[0]
            if i and tokens[i - 1].startswith("-") and len(tokens[i - 1]) > 1:
                return tokens[i - 1]
            return f"argument {i + 1}"
    return None


def _utf8(text: str) -> bool:
    """Whether ``text`` encodes as UTF-8 (Python holds bytes that are not as lone surrogates)."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError:
        return False
    return True


def _undecodable(args: argparse.Namespace) -> str | None:
    """The first option whose text is not UTF-8 (Python holds such bytes as lone surrogates)."""
    values = (
        (name, v)
        for name, value in vars(args).items()
        for v in (value if isinstance(value, (list, tuple)) else (value,))
    )
    return next((name for name, v in values if isinstance(v, str) and not _utf8(v)), None)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``jswim`` command; returns the exit status."""
    tokens = sys.argv[1:] if argv is None else list(argv)
    if (
        bad := _undecodable_token(tokens)
    ) is not None:  # before argparse, which would print '\udcff'
        print(f"jswim: error: {bad} is not valid UTF-8 text; write it in UTF-8", file=sys.stderr)
        return EXIT_USAGE
    # No command named (`jswim`, `jswim --help`): the outline parser says the same, without JAX.
    args = build_parser(outline=all(t.startswith("-") for t in tokens)).parse_args(argv)
    if (
        bad := _undecodable(args)
    ) is not None:  # bytes that are not UTF-8 (e.g. $'m\xff') fail deep inside
        print(
            f"jswim: error: --{bad.replace('_', '-')} is not valid UTF-8 text; write it in UTF-8",
            file=sys.stderr,
        )
        return EXIT_USAGE
    if args.command not in ("show", "compare", "migrate"):
        compile_cache.enable()  # compiled programs kept on disk: later sessions start in seconds
    # The command only writes figure files; never open a window. Through the environment, so
    # matplotlib (~0.5 s) is imported only by commands that draw (`--no-figures` never does).
    if "matplotlib" in sys.modules:
        sys.modules["matplotlib"].use("Agg")
    else:
        os.environ["MPLBACKEND"] = "Agg"
    # Folders, figures and caches: owner only under the usual umask; every jswim warning (a
    # skipped record of a damaged folder, ...) one line, whatever the command.
    forget_warnings()
    with private_files(), warnings_as_lines() as said:
        status = _main(args)
    if (
        status == 0
        and getattr(args, "reads_folder", False)
        and any(issubclass(c, SkippedRecord) for c in said)
    ):
        # A reader showed what it could of a folder with a record or field it had to skip (a
        # hand edit, a foreign writer, damage; each said in one line naming the file and the
        # field): the output is not the whole folder, and a script must be able to tell.
        return EXIT_USAGE
    return status


def _main(args: argparse.Namespace) -> int:
    try:
        return args.command_main(args)
    except JswimError as exc:  # every user or server mistake (jswim.errors); anything else is a bug
        print(
            f"jswim: error: {scrub(str(exc))}", file=sys.stderr
        )  # no key or URL password, in any form
        return EXIT_USAGE
    except KeyboardInterrupt:
        print(f"jswim: interrupted ({interrupts.name(interrupts.received())})", file=sys.stderr)
        return 128 + (interrupts.received() or signal.SIGINT)
    except MemoryError:
        print(
            "jswim: error: out of memory; use fewer swimmers/learners or a smaller --chunk",
            file=sys.stderr,
        )
        return EXIT_USAGE
    except (
        RuntimeError
    ) as exc:  # JAX's device errors are RuntimeErrors; only out-of-memory is the user's
        if "RESOURCE_EXHAUSTED" not in str(exc):
            raise
        print(
            "jswim: error: out of device memory; use fewer swimmers/learners, fewer --steps or a smaller --chunk",
            file=sys.stderr,
        )
        return EXIT_USAGE


def _show_warning(
    message: Any,
    category: Any,
    filename: str,
    lineno: int,
    file: Any = None,
    line: str | None = None,
) -> None:
    """Warnings as one line, ``jswim: warning: ...`` (not Python's file:line form)."""
    print(f"jswim: warning: {message}", file=sys.stderr if file is None else file)


def run() -> None:
    """Console-script wrapper: signals end a session as Ctrl-C does (`jswim._io.interrupts`)."""
    interrupts.install()
    warnings.showwarning = _show_warning
    try:
        status = main()
        interrupts.quiet()  # a signal from here on (cleanup, atexit) is only noted: no traceback
        sys.stdout.flush()
    except (
        BrokenPipeError
    ):  # output piped into a reader that quit (`jswim show F | head`): not an error
        os.dup2(
            os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno()
        )  # no second error at interpreter exit
        status = 0
    except (
        KeyboardInterrupt
    ):  # Ctrl-C before main's own handler (imports, parser): nothing to keep yet
        interrupts.quiet()
        print(
            f"jswim: interrupted ({interrupts.name(interrupts.received())}) while starting; nothing was written",
            file=sys.stderr,
        )
        status = 128 + (interrupts.received() or signal.SIGINT)
    interrupts.ignore()  # a signal during interpreter exit must not kill the process after its line
    sys.exit(status)
