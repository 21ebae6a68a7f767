"""Reasoning models: what they must be sent, learned from the server's own rejections.

Reasoning models think before they answer, so the paper's 10-token reply limit cuts them off, and
OpenAI's refuse ``max_tokens`` ("Use 'max_completion_tokens' instead") and any ``temperature`` but
their default ("Only the default (1) value is supported"). A client's `ReasoningState`
starts from the ``reasoning`` setting: ``"auto"`` (default; each such 400 switches once and the
refused request is sent again as amended, a 400 is not billed), ``"on"`` (the budget from the first
request) or ``"off"`` (never switch). docs/servers.md (*Reasoning models need no flags*) says what
each sends, how reasoning tokens are read and priced, and where each switch is recorded.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

from jswim.errors import ConfigError

#: Reply budget of a reasoning model when ``--max-tokens`` is not given: room for a few hundred
#: to a few thousand tokens of thinking before the answer (OpenAI suggests reserving at least
#: 25,000 for hard problems; this task's answer is one pair, and 4096 kept every call of the
#: reasoning fake server and of the measured runs below its limit).
REASONING_MAX_TOKENS = 4096

#: Values of the ``reasoning`` setting (``--reasoning``).
MODES = ("auto", "on", "off")

#: Values of ``reasoning_effort`` that OpenAI's API accepts (sent only when asked for).
EFFORTS = ("minimal", "low", "medium", "high")

_WANTS_COMPLETION_TOKENS = re.compile(r"max_completion_tokens", re.I)
_ONLY_TEMPERATURE = re.compile(
    r"temperature.*?only (?:the default )?\(?\s*(\d+(?:\.\d+)?)\s*\)?(?: value)? (?:is )?supported",
    re.I | re.S,
)


#: Model names of OpenAI's reasoning models (o1, o3, o4-mini, gpt-5 and their variants): their
#: API refuses ``max_tokens``, so ``--reasoning auto`` switches to the budget after the first 400,
#: and the dry run prices them with it. Matched on the name after any ``provider/`` prefix.
OPENAI_REASONING = re.compile(r"^(o[134](-|$)|gpt-5(?!-chat)(-|$|\.))", re.I)

#: Names of open reasoning models (behind vLLM or llama.cpp, which never refuse ``max_tokens``):
#: under ``--reasoning auto`` they are sent the paper's ``max_tokens`` and cut while thinking,
#: so the dry run says to give ``--reasoning on``.
OPEN_REASONING = re.compile(
    r"(deepseek-r1|deepseek-reasoner|qwq|qwen3|thinking|reasoner|-r1\b|magistral)", re.I
)

#: The dry run's estimate of the reasoning tokens per call, as a share of the budget sent, per
#: ``reasoning_effort`` (None: the provider's default, medium). An assumption, not a measurement
#: (no reasoning model was reachable where this was written); the worst case, every call using its
#: whole budget, is printed beside it.
ESTIMATE_SHARE = {"minimal": 1 / 16, "low": 1 / 8, "medium": 1 / 4, None: 1 / 4, "high": 1 / 2}


def _bare(model: str) -> str:
    return str(model or "").rsplit("/", 1)[-1]


def dry_run_budget(model: str, mode: str, budget: int) -> int | None:
    """The reply budget a study's calls will carry for reasoning (``None``: the plain ``max_tokens``).

    ``on``: the budget from the first call. ``auto``: the budget for OpenAI's reasoning models by name
    (`OPENAI_REASONING`; their first 400 switches the client). ``off``: never.
    """
    if mode == "on" or (mode == "auto" and OPENAI_REASONING.search(_bare(model))):
        return budget
    return None


def dry_run_warning(model: str, mode: str) -> str | None:
    """A dry run's warning for an open reasoning model that ``auto`` would cut while thinking."""
    if (
        mode == "auto"
        and not OPENAI_REASONING.search(_bare(model))
        and OPEN_REASONING.search(_bare(model))
    ):
        return (
            f"{model} looks like a reasoning model: --reasoning auto sends it the paper's max_tokens (an open "
            "server never refuses it) and its replies would be cut while thinking; give --reasoning on "
            "(priced here without thinking)"
        )
    return None


