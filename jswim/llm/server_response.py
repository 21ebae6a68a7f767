"""Reading a chat-completion body the way real servers send it.

Servers that speak the OpenAI chat API differ in ordinary ways (content as a string, ``null`` or a
list of parts; reasoning in a field or inline between tags such as ``<think>...</think>``, either
tag possibly missing; an SSE stream although ``"stream": false`` was sent), and this module absorbs
them; docs/servers.md (*Reasoning models*, *Streams*) lists each. The *answer* is what follows the
last closed reasoning block; reasoning is kept for transcripts, never parsed. Everything here is
pure (no I/O), so each server behaviour is a unit test.
"""

from __future__ import annotations

import email.utils
import json
import re
import time
import zlib
from dataclasses import dataclass
from typing import Any
from collections.abc import Mapping

from jswim.errors import MalformedReply

#: Message fields in which servers put reasoning next to (or instead of) the content.
REASONING_FIELDS = ("reasoning_content", "reasoning", "thinking")

#: Content-part types that hold reasoning rather than answer text.
REASONING_PARTS = ("thinking", "reasoning", "reasoning_text", "redacted_thinking")

#: Tag names that wrap inline reasoning (``<think>``, ``<thinking>``, ...).
REASONING_TAGS = ("think", "thinking", "reasoning", "thought")

_OPEN = re.compile(r"<\s*(?:" + "|".join(REASONING_TAGS) + r")\s*>", re.I)
_CLOSE = re.compile(r"<\s*/\s*(?:" + "|".join(REASONING_TAGS) + r")\s*>", re.I)
# OpenAI's "harmony" format (gpt-oss) when a server passes it through raw.
_HARMONY_FINAL = "<|channel|>final<|message|>"
_HARMONY_ANY = "<|channel|>"


@dataclass(frozen=True)
class Completion:
    """One chat completion, read.

    Attributes
    ----------
    content : str
        The message content as text (``""`` for null; text parts joined).
    reasoning : str
        Reasoning from the message's reasoning fields, reasoning parts and inline blocks,
        in that order, joined by blank lines (``""`` when there is none).
    answer : str
        The content after any reasoning: what the model answered.
    finish_reason : str or None
        As reported (``"stop"``, ``"length"``, ...).
    usage : mapping or None
        The ``usage`` object, as sent.
    streamed : bool
        The body was an SSE stream (assembled here).
    model : str or None
        The ``model`` field: the model the server says it ran.
    """

    content: str
    reasoning: str
    answer: str
    finish_reason: str | None
    usage: Mapping[str, Any] | None
    streamed: bool = False
    model: str | None = None

    @property
    def truncated(self) -> bool:
        """The server stopped the reply at the token limit (``finish_reason == "length"``)."""
        return self.finish_reason == "length"


def split_reasoning(text: str) -> tuple[str, str]:
    """Split content into ``(reasoning, answer)``.

    ``"<think>a</think> b"`` -> ``("a", "b")``; ``"a</think> b"`` (opening tag in the template)
    -> ``("a", "b")``; ``"<think>a"`` (cut off while thinking) -> ``("a", "")``; several blocks:
    the answer is what follows the last one. Text without tags is all answer.
    """
    if _HARMONY_ANY in text:
        head, sep, tail = text.rpartition(_HARMONY_FINAL)
        if sep:
            return _harmony_clean(head), tail.replace("<|return|>", "").replace(
                "<|end|>", ""
            ).strip()
        return _harmony_clean(text), ""
    closes = list(_CLOSE.finditer(text))
    if closes:
        last = closes[-1]
        head, answer = text[: last.start()], text[last.end() :]
        return _strip_tags(head), answer.strip()
    opened = _OPEN.search(text)
    if opened:  # never closed: the reply ended inside the reasoning
        return _strip_tags(text[opened.end() :]), text[: opened.start()].strip()
    return "", text.strip()


def _strip_tags(text: str) -> str:
    return _CLOSE.sub("\n", _OPEN.sub("\n", text)).strip()


def _harmony_clean(text: str) -> str:
    return re.sub(r"<\|[a-z_]+\|>", " ", text).strip()


