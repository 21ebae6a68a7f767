"""A study folder read into pandas ([`load`][jswim.results.load.load])."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import pandas as pd
from jswim import reprs
from jswim.results.read import (
    CALL_COLUMNS,
    TRANSCRIPT_COLUMNS,
    read_calls,
    read_metadata,
    read_runs,
    read_transcript,
    transcript_steps,
)
from jswim.results.row import as_run_rows
from jswim.results.schema import SCALAR_TYPES

# -- reading a study into pandas ----------------------------------------------------------------

#: Run columns repeated on every trajectory row, so one table answers "X/a of the LLM runs toward -x".
TRAJECTORY_KEYS = (
    "run_id",
    "agent",
    "swimmer",
    "direction",
    "group",
    "zeta",
    "n_ht",
    "init",
    "variant",
)


@dataclass
class Study:
    """A study folder read into pandas (see [`load`][jswim.results.load.load]).

    Attributes
    ----------
    folder : Path
    metadata : dict
        ``metadata.json``: study name, identity (settings), status, versions, summary.
    runs : pandas.DataFrame
        One row per finished run: every scalar field of its ``runs.jsonl`` record (``agent``,
        ``swimmer``, ``direction``, ``group``, ``zeta``, ``success``, ``steps_to_learn``,
        ``signed_final_x``, tokens, cost, ...).
    trajectories : pandas.DataFrame
        One row per run and step ``n = 1 .. steps`` (the state after the step; X = 0 at n = 0):
        the run's keys (`TRAJECTORY_KEYS`), ``x`` and ``y`` (centroid, in ``a``),
        ``orientation`` (rad; NaN in folders written before it was recorded), ``target_x``
        (``direction * x``: displacement in the target direction), ``dof`` and ``roc`` (the
        action), ``progress`` (that step's target-direction displacement) and ``stuck``.
    """

    folder: Path
    metadata: dict[str, Any]
    runs: pd.DataFrame
    trajectories: pd.DataFrame

    def __repr__(self) -> str:
        return reprs.study_text(self)

    def _repr_html_(self) -> str:
        return reprs.study_html(self)

    @property
    def name(self) -> str:
        """The study's name (``noise``, ``swim``, ...)."""
        return str(self.metadata.get("study", ""))

    @property
    def status(self) -> str:
        """``complete``, ``running`` (or interrupted), as recorded in ``metadata.json``."""
        return str(self.metadata.get("status", "unknown"))

    def transcript(self, run_id: str) -> pd.DataFrame:
        """The LLM transcript of ``run_id`` (``transcripts/RUN.jsonl``), one row per step.

        Columns: ``step`` (from 1), ``prompt`` (the exact text sent), ``reply`` (the last reply
        text), ``action`` (the action played, ``[DOF, ROC]``), ``failed`` (no valid action: the
        hold was played), ``attempts`` (replies asked for, the first plus parse retries),
        ``http_retries``, ``prompt_tokens``/``completion_tokens``/``cost_usd``/``latency_s``
        (summed over the attempts), ``cache_hit``, ``x_before``, ``x_after``, ``progress``,
        ``stuck``, ``cleared`` (the history was erased after this step), ``n_clears``,
        ``dofs_after``, and ``replies`` (every attempt's record). Empty for a run without a
        transcript (baselines, or an LLM run not started yet).
        """
        import pandas as pd  # lazy, as in load()

        return pd.DataFrame(
            transcript_steps(read_transcript(self.folder, run_id)), columns=TRANSCRIPT_COLUMNS
        )

    @property
    def calls(self) -> pd.DataFrame:
        """Every answered LLM call (``calls.jsonl``), one row per call, in the order answered.

        Columns: ``run`` (run id), ``n`` (the call's index in its run), ``key`` (hash of the
        request), ``text`` (the answer), ``raw`` (the reply as sent, reasoning included),
        ``prompt_tokens``, ``completion_tokens``, ``cached_tokens``, ``cost_usd``, ``cache_hit``,
        ``shared``, ``constraint``, ``finish_reason``. A torn last line (a kill) is skipped.
        """
        import pandas as pd

        return pd.DataFrame(read_calls(self.folder), columns=CALL_COLUMNS)


def load(folder: str | os.PathLike) -> Study:
    """Read a study folder into pandas DataFrames, without writing anything to it.

    Works on finished, interrupted and read-only folders: the runs come from ``runs.jsonl``, the
    durable record, not from the derived tables.

    Parameters
    ----------
    folder : path
        A folder written by ``jswim swim`` / ``jswim study`` / [`jswim.studies.run_study`][jswim.studies.run.run_study].

    Returns
    -------
    Study
        ``.runs`` (one row per run), ``.trajectories`` (one row per run and step, with ``x``,
        ``y``, ``orientation``), ``.metadata``.

    Raises
    ------
    ResultFolderError
        ``folder`` is not a study folder, or its metadata is unreadable.

    Examples
    --------
    >>> s = jswim.load("jswim-out/noise-1a2b3c4d")                    # doctest: +SKIP
    >>> s.runs.groupby(["swimmer", "agent", "zeta"]).success.mean()  # doctest: +SKIP
    """
    import pandas as pd  # lazy: ~0.4 s of import that only load() needs, not every study run

    folder = Path(folder)
    meta = read_metadata(folder)
    rows = read_runs(folder)
    scalar = [{k: v for k, v in r.items() if isinstance(v, SCALAR_TYPES)} for r in rows]
    runs = pd.DataFrame(scalar)
    lead = [k for k in ("run_id", "agent", "swimmer", "direction", "group") if k in runs.columns]
    runs = runs[lead + [c for c in runs.columns if c not in lead]] if len(runs.columns) else runs
    traj: dict[str, list[Any]] = {
        k: []
        for k in (
            *TRAJECTORY_KEYS,
            "step",
            "x",
            "y",
            "orientation",
            "target_x",
            "dof",
            "roc",
            "progress",
            "stuck",
        )
    }
    nan = float("nan")
    for r in as_run_rows(rows):  # the runs table above keeps every column of the file, as written
        xs = r.x or []
        n = len(xs)
        direction = r.direction or 1
        for k in TRAJECTORY_KEYS:
            traj[k] += [r.get(k)] * n
        traj["step"] += list(range(1, n + 1))
        traj["x"] += [float(v) for v in xs]
        traj["target_x"] += [direction * float(v) for v in xs]
        for k, vals in (("y", r.y), ("orientation", r.orientation), ("progress", r.progress)):
            traj[k] += [
                float(vals[i])
                if isinstance(vals, list) and i < len(vals) and vals[i] is not None
                else nan
                for i in range(n)
            ]
        acts = r.actions or []
        traj["dof"] += [int(acts[i][0]) if i < len(acts) else None for i in range(n)]
        traj["roc"] += [
            acts[i][1] if i < len(acts) else None for i in range(n)
        ]  # real for the continuous agent
        stuck = r.stuck
        traj["stuck"] += [
            bool(stuck[i]) if isinstance(stuck, list) and i < len(stuck) else None for i in range(n)
        ]
    trajectories = pd.DataFrame(traj)
    # Nullable dtypes: "not recorded" stays missing instead of turning a column into objects.
    real_roc = any(v is not None and v == v and float(v) != int(v) for v in traj["roc"])
    for table, cols in (
        (trajectories, ("dof", "n_ht") + (() if real_roc else ("roc",))),
        (runs, ("n_ht", "steps_to_learn")),
    ):
        for k in cols:
            if k in table.columns:
                table[k] = pd.array(
                    [None if v is None or v != v else int(v) for v in table[k]], dtype="Int64"
                )
    if real_roc:  # real-valued ROCs (the continuous study's RL baseline): a float column
        trajectories["roc"] = pd.array(
            [None if v is None or v != v else float(v) for v in trajectories["roc"]],
            dtype="Float64",
        )
    trajectories["stuck"] = trajectories["stuck"].astype("boolean")
    return Study(folder, meta, runs, trajectories)
