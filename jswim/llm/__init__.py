"""LLM I/O: an async OpenAI-compatible chat client, its cache and accounting, and the embedded
local model. No JAX here (see DESIGN.md)."""

import importlib
from typing import Any

#: Every name of the package and its module, loaded on first use: ``jswim.llm.urls`` (read by the
#: command line's parser) does not load httpx, the client or the embedded server.
_HOMES = {
    "Backend": "backend",
    "check_server": "backend",
    "ChatResult": "result",
    "ClientSettings": "settings",
    "LLMClient": "client",
    "LocalServer": "local",
    "default_model_path": "local",
    "DEFAULT_PRICES": "usage",
    "PriceTable": "usage",
    "Usage": "usage",
    "UsageTotals": "usage",
    **dict.fromkeys(
        (
            "LLMError",
            "LLMRequestError",
            "LLMResponseError",
            "LLMServerError",
            "LLMSetupError",
            "LLMTimeoutError",
            "LocalModelError",
        ),
        "jswim.errors",
    ),
}

__all__ = sorted(_HOMES)


def __getattr__(name: str) -> Any:
    if name not in _HOMES:
        raise AttributeError(f"module 'jswim.llm' has no attribute {name!r}")
    home = _HOMES[name]
    return getattr(importlib.import_module(home if "." in home else f"jswim.llm.{home}"), name)
