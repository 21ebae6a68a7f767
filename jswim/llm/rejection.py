"""What a server's 4xx answer means, in one line: its own words, the URL tried, what to change.

A rejection is recognised by what the server says, not only its status (`validation_error`:
never retried) and trimmed to the sentence that matters (`essential_message`). It is about
*this request* (the run fails, others go on) or *every request* of the client
([`LLMSetupError`][jswim.errors.LLMSetupError], naming the option that avoids it); jswim never drops a
field on its own. docs/servers.md (*Rejected fields*, *Errors per run*) has the details.
"""

from __future__ import annotations

import re
from typing import Any
from collections.abc import Mapping

import httpx

from jswim.llm.credentials import scrub
from jswim.errors import LLMRequestError, LLMSetupError
from jswim.llm.server_response import error_message

#: Fields every request carries; the others are optional and may be left out (``omit_fields``).
REQUIRED_FIELDS = ("model", "messages")

#: Server messages that say the prompt does not fit the model's context (a per-request problem).
_CONTEXT = re.compile(
    r"context[ _-]?(length|size|window)|too many tokens|(prompt|input) is too long|exceeds? the (available )?context",
    re.I,
)


#: What a request-validation error says (FastAPI/pydantic, OpenAI, vLLM, llama.cpp wordings).
_VALIDATION = re.compile(
    r"validation errors? for|input should be|extra (inputs|fields) (are )?not permitted|extra_forbidden|"
    r"literal_error|not supported|unsupported (parameter|value|field)|unrecogni[sz]ed|"
    r"unknown (field|parameter|argument)|invalid (request|value for|type for)",
    re.I,
)
#: A pydantic error block in text: the location on one line, the message indented below it.
_PYDANTIC_ITEM = re.compile(
    r"^([A-Za-z_][\w.\[\]-]*)\n[ \t]+(.+?)(?: \[type=[^\]]*\])?[ \t]*$", re.M
)
#: A pydantic error as Python prints the dict (llama-cpp-python 0.3's 500 bodies):
#: ``{'type': 'literal_error', 'loc': ('body', 'response_format', 'type'), 'msg': "Input should be ..."}``.
_PYDANTIC_REPR = re.compile(
    r"""'loc':\s*\(([^)]*)\),\s*'msg':\s*(?:"((?:[^"\\]|\\.)*)"|'((?:[^'\\]|\\.)*)')"""
)
#: File paths (a server's source files), replaced in what is shown.
_PATH = re.compile(r"""(?:[A-Za-z]:)?(?:[/\\][\w.@+-]+){2,}[/\\]?""")
_TRACEBACK = "Traceback (most recent call last)"


def raw_error_text(resp: httpx.Response) -> str:
    """The error text of a response as sent (line breaks kept): the ``error.message``, the
    pydantic ``detail`` list as ``loc: msg`` items, or the body text; credentials masked
    (`jswim.llm.credentials.scrub`) before anything trims it, so no cut leaves part of a key."""
    return scrub(_raw_error_text(resp))


def _raw_error_text(resp: httpx.Response) -> str:
    try:
        body = resp.json()
    except ValueError:
        return resp.text
    if isinstance(body, Mapping):
        err = body.get("error")
        if isinstance(err, Mapping) and isinstance(err.get("message"), str):
            return err["message"]
        if isinstance(err, str):
            return err
        if isinstance(body.get("message"), str) and "detail" not in body:
            return body["message"]
    return error_message(body)


def essential_message(text: str, limit: int = 240) -> str:
    """The part of a server's error text a user needs, on one line.

    Pydantic error blocks become ``loc: msg`` items (without ``[type=...]`` and the "for further
    information" link); a traceback is dropped (what precedes it is kept, else its last line,
    the exception); file paths become ``<path>``; of a long text the first sentence that reads
    like a validation error is kept.
    """
    items = [
        (loc, msg)
        for loc, msg in _PYDANTIC_ITEM.findall(text)
        if not loc.lower().startswith("for ")
    ]
    if not items:
        for loc, dq, sq in _PYDANTIC_REPR.findall(text):
            parts = [a or b for a, b in re.findall(r"'([^']*)'|(\d+)", loc)]
            items.append((".".join(p for p in parts[parts[:1] == ["body"] :]), dq or sq))
    if items:
        text = "; ".join(f"{loc}: {msg}" for loc, msg in items[:3])
    head, sep, tail = text.partition(_TRACEBACK)
    if sep:
        kept = [
            ln for ln in tail.splitlines() if ln.strip() and not ln.startswith((" ", "\t", "):"))
        ]
        text = head if head.strip() else (kept[-1] if kept else "")
    text = " ".join(ln for ln in text.splitlines() if not re.match(r'\s*File "', ln))
    text = re.sub(r"For further information visit \S+", "", text)
    text = " ".join(_PATH.sub("<path>", text).split())
    if len(text) > limit:
        for sentence in re.split(r"(?<=[.;!?])\s+", text):
            if _VALIDATION.search(sentence):
                text = sentence
                break
    return text if len(text) <= limit else text[: limit - 1] + "…"


