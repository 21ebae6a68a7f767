"""LLM I/O: an async OpenAI-compatible chat client, its cache and accounting, and the embedded
local model. No JAX here (see DESIGN.md)."""

from jswim._exports import lazy_exports

#: Every name of the package and its module, loaded on first use: ``jswim.llm.urls`` (read by the
#: command line's parser) does not load httpx, the client or the embedded server.
_HOMES = {
    "Backend": ".backend",
    "check_server": ".backend",
    "ChatResult": ".result",
    "ClientSettings": ".settings",
    "LLMClient": ".client",
    "LocalServer": ".local",
    "default_model_path": ".local",
    "DEFAULT_PRICES": ".usage",
    "PriceTable": ".usage",
    "Usage": ".usage",
    "UsageTotals": ".usage",
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

__getattr__, __dir__ = lazy_exports(__name__, _HOMES)
