"""Preflight: what serves the base URL, which models it lists, its slots and sampling defaults.

Before any run, `probe` asks the server two cheap questions (``GET /v1/models`` and, where it
may be llama.cpp, ``GET /props``) and decides its *family* (`FAMILIES`: which sampling knobs
it has, which constrained-decoding forms it takes, how many requests it serves at once); how each
family is told is tabled in docs/servers.md. ``--server-family`` overrides the guess. A 401/403 on
``/v1/models`` stops the study before any baseline runs, in one line that says whether the key's
environment variable is unset, empty or refused.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any
from collections.abc import Mapping
from urllib.parse import urlsplit, urlunsplit

import httpx

from jswim.errors import ConfigError, LLMSetupError
from jswim.llm.credentials import read_api_key
from jswim.llm.http_errors import unreachable
from jswim.llm.rejection import key_hint, server_text
from jswim.llm.urls import endpoint, is_loopback, normalize_base_url, safe_url

#: Server families jswim tells apart (docs/servers.md).
FAMILIES = ("llamacpp", "llama-cpp-python", "vllm", "ollama", "openai", "generic")

#: ``/v1/models`` ``owned_by`` values that name a family.
OWNED_BY = {
    "llamacpp": "llamacpp",
    "me": "llama-cpp-python",
    "vllm": "vllm",
    "library": "ollama",
    "ollama": "ollama",
    "openai": "openai",
    "system": "openai",
    "openai-internal": "openai",
}

#: Requests in flight for a server that serves one at a time: llama-cpp-python's server handles
#: one request per model (a lock around the model), so more only queue there.
SINGLE_SLOT = {"llama-cpp-python": 1}


def check_family(name: str | None) -> str | None:
    """``name`` if it is a known family (or ``None``), else [`ConfigError`][jswim.errors.ConfigError]."""
    if name is not None and name not in FAMILIES:
        raise ConfigError(f"--server-family must be one of {', '.join(FAMILIES)}, got {name!r}")
    return name


@dataclass(frozen=True)
class ServerInfo:
    """What the preflight learned about a server.

    Attributes
    ----------
    family : str
        One of `FAMILIES`.
    detected_by : str
        How the family was decided, in words (recorded with the run).
    models : tuple of str or None
        The ids ``/v1/models`` lists (``None``: it did not answer with a list).
    total_slots : int or None
        Requests the server decodes at once, where it says (llama.cpp's ``/props``).
    settings : dict
        The server's own sampling defaults where it reports them (llama.cpp's ``/props``
        ``default_generation_settings``; scalar values only).
    warnings : tuple of str
        What the user should know (a model the server does not list), one line each.
    """

    family: str = "generic"
    detected_by: str = "not probed"
    models: tuple[str, ...] | None = None
    total_slots: int | None = None
    settings: dict[str, Any] = field(default_factory=dict)
    warnings: tuple[str, ...] = ()

    @property
    def slots(self) -> int | None:
        """Requests the server serves at once: reported, or known for its family, else ``None``."""
        return self.total_slots or SINGLE_SLOT.get(self.family)

    def metadata(self) -> dict[str, Any]:
        """A JSON-able record for the study's metadata."""
        known = {
            "models": None if self.models is None else list(self.models[:20]),
            "total_slots": self.total_slots,
            "server_sampling_defaults": dict(self.settings) or None,
            "warnings": list(self.warnings) or None,
        }
        return {
            "family": self.family,
            "detected_by": self.detected_by,
            **{k: v for k, v in known.items() if v is not None},
        }


def server_root(base_url: str) -> str:
    """The server's root URL: the API root without a trailing ``/v1`` (where ``/props`` lives)."""
    parts = urlsplit(base_url)
    path = parts.path.rstrip("/")
    if path.endswith("/v1"):
        path = path[:-3]
    return urlunsplit((parts.scheme, parts.netloc, path, "", ""))


def generation_settings(props: Mapping[str, Any]) -> dict[str, Any]:
    """The scalar sampling defaults of a llama.cpp ``/props`` answer (both the older flat
    ``default_generation_settings`` and the newer one with a ``params`` object)."""
    dgs = props.get("default_generation_settings")
    if not isinstance(dgs, Mapping):
        return {}
    params = dgs.get("params") if isinstance(dgs.get("params"), Mapping) else dgs
    return {
        k: v
        for k, v in sorted(params.items())
        if isinstance(v, (int, float, bool))
        or (isinstance(v, str) and len(v) <= 40 and k != "grammar")
    }


def _get(client: httpx.Client, url: str) -> httpx.Response | None:
    """``GET url``; ``None`` when it does not answer JSON-ish (only reachability errors raise)."""
    try:
        return client.get(url)
    except httpx.TimeoutException:
        return None


