"""Running a bench: every model's suite at once, each model in its own processes and folders.

Each study is a ``jswim study`` child process with the model's own flags, so every model is
paced, bounded and capped on its own and one model's failure stops only that model; a model's
parts run one after another. The bench owns its children as a study owns its runs: the bench
holds its folder's lock, each child's cap is what the model's ``max_cost`` leaves after its other
parts' spent and unanswered calls (from their ledgers, passed exactly), a child dies with the
bench (Linux: ``PR_SET_PDEATHSIG``), and a child's arguments travel in its environment, not on a
command line. The bench folder's layout, Ctrl-C and resume are in docs/bench.md (*How it runs*).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from collections.abc import Callable, Sequence

from jswim._io.folderlock import HOLDER, LOCK, FolderLock
from jswim.bench.models_file import ModelEntry
from jswim.bench.suites import Part, Suite
from jswim.errors import ConfigError
from jswim.results import atomic_write, dumps
from jswim.llm.credentials import scrub
from jswim.llm.ledger import folder_money
from jswim.llm.reference import MODEL
from jswim.llm.urls import safe_url

REFERENCE = "reference"
BASELINES = "baselines"


@dataclass
class Job:
    """One study folder of the bench and the command that fills it."""

    label: str  # model name, "reference" or "baselines"
    kind: str  # "llm", "reference", "baseline"
    part: Part
    folder: Path
    argv: list[str]
    model: ModelEntry | None = None
    proc: subprocess.Popen | None = None
    rc: int | None = None
    log: Path | None = None


def _ignores(study: str) -> tuple[str, ...]:
    from jswim.studies.study import get  # lazy: the study kinds load JAX

    return get(study).ignores


def part_args(part: Part, suite: Suite) -> list[str]:
    """The part's study command with the bench's size overrides (those the study uses)."""
    sizes = {k: v for k, v in suite.sizes if k not in _ignores(part.study)}
    return part.args(suite.seed, sizes, suite.samples)


def plan(
    models: Sequence[ModelEntry],
    suite: Suite,
    out: Path,
    *,
    prices_file: Path | None,
    reference_url: str | None,
    baselines: bool = True,
) -> list[Job]:
    """Every study folder of the bench: per model (and the reference rule) and part; the baselines."""
    jobs: list[Job] = []
    for part in suite.parts:
        uses_baselines = "q_runs" not in _ignores(part.study)
        base = part_args(part, suite)
        for m in models:
            argv = base + m.args() + (["--prices", str(prices_file)] if prices_file else [])
            argv += ["--q-runs", "0"] if uses_baselines else []
            jobs.append(Job(m.name, "llm", part, out / m.name / part.name, argv, m))
        if reference_url is not None:
            argv = (
                base
                + ["--base-url", reference_url, "--model", MODEL]
                + (["--q-runs", "0"] if uses_baselines else [])
            )
            jobs.append(Job(REFERENCE, "reference", part, out / REFERENCE / part.name, argv))
        if baselines and uses_baselines:
            jobs.append(
                Job(
                    BASELINES, "baseline", part, out / BASELINES / part.name, base + ["--runs", "0"]
                )
            )
    for j in jobs:
        j.argv = j.argv + ["--out", str(j.folder), "--no-figures"]
        j.log = j.folder.parent / f"{j.part.name}.log"
    return jobs


def definition(
    suite: Suite, models: Sequence[ModelEntry], reference: bool, baselines: bool
) -> dict[str, Any]:
    return {
        "suite": suite.describe(),
        "samples": suite.samples or 1,
        "reference": reference,
        "baselines": baselines,
        "models": [m.describe() for m in models],
    }


def read_record(path: Path, hint: str = "") -> dict[str, Any]:
    """A bench's JSON record (``bench.json``, ``leaderboard.json``) as an object.

    Raises
    ------
    ConfigError
        Unreadable, not JSON, or not a JSON object (one line).
    """
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        why = getattr(exc, "strerror", None) or str(exc).splitlines()[0]
        raise ConfigError(f"{path} is not a bench record ({why}){hint}") from None
    if not isinstance(data, dict):
        raise ConfigError(
            f"{path} is not a bench record (a JSON {type(data).__name__}, not an object){hint}"
        )
    return data


def open_folder(out: Path, meta: dict[str, Any]) -> tuple[dict[str, Any], Any]:
    """Create or resume a bench folder and lock it; refuse one made with another suite definition.

    Returns the bench's record and the held `jswim._io.folderlock.FolderLock` (release it
    when the bench ends).

    Raises
    ------
    ConfigError
        ``out`` is a file, or a folder that is no bench of this suite, or cannot be written.
    FolderBusyError
        Another jswim session holds the bench.
    """
    if out.exists() and not out.is_dir():
        raise ConfigError(f"--out {out} is a file, not a folder; choose a folder")
    path = out / "bench.json"
    if (
        out.exists()
        and not path.exists()
        and any(p.name not in (LOCK, HOLDER) for p in out.iterdir())
    ):
        raise ConfigError(f"{out} is not empty and is not a bench folder; use another --out")
    try:
        out.mkdir(parents=True, exist_ok=True)
        lock = FolderLock(out).acquire()  # one bench per folder, before anything is read
    except OSError as exc:
        raise ConfigError(
            f"cannot write the bench folder {out} ({exc.strerror or exc}); choose a writable --out"
        ) from None
    try:
        if path.exists():
            old = read_record(path, "; use another --out")
            suite = old.get("suite")
            if suite != json.loads(dumps(meta["suite"])):  # compared as stored (tuples: lists)
                name = suite.get("name") if isinstance(suite, dict) else suite
                raise ConfigError(
                    f"{out} holds a bench of another suite definition ({name!r}, "
                    "its parts, seed or sizes differ); use another --out to keep both"
                )
            status = old.get("model_status")
            status = {str(k): v for k, v in (status if isinstance(status, dict) else {}).items()}
            meta = {**old, **meta, "model_status": status}
    except BaseException:
        lock.release()
        raise
    meta.setdefault("model_status", {})
    try:
        write_meta(out, meta)
    except BaseException:
        lock.release()
        raise
    return meta, lock


def write_meta(out: Path, meta: dict[str, Any]) -> None:
    """Write ``bench.json`` (one line on an unwritable folder)."""
    try:
        atomic_write(out / "bench.json", dumps(meta, indent=1))
    except OSError as exc:
        raise ConfigError(
            f"cannot write {out / 'bench.json'} ({exc.strerror or exc}); choose a writable --out"
        ) from None


def spent(folder: Path) -> float:
    """What a study folder's calls cost (recomputed from its journal and ledger)."""
    return folder_money(folder)[0] if folder.is_dir() else 0.0


