"""``jswim bench``: one suite over several models at once, and a leaderboard."""

from __future__ import annotations

import argparse
import dataclasses
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

from jswim.bench.models_file import ModelsFile, check_unique, load_models_file, parse_model_option
from jswim.bench.suites import SUITES
from jswim.cli import options
from jswim.console import LOCAL_UNPRICED, Column, plain_table, terminal_width
from jswim.errors import ConfigError, check_size
from jswim.llm.reasoning import ESTIMATE_SHARE
from jswim.llm.urls import is_local_host
from jswim.llm.usage import price_table

#: Exit status when a model failed or stopped at its cap (the others finished).
EXIT_SOME_FAILED = 2


def register(sub: argparse._SubParsersAction) -> None:
    """Add ``jswim bench`` to ``sub``."""
    p = sub.add_parser(
        "bench",
        help="run a suite over several models at once and print a leaderboard",
        description="Run a suite (core: the paper's headline results; paper: every figure; or one "
        "of the models file's [suites]) over every model of a models file (TOML) or of "
        "repeated --model options, all at once, each model paced and capped on its "
        "own, next to the reference rule and the Q-learning and random baselines; "
        "write each model's studies as ordinary study folders and a leaderboard "
        "(table, CSV, JSON, figure). The same command resumes.",
    )
    p.add_argument(
        "models_file",
        nargs="?",
        default=None,
        metavar="MODELS.toml",
        help="the models file ([[models]] entries, optional [prices] and [suites.NAME])",
    )
    p.add_argument(
        "--model",
        dest="model_options",
        action="append",
        default=[],
        metavar="KEY=VALUE,...",
        help="a model on the command line: base_url=URL,model=NAME[,name=LABEL,api_key_env=VAR,"
        "concurrency=N,rpm=N,tpm=N,max_cost=USD,reasoning=auto|on|off,...]; repeatable",
    )
    p.add_argument(
        "--suite",
        default="core",
        metavar="NAME",
        help="core (default), paper, or a [suites.NAME] of the models file",
    )
    p.add_argument(
        "--out",
        default=None,
        metavar="FOLDER",
        help="bench folder (default jswim-out/bench-<suite>)",
    )
    p.add_argument(
        "--dry-run",
        action="store_true",
        help="price the whole bench per model (calls, tokens, cost) and exit; nothing is sent or written",
    )
    p.add_argument("--no-reference", action="store_true", help="leave out the reference rule's row")
    p.add_argument(
        "--no-baselines", action="store_true", help="leave out the Q-learning and random rows"
    )
    g = p.add_argument_group(
        "sizes (change the suite: recorded, and its rows are then not the suite's own)"
    )
    g.add_argument("--runs", type=int, default=None, help="LLM runs per setting in every part")
    g.add_argument(
        "--q-runs", type=int, default=None, help="baseline runs per setting in every part"
    )
    g.add_argument("--steps", type=int, default=None, help="steps per run in every part")
    p.add_argument(
        "--samples",
        type=int,
        default=None,
        metavar="N",
        help="independent samples of every LLM run (each its own run id and seed), pooled into each "
        "row with the count shown; grows an existing bench folder (recorded, not part of the "
        "suite's definition)",
    )
    p.set_defaults(command_main=main)


def _models(args: argparse.Namespace) -> tuple[Any, Any]:
    mf = load_models_file(args.models_file) if args.models_file else ModelsFile(())
    models = mf.models + tuple(parse_model_option(t) for t in args.model_options)
    check_unique(models)
    return mf, models


def _suite(args: argparse.Namespace, mf: Any) -> Any:
    suites = {**SUITES, **{s.name: s for s in mf.suites}}
    if args.suite not in suites:
        raise ConfigError(f"unknown suite {args.suite!r}; choose one of {', '.join(suites)}")
    sizes = tuple(
        (k, getattr(args, k)) for k in ("runs", "q_runs", "steps") if getattr(args, k) is not None
    )
    for k, v in (*sizes, ("samples", args.samples)):
        if v is not None:
            check_size(k, v)
    return dataclasses.replace(suites[args.suite], sizes=sizes, samples=args.samples)


def main(args: argparse.Namespace) -> int:
    from jswim.bench import (
        runner,
    )  # lazy: start-up (NumPy and the study folders' readers)

    mf, models = _models(args)
    suite = _suite(args, mf)
    out = Path(args.out or f"jswim-out/bench-{suite.name}")
    if args.dry_run:
        return _dry_run(suite, models, mf, out)
    meta, lock = runner.open_folder(
        out,
        {
            **runner.definition(suite, models, not args.no_reference, not args.no_baselines),
            "status": "running",
        },
    )
    try:
        return _run(args, suite, models, mf, out, meta)
    finally:
        lock.release()


