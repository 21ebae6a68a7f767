"""The summary of a study's runs: one row per agent, swimmer, direction and group.

The figures and the report page are drawn from the folder by the pictures layer
(`jswim.viz.publish`); nothing here draws."""

from __future__ import annotations

import json
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
