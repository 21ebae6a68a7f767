"""Constrained decoding: make the server emit only one of a fixed set of reply strings.

Modes
-----
``"grammar"``      llama.cpp servers: a GBNF ``grammar`` field whose root is the alternatives.
``"json_schema"``  OpenAI-style ``response_format`` with a JSON schema; the reply is
                   ``{"action": "<one of the replies>"}`` and :func:`reply_text` unwraps it.
``"none"``         plain text, parsed afterwards.
``"auto"``         ``"grammar"`` for llama.cpp backends (the embedded default), else ``"none"``.
"""

from __future__ import annotations

import json
from typing import Any, Sequence

from jswim.errors import ConfigError

MODES = ("auto", "grammar", "json_schema", "none")

#: Server kinds the client knows; only used to resolve ``"auto"``.
SERVER_KINDS = ("generic", "llamacpp", "openai")


def resolve_mode(mode: str, server_kind: str, has_replies: bool = True) -> str:
    """The concrete mode (never ``"auto"``); ``"none"`` when there is nothing to constrain to."""
    if mode not in MODES:
        raise ConfigError(f"constrain must be one of {MODES}, got {mode!r}")
    if not has_replies:
        return "none"
    if mode == "auto":
        return "grammar" if server_kind == "llamacpp" else "none"
    return mode


def _gbnf_literal(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def gbnf(replies: Sequence[str]) -> str:
    """A GBNF grammar admitting exactly the given replies, e.g. ``root ::= "[1, -1]" | "[1, 0]"``."""
    if not replies:
        raise ConfigError("a grammar needs at least one reply")
    return "root ::= " + " | ".join(_gbnf_literal(r) for r in replies)


def json_schema(replies: Sequence[str]) -> dict[str, Any]:
    """An OpenAI ``response_format`` (strict JSON schema) whose ``action`` is one of ``replies``."""
    return {
        "type": "json_schema",
        "json_schema": {
            "name": "action",
            "strict": True,
            "schema": {
                "type": "object",
                "properties": {"action": {"type": "string", "enum": list(replies)}},
                "required": ["action"],
                "additionalProperties": False,
            },
        },
    }


def apply(payload: dict[str, Any], mode: str, replies: Sequence[str] | None) -> dict[str, Any]:
    """Add the fields of a resolved ``mode`` to a request payload (in place; returned)."""
    if mode == "grammar" and replies:
        payload["grammar"] = gbnf(replies)
    elif mode == "json_schema" and replies:
        payload["response_format"] = json_schema(replies)
    return payload


def reply_text(mode: str, content: str) -> str:
    """The reply proper: the ``action`` string of a JSON-schema reply, else ``content`` as is."""
    if mode != "json_schema":
        return content
    try:
        value = json.loads(content)
    except (TypeError, ValueError):
        return content
    if isinstance(value, dict) and isinstance(value.get("action"), str):
        return value["action"]
    return content
