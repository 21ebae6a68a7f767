"""Study reports: the summary table of a study's runs and its figures."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Sequence

from jswim import plots
from jswim.agents.variants import VARIANTS
from jswim.prompt import SENTENCES
from jswim.stats import learn_stats, mean_interval, wilson_interval
from jswim.studies.grids import SPECS
from jswim.swimmers.models import make_model


def summarize(rows: Sequence[dict[str, Any]]) -> list[dict[str, Any]]:
    """Per (agent, swimmer, direction, group): success rate with 95% Wilson CI, mean X/a in the
    target direction with a bootstrap CI, steps to learn (:func:`jswim.stats.learn_stats`:
    quartiles over the runs that learned, and ``learned``, how many did), tokens per step.

    ``tokens_per_step`` counts what the model read and wrote per decision (shared and cached calls
    included) where rows record it. ``distinct`` is the number of different runs (start and
    actions): at temperature 0 without noise, runs from the same start are identical copies, so
    the intervals of such groups rest on fewer independent runs than ``n``."""
    out = []
    keys = ("agent", "swimmer", "direction", "group")
    grouped: dict[tuple, list[dict]] = {}
    for r in rows:
        grouped.setdefault(tuple(r.get(k) for k in keys), []).append(r)
    for key, g in sorted(grouped.items(), key=lambda kv: tuple(str(v) for v in kv[0])):
        k = sum(bool(r["success"]) for r in g)
        lo, hi = wilson_interval(k, len(g))
        m, mlo, mhi = mean_interval([r["signed_final_x"] for r in g])
        ls = learn_stats([r.get("steps_to_learn") for r in g])
        steps = sum(r["steps"] for r in g) or 1
        tokens = sum(r["tokens_seen"] if r.get("tokens_seen") is not None
                     else (r.get("prompt_tokens") or 0) + (r.get("completion_tokens") or 0) for r in g)
        distinct = len({(r.get("init"), json.dumps(r.get("actions"))) for r in g})
        out.append({
            **dict(zip(keys, key)), "n": len(g), "distinct": distinct,
            "success_rate": k / len(g), "success_lo": lo, "success_hi": hi,
            "mean_x": m, "mean_x_lo": mlo, "mean_x_hi": mhi,
            "steps_to_learn_q25": ls.q25, "steps_to_learn_median": ls.median, "steps_to_learn_q75": ls.q75,
            "learned": ls.learned, "tokens_per_step": tokens / steps if tokens else None,
            "failed_steps": sum(r.get("failed_steps") or 0 for r in g),
            "parse_retries": sum(r.get("parse_retries") or 0 for r in g),
            "cost_usd": sum(r.get("cost_usd") or 0.0 for r in g),
        })
    return out


def draw_figures(study: str, rows: Sequence[dict[str, Any]], folder: str | Path) -> list[Path]:
    """The study's figures as PNG and PDF in ``folder``."""
    if not rows:
        return []
    kind = SPECS[study].figure if study in SPECS else study
    models = {sw: make_model(sw) for sw in {r["swimmer"] for r in rows}}
    paths: list[Path] = []
    if kind == "curves":
        cycles = {}
        for sw in models:
            ok = [r for r in rows if r["swimmer"] == sw and r["success"]]
            ok.sort(key=lambda r: ({"llm": 0, "qlearning": 1}.get(r["agent"], 2), r["steps_to_learn"]))
            if ok:
                r = ok[0]
                s = r["steps_to_learn"]
                acts = [tuple(a) for a in r["actions"]][s: s + r["period"]]
                levels = [1 if ch == "+" else 0 for ch in r["init"]]
                for dof, roc in [tuple(a) for a in r["actions"]][:s]:
                    if roc:
                        levels[dof - 1] = 1 if roc > 0 else 0
                cycles[sw] = (levels, acts, r["agent"])
        paths += plots.save(plots.curves_figure(rows, models, cycles), folder, study)  # swim.png or curves.png
    elif kind == "history":
        paths += plots.save(plots.history_figure(rows), folder, "history")
    elif kind == "noise":
        paths += plots.save(plots.noise_figure(rows), folder, "noise")
    elif kind == "ablation":
        order = ["full"] + [f"-{s}" for s in SENTENCES]
        paths += plots.save(plots.bars_figure(rows, "group", order, "(sentence removed)"), folder, "ablation")
    elif kind == "inits":
        paths += plots.save(plots.bars_figure(rows, "group", None, "(initial configuration)"), folder, "inits")
    elif kind == "competence":
        # One entry per LLM variant, then one per baseline (agent, allowed set).
        entries = [{**r, "entry": r["group"] if r["agent"] == "llm" else f"{r['agent']} ({r['group']})"} for r in rows]
        order = [v for v in VARIANTS if any(e["entry"] == v for e in entries)]
        order += sorted({e["entry"] for e in entries} - set(order))
        paths += plots.save(plots.competence_figure(entries, order), folder, "competence")
    return paths