def _run(args: argparse.Namespace, suite: Any, models: Any, mf: Any, out: Path, meta: Any) -> int:
    """The bench in its locked folder: run the parts, write the record and the leaderboard."""
    from jswim.bench import (
        leaderboard,
        runner,
    )  # lazy: start-up (NumPy and the study folders' readers)

    prices_file = None
    if mf.prices is not None:
        prices_file = out / "prices.json"
        try:
            runner.atomic_write(
                prices_file, json.dumps({"as_of": mf.prices_as_of, "prices": mf.prices}, indent=1)
            )
        except OSError as exc:
            raise ConfigError(
                f"cannot write {prices_file} ({exc.strerror or exc}); choose a writable --out"
            ) from None
    say = lambda text: print(text, file=sys.stderr, flush=True)
    say(
        f"bench {suite.name} (seed {suite.seed}) in {out}: {len(models)} model(s)"
        + ("" if args.no_reference else " + the reference rule")
        + ("" if args.no_baselines else " + baselines")
    )
    ref = None
    if not args.no_reference:
        from jswim.llm.reference import (
            ReferenceServer,
        )  # lazy: start-up (the reference rule loads only for a run)

        ref = ReferenceServer().start()
    try:
        jobs = runner.plan(
            models,
            suite,
            out,
            prices_file=prices_file,
            reference_url=ref.url if ref else None,
            baselines=not args.no_baselines,
        )
        outcome = runner.run_jobs(jobs, out, meta, say)
    finally:
        if ref is not None:
            ref.stop()
    meta["model_status"].update(outcome.status)
    meta["status"] = bench_status(outcome.status, outcome.interrupted)
    runner.write_meta(out, meta)
    rows = _rows(jobs, models, mf, outcome.status)
    missing = _missing(jobs, rows, meta["model_status"], outcome.stopped_at)
    paths = leaderboard.write_files(out, rows, meta, missing)
    if rows:  # the pictures layer draws what the bench computed
        from jswim.figures.leaderboard import figure  # lazy: matplotlib, only for a bench with rows

        paths += figure(out, rows)
    print(
        f"bench {suite.name}: {suite.about or 'user suite'} (seed {suite.seed}"
        + (f"; sizes changed: {dict(suite.sizes)}" if suite.sizes else "")
        + (f"; {suite.samples} samples of every LLM run" if (suite.samples or 1) > 1 else "")
        + ")"
    )
    print(leaderboard.table_text(rows, width=terminal_width()))
    for line in leaderboard.unpriced_notes(rows) + leaderboard.missing_text(
        missing
    ):  # under the table
        print(line)
    print(
        "success p: the paper's criterion, 95% Wilson interval; steps to learn counted from 1 over the runs that "
        "learned; suite $: what the model's calls cost over the whole suite"
    )
    for line in _sent_notes(jobs):
        print(line)
    for p in paths:
        print(f"wrote {p}")
    if outcome.interrupted:
        print(
            f"interrupted; finished runs and answered calls are kept in {out}. Run the same command to resume.",
            file=sys.stderr,
        )
        return 130
    bad = {k: v for k, v in outcome.status.items() if v not in ("complete",)}
    for label, status in bad.items():
        print(f"jswim: error: model {label}: {status}", file=sys.stderr)
    return EXIT_SOME_FAILED if bad else 0


def bench_status(status: dict[str, str], interrupted: bool) -> str:
    """What happened to the bench as a whole: ``interrupted``; ``complete`` when every row
    finished; ``incomplete`` when some did; when none did, what stopped them all if it was
    one thing (``stopped at the cost cap``), else ``failed``."""
    if interrupted:
        return "interrupted"
    done = [v == "complete" for v in status.values()]
    if all(done):
        return "complete"
    if any(done):
        return "incomplete"
    kinds = set(status.values())
    return kinds.pop() if len(kinds) == 1 and "stopped at the cost cap" in kinds else "failed"


def _sent_notes(jobs: list[Any]) -> list[str]:
    """What a reasoning model was sent instead of the paper's settings, once per model (from its folders)."""
    from jswim.results import read_metadata  # lazy: start-up (NumPy)

    out: list[str] = []
    for j in jobs:
        if j.kind != "llm" or not (j.folder / "metadata.json").exists():
            continue
        sent = (read_metadata(j.folder).get("summary") or {}).get("reasoning") or {}
        for note in sent.get("notes") or ():
            line = f"{j.label}: {note}"
            if line not in out:
                out.append(line)
    return out