def _json(resp: httpx.Response | None) -> Any:
    if resp is None or resp.status_code != 200:
        return None
    try:
        return resp.json()
    except ValueError:
        return None


def probe(
    base_url: str,
    *,
    api_key_env: str = "OPENAI_API_KEY",
    timeout_s: float = 5.0,
    family: str | None = None,
    model: str | None = None,
    strict_model: bool = False,
    local: bool = False,
) -> ServerInfo:
    """Ask the server at ``base_url`` what it is (docs/servers.md).

    Parameters
    ----------
    base_url : str
        The API root.
    api_key_env : str
        The environment variable of the key (sent as ``Authorization``, as the requests are).
    timeout_s : float
        Longest wait for each answer.
    family : str, optional
        Forced family (``--server-family``): not guessed.
    model : str, optional
        The model requests will name, checked against ``/v1/models``.
    strict_model : bool
        A model the server does not list is an error, not a warning.
    local : bool
        The embedded server (its family is llama.cpp's; its key variable is internal).

    Raises
    ------
    LLMServerError
        Nothing answers at ``base_url``.
    LLMTimeoutError
        The server took longer than ``timeout_s`` to answer (still loading its model).
    LLMSetupError
        HTTP 401/403 (the message says whether ``$api_key_env`` is unset, empty or refused), or
        a model the server does not list with ``strict_model``.
    """
    check_family(family)
    base_url = normalize_base_url(base_url)
    where = safe_url(base_url)
    key = read_api_key(api_key_env)
    headers = {"Authorization": f"Bearer {key}"} if key else {}
    models_url = endpoint(base_url, "models")
    with httpx.Client(
        timeout=timeout_s, headers=headers, trust_env=not is_loopback(base_url)
    ) as client:
        try:
            listed = client.get(models_url)
        except httpx.HTTPError as exc:
            raise unreachable(exc, where, safe_url(models_url), timeout_s) from None
        if listed.status_code in (401, 403):
            said = server_text(listed)
            said = f"HTTP {listed.status_code}: {said}" if said else f"HTTP {listed.status_code}"
            raise LLMSetupError(
                f"{where} refused the preflight request GET /v1/models ({said}); "
                f"{key_hint(api_key_env)}",
                listed.status_code,
                said,
            )
        body = _json(listed)
        entries = body.get("data") if isinstance(body, Mapping) else None
        entries = (
            [e for e in entries if isinstance(e, Mapping)] if isinstance(entries, list) else None
        )
        models = None
        if entries is not None:  # ids, and llama.cpp's aliases
            names = [e.get("id") for e in entries] + [
                a for e in entries if isinstance(e.get("aliases"), list) for a in e["aliases"]
            ]
            models = tuple(dict.fromkeys(str(n) for n in names if n is not None))
        props: Any = None
        if family in (None, "llamacpp"):
            props = _json(_get(client, server_root(base_url) + "/props"))
    is_props = isinstance(props, Mapping) and (
        "default_generation_settings" in props or "total_slots" in props
    )
    owned = {str(e.get("owned_by")) for e in entries or () if e.get("owned_by") is not None}
    if family is not None:
        how = "the embedded llama.cpp server" if local else "forced (--server-family)"
    elif is_props:
        family, how = "llamacpp", "GET /props answered (llama.cpp's server)"
    elif tells := sorted({OWNED_BY[o] for o in owned if o in OWNED_BY}):
        family = tells[0]
        how = f"/v1/models owned_by {', '.join(repr(o) for o in sorted(owned))}"
    elif (urlsplit(base_url).hostname or "").lower() == "api.openai.com":
        family, how = "openai", "host api.openai.com"
    else:
        family, how = "generic", "no tell (no /props, no known owned_by)"
    slots = props.get("total_slots") if is_props else None
    warnings: list[str] = []
    if model is not None and models is not None and model not in models and not local:
        shown = (
            ", ".join(repr(m) for m in models[:5]) + (", ..." if len(models) > 5 else "")
            or "nothing"
        )
        msg = (
            f"{where} does not list the model {model!r} (GET /v1/models lists {shown}); a server that "
            "accepts any name runs its own model under it: check --model"
        )
        if strict_model:
            raise LLMSetupError(msg + " (--strict-model)", 404, msg)
        warnings.append(msg + "; --strict-model makes this an error")
    return ServerInfo(
        family=family,
        detected_by=how,
        models=models,
        total_slots=slots if isinstance(slots, int) and slots > 0 else None,
        settings=generation_settings(props) if is_props else {},
        warnings=tuple(warnings),
    )
