"""Regenerate the Q-learning numbers of the docs pages from jswim, and check the pages.

- docs/results.md "Q-learning: steps to learn": ``jswim qlearn --seeds 10000`` (the authors'
  starts, zeta = 0, default ``QConfig``), printed as the page's table;
- docs/baselines.md's ``QConfig`` rows: NG toward +x on the shape-changing moves, 1,000 learners,
  the median steps to learn at other learning rates and discounts.

The learners are seeded (learner ``i`` gets key ``i`` of one split), so the numbers are exact
and the same on any machine and device count, in JAX's default float32 (a session with x64 on
draws other uniforms, so other learners); ``--check`` compares them with the pages, to the
pages' decimals (``tests/e2e/test_docs_numbers.py`` runs it in the slow tier).

    python benchmarks/qlearn_tables.py             # print both tables (~1-2 min on 2 cores)
    python benchmarks/qlearn_tables.py --check     # exit 1 where a page says otherwise
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path
from collections.abc import Callable

DOCS = Path(__file__).resolve().parents[1] / "docs"
SETS = {"all six": "all", "shape-changing (two)": "shape-changing"}


def results_rows(n_seeds: int = 10_000) -> list[list[str]]:
    """The results page's rows: swimmer, dir, actions, median [q25-q75], learned, success."""
    from jswim.agents.qlearning import QConfig
    from jswim.studies import qlearn

    by = {}
    for label, action_set in SETS.items():
        for r in qlearn.study(QConfig(action_set=action_set), n_seeds=n_seeds):
            by[(r.swimmer, r.direction, label)] = r
    out = []
    for swimmer in ("purcell", "ng"):
        for label in SETS:
            for d in (1, -1):
                r = by[(swimmer, d, label)]
                out.append(
                    [
                        {"purcell": "Purcell", "ng": "NG"}[swimmer],
                        "+x" if d > 0 else "-x",
                        label,
                        f"{r.median:g} [{r.q25:g}–{r.q75:g}]",
                        _pct(r.learned),
                        _pct(r.success),
                    ]
                )
    return out


def _pct(f: float) -> str:
    return f"{100 * f:.3g}%" if f < 1 else "100%"


def baseline_medians(n_seeds: int = 1000) -> dict[str, float]:
    """NG toward +x, shape-changing moves: the median steps to learn per learning rate and discount."""
    from jswim.agents.qlearning import QConfig
    from jswim.studies import qlearn

    def median(**kw) -> float:
        (r,) = qlearn.study(
            QConfig(action_set="shape-changing", **kw),
            swimmers=("ng",),
            directions=(1,),
            n_seeds=n_seeds,
        )
        return r.median

    out = {f"alpha {a:g}": median(learning_rate=a) for a in (1.0, 0.5, 0.25)}
    out.update({f"gamma {g:g}": median(discount=g) for g in (0.8, 0.9, 0.95, 0.99)})
    return out


def _page_rows() -> dict[tuple[str, str, str], list[str]]:
    text = (DOCS / "results.md").read_text()
    section = text.split("## Q-learning: steps to learn", 1)[1].split("\n## ", 1)[0]
    rows = {}
    for line in section.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 7 and cells[2] in SETS:
            rows[tuple(cells[:3])] = cells[:6]
    return rows


def _close(page: str, ours: str) -> bool:
    """Two cells agree: every number in them to the page's decimals."""
    a, b = re.findall(r"\d+(?:\.\d+)?", page), re.findall(r"\d+(?:\.\d+)?", ours)
    if len(a) != len(b):
        return False
    return all(
        abs(float(x) - float(y)) <= 0.5 * 10.0 ** -(len(x.split(".")[1]) if "." in x else 0) + 1e-9
        for x, y in zip(a, b)
    )


def _baselines_quotes() -> dict[str, str]:
    text = " ".join((DOCS / "baselines.md").read_text().split())
    m = re.search(r"median (\d+) steps at 1\.0, (\d+) at 0\.5, (\d+) at 0\.25", text)
    g = re.search(
        r"median (\d+) steps at 0\.8, (\d+) at 0\.9, (\d+) at 0\.95, (\d+) at 0\.99", text
    )
    out = {}
    if m:
        out.update(zip(("alpha 1", "alpha 0.5", "alpha 0.25"), m.groups()))
    if g:
        out.update(zip(("gamma 0.8", "gamma 0.9", "gamma 0.95", "gamma 0.99"), g.groups()))
    return out


def check(say: Callable[[str], None] = print, n_seeds: int = 10_000) -> list[str]:
    """Each number of the two pages that differs from jswim's (printed as it goes)."""
    wrong = []
    page = _page_rows()
    say(
        "| swimmer | dir | actions offered | steps to learn, median [q25–q75] | learned (200 steps) | success (50 steps) |"
    )
    for row in results_rows(n_seeds):
        say("| " + " | ".join(row) + " |")
        theirs = page.get(tuple(row[:3]))
        if theirs is None or not all(_close(p, o) for p, o in zip(theirs[3:], row[3:])):
            wrong.append(
                f"results.md {' '.join(row[:3])}: page {theirs and theirs[3:]}, jswim {row[3:]}"
            )
    quoted = _baselines_quotes()
    for name, value in baseline_medians().items():
        say(
            f"baselines.md NG +x shape-changing, {name}: median {value:g} (page: {quoted.get(name, 'NOT FOUND')})"
        )
        if name not in quoted or not _close(quoted[name], f"{value:g}"):
            wrong.append(f"baselines.md {name}: page {quoted.get(name)}, jswim {value:g}")
    return wrong


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument(
        "--check", action="store_true", help="exit 1 where a page's number differs from jswim's"
    )
    a = p.parse_args(argv)
    wrong = check()
    if wrong:
        print(f"{len(wrong)} number(s) differ from jswim's:", *wrong, sep="\n", file=sys.stderr)
    return 1 if wrong and a.check else 0


if __name__ == "__main__":
    raise SystemExit(main())