def _missing(
    jobs: list[Any],
    rows: list[dict[str, Any]],
    status: dict[str, str],
    stopped_at: dict[str, str] | None = None,
) -> list[dict[str, Any]]:
    """Every study folder of the bench that gave no leaderboard row, and why: its own study's
    last error when it ran and failed, the part that stopped its model when it was skipped, else
    its label's status, else that it has no finished run yet."""
    from jswim.bench import runner  # lazy: start-up (NumPy)

    have = {
        (r["kind"], r["part"]) if r["kind"] == "baseline" else (r["row"], r["part"]) for r in rows
    }
    out = []
    for j in jobs:
        if ("baseline" if j.kind == "baseline" else j.label, j.part.name) in have:
            continue
        why = status.get(j.label, "not run")
        stop = (stopped_at or {}).get(j.label)
        if stop is not None and stop != j.part.name and j.rc is None:
            why = f"not run: {j.label} stopped at {stop} ({why})"
        elif (
            stop != j.part.name
            and j.rc not in (None, 0, 3)
            and j.log is not None
            and j.log.exists()
        ):  # this part failed, and its label's status speaks of another part: quote its own
            why = f"failed: {runner.last_error(j.log)}"
        elif why in ("complete", "running"):
            why = (
                runner.last_error(j.log)
                if j.log is not None and j.log.exists()
                else "no finished run yet"
            )
        row = "Q-learning and random" if j.kind == "baseline" else j.label
        out.append({"row": row, "kind": j.kind, "part": j.part.name, "why": why})
    return out


def _unpriced(m: Any, mf: Any) -> str | None:
    """Why a model's calls are not priced (None: they are), in `jswim.console.cost_text`'s words."""
    local = is_local_host(m.get("base_url"))
    table, why = price_table(
        mf.prices, m.get("model"), local_host=local, price_local=bool(m.get("price_local"))
    )
    if why is not None:
        return why
    if table.entry(m.get("model")) is None:
        return (
            LOCAL_UNPRICED
            if local
            else f"no price for {m.get('model')!r} in the price table; [prices] prices it"
        )
    return None


def _rows(jobs: list[Any], models: Any, mf: Any, status: dict[str, str]) -> list[dict[str, Any]]:
    from jswim.bench import (
        leaderboard,
        runner,
    )  # lazy: start-up (NumPy and the study folders' readers)

    cost = {m.name: sum(runner.spent(j.folder) for j in jobs if j.label == m.name) for m in models}
    why = {m.name: _unpriced(m, mf) for m in models}
    rows: list[dict[str, Any]] = []
    for j in jobs:
        got = leaderboard.folder_rows(
            j.folder,
            j.label,
            j.kind,
            j.part.name,
            cost.get(j.label, 0.0),
            why.get(j.label) is None,
            status.get(j.label, "complete"),
        )
        for r in got:
            r["unpriced"] = why.get(j.label) if j.kind == "llm" else None
        rows += got
    return rows


