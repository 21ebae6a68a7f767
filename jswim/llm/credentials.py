"""API keys and URL credentials: read once, checked, and never shown in any form.

A key is read from the environment variable the user names (``--api-key-env``) and checked before
any request; every secret the process handles is registered here, and `scrub` removes it
from any text about to be printed or raised, in each form a library may have written it
(docs/studies.md, *Secrets*).
"""

from __future__ import annotations

import base64
import json
import os
import re
from typing import Any
from urllib.parse import quote, quote_plus, unquote, urlsplit, urlunsplit

from jswim.errors import ConfigError

#: What replaces a secret in text.
MASK = "***"

#: Secrets shorter than this are not searched for in text (they would mask ordinary words);
#: a key or password that short is no protection anyway.
MIN_SECRET = 4

_secrets: set[str] = set()
_forms: list[str] = []  # every form of every secret, longest first


def forms(secret: str) -> set[str]:
    """The ways ``secret`` may appear in text: raw, escaped, JSON, percent-encoded, base64, and
    the encodings of its base64 (a ``Basic`` header percent-encoded into an error body)."""
    out = {secret, secret.strip()}
    for s in list(out):
        b64 = base64.b64encode(s.encode("utf-8", "replace")).decode()
        url64 = base64.urlsafe_b64encode(s.encode("utf-8", "replace")).decode()
        out |= {
            repr(s)[1:-1],
            ascii(s)[1:-1],
            json.dumps(s)[1:-1],
            json.dumps(s, ensure_ascii=False)[1:-1],
            repr(s.encode("utf-8", "surrogateescape"))[2:-1],
            s.encode("unicode_escape").decode("ascii"),
            quote(s, safe=""),
            quote_plus(s, safe=""),
            quote(s),
            b64,
            url64,
            quote(b64, safe=""),
            quote(url64, safe=""),
        }
        # Unpadded base64 matches inside a padded echo whatever its padding was encoded as.
        out |= {b64.rstrip("="), url64.rstrip("=")}
    return {f for f in out if len(f) >= MIN_SECRET}


def register(secret: str | None) -> None:
    """Remember ``secret`` so that `scrub` masks it from now on (in this process)."""
    if not secret or secret in _secrets:
        return
    _secrets.add(secret)
    _forms[:] = sorted(set(_forms) | forms(secret), key=len, reverse=True)


#: The masks providers print inside a key's echo: a run of ``*``, ``.``, ``•``, ``x`` or an
#: ellipsis between a visible head and tail (``sk-proj-****789XyZ``, ``sk-...XyZ``).
_MASK_RUN = re.compile(r"\*{2,}|\.{3,}|…|x{4,}|•{2,}")

#: The characters of a key's visible head and tail, and how far each is looked for.
_KEY_CHARS = frozenset("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_-")
_ECHO_REACH = 64

#: The shortest visible head or tail of a masked echo that is taken as the secret's own.
MIN_ECHO = 3


def _masked_echoes(text: str) -> str:
    """``text`` with each masked echo that shows a registered secret's head or tail replaced
    whole (linear in ``text``: heads and tails are read at most `_ECHO_REACH` away)."""
    keys = [k for k in _secrets if len(k) >= 8]
    if not keys:
        return text
    out, last = [], 0
    for m in _MASK_RUN.finditer(text):
        a = m.start()
        while a > max(last, m.start() - _ECHO_REACH) and text[a - 1] in _KEY_CHARS:
            a -= 1
        b = m.end()
        while b < min(len(text), m.end() + _ECHO_REACH) and text[b] in _KEY_CHARS:
            b += 1
        head, tail = text[a : m.start()], text[m.end() : b]
        if any(
            (len(head) >= MIN_ECHO and k.startswith(head))
            or (len(tail) >= MIN_ECHO and k.endswith(tail))
            for k in keys
        ):
            out += [text[last:a], MASK]
            last = b
    return "".join(out) + text[last:] if out else text


def scrub(text: str) -> str:
    """``text`` with every registered secret, in every form of `forms`, replaced by ``***``;
    a masked echo that still shows a secret's head or tail (``sk-proj-****789XyZ``) goes whole."""
    if not _forms or not text:
        return text
    for f in _forms:
        if f in text:
            text = text.replace(f, MASK)
    return _masked_echoes(text)


#: Request-field names whose text values are credentials (OpenAI's ``user`` is an end-user id,
#: often set to a key or an account name).
_CREDENTIAL_NAME = re.compile(
    r"(^|[_\-.])(api_?key|key|token|secret|passw(or)?d|auth|authorization|credentials?|user|"
    r"session|cookie|signature|bearer)($|[_\-.])",
    re.I,
)


