"""A study's session: what one sitting of `run_study` works with (`StudySession`: the folder's
store, the options, the backend, the progress and the cap), the server's preflight, the cost cap
checked before any call, and what each session sent and cost, recorded in the study's metadata
(``llm_server``, ``llm_totals``)."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from jswim._io.callsite import warn_user
from jswim.errors import ConfigError, JswimWarning
from jswim.llm.backend import Backend
from jswim.llm.client import LLMClient
from jswim.llm.ledger import RequestLedger
from jswim.llm.probe import ServerInfo
from jswim.llm.sampling import describe as describe_sampling
from jswim.llm.urls import is_local_host
from jswim.llm.usage import cap_refusal
from jswim.prompt import PromptTemplate
from jswim.results import StudyStore
from jswim.studies.options import StudyOptions

#: ``progress(phase, done, total, info)``: runs done of the study's runs, except in the phases
#: ``"llm"`` and ``"llm-live"``, where the work counted is LLM steps (runs are in ``info``);
#: ``info`` is a short status text.
ProgressFn = Callable[[str, int, int, str], None]


def no_progress(phase: str, done: int, total: int, info: str = "") -> None:
    """A `ProgressFn` that shows nothing (the default of `StudySession`)."""


@dataclass
class StudySession:
    """One sitting of a study: what its runners share, in place of loose arguments.

    `run_study` makes one per call; `jswim.studies.execute.run_baselines` and
    `jswim.studies.execute.run_llm` take it, store each run the moment it ends and move
    ``finished`` on; what they measured comes back as their return value.

    Attributes
    ----------
    store : StudyStore
        The study folder's one writer.
    options : StudyOptions
        The grid and agent knobs.
    backend : Backend or None
        The LLM server (``None``: a study without LLM runs).
    template : PromptTemplate or None
        The prompt template of ``--prompt-file`` (``None``: the variant's own).
    total : int
        Runs in the study's grid.
    finished : int
        Runs done so far, this session's and earlier sessions' (moved on by the runners).
    progress : ProgressFn
        Called after each stored batch of runs (`ProgressFn`).
    max_cost : float or None
        Cap in USD over all the study's sessions (`check_max_cost`).
    server : ServerInfo or None
        The server's preflight, once made (a remote server's is made before the baselines run).
    """

    store: StudyStore
    options: StudyOptions
    backend: Backend | None
    template: PromptTemplate | None = None
    total: int = 0
    finished: int = 0
    progress: ProgressFn = field(default=no_progress)
    max_cost: float | None = None
    server: ServerInfo | None = None

    def tick(
        self, phase: str, done: int | None = None, info: str = "", total: int | None = None
    ) -> None:
        """Report progress: ``done`` of ``total`` (default: runs finished of the grid's runs)."""
        self.progress(
            phase,
            self.finished if done is None else done,
            self.total if total is None else total,
            info,
        )


def check_max_cost(max_cost: Any) -> float | None:
    """The one validation of a study's cost cap (``--max-cost``, ``run_study(max_cost=...)``).

    Parameters
    ----------
    max_cost : float or None
        Dollars; ``None`` sets no cap.

    Returns
    -------
    float or None
        The cap as a float.

    Raises
    ------
    ConfigError
        One line where the cap is not a finite number of dollars >= 0 (a string, a bool, NaN,
        infinity: no cap is ``None``).
    """
    if max_cost is None:
        return None
    if not _number(max_cost):
        raise ConfigError(f"--max-cost must be a finite number of dollars >= 0, got {max_cost!r}")
    return float(max_cost)


def cap_check(backend: Backend, info: ServerInfo | None, max_cost: float | None) -> None:
    """Refuse a cost cap the study's calls could not reach ([`jswim.llm.usage.cap_refusal`][jswim.llm.usage.cap_refusal]),
    by the pricing rule of the run and of its dry run alike: the server's listed models
    (``info``), the host, ``--price-local`` and ``--prices``.

    Raises
    ------
    ConfigError
        One line naming ``--prices``, before any request is sent.
    """
    if backend.local or max_cost is None:
        return
    s = backend.client_settings(info=info)
    why = cap_refusal(
        s.prices,
        s.model,
        max_cost,
        local_host=is_local_host(s.base_url),
        listed=s.listed_models,
        price_local=s.price_local,
    )
    if why is not None:
        raise ConfigError(why)


def preflight(
    store: StudyStore, backend: Backend, server: Any = None, max_cost: float | None = None
) -> ServerInfo:
    """The server's preflight ([`Backend.preflight`][jswim.llm.backend.Backend.preflight]), recorded in the study's metadata
    (``llm_server``); its warnings go out as [`JswimWarning`][jswim.errors.JswimWarning]. A cost cap the
    calls could not reach is refused here ([`cap_check`][jswim.studies.session.cap_check]), before the status says running."""
    info = backend.preflight(server)
    cap_check(backend, info, max_cost)
    store.set_status("running", llm_server=info.metadata())
    for text in info.warnings:
        warn_user(text, JswimWarning)  # at the user's call, also from the study's worker thread
    return info


def record_session(
    store: StudyStore, backend: Backend, info: ServerInfo, client: LLMClient, notes: list[str]
) -> None:
    """What the session sent and what the server made of it: the sampling fields (with the
    server's reported defaults, from the preflight), the decoding form ``auto`` settled on, and
    why calls were not priced; into the metadata's ``llm_server`` and the printed ``notes``."""
    s = client.settings
    record = dict(store.meta.get("llm_server") or info.metadata())
    record.update(
        sampling={"preset": backend.sampling, "sent": dict(s.sampling)},
        max_concurrency=s.max_concurrency,
    )
    notes.append(describe_sampling(backend.sampling, backend.family(info), s.sampling))
    if client.fallbacks:
        record["constrain_fallbacks"] = list(client.fallbacks)
        for f in client.fallbacks:
            notes.append(
                f"constrained decoding: the server rejected {f['rejected']} ({f['server']}); "
                f"--constrain auto moved on to {f['next']}"
            )
    if client.unpriced:
        record["unpriced"] = client.unpriced
        notes.append(f"cost: {client.unpriced}")
    store.set_status(store.meta.get("status", "running"), llm_server=record)


def study_totals(ledger: RequestLedger, answered_calls: int) -> dict[str, Any]:
    """The study's LLM totals over all its sessions, recomputed from its ledger (``llm_totals``).

    Every session the ledger names is counted, one killed without a word included (kill -9: its
    requests and its time to its last line; ``not_ended`` says how many). ``answered_calls`` is
    the call journal's count (every answered call of the study, all sessions, finished runs or
    not), so calls per second divide the study's calls by the study's LLM wall time.
    ``requests`` are HTTP requests sent (what the server counts: first attempts and retries),
    ``faults`` transient failures by kind, ``unanswered`` requests sent with no answer in the
    ledger (the server may have billed them; at most ``unanswered_usd``): a kill's requests in
    flight included. [`jswim.llm.ledger.RequestLedger.totals`][jswim.llm.ledger.RequestLedger.totals]
    counts them; ``metadata.json`` holds the result as a report, never as the ledger.
    """
    t = ledger.totals()
    t["answered_calls"] = answered_calls
    t["calls_per_s"] = answered_calls / t["wall_s"] if t["wall_s"] > 0 else 0.0
    return t


def _number(v: Any) -> bool:
    """A finite number >= 0 (not a bool)."""
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) and v >= 0
