"""Every error a user can cause, under one root, [`JswimError`][jswim.errors.JswimError].

Catch ``JswimError`` to handle all of them (the ``jswim`` command does, once, and turns each into
one line on stderr with exit status 2). Each message is one line, names what to change and never
contains an API key. The tree::

    JswimError
    +-- ConfigError (also ValueError)      a parameter, option or input file has a bad value
    |   +-- PositionBelowMinimumError       X fell below x_min, so the prompt cannot encode it
    +-- LLMError (also RuntimeError)       the LLM server or the embedded model failed
    |   +-- LLMServerError                  unreachable, or kept failing (network, timeouts, 429, 5xx)
    |   |   +-- LLMTimeoutError             kept answering slower than the timeout (a cold server)
    |   +-- LLMRequestError                 this request was rejected (4xx; retrying won't help)
    |   |   +-- LLMSetupError               every request would be: URL, key, model or a field
    |   +-- LLMResponseError                the server answered, but not with a usable completion
    |   |   +-- MalformedReply (also ValueError)  the body is not a chat completion (jswim.llm.server_response)
    |   +-- LocalModelError                 the embedded model cannot start (package or file missing)
    |   +-- BudgetExhausted                 the cost cap is reached (jswim.llm.budget)
    +-- ResultFolderError (also ValueError) a study folder is unusable: another study, other
        |                                   settings, not a study folder, unreadable
        +-- FolderBusyError                 another live session holds the folder's lock
        +-- StudyFolderError                a study or output folder cannot be written

Each is defined here and also read from the module that raises it (``jswim.llm.budget``,
``jswim.llm.server_response``, ``jswim._io.folderlock``, ``jswim.results``).

[`JswimWarning`][jswim.errors.JswimWarning] (a ``UserWarning``) is what does not stop the work; the command prints each as
one ``jswim: warning:`` line.

``ConfigError`` and ``ResultFolderError`` subclass `ValueError` and ``LLMError``
`RuntimeError`, as they did before the root existed, so older ``except`` clauses still work.
"""

from __future__ import annotations

import math
import numbers

__all__ = [
    "MAX_COUNT",
    "SIZE_RANGES",
    "BudgetExhausted",
    "ConfigError",
    "FolderBusyError",
    "JswimError",
    "JswimWarning",
    "LLMError",
    "LLMRequestError",
    "LLMResponseError",
    "LLMServerError",
    "LLMSetupError",
    "LLMTimeoutError",
    "LocalModelError",
    "MalformedReply",
    "PositionBelowMinimumError",
    "ResultFolderError",
    "StudyFolderError",
    "check_choice",
    "check_count",
    "check_direction",
    "check_size",
    "check_zeta",
]


class JswimError(Exception):
    """Root of every error a user of jswim can cause (see the module docstring for the tree)."""


class ConfigError(JswimError, ValueError):
    """A parameter has a bad value; the message names the parameter and what to change."""


def check_choice(value: object, choices: tuple[str, ...], what: str) -> str:
    """``value`` if it is one of ``choices``, else a one-line [`ConfigError`][jswim.errors.ConfigError] that names
    ``what`` and every choice."""
    if value not in choices:
        raise ConfigError(f"{what} must be one of {', '.join(choices)}, got {value!r}")
    return value  # type: ignore[return-value]


def check_zeta(value: object, option: str | None = None) -> float:
    """The noise level zeta as a float >= 0 (each step's displacement becomes dX(1 + zeta Y), Y ~
    U[-1, 1]): the one check of every zeta (the environment, the scenes, the studies and their
    ensembles, ``--noise``, ``--zetas``); ``option`` names it as the user gave it."""
    try:
        z = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise ConfigError(f"{option or 'zeta'} must be a number, got {value!r}") from None
    if not (math.isfinite(z) and z >= 0):
        raise ConfigError(
            f"{option + ' (zeta)' if option else 'zeta (noise level)'} must be >= 0, got {value!r}"
        )
    return z


def check_direction(direction: object) -> int:
    """The target direction, +1 or -1 (a number; [`jswim.env.parse_direction`][jswim.env.params.parse_direction] also reads
    ``"+x"``/``"-x"``)."""
    if isinstance(direction, bool) or direction not in (1, -1):
        raise ConfigError(f"direction must be +1 or -1, got {direction!r}")
    return int(direction)  # type: ignore[call-overload]


