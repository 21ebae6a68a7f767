"""Server addresses: the shapes users write, made into one API root.

`normalize_base_url` accepts the common shapes users copy from server docs and logs (no
path, a pasted ``/v1/chat/completions``, no scheme) and returns the API root the client appends
``/chat/completions`` to; docs/servers.md (*Base URL*) lists them.
"""

from __future__ import annotations

import ipaddress
from urllib.parse import urlsplit, urlunsplit

from jswim.errors import ConfigError
from jswim.llm.credentials import redact_url, register_url

#: Path endings that name an endpoint rather than the API root (removed).
ENDPOINT_SUFFIXES = ("/chat/completions", "/completions")


def safe_url(url: str) -> str:
    """``url`` without user info, query or fragment (safe to print)."""
    parts = urlsplit(url)
    host = parts.hostname or ""
    if ":" in host:  # IPv6 literal
        host = f"[{host}]"
    if parts.port:
        host = f"{host}:{parts.port}"
    return urlunsplit((parts.scheme, host, parts.path.rstrip("/"), "", ""))


def is_loopback(url: str) -> bool:
    """Whether ``url`` points at this machine."""
    host = urlsplit(url).hostname or ""
    try:
        return host == "localhost" or ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def is_local_host(url: str) -> bool:
    """Whether ``url`` points at this machine or a LAN host (private or link-local address, a
    single-label name, ``.local``/``.lan``/``.internal``): servers no cloud provider bills for."""
    return _is_local_name((urlsplit(url).hostname or "").lower())


def _is_local_name(host: str) -> bool:
    """A host a scheme-less URL most likely reaches over plain http (this machine, a LAN box)."""
    if (
        host in ("localhost", "")
        or host.endswith((".local", ".lan", ".internal"))
        or "." not in host
    ):
        return True
    try:
        ip = ipaddress.ip_address(host)
    except ValueError:
        return False
    return ip.is_loopback or ip.is_private or ip.is_link_local


def normalize_base_url(url: str) -> str:
    """The API root for a base URL as a user wrote it (docs/servers.md).

    Raises
    ------
    ConfigError
        Empty, not http(s), or without a host; the message says what to write.
    """
    text = (url or "").strip()
    register_url(text)  # a password in the URL is masked in every message from now on
    example = "write e.g. http://localhost:8080/v1 or https://api.openai.com/v1"
    if not text:
        raise ConfigError(f"the server base URL is empty; {example}")
    try:
        if "://" not in text:
            host = urlsplit("//" + text).hostname or ""
            text = ("http://" if _is_local_name(host) else "https://") + text
        parts = urlsplit(text)
    except ValueError as exc:  # e.g. "Invalid IPv6 URL" for http://[::1/v1 (the URL is not echoed: it may hold a password)
        raise ConfigError(f"the server base URL is not a URL ({exc}); {example}") from None
    if parts.scheme.lower() not in ("http", "https"):
        raise ConfigError(f"the server base URL {redact_url(text)!r} is not http(s); {example}")
    try:
        parts.port  # noqa: B018 - raises on a bad port
    except ValueError:
        raise ConfigError(
            f"the server base URL {redact_url(text)!r} has a bad port; {example}"
        ) from None
    if not parts.hostname:
        raise ConfigError(f"the server base URL {redact_url(text)!r} has no host; {example}")
    path = parts.path.rstrip("/")  # the first endpoint suffix cut off; no path at all means /v1
    path = next((path[: -len(s)] for s in ENDPOINT_SUFFIXES if path.endswith(s)), path) or "/v1"
    return urlunsplit((parts.scheme.lower(), parts.netloc, path, parts.query, ""))


def endpoint(base_url: str, name: str = "chat/completions") -> str:
    """``base_url`` + ``/name``, keeping a query string (``?api-version=...``) at the end."""
    parts = urlsplit(base_url)
    return urlunsplit(
        (parts.scheme, parts.netloc, parts.path.rstrip("/") + "/" + name, parts.query, "")
    )
