"""A rerunnable mutation check of the money, protocol and physics code.

Each mutant is one small edit of the source (an operator, a constant, a sign, a dropped term)
that a user would pay for or publish wrong numbers from. For each, the repository is copied to a
scratch folder, the edit applied there, and only the test files that guard that module are run
(``pytest -x``): a failing test *catches* the mutant, a clean pass means it *survived*. The list
is fixed (:data:`MUTANTS`, the same every run, so before/after tables compare), so the check runs
in bounded time on two cores: about one pytest session per mutant.

    python benchmarks/mutation_check.py                  # every mutant, a Markdown table
    python benchmarks/mutation_check.py --only journal   # names containing "journal"
    python benchmarks/mutation_check.py --root /other/checkout   # e.g. main's tests, for "before"
    python benchmarks/mutation_check.py --list           # what would run

Nothing is edited in place: the working tree is never touched. A mutant whose original text is
no longer in the file (the code moved on) is reported as ``gone`` (update its entry). The
unmutated copy's tests run first per test set; if they fail, the check stops (a red baseline
proves nothing). Timing per mutant is printed; run it ``nice``d on a shared machine.
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

_PAID = "tests/studies/test_paid_api.py::"
#: The money tests, fastest and most direct first (pytest -x stops at the first failure).
_BUDGET = tuple(
    "tests/llm/test_pacing.py::" + t
    for t in (
        "test_budget_refuses_past_the_cap_and_stays_closed",
        "test_call_bound_prices_prompt_and_max_tokens",
        "test_client_stops_at_the_cap_before_sending",
        "test_failed_attempts_release_their_reservation",
    )
)
MONEY = (
    _BUDGET
    + tuple(
        _PAID + t
        for t in (
            "test_the_journal_sums_what_every_session_paid",
            "test_the_journal_answers_only_the_very_request_it_recorded",
            "test_dry_run_cost_and_worst_case_match_the_hand_computed_prices",
            "test_a_cap_below_one_call_sends_nothing",
            "test_the_cap_holds_over_three_sessions_and_a_higher_cap_bills_each_call_once",
            "test_max_cost_stops_below_the_cap_and_a_higher_cap_finishes_without_rebilling",
            "test_dry_run_sends_nothing_and_estimates_the_real_tokens",
        )
    )
    + (
        "tests/agents/test_pipelines.py::test_journal_replays_a_runs_own_paid_calls",
        "tests/agents/test_pipelines.py::test_journal_stops_replaying_where_a_run_diverges",
    )
)
CLIENT = ("tests/llm/test_llm_client.py", *MONEY)
#: The cap under servers that report oddly (tests/llm/test_cost_cap.py).
CAP = ("tests/llm/test_cost_cap.py",)
PACING = ("tests/llm/test_pacing.py",)
MEMORY = ("tests/agents/test_memory.py", "tests/agents/test_llm_agent.py")
PROTOCOL = ("tests/agents/test_protocol.py", "tests/agents/test_llm_agent.py")
PROMPT = ("tests/prompt/test_prompt.py",)
PHYSICS = (
    "tests/physics/test_physics.py",
    "tests/env/test_env.py",
    "tests/physics/test_four_dof.py",
)
PROGRESS = (
    "tests/agents/test_memory.py",
    "tests/agents/test_llm_agent.py",
    "tests/agents/test_pipelines.py",
)


#: Where the env step lives (a package since the continuous-env change; a module before).
ENV_STEP = "jswim/env/stepping.py|jswim/env.py"


@dataclass(frozen=True)
class Mutant:
    """One edit: ``old`` (which must occur once in ``path``) becomes ``new``.

    ``path`` may list alternatives separated by ``|`` (the first that exists is used), so the
    same list checks a checkout from before a module moved."""

    name: str
    path: str
    old: str
    new: str
    tests: tuple[str, ...]
    why: str = ""  # what a user would see if it shipped


MUTANTS: tuple[Mutant, ...] = (
    # -- money: the ledger, the cap, the dry run, prices -------------------------------------------
    Mutant(
        "journal-spent-assign",
        "jswim/llm/journal.py",
        'self.spent_usd += float(rec.get("cost_usd") or 0.0)',
        'self.spent_usd = float(rec.get("cost_usd") or 0.0)',
        MONEY,
        "earlier sessions' spend forgotten: the cap is passed on a rerun",
    ),
    Mutant(
        "journal-replay-or",
        "jswim/llm/journal.py",
        'if rec.get("n") != index or rec.get("key") != key:',
        'if rec.get("n") != index and rec.get("key") != key:',
        MONEY,
        "a changed request answered from the journal",
    ),
    Mutant(
        "journal-bills-cache-hits",
        "jswim/llm/journal.py",
        '"cost_usd": res.cost_usd if billed else 0.0',
        '"cost_usd": res.cost_usd',
        MONEY,
        "disk-cache hits counted as paid",
    ),
    Mutant(
        "dryrun-cost-scale",
        "jswim/llm/dryrun.py",
        "cost = (prompt_tokens * p_in + completion_tokens * p_out) / 1e6",
        "cost = (prompt_tokens * p_in + completion_tokens * p_out) / 1e5",
        MONEY,
        "estimate 10x",
    ),
    Mutant(
        "dryrun-worst-scale",
        "jswim/llm/dryrun.py",
        "cost_max = (prompt_tokens * p_in + most * p_out) / 1e6",
        "cost_max = (prompt_tokens * p_in + most * p_out) / 1e5",
        MONEY,
        "worst case 10x",
    ),
    Mutant(
        "dryrun-worst-ignores-max-tokens",
        "jswim/llm/dryrun.py",
        "most = max(client.max_completion_tokens, completion_tokens)",
        "most = completion_tokens",
        MONEY,
        "worst case = estimate",
    ),
    Mutant(
        "budget-ignores-in-flight",
        "jswim/llm/budget.py",
        "self.spent_usd + self.reserved_usd + usd > self.cap_usd",
        "self.spent_usd + usd > self.cap_usd",
        MONEY,
        "concurrent calls pass the cap together",
    ),
    Mutant(
        "budget-bound-scale",
        "jswim/llm/budget.py",
        "return (prompt * p_in + int(completion) * p_out) / 1e6",
        "return (prompt * p_in + int(completion) * p_out) / 1e8",
        MONEY,
        "a call's bound 100x too small",
    ),
    Mutant(
        "budget-settle-forgets",
        "jswim/llm/budget.py",
        "self.spent_usd += actual_usd",
        "self.spent_usd += 0.0 * actual_usd",
        MONEY,
        "spend never grows",
    ),
    Mutant(
        "budget-not-sticky",
        "jswim/llm/budget.py",
        "(self.exhausted or self.spent_usd",
        "(False or self.spent_usd",
        MONEY,
        "after the first refusal, smaller calls still go out",
    ),
    Mutant(
        "budget-ratio-unlearned",
        "jswim/llm/budget.py",
        "self.ratio = max(self.ratio, actual_usd / hold.bound_usd)",
        "self.ratio = self.ratio",
        CAP,
        "a provider billing 3x its reservations passes the cap with every wave in flight",
    ),
    Mutant(
        "unpriceable-at-zero",
        "jswim/llm/client.py",
        "cost = max(cost, reserved)",
        "cost = cost",
        CAP,
        "a server without usage is free: every call is sent",
    ),
    Mutant(
        "bad-body-released",
        "jswim/llm/client.py",
        "self.budget.settle(held, bound)",
        "self.budget.release(held)",
        CAP,
        "200s that are no chat completion are neither spent nor unanswered",
    ),
    Mutant(
        "ledger-forgets-unanswered",
        "jswim/llm/ledger.py",
        "return sum(self._bounds.values())",
        "return 0.0",
        CAP,
        "a resume forgets the requests that got no answer",
    ),
    Mutant(
        "price-swap",
        "jswim/llm/usage.py",
        "return (usage.prompt_tokens * p_in + usage.completion_tokens * p_out) / 1e6",
        "return (usage.prompt_tokens * p_out + usage.completion_tokens * p_in) / 1e6",
        CLIENT,
        "prompt billed at the completion price",
    ),
    Mutant(
        "price-shortest-prefix",
        "jswim/llm/usage.py",
        "key=len, default=None",
        "key=lambda k: -len(k), default=None",
        CLIENT,
        "gpt-4o-2024 priced as gpt-4",
    ),
    Mutant(
        "totals-bill-cache-hits",
        "jswim/llm/usage.py",
        "        if result.cache_hit:\n            self.cache_hits += 1\n        elif",
        "        if False:\n            self.cache_hits += 1\n        elif",
        CLIENT,
        "cache hits billed",
    ),
    Mutant(
        "pacing-rpm-interval",
        "jswim/llm/pacing.py",
        "AsyncLimiter(1, 60.0 / rpm)",
        "AsyncLimiter(1, 6.0 / rpm)",
        PACING,
        "--rpm 60 sends 10/s",
    ),
    Mutant(
        "pacing-remaining-ge",
        "jswim/llm/pacing.py",
        "if remaining is None or remaining >= margin:",
        "if remaining is None or remaining >= 0:",
        PACING,
        "x-ratelimit-remaining ignored",
    ),
    Mutant(
        "pacing-retry-after-ms",
        "jswim/llm/pacing.py",
        "after = ms / 1000.0 if ms",
        "after = ms / 1.0 if ms",
        PACING,
        "retry-after-ms read as seconds",
    ),
    # -- protocol: memory, requests, parsing ------------------------------------------------------
    Mutant(
        "clear-threshold-le",
        "jswim/agents/memory.py",
        "return total < self.threshold",
        "return total <= self.threshold",
        MEMORY,
        "clears at exactly 0.01 (the code: strictly below)",
    ),
    Mutant(
        "clear-window-head",
        "jswim/agents/memory.py",
        "progress[-self.window :]",
        "progress[: self.window]",
        MEMORY,
        "looks at the first steps",
    ),
    Mutant(
        "clear-min-steps",
        "jswim/agents/memory.py",
        "n_steps < self.min_steps",
        "n_steps <= self.min_steps",
        MEMORY,
        "first clear a step late",
    ),
    Mutant(
        "clear-no-rounding",
        "jswim/agents/memory.py",
        "total = round(total, self.decimals)",
        "total = total",
        MEMORY,
        "the code rounds to 3 decimals",
    ),
    Mutant(
        "protocol-shuffle-seed",
        "jswim/agents/protocol.py",
        'derived_seed(seed, step, "shuffle")',
        'derived_seed(seed, 0, "shuffle")',
        PROTOCOL,
        "one order for every step",
    ),
    Mutant(
        "protocol-sample-seed-temp",
        "jswim/agents/protocol.py",
        "if temperature > 0 else None",
        "if temperature >= 0 else None",
        PROTOCOL,
        "seeds sent at T=0",
    ),
    Mutant(
        "parse-rejection-ignored",
        "jswim/prompt.py",
        "and not _rejected(text[max(0, start - 40):start])",
        "",
        PROMPT,
        "'not [1, 1]' executes [1, 1]",
    ),
    Mutant(
        "parse-last-marker",
        "jswim/prompt.py",
        "for at in reversed(markers):",
        "for at in markers:",
        PROMPT,
        "the first 'answer' word wins",
    ),
    Mutant(
        "parse-unambiguous",
        "jswim/prompt.py",
        "if len({c[2] for c in cands}) == 1:",
        "if len({c[2] for c in cands}) >= 1:",
        PROMPT,
        "guesses among several candidates",
    ),
    # -- physics and the environment step ----------------------------------------------------------
    Mutant(
        "env-progress-sign-exact",
        ENV_STEP,
        "progress = (jnp.asarray(params.direction, f64) * dx)",
        "progress = (-jnp.asarray(params.direction, f64) * dx)",
        PROGRESS,
        "reward of the wrong sign (the exact path, every default run)",
    ),
    Mutant(
        "env-stuck-level",
        ENV_STEP,
        "stuck = ((roc == 1) & (level == 1))",
        "stuck = ((roc == 1) & (level == 0))",
        PHYSICS,
        "pushing past a limit moves",
    ),
    Mutant(
        "env-noise-factor",
        ENV_STEP,
        "factor = 1.0 + jnp.asarray(params.zeta, f64) * jnp.asarray(y_noise, f64)",
        "factor = 1.0 + 0.5 * jnp.asarray(params.zeta, f64) * jnp.asarray(y_noise, f64)",
        PHYSICS,
        "noise half as strong as zeta says",
    ),
    Mutant(
        "purcell-coefficient",
        "jswim/swimmers/purcell.py",
        "262 * f(dc - d1) - 26 * f(d1 + dc)",
        "262 * f(dc - d1) - 25 * f(d1 + dc)",
        PHYSICS,
        "one coefficient of the closed form off by one",
    ),
    Mutant(
        "purcell-rotation-sign",
        "jswim/swimmers/purcell.py",
        "dc_dot = 2.0 * (r1 * w1 + r2 * w2) / den",
        "dc_dot = 2.0 * (r1 * w1 - r2 * w2) / den",
        PHYSICS,
        "rotation of the middle link wrong",
    ),
    Mutant(
        "ng-velocity-factor",
        "jswim/swimmers/ng.py",
        "2.0 * (r1 / d2 - r2 / d1)) / 6.0",
        "2.0 * (r1 / d2 - r2 / d1)) / 5.0",
        PHYSICS,
        "NG speed 20% off",
    ),
    Mutant(
        "ng-step-log-sign",
        "jswim/swimmers/ng.py",
        "return (-math.log((d1b + d2) / (d1a + d2))",
        "return (math.log((d1b + d2) / (d1a + d2))",
        PHYSICS,
        "NG's exact step of arm 1 wrong",
    ),
)


COPY = ("jswim", "tests", "pyproject.toml", "README.md", "docs", "notebooks", "benchmarks")


def scratch_copy(root: Path, into: Path) -> None:
    for name in COPY:
        src = root / name
        if src.is_dir():
            shutil.copytree(
                src,
                into / name,
                ignore=shutil.ignore_patterns("__pycache__", "*.pyc", ".pytest_cache"),
            )
        elif src.exists():
            shutil.copy2(src, into / name)


def run_tests(copy: Path, tests: tuple[str, ...], timeout: float) -> tuple[str, float, str]:
    """``"pass"``, ``"fail"`` or ``"timeout"``, the seconds it took and pytest's last lines."""
    env = {**os.environ, "PYTHONPATH": str(copy), "PYTHONDONTWRITEBYTECODE": "1"}
    # -m "": every guarding test, the slow tier too (pyproject deselects it by default)
    cmd = [sys.executable, "-m", "pytest", "-q", "-x", "-p", "no:cacheprovider", "-m", "", *tests]
    t0 = time.perf_counter()
    try:
        proc = subprocess.run(
            cmd,
            cwd=copy,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            timeout=timeout,
            text=True,
        )
    except subprocess.TimeoutExpired:  # subprocess.run kills the child on timeout and on Ctrl-C
        return "timeout", time.perf_counter() - t0, ""
    dt = time.perf_counter() - t0
    tail = "\n".join(proc.stdout.splitlines()[-15:])
    if proc.returncode == 0:
        return "pass", dt, tail
    if proc.returncode in (1,):
        return "fail", dt, tail
    raise SystemExit(
        f"pytest exited {proc.returncode} (collection or usage error):\n{proc.stdout[-2000:]}"
    )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument(
        "--root",
        type=Path,
        default=ROOT,
        help="checkout whose code and tests are mutated (default: this one)",
    )
    ap.add_argument(
        "--only",
        default=None,
        help="run only mutants whose name contains one of these (comma-separated)",
    )
    ap.add_argument("--list", action="store_true", help="list the mutants and exit")
    ap.add_argument(
        "--timeout",
        type=float,
        default=900.0,
        help="seconds per pytest session (a timeout counts as caught)",
    )
    ap.add_argument(
        "--whole-files",
        action="store_true",
        help="run each mutant's whole test files, not the listed tests (for checkouts that lack them)",
    )
    ap.add_argument(
        "--no-baseline", action="store_true", help="skip the unmutated runs (when known green)"
    )
    args = ap.parse_args()
    # SIGTERM (kill, a batch system) unwinds like Ctrl-C, so the scratch copy is removed.
    signal.signal(signal.SIGTERM, lambda *_: (_ for _ in ()).throw(KeyboardInterrupt()))
    mutants = [m for m in MUTANTS if m.old]
    if args.whole_files:
        mutants = [
            dataclasses.replace(m, tests=tuple(dict.fromkeys(t.split("::")[0] for t in m.tests)))
            for m in mutants
        ]
    if args.only:
        words = [w for w in args.only.split(",") if w]
        mutants = [m for m in mutants if any(w in m.name for w in words)]
    if args.list:
        for m in mutants:
            print(
                f"{m.name:34} {m.path:28} {' '.join(sorted({Path(t.split('::')[0]).name for t in m.tests}))}"
            )
        return
    with tempfile.TemporaryDirectory(prefix="jswim-mutants-") as tmp:
        copy = Path(tmp)
        scratch_copy(args.root, copy)
        if not args.no_baseline:
            for tests in sorted({m.tests for m in mutants}):
                got, dt, tail = run_tests(copy, tests, args.timeout)
                print(
                    f"baseline {' '.join(Path(t).name for t in tests)}: {got} ({dt:.0f} s)",
                    file=sys.stderr,
                )
                if got != "pass":  # once more: a flaky test is reported, a red one stops the check
                    print(tail, file=sys.stderr)
                    got, dt, tail = run_tests(copy, tests, args.timeout)
                    print(f"  again: {got} ({dt:.0f} s) -- FLAKY if pass", file=sys.stderr)
                if got != "pass":
                    raise SystemExit(f"the unmutated tests do not pass: fix them first\n{tail}")
        rows = []
        for m in mutants:
            path = next((copy / p for p in m.path.split("|") if (copy / p).is_file()), None)
            if path is None:
                rows.append((m, "?", "gone (no such file)", 0.0))
                continue
            original = path.read_text()
            count = original.count(m.old)
            if count != 1:
                rows.append((m, "?", "gone" if count == 0 else f"ambiguous ({count})", 0.0))
                continue
            line = original[: original.index(m.old)].count("\n") + 1
            path.write_text(original.replace(m.old, m.new))
            try:
                got, dt, _ = run_tests(copy, m.tests, args.timeout)
            finally:
                path.write_text(original)
            verdict = {"fail": "caught", "timeout": "caught (timeout)", "pass": "SURVIVED"}[got]
            rows.append((m, line, verdict, dt))
            print(f"{m.name}: {verdict} ({dt:.0f} s)", file=sys.stderr)
    print("| mutant | place | change | tests | result |")
    print("|---|---|---|---|---|")
    for m, line, verdict, dt in rows:
        change = (
            f"`{m.old.strip()[:60]}` -> `{m.new.strip()[:60]}`"
            if m.new
            else f"`{m.old.strip()[:60]}` removed"
        )
        change = change.replace("\n", " ").replace("|", "\\|")
        tests = ", ".join(sorted({Path(t.split("::")[0]).stem for t in m.tests}))
        print(
            f"| {m.name} | {m.path.split('|')[0]}:{line} | {change} | {tests} | {verdict} ({dt:.0f} s) |"
        )
    survived = [r for r in rows if r[2] == "SURVIVED"]
    print(f"\n{len(rows) - len(survived)} of {len(rows)} caught; {len(survived)} survived.")


if __name__ == "__main__":
    main()