def check_mode(mode: str, effort: str | None = None) -> None:
    """Raise [`ConfigError`][jswim.errors.ConfigError] for an unknown ``--reasoning`` or ``--reasoning-effort``."""
    if mode not in MODES:
        raise ConfigError(f"--reasoning must be one of {', '.join(MODES)}, got {mode!r}")
    if effort is not None and effort not in EFFORTS:
        raise ConfigError(f"--reasoning-effort must be one of {', '.join(EFFORTS)}, got {effort!r}")


def wants_completion_tokens(server_message: str, payload: dict[str, Any]) -> bool:
    """The server refused ``max_tokens`` and named ``max_completion_tokens`` instead."""
    return (
        "max_tokens" in payload
        and bool(_WANTS_COMPLETION_TOKENS.search(server_message))
        and "max_tokens" in server_message.replace("max_completion_tokens", "")
    )


def accepted_temperature(server_message: str, payload: dict[str, Any]) -> float | None:
    """The one temperature the server says the model accepts, if it refused the one sent."""
    if "temperature" not in payload:
        return None
    m = _ONLY_TEMPERATURE.search(server_message)
    if m is None:
        return None
    value = float(m.group(1))
    return value if value != payload["temperature"] and 0.0 <= value <= 2.0 else None


@dataclass
class ReasoningState:
    """What one client sends a reasoning model, amended as the server answers (mutable).

    Attributes
    ----------
    mode : {"auto", "on", "off"}
    budget : int
        ``max_completion_tokens`` (or ``max_tokens`` for open models) once reasoning is on.
    effort : str or None
        ``reasoning_effort`` sent with every request when set.
    openai : bool
        The API is OpenAI's: ``"on"`` sends ``max_completion_tokens`` from the start.
    token_field : str
        ``"max_tokens"`` or ``"max_completion_tokens"``.
    active : bool
        Reasoning budget in use.
    temperature : float or None
        The temperature the model accepts, when it refused the one asked for.
    notes : list of str
        One sentence per switch, with the server's words (metadata and the printed summary).
    """

    mode: str = "auto"
    budget: int = REASONING_MAX_TOKENS
    effort: str | None = None
    openai: bool = False
    token_field: str = "max_tokens"
    active: bool = False
    temperature: float | None = None
    notes: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        check_mode(self.mode, self.effort)
        if not 1 <= self.budget <= 1_000_000:
            raise ConfigError(
                f"the reasoning budget (--max-tokens) must be between 1 and 1000000, got {self.budget}"
            )
        if self.mode == "on":
            self.active = True
            if self.openai:
                self.token_field = "max_completion_tokens"

    def apply(self, payload: dict[str, Any]) -> dict[str, Any]:
        """``payload`` as this state sends it (a new dict; the original is left alone)."""
        out = dict(payload)
        if self.active and "max_tokens" in out:
            out.pop("max_tokens")
            out[self.token_field] = self.budget
        elif self.token_field != "max_tokens" and "max_tokens" in out:
            out[self.token_field] = out.pop("max_tokens")
        if self.temperature is not None and "temperature" in out:
            out["temperature"] = self.temperature
        if self.effort is not None:
            out["reasoning_effort"] = self.effort
        return out

    def adapt(self, server_message: str, payload: dict[str, Any], model: str) -> bool:
        """Switch what is sent after a 400 saying what the model wants; ``True`` if it switched
        (the request is then sent again), ``False`` if the message asks for nothing known."""
        if self.mode == "off":
            return False
        changed = False
        if wants_completion_tokens(server_message, payload):
            if (
                self.token_field != "max_completion_tokens" or not self.active
            ):  # the first of many in flight
                self.token_field, self.active = "max_completion_tokens", True
                self.notes.append(
                    f"{model} refused max_tokens: sent max_completion_tokens={self.budget} instead "
                    "(room to think; --max-tokens sets it)"
                )
            changed = True
        t = accepted_temperature(server_message, payload)
        if t is not None:
            if self.temperature != t:
                self.temperature = t
                self.notes.append(
                    f"{model} accepts only temperature {t:g}: sent {t:g} instead of "
                    f"{payload['temperature']:g} (a deviation from the paper's temperature 0)"
                )
            changed = True
        return changed

    def describe(self) -> dict[str, Any]:
        """What was sent because of this state (recorded with the study)."""
        return {
            "mode": self.mode,
            "active": self.active,
            "token_field": self.token_field,
            "budget": self.budget if self.active else None,
            "temperature_sent": self.temperature,
            "effort": self.effort,
            "notes": list(self.notes),
        }