def server_text(resp: httpx.Response) -> str:
    """The server's own error message from an error response (one line, trimmed; ``""`` if none)."""
    return essential_message(raw_error_text(resp))


def validation_error(resp: httpx.Response) -> str | None:
    """The trimmed message of a response whose body is a request-validation error (whatever
    its status), else ``None``."""
    try:
        body = resp.json()
    except ValueError:
        body = None
    shaped = (
        isinstance(body, Mapping)
        and isinstance(body.get("detail"), list)
        and any(isinstance(d, Mapping) and "msg" in d for d in body["detail"])
    )
    raw = raw_error_text(resp)
    if shaped or _VALIDATION.search(raw):
        return essential_message(raw)
    return None


def key_hint(api_key_env: str) -> str:
    """What to do about a refused key, naming the variable's state (unset, empty, set)."""
    import os

    if not api_key_env:
        return (
            "no API key was sent: $OPENAI_API_KEY goes only to api.openai.com unless --api-key-env names "
            "it; name the variable that holds this server's key with --api-key-env"
        )
    value = os.environ.get(api_key_env)
    if value is None:
        return (
            f"${api_key_env} (the variable --api-key-env names) is not set: export the key in it, or name "
            "the variable that holds it with --api-key-env"
        )
    if not value.strip():
        return (
            f"${api_key_env} (the variable --api-key-env names) is set but empty: put the key in it"
        )
    return f"check the API key in ${api_key_env}"


def rejected_field(server_message: str, payload: Mapping[str, Any]) -> str | None:
    """The optional request field a server's error message names, if it names one we sent."""
    for name in payload:
        if name in REQUIRED_FIELDS:
            continue
        if re.search(r"(?<![A-Za-z0-9_])" + re.escape(name) + r"(?![A-Za-z0-9_])", server_message):
            return name
    return None


#: Sampling fields jswim sends under ``--sampling neutral`` (see `jswim.llm.sampling`).
SAMPLING_FIELDS = (
    "repeat_penalty",
    "repetition_penalty",
    "top_k",
    "top_p",
    "min_p",
    "presence_penalty",
    "frequency_penalty",
)


def field_hint(name: str) -> str:
    """What to pass so that requests go out without field ``name``."""
    if name in ("grammar", "response_format"):
        return (
            "the server does not take this form of constrained decoding: --constrain auto tries the forms in "
            "turn (json_schema, json_object with a schema, grammar), or choose one with --constrain "
            "grammar/json_object/json_schema, or --constrain none"
        )
    if name in SAMPLING_FIELDS:
        return f"--sampling server sends no sampling fields (the server's own defaults), or --omit-field {name}"
    if name == "max_tokens":
        return (
            "run with --reasoning auto (it sends max_completion_tokens when the server asks), or leave the "
            "field out with --omit-field max_tokens"
        )
    if name == "temperature":
        return "run with --reasoning auto (it sends the temperature the model accepts), or set --temperature"
    return f"leave it out with --omit-field {name}"


def rejection(
    status: int,
    server: str,
    payload: Mapping[str, Any],
    *,
    where: str,
    url: str,
    model: str,
    api_key_env: str,
    invalid: bool = False,
) -> LLMRequestError:
    """The error for a 4xx answer (not 408/409/429, which are retried), or for any answer whose
    body is a request-validation error (``invalid``, `validation_error`).

    Parameters
    ----------
    status : int
        HTTP status.
    server : str
        The server's error message (see `server_text`).
    payload : mapping
        The request body sent (to find the field the server names).
    where, url : str
        The base URL and the full endpoint URL tried (both without secrets).
    model, api_key_env : str
        For the hints.
    invalid : bool
        The body is a request-validation error (then never a per-request failure).
    """
    said = f"HTTP {status}: {server}" if server else f"HTTP {status}"
    if status in (401, 403):
        return LLMSetupError(f"{where}: {said}; {key_hint(api_key_env)}", status, server)
    if status in (404, 405):
        if re.search(r"\bmodel\b", server, re.I):
            msg = f"{where}: the server has no model {model!r} ({said}); check --model"
        else:
            msg = (
                f"no chat-completions endpoint at {url} ({said}); give the server's API root as "
                "--base-url, usually ending in /v1 (e.g. http://localhost:8080/v1)"
            )
        return LLMSetupError(msg, status, server)
    if _CONTEXT.search(server):
        msg = (
            f"{where}: the prompt does not fit the model's context ({said}); "
            "use a shorter history (--n-ht) or a model with a longer context"
        )
        return LLMRequestError(msg, status, server)
    named = rejected_field(server, payload)
    if named is not None:
        msg = f"{where}: the server rejected the request field {named!r} ({said}); {field_hint(named)}"
        return LLMSetupError(msg, status, server, named)
    if invalid:  # a request-validation error naming no field we sent: every request would get it
        return LLMSetupError(
            f"{where}: the server rejected the request as invalid ({said}); check --constrain, "
            "--sampling and --omit-field",
            status,
            server,
        )
    return LLMRequestError(f"{where}: {said} for model {model!r}", status, server)
