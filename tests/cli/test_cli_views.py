"""The command line as a log reads it, options that a study would drop, show/compare/plot, help text."""

from __future__ import annotations

import argparse
import json
import re

import pytest

from jswim import cli
from tests.fakeserver import FakeServer, hash_reply


@pytest.fixture(scope="module")
def server():
    with FakeServer(reply=hash_reply, latency=0.002) as srv:
        yield srv


def backend_args(srv):
    return [
        "--base-url",
        srv.url,
        "--model",
        "fake",
    ]  # no --api-key-env: a named unset variable is warned about


@pytest.mark.slow  # a noise study end to end (75 s under load 8)
def test_noise_study_in_a_log_keeps_every_zeta_and_number(server, tmp_path, capsys):
    # capsys is not a terminal: the table must be whole plain text, progress plain lines
    out = tmp_path / "noise"
    rc = cli.main(
        [
            "study",
            "noise",
            "--swimmer",
            "both",
            "--zetas",
            "0,0.5,1,10.25",
            "--runs",
            "1",
            "--q-runs",
            "3",
            "--steps",
            "12",
            "--no-figures",
            "--out",
            str(out),
            *backend_args(server),
        ]
    )
    assert rc == 0
    captured = capsys.readouterr()
    text, err = captured.out, captured.err
    assert "\u2026" not in text and "\x1b[" not in text and "\r" not in err
    for z in ("zeta=0 ", "zeta=0.5 ", "zeta=1 ", "zeta=10.25 "):
        assert text.count(z) == 2 * 3, z  # 2 swimmers x 3 agents, each label whole
    for label in ("qlearning", "purcell", "random"):
        assert re.search(rf"^{label}|\s{label}\s", text, flags=re.M), label
    rows = [
        line for line in text.splitlines() if line.startswith(("llm ", "qlearning ", "random "))
    ]
    assert len(rows) == 2 * 4 * 3
    for line in rows:  # every interval closes: no cell was cut
        # X/a end: its bootstrap interval, or "[n<3]" where one or two runs give none
        assert re.search(r"\d\.\d\d \[\d\.\d\d,\d\.\d\d\]", line) and re.search(
            r"[+-]\d\.\d{3} (\[[+-]\d\.\d\d,[+-]\d\.\d\d\]|\[n<3\])", line
        )
    assert "runs (" in err and "LLM runs" in err  # dated progress lines, one per update


@pytest.mark.parametrize(
    "argv,option",
    [
        (["study", "history", "--q-runs", "5"], "--q-runs"),
        (["study", "ablation", "--q-runs", "5"], "--q-runs"),
        (["study", "inits", "--q-runs", "5"], "--q-runs"),
        (["study", "inits", "--init", "++"], "--init"),
        (["study", "noise", "--noise", "1"], "--noise"),
        (["study", "history", "--zetas", "0,1"], "--zetas"),
        (["study", "curves", "--zetas", "0,1"], "--zetas"),
        (["study", "noise", "--n-hts", "1,2"], "--n-hts"),
        (["study", "history", "--n-ht", "3"], "--n-ht"),
        (["study", "navigate", "--direction=-x"], "--direction"),
        (["study", "navigate", "--direction", "both"], "--direction"),
    ],
)
def test_options_a_study_would_ignore_are_refused(argv, option, tmp_path, capsys):
    rc = cli.main([*argv, "--out", str(tmp_path / "x")])
    err = capsys.readouterr().err
    assert rc == 2 and err.count("\n") == 1 and err.startswith("jswim: error: ")
    assert f"has no use for {option} " in err
    assert not (tmp_path / "x").exists()  # refused before anything was written


def test_no_runs_at_all_is_an_error(server, tmp_path, capsys):
    rc = cli.main(
        [
            "swim",
            "--runs",
            "0",
            "--q-runs",
            "0",
            "--out",
            str(tmp_path / "x"),
            *backend_args(server),
        ]
    )
    err = capsys.readouterr().err
    assert rc == 2 and "no runs at all" in err and not (tmp_path / "x").exists()


@pytest.mark.slow  # a study end to end after the warning (40 s under load 8)
def test_short_steps_warn_that_nothing_can_succeed(server, tmp_path, capsys):
    rc = cli.main(
        [
            "swim",
            "--runs",
            "0",
            "--q-runs",
            "2",
            "--steps",
            "11",
            "--no-figures",
            "--out",
            str(tmp_path / "s"),
            *backend_args(server),
        ]
    )
    assert rc == 0
    assert "jswim: warning: --steps 11 is shorter than 3 stroke cycles" in capsys.readouterr().err
    rc = cli.main(
        [
            "swim",
            "--runs",
            "0",
            "--q-runs",
            "2",
            "--steps",
            "12",
            "--no-figures",
            "--out",
            str(tmp_path / "t"),
            *backend_args(server),
        ]
    )
    assert rc == 0 and "warning" not in capsys.readouterr().err


