"""Small text tools of the prompt: prose lists, filling a template, tidying masked sentences.

Text only (no JAX).
"""

from __future__ import annotations

import re
import string
from collections.abc import Sequence

from jswim.errors import ConfigError


def join_prose(items: Sequence[str], last: str = "and") -> str:
    """``a``, ``a and b``, ``a, b and c``: ``items`` as a prose list joined by ``last``."""
    if len(items) <= 1:
        return "".join(items)
    return ", ".join(items[:-1]) + f" {last} " + items[-1]


def fill(template: str, values: dict[str, str], what: str) -> str:
    """``template`` with its placeholders filled from ``values``.

    Raises
    ------
    ConfigError
        An unknown placeholder or bad braces (``what`` names the template in the message).
    """
    try:
        return template.format_map(values)
    except KeyError as exc:
        raise ConfigError(
            f"unknown placeholder {{{exc.args[0]}}} in the {what} template; known: "
            + ", ".join(sorted(values))
        ) from None
    except (ValueError, IndexError) as exc:
        raise ConfigError(
            f"bad {what} template ({exc}); write literal braces as {{{{ }}}}"
        ) from None


def tidy_lines(text: str) -> str:
    """``text`` without the doubled spaces and empty lines that masked sentences leave behind."""
    lines = [re.sub(r"[ \t]{2,}", " ", ln).strip() for ln in text.split("\n")]
    return "\n".join(ln for ln in lines if ln)


def placeholder_names(template: str) -> set[str]:
    """Placeholder names used by a format string (escaped braces are not placeholders)."""
    try:
        return {name for _, name, _, _ in string.Formatter().parse(template) if name}
    except ValueError:
        return set()  # malformed: fill reports it
