"""What a path is, in words, for the one-line errors that name it (JAX-free)."""

from __future__ import annotations

import os
import stat

from jswim.errors import ConfigError


def path_kind(path: str | os.PathLike, wanted: str) -> str:
    """Why ``path`` is not ``wanted`` (``"a file"``, ``"a folder"``): what is there instead, or
    that nothing is (a FIFO or a device is said to be one, never "no such file")."""
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        return "no such " + wanted.split()[-1]
    except OSError as exc:
        return f"cannot read it ({exc.strerror or type(exc).__name__})"
    kinds = (
        (stat.S_ISDIR, "a folder"),
        (stat.S_ISREG, "a file"),
        (stat.S_ISFIFO, "a FIFO (named pipe)"),
        (stat.S_ISCHR, "a device"),
        (stat.S_ISBLK, "a device"),
        (stat.S_ISSOCK, "a socket"),
    )
    what = next((name for test, name in kinds if test(mode)), "not a regular file")
    return f"{what}, not {wanted}"


def check_file(path: str | os.PathLike, option: str) -> None:
    """The one check of a file a user names (``--prompt-file``, ``--prompt-files``, ``--gguf``):
    a [`ConfigError`][jswim.errors.ConfigError] ``OPTION PATH: what is there instead`` unless it is a regular file."""
    if not os.path.isfile(path):
        raise ConfigError(f"{option} {path}: {path_kind(path, 'a file')}")
