"""``jswim swim`` and ``jswim study NAME``: run a study (argv -> options in `jswim.cli.options`),
publish it (figures and report.html, `jswim.viz.publish`; ``--no-figures`` skips that), then print
its summary, scene table, LLM calls and cost, and where the folder, page and figures are."""

from __future__ import annotations

import argparse
import json
import signal
import sys
from pathlib import Path
from typing import Any
from collections.abc import Sequence

from jswim._io import interrupts
from jswim.cli import base, options
from jswim.console import (
    EMBEDDED_UNPRICED,
    LOCAL_UNPRICED,
    REFERENCE_UNPRICED,
    Progress,
    cost_text,
    phase_ticker,
    print_table,
    requests_text,
)
from jswim.errors import ConfigError, LLMServerError
from jswim.llm.urls import is_local_host


def register(sub: argparse._SubParsersAction) -> None:
    for p in options.add_study_commands(sub):
        p.set_defaults(command_main=main)


def main(args: argparse.Namespace) -> int:
    return _run(args.name, args)  # jswim swim's parser sets its study's name


#: Exit status of a study stopped by ``--max-cost`` (cleanly: rerun with a higher cap to go on).
EXIT_COST_CAP = 3


def _publish(folder: Path) -> list[Path]:
    """The publish step (`jswim.viz.publish.report`): the folder's figures and ``report.html``.

    The runs are safe on disk by now: a page or figure that cannot be written is a warning, not a
    lost study; the figure files are returned (none when it failed)."""
    from jswim.viz.publish import report  # lazy: matplotlib, which --no-figures never loads

    try:
        with base.warnings_as_lines():
            return report(folder).figures
    except Exception as exc:
        base.warn(
            f"report.html not written ({type(exc).__name__}: {exc}); jswim report {folder} retries"
        )
        return []


