"""LLM I/O: an async OpenAI-compatible chat client, its cache and accounting, and the embedded
local model. No JAX here (see DESIGN.md)."""

from jswim.llm.backend import Backend, check_server
from jswim.llm.client import ChatResult, ClientSettings, LLMClient
from jswim.llm.errors import (
    LLMError,
    LLMRequestError,
    LLMResponseError,
    LLMServerError,
    LLMSetupError,
    LLMTimeoutError,
    LocalModelError,
)
from jswim.llm.local import LocalServer, default_model_path
from jswim.llm.usage import DEFAULT_PRICES, PriceTable, Usage, UsageTotals

__all__ = [
    "Backend",
    "ChatResult",
    "ClientSettings",
    "DEFAULT_PRICES",
    "LLMClient",
    "LLMError",
    "LLMRequestError",
    "LLMResponseError",
    "LLMServerError",
    "LLMSetupError",
    "LLMTimeoutError",
    "LocalModelError",
    "LocalServer",
    "PriceTable",
    "Usage",
    "UsageTotals",
    "check_server",
    "default_model_path",
]
