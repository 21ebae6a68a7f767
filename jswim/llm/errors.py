"""The LLM layer's errors; they live in :mod:`jswim.errors` under the one root ``JswimError``.

Kept as a module so ``from jswim.llm.errors import LLMServerError`` goes on working.
"""

from jswim.errors import (
    LLMError,
    LLMRequestError,
    LLMResponseError,
    LLMServerError,
    LLMSetupError,
    LLMTimeoutError,
    LocalModelError,
)

__all__ = ["LLMError", "LLMRequestError", "LLMResponseError", "LLMServerError", "LLMSetupError", "LLMTimeoutError",
           "LocalModelError"]