def _dry_run(suite: Any, models: Any, mf: Any, out: Path) -> int:
    """Price every model's suite in process (nothing sent, nothing written); each job's argv is read
    as ``jswim study`` reads it (`jswim.cli.options`)."""
    from jswim.bench import runner  # lazy: start-up (NumPy)
    from jswim.studies.run import estimate_study  # lazy: JAX loads only for commands that run

    with tempfile.TemporaryDirectory() as tmp:
        prices_file = None
        if mf.prices is not None:
            prices_file = Path(tmp) / "prices.json"
            prices_file.write_text(json.dumps({"as_of": mf.prices_as_of, "prices": mf.prices}))
        jobs = runner.plan(
            models, suite, out, prices_file=prices_file, reference_url=None, baselines=False
        )
        totals: dict[str, dict[str, Any]] = {}
        parser = options.study_parser()
        for j in jobs:
            args = parser.parse_args(j.argv)
            study = args.name  # jswim swim's parser sets its study's name
            est = estimate_study(
                study, options.options(args, study), options.backend(args), j.folder
            )
            t = totals.setdefault(
                j.label,
                {
                    "model": j.model.get("model"),
                    "calls": 0,
                    "prompt_tokens": 0,
                    "completion_tokens": 0,
                    "reasoning_tokens": 0,
                    "cost_usd": 0.0,
                    "cost_max_usd": 0.0,
                    "priced": bool(est.price_in or est.price_out),
                    "prices_as_of": est.prices_as_of,
                    "note": est.unpriced,
                    "reasoning_budget": est.reasoning_budget,
                    "reasoning_warning": est.reasoning_warning,
                },
            )
            for k in (
                "calls",
                "prompt_tokens",
                "completion_tokens",
                "reasoning_tokens",
                "cost_usd",
                "cost_max_usd",
            ):
                t[k] += getattr(est, k)
    cols = [
        Column("model", False),
        Column("calls"),
        Column("prompt tok"),
        Column("completion tok"),
        Column("of which reasoning"),
        Column("cost $"),
        Column("at most $"),
        Column("prices", False),
    ]
    cells = [
        [
            name,
            f"{t['calls']:,}",
            f"{t['prompt_tokens']:,}",
            f"{t['completion_tokens']:,}",
            f"~{t['reasoning_tokens']:,}" if t["reasoning_budget"] else "-",
            f"{t['cost_usd']:.2f}" if t["priced"] else "not priced",
            f"{t['cost_max_usd']:.2f}" if t["priced"] else "-",
            t["prices_as_of"]
            if t["priced"]
            else (t["note"] or f"no price for {t['model']!r}: --prices FILE"),
        ]
        for name, t in totals.items()
    ]
    print(
        f"dry run of bench {suite.name} (seed {suite.seed}): {len(suite.parts)} part(s) per model "
        f"({', '.join(p.name for p in suite.parts)}); no request sent, nothing written"
    )
    print(plain_table(cols, cells))
    total = sum(t["cost_usd"] for t in totals.values() if t["priced"])
    print(
        f"total: ${total:.2f} for the priced models; the reference rule and the baselines are not priced (a rule and "
        "baselines on this machine; $0 counted); not counted: "
        "parse retries"
    )
    thinking = [name for name, t in totals.items() if t["reasoning_budget"]]
    if thinking:
        print(
            f"reasoning models ({', '.join(thinking)}): their thinking is in the completion tokens and the cost, "
            "estimated as a share of the reasoning budget per call ("
            + ", ".join(f"{v:g} {k or 'default'}" for k, v in ESTIMATE_SHARE.items())
            + " reasoning_effort; an assumption, not a measurement); 'at most' is every call using its whole budget"
        )
    for name, t in totals.items():
        if t["reasoning_warning"]:
            print(f"warning: {name}: {t['reasoning_warning']}")
    caps = {m.name: m.max_cost for m in models if m.max_cost is not None}
    for name, t in totals.items():
        cap = caps.get(name)
        if cap is None or not t["priced"]:
            continue
        if t["cost_usd"] > cap:
            print(
                f"warning: {name}: its max_cost ${cap:g} is below the estimated ${t['cost_usd']:.2f}: the suite "
                "would stop at the cap, its later parts skipped (raise max_cost, or the same command with a "
                "higher one goes on, paying no call twice)"
            )
        elif t["cost_max_usd"] > cap:
            print(
                f"note: {name}: its max_cost ${cap:g} covers the estimate (${t['cost_usd']:.2f}) but not the worst "
                f"case (${t['cost_max_usd']:.2f}): long replies would stop it at the cap"
            )
    print(json.dumps({"suite": suite.name, "models": totals, "total_usd": total}, sort_keys=True))
    return 0


def show_text(folder: Path, width: int | None = None) -> str:
    """``jswim show BENCH``: the bench's definition, each model's status and its last leaderboard
    (read from ``bench.json`` and ``leaderboard.json``; nothing is run or written)."""
    from jswim.bench import leaderboard  # lazy: start-up (the study folders' readers)

    from jswim.bench.runner import read_record  # lazy: start-up (the bench's readers)

    meta = read_record(folder / "bench.json")
    suite = meta.get("suite") if isinstance(meta.get("suite"), dict) else {}
    status = meta.get("status")
    if status == "running":  # as a study's show says it: is a live session still running it?
        from jswim._io.folderlock import describe_holder, holder  # lazy: start-up (show only)

        info = holder(folder)
        status = (
            f"running now: {describe_holder(info)}"
            if info is not None and info.get("alive") is not False
            else "running, but no live session holds the folder (killed?); the same command resumes"
        )
    lines = [
        f"bench {suite.get('name')} (seed {suite.get('seed')}) in {folder}: {status}"
        + (
            f"; {meta['samples']} samples of every LLM run"
            if isinstance(meta.get("samples"), int) and meta["samples"] > 1
            else ""
        )
    ]
    status = meta.get("model_status")
    lines += [
        f"  {name}: {status}"
        for name, status in (status if isinstance(status, dict) else {}).items()
    ]
    try:
        board = read_record(folder / "leaderboard.json")
    except ConfigError:
        board = {}
    rows = leaderboard.valid_rows(board.get("rows"))
    if rows:
        lines += ["", leaderboard.table_text(rows, width=width)] + leaderboard.unpriced_notes(rows)
    else:
        lines.append("no leaderboard yet: the same jswim bench command writes it")
    missing = board.get("missing")
    lines += leaderboard.missing_text(
        [m for m in missing if isinstance(m, dict)] if isinstance(missing, list) else []
    )
    lines.append(f"each model's studies: {folder}/<model>/<part>/ (jswim show on each)")
    return "\n".join(lines)
