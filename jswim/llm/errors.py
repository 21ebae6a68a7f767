"""Errors of the LLM layer; every message is one line and never contains the API key."""

from __future__ import annotations


class LLMError(RuntimeError):
    """Base class of LLM-layer failures."""


class LLMServerError(LLMError):
    """The server could not be reached or kept failing (network, timeouts, 429, 5xx)."""


class LLMRequestError(LLMError):
    """The server rejected the request (4xx other than 408/409/429): retrying will not help."""

    def __init__(self, message: str, status: int) -> None:
        super().__init__(message)
        self.status = status


class LLMResponseError(LLMError):
    """The server answered, but not with a usable chat completion (bad JSON, no choices)."""


class LocalModelError(LLMError):
    """The embedded local model cannot be started (missing package or model file)."""