def _run(study: str, args: argparse.Namespace) -> int:
    from jswim.studies import (
        default_folder,
        run_study,
    )  # lazy: JAX loads only for commands that run
    from jswim.studies.specs import short_steps_warning  # lazy: as above
    from jswim.studies.session import check_max_cost  # lazy: as above

    opts, backend = options.options(args, study), options.backend(args)
    check_max_cost(args.max_cost)
    out = Path(args.out) if args.out else default_folder(study, opts, backend)
    try:
        out.stat()
    except FileNotFoundError:
        pass  # a new folder
    except OSError as exc:  # a name longer than the file system allows, a file on the way, ...
        raise ConfigError(
            f"cannot write --out {out}: {exc.strerror or type(exc).__name__}; choose another --out"
        ) from None
    if args.dry_run:
        from jswim.studies.run import estimate_study  # lazy: JAX loads only for commands that run

        est = estimate_study(study, opts, backend, out, max_cost=args.max_cost)
        print("\n".join(est.lines()))
        print(json.dumps(est.as_dict(), sort_keys=True))  # the same, for scripts
        return 0
    if (text := short_steps_warning(opts, study)) is not None:
        base.warn(text)
    with Progress() as bar:
        tick = phase_ticker(bar)

        try:
            with base.warnings_as_lines():
                result = run_study(
                    study,
                    opts,
                    backend,
                    out,
                    progress=tick,
                    max_cost=args.max_cost,
                )
        except KeyboardInterrupt:
            bar.stop()
            sig = interrupts.received()
            print(
                f"jswim: interrupted ({interrupts.name(sig)}); every finished run and answered call is kept in "
                f"{out}. Run the same command to resume (jswim report {out}: a page of what is done).",
                file=sys.stderr,
            )
            return 128 + (sig or signal.SIGINT)
        except (
            LLMServerError
        ) as exc:  # the retry budget is spent: the study stops cleanly, nothing lost
            bar.stop()
            print(f"jswim: error: {exc}. {_kept(out)}", file=sys.stderr)
            return base.EXIT_USAGE
        bar.update("done", len(result.rows), len(result.rows), f"{result.wall_s:.1f} s", final=True)
    if not args.no_figures:  # the study ended at its folder; the pictures are drawn from it
        result.figures = _publish(result.folder)
    _print_summary(
        study,
        result.summary.to_dict("records"),
        result.rows,
        f"{study}: {len(result.rows)} runs in {result.wall_s:.1f} s",
    )
    _print_reasoning(result)
    for note in result.notes:
        print(note)
    sp = result.llm_speed
    from jswim.results import as_run_rows  # lazy: start-up (results loads NumPy)

    n_llm = sum(r.agent == "llm" for r in as_run_rows(result.rows))
    if not sp and n_llm:  # a resume with every LLM run done
        from jswim.llm.ledger import folder_money  # lazy: httpx loads only for commands that run

        print(
            f"LLM calls: none this session (every LLM run was done already; nothing sent, nothing paid); the "
            f"study's calls: {_cost_clause(None, folder_money(result.folder)[0], backend)}"
        )
    if sp.get("calls"):
        print(
            f"LLM calls: {sp['calls']:.0f} ({sp.get('billed_calls', 0):.0f} sent, "
            f"{sp.get('replayed_calls', 0):.0f} replayed from earlier sessions), {sp.get('tokens', 0):,.0f} tokens, "
            + _cost_clause(sp.get("cost_usd", 0), sp.get("study_cost_usd", 0), backend)
        )
    if sp.get("requests") is not None and (sp.get("calls") or sp.get("requests")):
        print(f"HTTP requests: {requests_text(sp)}")
    print(f"results: {result.folder}")
    if not args.no_figures and (result.folder / "report.html").is_file():  # not an old page
        print(f"report:  {result.folder / 'report.html'} (open it in a browser)")
    for f in result.figures:
        if f.suffix == ".png":
            print(f"figure:  {f}")
    if result.stopped == "cost cap":
        print(
            f"jswim: stopped at the cost cap (--max-cost {args.max_cost:g}): ${sp.get('study_cost_usd', 0):.4f} "
            f"spent; {len(result.rows)} of {result.total} runs done and kept in {result.folder}. Rerun with a "
            "higher --max-cost to continue (no call is paid twice)",
            file=sys.stderr,
        )
        return EXIT_COST_CAP
    if result.failed_runs:
        first = result.failed_runs[0]
        print(
            f"jswim: error: {len(result.failed_runs)} of {n_llm} LLM runs failed ({first['run_id']}: "
            f"{first['error']}); they are recorded as failed in {result.folder}: run the same command to "
            "run them again",
            file=sys.stderr,
        )
        return base.EXIT_USAGE
    return 0


def _print_reasoning(result: Any) -> None:
    """What a reasoning model was sent, and the replies cut off (never executed)."""
    sent = result.reasoning or {}
    for note in sent.get("notes") or ():
        print(f"reasoning model: {note}")
    if sent.get("active") and not sent.get("notes"):
        print(
            f"reasoning: {sent.get('token_field')}={sent.get('budget')} (--reasoning {sent.get('mode')})"
        )
    from jswim.results import as_run_rows  # lazy: start-up (results loads NumPy)

    thought = sum(r.reasoning_tokens or 0 for r in as_run_rows(result.rows) if r.agent == "llm")
    if thought:
        print(f"reasoning tokens: {thought:,} (priced as output)")
    if sent.get("active"):
        cut = sum(result.truncated.values())
        if cut:
            print(
                f"{cut} replies cut at {sent.get('token_field')}={sent.get('budget')}, {result.cut_thinking} of them "
                "while still thinking (no answer, never executed; each went to the follow-up); raise --max-tokens"
            )
        return
    for limit, n in sorted(result.truncated.items()):
        print(
            f"{n} replies cut at max_tokens={limit} (no answer; each went to the follow-up)"
            + (
                f", {result.cut_thinking} of them while still thinking"
                if result.cut_thinking
                else ""
            )
            + "; a reasoning model needs room to think: --reasoning on (or a larger --max-tokens)"
        )


