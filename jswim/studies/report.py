"""Study reports: the summary table of a study's runs and its figures."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any
from collections.abc import Sequence

from jswim.results import as_run_rows, is_failed
from jswim.judging.stats import learn_stats, mean_interval, wilson_interval


def summarize(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per (agent, swimmer, direction, group): success rate with 95% Wilson CI, mean X/a in the
    target direction with a bootstrap CI, steps to learn ([`jswim.judging.stats.learn_stats`][jswim.judging.stats.learn_stats]:
    quartiles over the runs that learned, and ``learned``, how many did), tokens per step.

    ``tokens_per_step`` counts what the model read and wrote per decision (shared and cached calls
    included) where rows record it. ``distinct`` is the number of different runs (start and
    actions): at temperature 0 without noise, runs from the same start are identical copies, so
    the intervals of such groups rest on fewer independent runs than ``n``. ``samples`` is how many
    independent samples of each run (``--samples``) the group pools (``n`` counts them all).

    Failed runs ([`jswim.results.is_failed`][jswim.results.is_failed]: the server stopped them) are left out: they
    are not results, and the study reports them apart."""
    rows = as_run_rows(rows)
    out = []
    keys = ("agent", "swimmer", "direction", "group")
    grouped: dict[tuple, list[dict]] = {}
    for r in rows:
        if is_failed(r):
            continue
        grouped.setdefault(tuple(r.get(k) for k in keys), []).append(r)
    for key, g in sorted(grouped.items(), key=lambda kv: tuple(str(v) for v in kv[0])):
        k = sum(bool(r.success) for r in g)
        lo, hi = wilson_interval(k, len(g))
        m, mlo, mhi = mean_interval([r.signed_final_x for r in g])
        ls = learn_stats([r.steps_to_learn for r in g])
        steps = sum(r.steps for r in g) or 1
        tokens = sum(
            r.tokens_seen
            if r.tokens_seen is not None
            else (r.prompt_tokens or 0) + (r.completion_tokens or 0)
            for r in g
        )
        distinct = len({(r.init, json.dumps(r.actions)) for r in g})
        out.append(
            {
                **dict(zip(keys, key)),
                "n": len(g),
                "distinct": distinct,
                "samples": len({int(r.sample or 0) for r in g}),
                "success_rate": k / len(g),
                "success_lo": lo,
                "success_hi": hi,
                "mean_x": m,
                "mean_x_lo": mlo,
                "mean_x_hi": mhi,
                "steps_to_learn_q25": ls.q25,
                "steps_to_learn_median": ls.median,
                "steps_to_learn_q75": ls.q75,
                "learned": ls.learned,
                "tokens_per_step": tokens / steps if tokens else None,
                "failed_steps": sum(r.failed_steps or 0 for r in g),
                "parse_retries": sum(r.parse_retries or 0 for r in g),
                "cost_usd": sum(r.cost_usd or 0.0 for r in g),
            }
        )
    return out


def draw_figures(
    study: str, rows: Sequence[dict[str, Any]], folder: str | Path, note: str | None = None
) -> list[Path]:
    """The study's figures ([`jswim.figures.plots.study_figures`][jswim.figures.plots.study_figures]) as PNG and PDF in ``folder``.

    ``note`` (see [`jswim.results.unfinished_note`][jswim.results.unfinished_note]) is written across each figure.
    """
    rows = as_run_rows(rows)
    from jswim.figures import (
        plots,
    )  # lazy: matplotlib is ~0.5 s of import that --no-figures never needs

    paths: list[Path] = []
    rows = [r for r in rows if not is_failed(r)]  # failed runs are not results
    for name, fig in plots.study_figures(study, rows, note=note).items():
        paths += plots.save(fig, folder, name)
    return paths