@pytest.mark.parametrize(
    "extra,message",
    [
        (["--noise", "-2"], "--noise (zeta) must be >= 0"),
        (["--noise", "nan"], "--noise (zeta) must be >= 0"),
        (["--learning-rate", "0"], "--learning-rate must lie in (0, 1]"),
        (["--learning-rate", "1.5"], "--learning-rate must lie in (0, 1]"),
        (["--lr-decay", "1.2"], "--lr-decay must lie in (0, 1]"),
        (["--lr-min", "0.1"], "give --lr-decay too"),
        (
            ["--learning-rate", "0.5", "--lr-decay", "0.9", "--lr-min", "0.6"],
            "--lr-min must lie in [0, 0.5]",
        ),
    ],
)
def test_qlearn_validates_noise_and_learning_rate(extra, message, capsys):
    rc = cli.main(["qlearn", "--swimmer", "purcell", "--seeds", "2", "--steps", "5", *extra])
    err = capsys.readouterr().err
    assert rc == 2 and message in err and err.count("\n") == 1


def _median(text: str) -> float:
    line = next(line for line in text.splitlines() if line.startswith("ng "))
    return float(line.split()[10])  # swimmer dir zeta actions n learned "of" n success q25 median


@pytest.mark.slow  # two jswim qlearn runs end to end (43 s under load 8)
def test_qlearn_learning_rate_reaches_the_learner(capsys):
    # NG on the shape-changing set: alpha = 1 learns in ~32 steps, alpha = 0.25 in ~73 (README)
    base = [
        "qlearn",
        "--swimmer",
        "ng",
        "--direction",
        "+x",
        "--seeds",
        "200",
        "--action-set",
        "shape-changing",
    ]
    assert cli.main(base) == 0
    fast = _median(capsys.readouterr().out)
    assert cli.main([*base, "--learning-rate", "0.25"]) == 0
    slow = _median(capsys.readouterr().out)
    assert fast < 45 < 60 < slow
    assert cli.main([*base, "--learning-rate", "1", "--lr-decay", "0.98", "--lr-min", "0.1"]) == 0
    assert fast < _median(capsys.readouterr().out)


@pytest.fixture(scope="module")
def figures_folder(server, tmp_path_factory):
    out = tmp_path_factory.mktemp("views") / "swim"
    assert (
        cli.main(
            [
                "swim",
                "--swimmer",
                "both",
                "--direction",
                "both",
                "--runs",
                "1",
                "--q-runs",
                "3",
                "--steps",
                "12",
                "--out",
                str(out),
                *backend_args(server),
            ]
        )
        == 0
    )
    return out


@pytest.fixture
def folder(small_swim_study):
    return (
        small_swim_study  # the session's small swim study (tests/conftest.py): read, never written
    )


@pytest.mark.slow  # two studies end to end, then show and compare (38 s under load 8)
def test_show_and_compare_commands(figures_folder, tmp_path, capsys):
    folder = figures_folder
    capsys.readouterr()
    assert cli.main(["show", str(folder)]) == 0
    text = capsys.readouterr().out
    assert (
        text.startswith(f"study swim in {folder}: complete")
        and "figures:" in text
        and "swim.png" in text
    )
    assert cli.main(["compare", str(folder), str(folder)]) == 0
    text = capsys.readouterr().out
    assert text.count("[1]") == text.count("[2]") == 1 + 2 * 2 * 3  # header + one row per setting
    # each baseline printed once (the same runs in both folders), each LLM row once per study
    lines = text.splitlines()
    assert (
        sum(ln.startswith("qlearning") for ln in lines)
        == sum(ln.startswith("random") for ln in lines)
        == 4
    )
    assert all("[1][2]" in ln for ln in lines if ln.startswith(("qlearning", "random")))
    assert sum(ln.startswith("llm") for ln in lines) == 2 * 4
    assert cli.main(["compare", str(folder)]) == 2
    assert "at least two" in capsys.readouterr().err
    assert cli.main(["show", str(tmp_path)]) == 2
    assert "not a jswim study folder" in capsys.readouterr().err


def test_plot_marks_an_unfinished_study(folder, tmp_path, capsys, monkeypatch):
    part = tmp_path / "part"
    part.mkdir()
    meta = json.loads((folder / "metadata.json").read_text())
    meta.update(status="running", n_planned=40)
    (part / "metadata.json").write_text(json.dumps(meta))
    lines = (folder / "runs.jsonl").read_text().splitlines()
    (part / "runs.jsonl").write_text("\n".join(lines[:9]) + "\n")
    from jswim.figures import plots

    notes = []
    original = plots.study_figures
    monkeypatch.setattr(
        plots,
        "study_figures",
        lambda study, rows, note=None: notes.append(note) or original(study, rows, note),
    )
    assert cli.main(["plot", str(part)]) == 0
    assert notes == ["UNFINISHED STUDY: 9 of 40 runs done (running)"]
    assert (part / "figures" / "swim.png").is_file() and (part / "figures" / "swim.pdf").is_file()


def _actions(parser):
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from ((f"{name} {opt}", a) for opt, a in _actions(sub))
        elif not isinstance(action, argparse._HelpAction):
            yield (action.option_strings[0] if action.option_strings else action.dest), action