def looks_like_key(text: str) -> bool:
    """Whether ``text`` has the shape of a key: 20 or more characters, no space, letters and
    digits mixed (``sk-...``, a JWT, a hex token)."""
    return (
        len(text) >= 20
        and not any(c.isspace() for c in text)
        and any(c.isdigit() for c in text)
        and any(c.isalpha() for c in text)
    )


def mask_fields(fields: Any, name: str = "") -> Any:
    """Request fields as they may be written or shown: a text value under a credential's name
    (``user``, ``api_key``, ``token``...) or shaped like a key is ``***`` (and registered for
    `scrub`); numbers, flags and ordinary text stay as given."""
    if isinstance(fields, dict):
        return {k: mask_fields(v, str(k)) for k, v in fields.items()}
    if isinstance(fields, (list, tuple)):
        return [mask_fields(v, name) for v in fields]
    if isinstance(fields, str) and (_CREDENTIAL_NAME.search(name) or looks_like_key(fields)):
        register(fields)
        return MASK
    return fields


def _bad_character(value: str) -> str | None:
    """What in ``value`` no header value may carry, said without showing the value."""
    names = {
        "\r": "a carriage return (\\r)",
        "\n": "a line feed (\\n)",
        "\t": "a tab",
        " ": "a space",
        "\x00": "a NUL byte",
    }
    for i, ch in enumerate(value):
        if "\x21" <= ch <= "\x7e":
            continue
        what = names.get(ch) or (
            f"a control character (U+{ord(ch):04X})"
            if ord(ch) < 0x20 or ord(ch) == 0x7F
            else f"a non-ASCII character (U+{ord(ch):04X})"
        )
        where = (
            "at its end"
            if i == len(value) - 1
            else "at its start"
            if i == 0
            else f"at position {i + 1}"
        )
        return f"{what} {where}"
    return None


def read_api_key(env_name: str) -> str | None:
    """The key in ``$env_name`` (``None`` when unset or empty), registered for `scrub`.

    Raises
    ------
    ConfigError
        When the value holds a character an HTTP header cannot carry; the message names the
        variable and the character, never the value.
    """
    value = os.environ.get(env_name) if env_name else None  # "": no variable named, no key sent
    if not value:
        return None
    register(value)
    bad = _bad_character(value)
    if bad:
        hint = " (a key pasted from a Windows file?)" if "\r" in value else ""
        raise ConfigError(
            f"the API key in ${env_name} has {bad}{hint}, which no HTTP header can carry; "
            f"set ${env_name} again without it (the value is not shown)"
        )
    return value


def register_url(url: str | None) -> None:
    """Register the user and password of ``url`` (``http://user:pw@host/v1``), if any."""
    if not url or "@" not in url:
        return
    try:
        parts = urlsplit(url if "://" in url else "//" + url)
        user, password = parts.username, parts.password
    except ValueError:
        return
    for s in (password, user):
        if s:
            register(s)
            register(unquote(s))
    if user and password:
        register(f"{unquote(user)}:{unquote(password)}")


def split_userinfo(url: str) -> tuple[str, str | None]:
    """``url`` without its user info, and the ``Authorization`` value of that user info (or ``None``).

    ``http://user:pw@host/v1`` -> ``("http://host/v1", "Basic dXNlcjpwdw==")``: the credentials
    travel in a header the client controls, not in a URL that libraries print.
    """
    parts = urlsplit(url)
    if "@" not in parts.netloc:
        return url, None
    userinfo, host = parts.netloc.rsplit("@", 1)
    user, _, password = userinfo.partition(":")
    pair = f"{unquote(user)}:{unquote(password)}"
    register_url(url)
    return urlunsplit(
        (parts.scheme, host, parts.path, parts.query, parts.fragment)
    ), "Basic " + base64.b64encode(pair.encode("utf-8")).decode("ascii")


def redact_url(url: str) -> str:
    """``url`` with its user info shown as ``***@`` (for messages about the URL as written)."""
    text = str(url)
    try:
        parts = urlsplit(text if "://" in text else "//" + text)
        netloc = parts.netloc
    except ValueError:
        return scrub(text)
    if "@" not in netloc:
        return scrub(text)
    netloc = MASK + "@" + netloc.rsplit("@", 1)[1]
    if "://" not in text:
        return scrub(urlunsplit(("", netloc, parts.path, parts.query, parts.fragment))[2:])
    return scrub(urlunsplit((parts.scheme, netloc, parts.path, parts.query, parts.fragment)))