def _part_text(part: Any) -> tuple[str, str]:
    """``(text, reasoning)`` of one content part."""
    if isinstance(part, str):
        return part, ""
    if not isinstance(part, Mapping):
        return "", ""
    kind = str(part.get("type") or "text")
    if kind in REASONING_PARTS:
        for key in ("thinking", "reasoning", "text", "content"):
            if isinstance(part.get(key), str):
                return "", part[key]
        summary = part.get("summary")  # OpenAI reasoning items: a list of summary texts
        if isinstance(summary, list):
            return "", "\n".join(_part_text(s)[0] for s in summary)
        return "", ""
    for key in ("text", "content", "refusal"):
        if isinstance(part.get(key), str):
            return part[key], ""
    return "", ""  # images, audio, tool calls: no text


def content_text(content: Any) -> tuple[str, str]:
    """``(text, reasoning)`` of a message's ``content``: a string, null, one part or a list of parts.

    Raises
    ------
    MalformedReply
        For any other type (a number, ...).
    """
    if content is None:
        return "", ""
    if isinstance(content, str):
        return content, ""
    if isinstance(content, Mapping):
        content = [content]
    if isinstance(content, list):
        texts, thoughts = zip(*(_part_text(p) for p in content)) if content else ((), ())
        return "".join(texts), "\n\n".join(t for t in thoughts if t)
    raise MalformedReply(f"message content is a {type(content).__name__}, not text")


def read_completion(body: Any, *, streamed: bool = False) -> Completion:
    """Read a decoded chat-completion body.

    Raises
    ------
    MalformedReply
        The body has no first choice with a message (or legacy ``text``), or carries an ``error``.
    """
    if not isinstance(body, Mapping):
        raise MalformedReply(f"the body is a JSON {type(body).__name__}, not an object")
    if "choices" not in body and isinstance(body.get("error"), (Mapping, str)):
        raise MalformedReply(f"the body is an error: {error_message(body)}")
    choices = body.get("choices")
    if not isinstance(choices, list) or not choices or not isinstance(choices[0], Mapping):
        raise MalformedReply("the body has no choices")
    choice = choices[0]
    message = choice.get("message")
    if isinstance(message, Mapping):
        text, part_reasoning = content_text(message.get("content"))
        if not text and isinstance(message.get("refusal"), str):
            text = message["refusal"]
        fields = [
            message[k] for k in REASONING_FIELDS if isinstance(message.get(k), str) and message[k]
        ]
    elif isinstance(choice.get("text"), str):  # legacy completions shape, from some gateways
        text, part_reasoning, fields = choice["text"], "", []
    else:
        raise MalformedReply("the first choice has no message")
    inline, answer = split_reasoning(text)
    reasoning = "\n\n".join(r for r in (*fields, part_reasoning, inline) if r)
    finish = choice.get("finish_reason")
    usage = body.get("usage")
    return Completion(
        content=text,
        reasoning=reasoning,
        answer=answer,
        finish_reason=finish if isinstance(finish, str) else None,
        usage=usage if isinstance(usage, Mapping) else None,
        streamed=streamed,
        model=body["model"] if isinstance(body.get("model"), str) and body["model"] else None,
    )


def looks_like_sse(content_type: str, text: str) -> bool:
    """Whether a body is a server-sent-event stream (by its type, or by its first line)."""
    if content_type.split(";")[0].strip().lower() == "text/event-stream":
        return True
    for line in text[:4096].splitlines():
        if line.strip() and not line.startswith(":"):  # skip blank lines and SSE comments
            return line.startswith(("data:", "event:"))
    return False