def _price_note(backend: Any) -> tuple[str | None, str]:
    """Where a cost line's prices come from, or why the model has none (never a silent $0):
    ``(why not priced, None)`` or ``(None, where the prices come from)``. The user's ``--prices``
    price any model they name, the reference rule included (the client bills by them)."""
    from jswim.llm.reference import (
        MODEL as REFERENCE_MODEL,
    )  # lazy: start-up (the reference rule loads only for a run)
    from jswim.llm.usage import (
        PRICES_AS_OF,
        price_table,
    )  # lazy: httpx loads only for commands that run

    if backend is None or backend.local:
        return EMBEDDED_UNPRICED, ""
    table, why = price_table(
        dict(backend.prices) if backend.prices is not None else None,
        backend.model,
        local_host=is_local_host(backend.base_url),
        price_local=backend.price_local,
    )
    if why:
        return why, ""
    if table.entry(backend.model) is None:
        if backend.model == REFERENCE_MODEL:
            return REFERENCE_UNPRICED, ""
        if is_local_host(backend.base_url) and backend.prices is None:
            return LOCAL_UNPRICED, ""
        return (
            f"no price for {backend.model!r} in the "
            f"{'price table ' + backend.prices_as_of if backend.prices else 'built-in price table of ' + PRICES_AS_OF}"
            "; --prices FILE prices it"
        ), ""
    return None, f"prices of {backend.prices_as_of or PRICES_AS_OF}" + (
        "" if backend.prices else " (built-in list prices)"
    )


def _cost_clause(session_usd: float | None, study_usd: float, backend: Any) -> str:
    """The dollars of a study's cost line, true to how its calls were priced: ``$a this
    session, $b for the study (prices of ...)``; calls with no price say why, with no dollar
    figure (``not priced (WHY); $0 counted``), and dollars that earlier sessions were billed
    under their prices are named as theirs (``session_usd`` ``None``: no call this session)."""
    why, source = _price_note(backend)
    this = "" if session_usd is None else f"${session_usd:.4f} this session, "
    if why is None:
        return f"{this}${study_usd:.4f} for the study ({source})"
    if not study_usd and not session_usd:
        return cost_text(None, why)
    if session_usd:  # billed after all (a price the client found): the dollars are the ledger's
        return f"{this}${study_usd:.4f} for the study"
    now = "" if session_usd is None else f"this session's calls {cost_text(None, why)}; "
    return f"{now}${study_usd:.4f} for the study, billed in earlier sessions under their prices"


def _kept(out: Path) -> str:
    """What a stopped session leaves: ``The study stopped cleanly: 3 of 8 runs done and kept ...``."""
    from jswim.results import read_runs  # lazy: start-up (results loads NumPy)

    try:
        done, planned = (
            len(read_runs(out)),
            (json.loads((out / "metadata.json").read_text()) or {}).get("n_planned"),
        )
    except (OSError, ValueError, AttributeError):
        done, planned = 0, None
    of = f" of {planned}" if isinstance(planned, int) else ""
    if not done and not (out / "calls.jsonl").exists():
        return "Nothing was done yet; run the same command once the server is back"
    return (
        f"The study stopped cleanly: {done}{of} runs done and kept in {out}, every answered call journaled; "
        "run the same command to resume (no call is paid twice)"
    )


def _print_summary(
    study: str, summary: Sequence[dict[str, Any]], rows: Sequence[dict[str, Any]], title: str
) -> None:
    """The study's tables (`jswim.studies.overview.study_tables`), the run's ``title`` over the
    first (or above them, where the first has its own caption), then the LLM runs' notes."""
    from jswim.agents.fidelity import (
        describe_constraint,
    )  # lazy: JAX loads only for commands that run
    from jswim.studies.overview import study_tables  # lazy: as above

    tables = study_tables(study, rows, summary)
    if not tables or tables[0].caption:
        print(title)
    for t in tables:
        print_table(t.columns, t.cells, t.caption or title)
        for note in t.notes:
            print(note)
    from jswim.results import as_run_rows  # lazy: as above

    llm = [r for r in as_run_rows(rows) if r.agent == "llm"]
    if line := describe_constraint(r.constraint for r in llm):
        print(line)
    if any(r.share_identical for r in llm):
        print(
            "LLM runs: --share-identical: identical requests of different runs were sent once, so runs from one "
            "start are copies of one run, not independent repeats"
        )
