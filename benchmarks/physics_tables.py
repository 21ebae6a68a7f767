"""Recompute the physics numbers the docs pages quote, from jswim's code, and check the pages.

Each number is computed here from jswim (the exact step tables, the gait and lattice searches),
printed with the page and the sentence it appears in, and with ``--check`` compared with the
number the page gives, to the page's own decimals: a page that drifts from the code fails
(``tests/e2e/test_docs_numbers.py`` runs the check). The tests under ``tests/physics`` check the
same values against independent ones (closed forms, symmetries, the authors' code).

    python benchmarks/physics_tables.py            # print every number (~6 min on 2 shared cores)
    python benchmarks/physics_tables.py --check    # exit 1 where a page says otherwise
    python benchmarks/physics_tables.py --fast     # without the K = 20 and three-DOF searches (~15 s)
"""

from __future__ import annotations

import argparse
import functools
import math
import re
import sys
from pathlib import Path
from typing import NamedTuple
from collections.abc import Callable, Iterator

import numpy as np

DOCS = Path(__file__).resolve().parents[1] / "docs"


class Quote(NamedTuple):
    """A number a page gives: ``pattern`` matches the page (whitespace-insensitive) with the number
    as its one group; ``value`` is jswim's."""

    page: str
    pattern: str
    value: float


def _square(swimmer: str, direction: int = 1, **model_kwargs) -> tuple[float, np.ndarray]:
    """The best closed cycle (the square gait) per cycle, and its per-step displacements."""
    from jswim import env
    from jswim.action_codes import decode_action
    from jswim.judging import gait

    model = env.make_params(swimmer, **model_kwargs).model
    best = gait.best_cycles(model, direction)[0]
    moves = [decode_action(int(a)) for a in best.actions]
    x = np.asarray(env.rollout_moves(swimmer, moves, init=best.start, **model_kwargs).x, np.float64)
    return best.displacement, np.diff(np.concatenate([[0.0], x]))


@functools.cache
def _corner_mdp(swimmer: str) -> tuple[np.ndarray, np.ndarray]:
    """The noiseless two-DOF swimmer as a deterministic MDP on its four corners (toward +x):
    reward ``r[s, a]`` (the step's displacement) and next corner ``nxt[s, a]``, read from the
    exact step table through ``env.rollout`` one step at a time."""
    from jswim import env
    from jswim.action_codes import decode_action, n_actions

    corners = env.all_inits(2)
    index = {c: i for i, c in enumerate(corners)}
    acts = n_actions(2)
    r, nxt = np.zeros((4, acts)), np.zeros((4, acts), int)
    for s, c in enumerate(corners):
        for a in range(acts):
            dof, roc = decode_action(a)
            ro = env.rollout_moves(swimmer, [(dof, roc)], init=c)
            r[s, a] = float(np.asarray(ro.x)[0])
            lv = list(c)
            lv[dof - 1] = min(1, max(0, lv[dof - 1] + roc))
            nxt[s, a] = index[tuple(lv)]
    return r, nxt


def _greedy(r: np.ndarray, nxt: np.ndarray, gamma: float) -> tuple[np.ndarray, np.ndarray]:
    """Optimal values and greedy actions (value iteration to convergence)."""
    v = np.zeros(len(r))
    for _ in range(20_000):
        q = r + gamma * v[nxt]
        new = q.max(1)
        if np.max(np.abs(new - v)) < 1e-15:
            break
        v = new
    return v, q.argmax(1)


def _gait_threshold(swimmer: str) -> float:
    """The smallest discount for which the optimal policy is the square gait (bisection)."""
    r, nxt = _corner_mdp(swimmer)
    _, gait_policy = _greedy(r, nxt, 0.999)  # far-sighted: the gait

    def is_gait(g: float) -> bool:
        return bool(np.all(_greedy(r, nxt, g)[1] == gait_policy))

    lo, hi = 0.01, 0.999
    for _ in range(40):
        mid = (lo + hi) / 2
        lo, hi = (lo, mid) if is_gait(mid) else (mid, hi)
    return hi


def _gait_value(swimmer: str, gamma: float) -> float:
    """The discounted value of keeping the square gait up forever, from its best phase."""
    r, nxt = _corner_mdp(swimmer)
    return float(_greedy(r, nxt, gamma)[0].max())


def _four_link_x() -> tuple[float, float]:
    """Along x per 6-step cycle of the best four-link stroke from the paper's start (the chain
    symmetric about x: links at -pi/3, -pi/9, pi/9, pi/3), and from a start turned by pi/9 so
    that one middle link lies along x."""
    from jswim import env

    cycle = [(3, -1), (2, -1), (1, -1), (3, 1), (2, 1), (1, 1)]
    r = env.rollout_moves("nlink", cycle, init=(1, 1, 1))
    x, y = float(np.asarray(r.x)[-1]), float(np.asarray(r.y)[-1])
    return x, x * math.cos(math.pi / 9) - y * math.sin(math.pi / 9)