def committed(folder: Path) -> float:
    """What a study folder spent plus what its unanswered requests may still be billed."""
    if not folder.is_dir():
        return 0.0
    paid, unanswered = folder_money(folder)
    return paid + unanswered


def shown_argv(argv: Sequence[str]) -> str:
    """A study's arguments as a log may show them: no URL user info, no request field's value."""
    out: list[str] = []
    hide = None
    for a in argv:
        if hide == "--base-url":
            a = safe_url(a)
        elif hide == "--extra-field":
            a = a.partition("=")[0] + "=..."
        out.append(scrub(a))
        hide = a if a in ("--base-url", "--extra-field") else None
    return " ".join(out)


def _die_with_parent(parent: int) -> Callable[[], None]:
    """A ``preexec_fn`` that makes the child die (SIGKILL) when the bench dies, on Linux; the
    child's study folder is safe against a kill at any point (docs/studies.md)."""

    try:  # loaded here, in the bench: the child only calls it between fork and exec
        import ctypes

        prctl = ctypes.CDLL(None, use_errno=True).prctl
    except (OSError, AttributeError):
        prctl = None  # not Linux: the bench's lock still keeps a second bench out

    def arm() -> None:
        if prctl is None:
            return
        prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
        if os.getppid() != parent:  # the bench died before the line above: go with it
            os.kill(os.getpid(), signal.SIGKILL)

    return arm


def last_error(log: Path) -> str:
    """The last ``jswim: error:`` line of a part's log (without its prefix), else its last
    non-empty line, else ``"no output"``: what a failed part says to the bench's reader."""
    try:
        lines = log.read_text(encoding="utf-8", errors="replace").splitlines()
    except OSError:
        return "no output"
    errors = [ln for ln in lines if ln.startswith("jswim: error:")]
    text = errors[-1] if errors else next((ln for ln in reversed(lines) if ln.strip()), "no output")
    return text.removeprefix("jswim: error: ").strip()


def _count(folder: Path) -> tuple[int, int | None]:
    """Runs done and planned of a study folder (cheap: line counts)."""
    done = 0
    try:
        with open(folder / "runs.jsonl", "rb") as fh:
            done = sum(1 for _ in fh)
    except OSError:
        pass
    try:
        planned = json.loads((folder / "metadata.json").read_text(encoding="utf-8")).get(
            "n_planned"
        )
    except (OSError, ValueError):
        planned = None
    return done, planned