def test_every_option_has_help_text():
    missing = [
        name for name, action in _actions(cli.build_parser()) if not (action.help or "").strip()
    ]
    assert not missing, f"options without help: {missing}"


@pytest.mark.parametrize(
    "argv,message",
    [
        (
            ["ensemble", "--n", "99999999999999999999", "--steps", "2", "--zetas", "0"],
            "--n must be at most",
        ),
        (
            ["ensemble", "--n", "4", "--steps", "99999999999", "--zetas", "0"],
            "--steps must be at most",
        ),
        (
            ["ensemble", "--n", "4", "--steps", "2", "--zetas", "0", "--chunk", "99999999999"],
            "--chunk must be at most",
        ),
        (
            ["qlearn", "--swimmer", "purcell", "--seeds", "99999999999999999999", "--steps", "5"],
            "--seeds must be at most",
        ),
        (
            ["qlearn", "--swimmer", "purcell", "--seeds", "2", "--steps", "99999999999"],
            "--steps must be at most",
        ),
    ],
)
def test_huge_counts_are_one_line_errors(argv, message, capsys):
    # QA: these reached JAX/NumPy (int32 overflow, a 745 GiB allocation) and ended in a traceback
    assert cli.main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_absurd_concurrency_is_refused_before_any_run(tmp_path, capsys):
    # QA: --concurrency 10**10 built one client slot per request in flight and never returned
    rc = cli.main(
        [
            "study",
            "noise",
            "--swimmer",
            "purcell",
            "--zetas",
            "0",
            "--runs",
            "1",
            "--q-runs",
            "0",
            "--steps",
            "12",
            "--base-url",
            "http://127.0.0.1:9/v1",
            "--model",
            "m",
            "--concurrency",
            "10000000000",
            "--out",
            str(tmp_path / "s"),
            "--no-figures",
        ]
    )
    err = capsys.readouterr().err
    assert rc == 2 and "--concurrency must be at most" in err and err.count("\n") == 1


@pytest.mark.parametrize(
    "content,message",
    [
        ("[1]", "not a study's metadata"),
        ('"swim"', "not a study's metadata"),
        (b"\xff\xfe", "is unreadable"),
    ],
)
def test_show_of_a_foreign_metadata_file_is_one_line(content, message, tmp_path, capsys):
    # QA: a metadata.json that is JSON but not an object (or not UTF-8) gave a traceback
    meta = tmp_path / "metadata.json"
    meta.write_bytes(content if isinstance(content, bytes) else content.encode())
    assert cli.main(["show", str(tmp_path)]) == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_show_into_a_closed_pipe_is_quiet(folder, tmp_path, monkeypatch, capsys):
    # QA: `jswim show F | head -2` ended in a BrokenPipeError traceback once head had quit
    class ClosedPipe:
        def __init__(self, fd: int) -> None:
            self.fd = fd

        def write(self, text: str) -> int:
            raise BrokenPipeError(32, "Broken pipe")

        def flush(self) -> None:
            raise BrokenPipeError(32, "Broken pipe")

        def fileno(self) -> int:
            return self.fd

    with open(tmp_path / "stdout", "w") as sink:
        monkeypatch.setattr("sys.stdout", ClosedPipe(sink.fileno()))
        monkeypatch.setattr("sys.argv", ["jswim", "show", str(folder)])
        with pytest.raises(SystemExit) as stop:
            cli.run()
    assert stop.value.code == 0 and capsys.readouterr().err == ""


def test_ctrl_c_before_main_handles_it_is_one_line(monkeypatch, capsys):
    # QA: Ctrl-C in the first seconds (imports, parser) ended in a KeyboardInterrupt traceback
    def interrupted(argv=None):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "main", interrupted)
    with pytest.raises(SystemExit) as stop:
        cli.run()
    err = capsys.readouterr().err
    assert (
        stop.value.code == 130
        and err == "jswim: interrupted (Ctrl-C) while starting; nothing was written\n"
    )


def test_short_runs_warn_only_where_the_paper_criterion_judges_them():
    from jswim.studies import StudyOptions
    from jswim.studies.specs import short_steps_warning

    short = StudyOptions(steps=8)
    assert "no run can meet the success criterion" in short_steps_warning(short, "curves")
    nav = short_steps_warning(short, "navigate")  # success there is reaching the target
    assert "success criterion" not in nav and "the steering controller needs" in nav
    assert short_steps_warning(StudyOptions(steps=50), "curves") is None


def test_every_agent_s_progress_line_names_it_as_it_runs():
    # A study's progress names each phase by the agent that runs (PPO is categorical in the
    # navigation study, real-valued elsewhere: "PPO", not "continuous RL"; no agent is "runs").
    from jswim.console import PHASE_LABELS
    from jswim.studies.options import ALL_AGENTS

    assert all(agent in PHASE_LABELS for agent in ALL_AGENTS), set(ALL_AGENTS) - set(PHASE_LABELS)
    assert PHASE_LABELS["ppo"] == "PPO" and PHASE_LABELS["controller"] == "steering controller"
