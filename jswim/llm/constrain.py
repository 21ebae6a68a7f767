"""Constrained decoding: make the server emit only one of a fixed set of reply strings.

Modes
-----
``"grammar"``      llama.cpp servers: a GBNF ``grammar`` field whose root is the alternatives.
``"json_schema"``  OpenAI-style ``response_format`` with a JSON schema; the reply is
                   ``{"action": "<one of the replies>"}`` and `reply_text` unwraps it.
``"json_object"``  ``response_format`` ``{"type": "json_object", "schema": ...}``, the form
                   llama-cpp-python's server takes (it rejects ``json_schema``); same reply.
``"none"``         plain text, parsed afterwards.
``"auto"``         by server family, falling back through `FALLBACK` where the server
                   rejects the form (docs/servers.md, *Constrained decoding*).
"""

from __future__ import annotations

import json
from typing import Any
from collections.abc import Sequence

from jswim.errors import ConfigError

MODES = ("auto", "grammar", "json_schema", "json_object", "none")

#: Server families the client knows (`jswim.llm.probe` tells them apart).
SERVER_KINDS = ("generic", "llamacpp", "llama-cpp-python", "vllm", "ollama", "openai")

#: ``"auto"``'s first form per family (the others: ``"none"``).
AUTO_FORM = {
    "llamacpp": "grammar",
    "llama-cpp-python": "grammar",
    "vllm": "json_schema",
    "ollama": "json_schema",
}

#: The forms ``"auto"`` falls back through when the server rejects one, in this order.
FALLBACK = ("json_schema", "json_object", "grammar")


def resolve_mode(mode: str, server_kind: str, has_replies: bool = True) -> str:
    """The concrete mode (never ``"auto"``); ``"none"`` when there is nothing to constrain to."""
    if mode not in MODES:
        raise ConfigError(f"constrain must be one of {MODES}, got {mode!r}")
    if not has_replies:
        return "none"
    if mode == "auto":
        return AUTO_FORM.get(server_kind, "none")
    return mode


def next_form(tried: set[str] | frozenset[str]) -> str | None:
    """The next form of `FALLBACK` not yet ``tried`` (``None``: none left)."""
    return next((f for f in FALLBACK if f not in tried), None)


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
    elif mode == "json_object" and replies:
        payload["response_format"] = {
            "type": "json_object",
            "schema": json_schema(replies)["json_schema"]["schema"],
        }
    return payload


def reply_text(mode: str, content: str) -> str:
    """The reply proper: the ``action`` string of a JSON-schema reply, else ``content`` as is."""
    if mode not in ("json_schema", "json_object"):
        return content
    try:
        value = json.loads(content)
    except (TypeError, ValueError):
        return content
    if isinstance(value, dict) and isinstance(value.get("action"), str):
        return value["action"]
    return content