@dataclass
class Outcome:
    """What happened to each row of the bench in this call."""

    status: dict[str, str] = field(default_factory=dict)  # label -> complete / failed: ... / ...
    interrupted: bool = False
    stopped_at: dict[str, str] = field(default_factory=dict)  # label -> the part that stopped it


def run_jobs(
    jobs: list[Job],
    out: Path,
    meta: dict[str, Any],
    say: Callable[[str], None],
    every_s: float = 10.0,
) -> Outcome:
    """Run the jobs: one at a time per label, every label at once; returns each label's status."""
    queues: dict[str, list[Job]] = {}
    for j in jobs:
        queues.setdefault(j.label, []).append(j)
    result = Outcome({label: "running" for label in queues})
    running: dict[str, Job] = {}
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    me = os.getpid()

    def launch(label: str) -> None:
        job = queues[label].pop(0)
        argv = list(job.argv)
        if job.model is not None and job.model.max_cost is not None:
            # The model's cap is over its whole suite: this part may commit what the others left
            # (their spent and unanswered calls, from their ledgers), on top of what its own
            # folder already committed (the study counts that itself). Passed exactly: repr
            # round-trips the float, no digit is rounded away.
            others = sum(
                committed(j.folder) for j in jobs if j.label == label and j.folder != job.folder
            )
            argv += [
                "--max-cost",
                repr(max(0.0, job.model.max_cost - others) + committed(job.folder)),
            ]
        job.folder.parent.mkdir(parents=True, exist_ok=True)
        log = open(job.log, "a", encoding="utf-8")
        log.write(f"$ jswim {shown_argv(argv)}\n")
        log.flush()
        job.proc = subprocess.Popen(
            [sys.executable, "-m", "jswim"],
            stdout=log,
            stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL,
            env={**env, "JSWIM_BENCH_ARGV": json.dumps(argv)},
            start_new_session=True,  # Ctrl-C reaches the bench, which stops each child in turn
            preexec_fn=_die_with_parent(me),
        )
        log.close()
        running[label] = job

    def finish(label: str, job: Job) -> None:
        job.rc = job.proc.returncode
        del running[label]
        what = f"{label} {job.part.name}"
        if job.rc == 0:
            say(f"bench: {what}: done")
        elif job.rc == 3:
            result.status[label] = "stopped at the cost cap"
            result.stopped_at[label] = job.part.name
            say(
                f"bench: {what}: stopped at the model's cost cap (max_cost); its other parts are skipped"
            )
            queues[label].clear()
        elif job.rc == 2 and "LLM runs failed" in last_error(job.log):
            result.status[label] = "incomplete"
            say(f"bench: {what}: some runs failed ({last_error(job.log)})")
        elif job.rc == 130:
            result.status[label] = "interrupted"
        else:
            result.status[label] = f"failed: {last_error(job.log)}"
            result.stopped_at[label] = job.part.name
            say(
                f"bench: {label} failed at {job.part.name}: {last_error(job.log)} (see {job.log}); "
                "the other models go on"
            )
            queues[label].clear()
        if not queues[label] and result.status[label] == "running":
            result.status[label] = "complete"

    last = 0.0
    try:
        for label in queues:
            launch(label)
        while running:
            time.sleep(0.2)
            for label, job in list(running.items()):
                if job.proc.poll() is not None:
                    finish(label, job)
                    if queues[label]:
                        launch(label)
            if time.monotonic() - last >= every_s and running:
                last = time.monotonic()
                parts = []
                for label, job in running.items():
                    done, planned = _count(job.folder)
                    parts.append(
                        f"{label} {job.part.name} {done}/{planned if planned is not None else '?'}"
                    )
                say("bench: running " + " · ".join(parts))
    except KeyboardInterrupt:
        result.interrupted = True
        for job in running.values():
            if job.proc.poll() is None:
                job.proc.send_signal(signal.SIGINT)  # each study keeps its runs and answered calls
        deadline = time.monotonic() + 30
        for job in running.values():
            wait_through_interrupts(job.proc, deadline)
        for label in running:
            result.status[label] = "interrupted"
    return result


def wait_through_interrupts(proc: subprocess.Popen, deadline: float) -> None:
    """Wait for an interrupted part to end (it journals its calls in flight as it stops); a
    second interrupt (a notebook's Stop pressed again) does not cut the wait short and leave the
    part running unseen; a part still running at ``deadline`` is killed."""
    while True:
        try:
            proc.wait(max(0.1, deadline - time.monotonic()))
            return
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
            return
        except KeyboardInterrupt:
            continue