def assemble_sse(text: str) -> dict[str, Any]:
    """One chat-completion body from the ``data:`` events of a streamed reply.

    Content, reasoning fields and text parts of every chunk's ``delta`` (or ``message``) are
    concatenated; the last ``finish_reason`` and ``usage`` seen win.

    Raises
    ------
    MalformedReply
        No event carried a choice, an event is not JSON, or an event is an error.
    """
    content: list[str] = []
    reasoning: dict[str, list[str]] = {k: [] for k in REASONING_FIELDS}
    finish: str | None = None
    usage: Any = None
    model: Any = None
    seen = False
    for line in text.splitlines():
        if not line.startswith("data:"):
            continue  # comments (": ping"), event names, ids, blank separators
        data = line[5:].strip()
        if not data or data == "[DONE]":
            continue
        try:
            chunk = json.loads(data)
        except ValueError:
            raise MalformedReply("a streamed event is not JSON") from None
        if not isinstance(chunk, Mapping):
            continue
        if "choices" not in chunk and chunk.get("error"):
            raise MalformedReply(f"the stream carried an error: {error_message(chunk)}")
        if isinstance(chunk.get("usage"), Mapping):
            usage = chunk["usage"]
        if isinstance(chunk.get("model"), str):
            model = chunk["model"]
        for choice in chunk.get("choices") or []:
            if not isinstance(choice, Mapping) or choice.get("index", 0) != 0:
                continue
            seen = True
            delta = choice.get("delta") or choice.get("message") or {}
            if isinstance(delta, Mapping):
                piece, part_reasoning = content_text(delta.get("content"))
                content.append(piece)
                if part_reasoning:
                    reasoning["thinking"].append(part_reasoning)
                for k in REASONING_FIELDS:
                    if isinstance(delta.get(k), str):
                        reasoning[k].append(delta[k])
            if isinstance(choice.get("finish_reason"), str):
                finish = choice["finish_reason"]
    if not seen:
        raise MalformedReply("the stream carried no choices")
    message: dict[str, Any] = {"role": "assistant", "content": "".join(content)}
    message.update({k: "".join(v) for k, v in reasoning.items() if v})
    return {
        "choices": [{"index": 0, "message": message, "finish_reason": finish}],
        "usage": usage,
        "model": model,
    }


def error_message(body: Any) -> str:
    """The server's own error text from an error body (OpenAI, FastAPI/pydantic, plain shapes)."""
    if isinstance(body, Mapping):
        err = body.get("error")
        if isinstance(err, Mapping):
            msg = err.get("message") or err.get("msg") or err.get("type")
            if msg:
                return _one_line(str(msg))
        elif isinstance(err, str) and err:
            return _one_line(err)
        detail = body.get("detail")
        if isinstance(detail, list):  # pydantic: [{"loc": [...], "msg": ...}]
            items = []
            for d in detail:
                if isinstance(d, Mapping):
                    loc = ".".join(str(x) for x in d.get("loc", ()) if x != "body")
                    items.append(f"{loc}: {d.get('msg', '')}" if loc else str(d.get("msg", "")))
            if items:
                return _one_line("; ".join(items))
        if isinstance(detail, str) and detail:
            return _one_line(detail)
        if isinstance(body.get("message"), str) and body["message"]:
            return _one_line(body["message"])
    return _one_line(json.dumps(body)) if not isinstance(body, str) else _one_line(body)


def _one_line(text: str, limit: int = 300) -> str:
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 1] + "…"


def decode_body(raw: bytes, content_encoding: str) -> bytes:
    """The body ``raw`` undone from its ``Content-Encoding`` (gzip, deflate, identity).

    A header that lies (a plain JSON body labelled ``gzip`` by a misconfigured proxy) or names
    an encoding we did not ask for leaves the body as it came: whether it is a completion is then
    decided by reading it, never by a decoding traceback.
    """
    out = raw
    for name in reversed([t.strip().lower() for t in content_encoding.split(",") if t.strip()]):
        try:
            if name in ("gzip", "x-gzip"):
                out = zlib.decompress(out, 16 + zlib.MAX_WBITS)
            elif name == "deflate":
                try:
                    out = zlib.decompress(out)
                except zlib.error:  # raw deflate, as some servers send it
                    out = zlib.decompress(out, -zlib.MAX_WBITS)
            elif name != "identity":
                return raw
        except zlib.error:
            return raw
    return out


def parse_retry_after(headers: Mapping[str, str], now: float | None = None) -> float | None:
    """Seconds to wait from ``retry-after-ms``, or ``Retry-After`` (seconds or an HTTP date)."""
    ms = headers.get("retry-after-ms")
    if ms:
        try:
            return max(0.0, float(ms) / 1000.0)
        except ValueError:
            pass
    value = headers.get("retry-after")
    if not value:
        return None
    try:
        return max(0.0, float(value))
    except ValueError:
        pass
    try:
        when = email.utils.parsedate_to_datetime(value)
    except (TypeError, ValueError, IndexError):
        return None
    now = time.time() if now is None else now
    return max(0.0, when.timestamp() - now)
