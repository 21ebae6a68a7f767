"""What every ``jswim`` command shares: the parser that reports a mistake in one line (exit 2),
the outline parser of ``jswim --help``, the checks of counts and folders, and warnings as one line."""

from __future__ import annotations

import argparse
import contextlib
import sys
import time
import warnings
from pathlib import Path
from typing import Any
from collections.abc import Iterator

from jswim.console import eta as _eta_text
from jswim.errors import MAX_COUNT, ConfigError, JswimWarning, check_count  # noqa: F401  (MAX_COUNT read from here)

EXIT_USAGE = 2


class Parser(argparse.ArgumentParser):
    """argparse that reports mistakes in one line with exit status 2 (its own default too)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see --help)\n")


class Outline(Parser):
    """A parser that keeps only the subcommands' names and help: all ``jswim --help`` shows, built
    without the options' defaults (which import the study grids, and with them JAX: ~1.4 s)."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._outlined = (
            True  # argparse's own groups and -h/--help exist; every later option is left out
        )

    def add_argument(self, *args: Any, **kwargs: Any) -> Any:
        return (
            super().add_argument(*args, **kwargs) if not getattr(self, "_outlined", False) else None
        )

    def add_argument_group(self, *args: Any, **kwargs: Any) -> Any:
        return (
            super().add_argument_group(*args, **kwargs)
            if not getattr(self, "_outlined", False)
            else self
        )

    def add_mutually_exclusive_group(self, *args: Any, **kwargs: Any) -> Any:
        return self

    def add_subparsers(self, **kwargs: Any) -> Any:
        return super().add_subparsers(**{**kwargs, "parser_class": Outline})


def outlined(p: argparse.ArgumentParser) -> bool:
    """Whether ``p`` is an outline (``jswim --help``): its command adds no options, imports nothing."""
    return isinstance(p, Outline)


def check_out_folder(out: str) -> None:
    """``--out FOLDER`` of a command: an existing file there is a mistake, caught before any work."""
    if Path(out).exists() and not Path(out).is_dir():
        raise ConfigError(f"--out {out} is a file; give a folder for the figures and the table")


def check_counts(args: argparse.Namespace, *names: str) -> None:
    """The one check of a command's counts (``--n``, ``--steps``, ``--seeds``, ``--chunk``, ...):
    each given one ``>= 1`` and at most `MAX_COUNT` (the device's int32 indices; else a deep
    traceback)."""
    for name in names:
        if getattr(args, name) is not None:
            check_count(name, getattr(args, name))


def eta(t0: float, done: int, total: int) -> str:
    """``ETA 1 min`` of a progress bar started at ``t0`` (``time.perf_counter``), or ``""``."""
    left = _eta_text(time.perf_counter() - t0, done / total) if total else None
    return f"ETA {left}" if left and done < total else ""


def warn(message: str) -> None:
    print(f"jswim: warning: {message}", file=sys.stderr)


@contextlib.contextmanager
def warnings_as_lines() -> Iterator[list[type[Warning]]]:
    """Inside: each [`JswimWarning`][jswim.errors.JswimWarning] is one ``jswim: warning:`` line on stderr
    (others as Python shows them); the hook is restored after. Yields the list of the categories
    said, in order (the command's exit status may depend on them: `jswim.cli.main`)."""
    shown = warnings.showwarning
    said: list[type[Warning]] = []

    def one_line(message, category, filename, lineno, file=None, line=None):
        said.append(category)
        if issubclass(category, JswimWarning):
            warn(str(message))
        else:
            shown(message, category, filename, lineno, file, line)

    with warnings.catch_warnings():
        warnings.showwarning = one_line
        yield said