#: The one range of each study size, read by every check of it ([`jswim.studies.StudyOptions`][jswim.studies.options.StudyOptions],
#: ``jswim study``, ``jswim bench``, [`jswim.prompt.PromptConfig`][jswim.prompt.PromptConfig]): name -> (lowest, highest).
#: ``n_ht``: the paper sweeps 1 to 8 history records (its Fig. 3; the history study's default
#: ``--n-hts``) and picks 3 and 6; 0 is the no-history ablation; 100 is far past the sweep (a run
#: of the paper's 50 steps never holds more than 50 records).
SIZE_RANGES = {
    "steps": (1, 10_000),
    "runs": (0, 100_000),
    "q_runs": (0, 100_000),
    "samples": (1, 10_000),
    "n_ht": (0, 100),
    "train_episodes": (1, 10_000),
    "starts": (1, 1_000),
}


def check_size(name: str, value: object, option: str | None = None) -> int:
    """``value`` as an int if it lies in `SIZE_RANGES` ``[name]``: the one check of that size,
    whose one-line message names the command-line option (``--n-ht``, ``--q-runs``, ...; ``option``
    for a grid of it, ``--n-hts``)."""
    lo, hi = SIZE_RANGES[name]
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or not lo <= value <= hi:
        raise ConfigError(
            f"{option or '--' + name.replace('_', '-')} must be between {lo} and {hi}, got {value!r}"
        )
    return int(value)


#: Largest count a batched command accepts (``--n``, ``--seeds``, ``--steps``, ``--chunk``): swimmer
#: and learner indices are int32 on the device, and anything larger would fail deep inside JAX or NumPy.
MAX_COUNT = 2**31 - 1


def check_count(name: str, value: object) -> int:
    """``value`` as an int if it is a count in ``1..MAX_COUNT``: the one check of a batched command's
    counts, from the command line (`jswim.cli.base.check_counts`) and from Python
    (`jswim.studies.qlearn.study`); the message names the option ``--name``."""
    if (
        isinstance(value, bool)
        or not isinstance(value, numbers.Integral)
        or not 1 <= value <= MAX_COUNT
    ):
        raise ConfigError(
            f"--{name} must be "
            + (
                f"at most {MAX_COUNT:,}"
                if isinstance(value, numbers.Integral) and value > 1
                else ">= 1"
            )
            + f", got {value!r}"
        )
    return int(value)


class PositionBelowMinimumError(ConfigError):
    """X fell below ``X_min``, so it cannot be sent as a non-negative integer.

    An LLM run stops and reports it; lower ``x_min`` to go on.
    """

    def __init__(self, x: float, x_min: float) -> None:
        super().__init__(f"position X = {x:.4f} is below x_min = {x_min}; lower x_min")
        self.x = x
        self.x_min = x_min


class LLMError(JswimError, RuntimeError):
    """Base class of LLM-layer failures."""


class LLMServerError(LLMError):
    """The server could not be reached or kept failing (network, timeouts, 429, 5xx)."""


class LLMTimeoutError(LLMServerError):
    """The server kept answering slower than the timeout (a cold or overloaded server)."""


class LLMRequestError(LLMError):
    """The server rejected the request (4xx other than 408/409/429): retrying will not help.

    Attributes
    ----------
    status : int
        The HTTP status.
    server_message : str
        The server's own error text (one line).
    field : str or None
        The request field the server named as the cause, when it named one we sent.
    """

    def __init__(
        self, message: str, status: int, server_message: str = "", field: str | None = None
    ) -> None:
        super().__init__(message)
        self.status = status
        self.server_message = server_message
        self.field = field


class LLMSetupError(LLMRequestError):
    """A rejection no request of this client can avoid: wrong URL (404), key (401/403), model,
    or a request field the server does not accept. Stop and fix the settings."""


class LLMResponseError(LLMError):
    """The server answered, but not with a usable chat completion (bad JSON, no choices)."""


class MalformedReply(LLMResponseError, ValueError):
    """The body is not a chat completion; the message says what was wrong (one line)."""


class LocalModelError(LLMError):
    """The embedded local model cannot be started (missing package or model file)."""


class BudgetExhausted(LLMError):
    """The next call would take the study past its ``--max-cost`` cap."""


class ResultFolderError(JswimError, ValueError):
    """A study folder cannot be used: it holds another study or other settings, is not a study
    folder, or cannot be read. The message says which and what to do."""


class FolderBusyError(ResultFolderError):
    """Another live session holds the study folder's lock."""


class StudyFolderError(ResultFolderError):
    """A study or output folder cannot be written (read-only, missing permission, disk full)."""


class JswimWarning(UserWarning):
    """Something a user should know that does not stop the work (a model the server does not
    list, more requests in flight than the server has slots). The command prints each as one
    ``jswim: warning:`` line."""
