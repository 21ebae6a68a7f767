"""A price table from a file (``--prices FILE``, or the ``prices`` table of a bench's models file).

The file is TOML (``.toml``) or JSON (anything else), USD per 1M tokens, prompt then completion;
it replaces the built-in table (`jswim.llm.usage.DEFAULT_PRICES`) on any host. Its format
and matching rule are in docs/paid-apis.md (*Estimate first*).
"""

from __future__ import annotations

import json
import math
import os
import tomllib
from pathlib import Path
from typing import Any
from collections.abc import Mapping

from jswim.errors import ConfigError


#: The largest settings file read (a price table, a models file): a few KiB in practice.
MAX_SETTINGS_BYTES = 1 << 20


def read_small_text(path: Path, what: str) -> str:
    """The UTF-8 text of a small regular file.

    Raises
    ------
    ConfigError
        ``path`` is not a regular file (a FIFO, a device such as /dev/zero, a folder) or is
        larger than `MAX_SETTINGS_BYTES`.
    OSError, UnicodeDecodeError
        It cannot be read.
    """
    import stat

    # Opened without blocking (a FIFO with no writer would hang open()), then checked.
    fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK)
    with os.fdopen(fd, "rb") as fh:
        mode = os.fstat(fh.fileno()).st_mode
        if not stat.S_ISREG(mode):
            kind = "a folder" if stat.S_ISDIR(mode) else "not a regular file"
            raise ConfigError(f"{what} {path}: {kind}; give a file")
        data = fh.read(MAX_SETTINGS_BYTES + 1)
    if len(data) > MAX_SETTINGS_BYTES:
        raise ConfigError(
            f"{what} {path}: larger than {MAX_SETTINGS_BYTES >> 10} KiB; not a settings file"
        )
    return data.decode("utf-8")


def parse_prices(table: Any, where: str) -> dict[str, tuple[float, float]]:
    """``{model: (prompt, completion)}`` from a mapping of model -> ``[in, out]`` or
    ``{input, output}`` (USD per 1M tokens).

    Raises
    ------
    ConfigError
        For anything else, naming ``where`` and the entry.
    """
    if not isinstance(table, Mapping):
        raise ConfigError(
            f"{where}: prices must be a table of model = [prompt, completion] USD per 1M tokens"
        )
    out: dict[str, tuple[float, float]] = {}
    for name, value in table.items():
        if isinstance(value, Mapping):
            value = [
                value.get("input", value.get("prompt")),
                value.get("output", value.get("completion")),
            ]
        # Two numbers, as written: no text ("12" is not [1, 2]), no true/false (not $1/$0).
        if not (
            isinstance(value, (list, tuple))
            and len(value) == 2
            and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value)
        ):
            raise ConfigError(
                f"{where}: the price of {name!r} must be [prompt, completion] USD per 1M tokens, "
                f"got {value!r}"
            )
        p_in, p_out = float(value[0]), float(value[1])
        if not all(math.isfinite(v) and v >= 0 for v in (p_in, p_out)):
            raise ConfigError(
                f"{where}: the price of {name!r} must be two numbers >= 0, got {value!r}"
            )
        out[str(name)] = (p_in, p_out)
    return out


def load_prices(path: str | Path) -> tuple[dict[str, tuple[float, float]], str]:
    """The table in ``path`` and its date (``as_of``, else ``"your table <path>"``).

    Raises
    ------
    ConfigError
        A missing or unreadable file, bad TOML/JSON, or a malformed entry (one line).
    """
    p = Path(path)
    try:
        text = read_small_text(p, "--prices")
    except FileNotFoundError:
        raise ConfigError(f"--prices {path}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(
            f"--prices {path}: cannot read it ({getattr(exc, 'strerror', None) or exc})"
        ) from None
    try:
        data = tomllib.loads(text) if p.suffix.lower() == ".toml" else json.loads(text)
    except (tomllib.TOMLDecodeError, ValueError) as exc:
        raise ConfigError(
            f"--prices {path}: not valid {'TOML' if p.suffix.lower() == '.toml' else 'JSON'} "
            f"({str(exc).splitlines()[0]})"
        ) from None
    if not isinstance(data, Mapping):
        raise ConfigError(f"--prices {path}: expected a table with a 'prices' table")
    table = data.get("prices", {k: v for k, v in data.items() if k != "as_of"})
    as_of = str(data.get("as_of") or f"your table {p.name}")
    return parse_prices(table, f"--prices {path}"), as_of
