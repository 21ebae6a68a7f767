"""What a server's 4xx answer means, in one line: its own words, the URL tried, what to change.

A rejection is either about *this request* (the prompt does not fit the context: the run that
sent it fails, others go on) or about *every request* of the client (wrong URL, key or model; a
request field the server does not accept): :class:`~jswim.llm.errors.LLMSetupError`, and the
message names the option that avoids it. jswim never drops a field on its own: what is sent is
what the settings say, and the run metadata records it.
"""

from __future__ import annotations

import re
from typing import Any, Mapping

import httpx

from jswim.llm.errors import LLMRequestError, LLMSetupError
from jswim.llm.reply import error_message

#: Fields every request carries; the others are optional and may be left out (``omit_fields``).
REQUIRED_FIELDS = ("model", "messages")

#: Server messages that say the prompt does not fit the model's context (a per-request problem).
_CONTEXT = re.compile(
    r"context[ _-]?(length|size|window)|too many tokens|(prompt|input) is too long|exceeds? the (available )?context",
    re.I,
)


def server_text(resp: httpx.Response) -> str:
    """The server's own error message from an error response (one line; ``""`` if none)."""
    try:
        return error_message(resp.json())
    except ValueError:
        return " ".join(resp.text.split())[:300]


def rejected_field(server_message: str, payload: Mapping[str, Any]) -> str | None:
    """The optional request field a server's error message names, if it names one we sent."""
    for name in payload:
        if name in REQUIRED_FIELDS:
            continue
        if re.search(r"(?<![A-Za-z0-9_])" + re.escape(name) + r"(?![A-Za-z0-9_])", server_message):
            return name
    return None


def field_hint(name: str) -> str:
    """What to pass so that requests go out without field ``name``."""
    if name in ("grammar", "response_format"):
        return "run with --constrain none (no constrained decoding) or the other --constrain mode"
    if name == "max_tokens":
        return ("run with --reasoning auto (it sends max_completion_tokens when the server asks), or leave the "
                "field out with --omit-field max_tokens")
    if name == "temperature":
        return "run with --reasoning auto (it sends the temperature the model accepts), or set --temperature"
    return f"leave it out with --omit-field {name}"


def rejection(status: int, server: str, payload: Mapping[str, Any], *, where: str, url: str, model: str,
              api_key_env: str) -> LLMRequestError:
    """The error for a 4xx answer (not 408/409/429, which are retried).

    Parameters
    ----------
    status : int
        HTTP status.
    server : str
        The server's error message (see :func:`server_text`).
    payload : mapping
        The request body sent (to find the field the server names).
    where, url : str
        The base URL and the full endpoint URL tried (both without secrets).
    model, api_key_env : str
        For the hints.
    """
    said = f"HTTP {status}: {server}" if server else f"HTTP {status}"
    if status in (401, 403):
        return LLMSetupError(f"{where}: {said}; check the API key in ${api_key_env}", status, server)
    if status in (404, 405):
        if re.search(r"\bmodel\b", server, re.I):
            msg = f"{where}: the server has no model {model!r} ({said}); check --model"
        else:
            msg = (f"no chat-completions endpoint at {url} ({said}); give the server's API root as "
                   "--base-url, usually ending in /v1 (e.g. http://localhost:8080/v1)")
        return LLMSetupError(msg, status, server)
    if _CONTEXT.search(server):
        msg = (f"{where}: the prompt does not fit the model's context ({said}); "
               "use a shorter history (--n-ht) or a model with a longer context")
        return LLMRequestError(msg, status, server)
    named = rejected_field(server, payload)
    if named is not None:
        msg = f"{where}: the server rejected the request field {named!r} ({said}); {field_hint(named)}"
        return LLMSetupError(msg, status, server, named)
    return LLMRequestError(f"{where}: {said} for model {model!r}", status, server)