def quotes(fast: bool = False) -> Iterator[Quote]:
    """Every checked number, computed (lazily: one computation per group)."""
    from jswim.judging import lattice
    from jswim.swimmers.models import make_model

    purcell, _purcell_steps = _square("purcell")
    purcell_back, _ = _square("purcell", -1)
    ng, ng_steps = _square("ng")
    pi4, _ = _square("purcell", d_max=math.pi / 4)
    s = r"\s+"
    yield Quote("physics.md", r"exact value, the same both ways by symmetry, is (0\.\d+)", purcell)
    yield Quote(
        "physics.md", r"exact value, the same both ways by symmetry, is (0\.\d+)", purcell_back
    )
    yield Quote("physics.md", r"square gait per cycle (0\.\d+) \(`d_max =" + s + r"pi/4`\)", pi4)
    yield Quote("physics.md", r"(0\.\d+) \(`pi/3`\)", purcell)
    yield Quote("physics.md", r"NG \(6, 10\) (0\.\d+)", ng)
    yield Quote("fidelity.md", r"exact: (0\.\d+) both ways", purcell)
    yield Quote("continuous.md", r"the whole range \| (0\.\d+) \|", purcell / 4)
    yield Quote("continuous.md", r"the whole range \| 0\.\d+ \| (0\.\d+) \|", purcell)
    yield Quote(
        "continuous.md", r"\| NG \(arms 6\.\.10\) \| the full square \| (0\.\d+) \|", ng / 4
    )
    yield Quote(
        "continuous.md", r"\| NG \(arms 6\.\.10\) \| the full square \| 0\.\d+ \| (0\.\d+) \|", ng
    )
    yield Quote("continuous.md", r"\(0\.\d+, (0\.\d+) per cycle\) and with K = 2", ng)
    # NG's square gait: two strokes forward, two back (bench.md's reading of the reference rule)
    big, small = float(np.max(np.abs(ng_steps))), float(np.min(np.abs(ng_steps)))
    yield Quote("bench.md", r"the \+-(0\.\d+) and", big)
    yield Quote("bench.md", r"and\s+\+-(0\.\d+) strokes", small)
    yield Quote("bench.md", r"strokes net (0\.\d+) per cycle", ng)
    # The Q-learner's discount and optimistic start (baselines.md)
    yield Quote("baselines.md", r"optimal policy only for gamma > (0\.\d+)", _gait_threshold("ng"))
    yield Quote(
        "baselines.md",
        r"kept up forever \((0\.\d+) for Purcell at gamma = 0\.9\)",
        _gait_value("purcell", 0.9),
    )
    if fast:
        return
    # The lattice search's runner-up at K = 20 (continuous.md's best-stroke table; ~2 min each)
    for name, label in (
        ("purcell", r"the whole range"),
        ("ng", r"NG \(arms 6\.\.10\) \| the full square"),
    ):
        cycles = lattice.best_lattice_cycles(make_model(name), 1, 20, max_len=4)
        runner_up = next(c.per_step for c in cycles if c.per_step < cycles[0].per_step - 1e-12)
        yield Quote(
            "continuous.md",
            label + r" \| 0\.\d+ \| 0\.\d+ \|[^|]*\| K = 20: [^|]*?(0\.\d+) per step",
            runner_up,
        )
    from jswim import env
    from jswim.judging import gait

    for swimmer, pattern in (
        ("nlink", r"best four-link cycle \(period 6\) moves (0\.\d+) a per step"),
        ("nsphere", r"the\s+best four-sphere cycle (0\.\d+) a per step"),
    ):
        best = gait.best_cycles(env.make_params(swimmer).model, 1)[0]
        yield Quote("physics.md", pattern, best.per_step)
    yield Quote(
        "physics.md",
        r"four-sphere swimmer agrees exactly \((0\.\d+) per cycle\)",
        best.displacement,
    )
    # README's and getting-started's wall example: three square cycles 5 a above a wall
    import jswim
    from jswim.env import encode_action
    from jswim.scenes import Scene

    world, params = jswim.make("ng", Scene(medium="wall", height=5.0))
    square = [encode_action(d, r) for d, r in [(1, -1), (2, -1), (1, 1), (2, 1)]]
    progress = float(jswim.rollout(world, params, 0, square * 3).info.progress.sum())
    for page in ("../README.md", "getting-started.md"):
        yield Quote(page, r"wall: (0\.\d+) a toward \+x in 3 cycles", progress)
    along_x, orientation0 = _four_link_x()
    yield Quote(
        "physics.md", r"the best stroke moves (0\.\d+)\s+a per 6-step cycle along x", along_x
    )
    yield Quote("physics.md", r"\((0\.\d+) if the middle link started along x\)", orientation0)


def _page_number(q: Quote) -> tuple[str | None, int]:
    """The number the page gives (as written) and its decimals."""
    text = " ".join((DOCS / q.page).read_text().split())
    m = re.search(q.pattern.replace(r"\s+", " "), text)
    if m is None:
        return None, 0
    written = m.group(1)
    return written, len(written.split(".")[1]) if "." in written else 0


def check(fast: bool = False, say: Callable[[str], None] = print) -> list[str]:
    """Each quote whose page number differs from jswim's beyond the page's last decimal."""
    wrong = []
    for q in quotes(fast):
        written, decimals = _page_number(q)
        ok = written is not None and abs(float(written) - q.value) <= 0.5 * 10.0**-decimals + 1e-12
        line = f"{q.page:14} {written or 'NOT FOUND':>11}  jswim {q.value:.10f}  {'ok' if ok else 'DIFFERS'}  /{q.pattern}/"
        say(line)
        if not ok:
            wrong.append(line)
    return wrong


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument(
        "--check", action="store_true", help="exit 1 where a page's number differs from jswim's"
    )
    p.add_argument(
        "--fast", action="store_true", help="leave out the K = 20 and three-DOF searches"
    )
    a = p.parse_args(argv)
    wrong = check(a.fast)
    if wrong:
        print(f"{len(wrong)} number(s) differ from jswim's:", *wrong, sep="\n", file=sys.stderr)
    return 1 if wrong and a.check else 0


if __name__ == "__main__":
    raise SystemExit(main())
