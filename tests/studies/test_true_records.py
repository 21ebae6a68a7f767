"""Records that say what is true (issue 61, item 3): the study's LLM totals counted from the
ledger (every session, a killed one included), each study kind's own success rule in its
metadata, a resume that never narrows what the metadata says the folder holds, ``compare``
naming every setting that differs, and a cost line that says where its dollars come from.
"""

from __future__ import annotations

import json
import signal
import time
from pathlib import Path

import pytest

from jswim import cli
from jswim.llm.ledger import LEDGER, RequestLedger, folder_totals
from jswim.results import read_metadata
from tests.fakeserver import FakeServer, hash_reply
from tests.studies.test_folder_safety import no_traceback, start_swim, swim_args, wait_for_calls


def ledger_lines(folder: Path) -> list[dict]:
    return [json.loads(line) for line in (folder / LEDGER).read_text().splitlines()]


def no_outcome(folder: Path) -> int:
    """Requests sent with no outcome line, counted here from the file itself."""
    lines = ledger_lines(folder)
    sent = {r["id"] for r in lines if "bound_usd" in r}
    done = {r["id"] for r in lines if "cost_usd" in r or "released" in r}
    return len(sent - done)


def wait_in_flight(srv: FakeServer, proc, timeout: float = 60.0) -> None:
    """Return once the server is answering a request of ``proc``'s (its latency holds it open)."""
    t0 = time.monotonic()
    while srv.in_flight < 1:
        assert proc.poll() is None and time.monotonic() - t0 < timeout, "no request in flight"
        time.sleep(0.002)


# -- (a) the study's totals come from the ledger -------------------------------------------------


def test_a_killed_session_is_counted_from_its_ledger_lines(tmp_path):
    first = RequestLedger(tmp_path)
    assert first.begin_session() == 1
    a, b, c = first.sent(0.5), first.sent(0.25), first.sent(0.125, retry=True)
    first.billed(a, 0.5)
    first.released(b, "429")
    first.no_answer(c, "timeout")
    first._fh.close()  # killed: no end line, request c never answered
    again = RequestLedger(tmp_path)
    t = again.totals()
    assert (t["sessions"], t["not_ended"], t["requests"], t["retries"]) == (1, 1, 3, 1)
    assert t["faults"] == {"429": 1, "timeout": 1}
    assert (t["unanswered"], t["unanswered_usd"]) == (1, 0.125)
    assert again.begin_session() == 2
    again.billed(again.sent(0.5), 0.5)
    again.end_session()
    again.close()
    t = folder_totals(tmp_path)
    assert (t["sessions"], t["not_ended"], t["requests"], t["unanswered"]) == (2, 1, 4, 1)
    assert t["answered_calls"] == 0  # no journal in this folder


def test_an_older_jswims_folder_keeps_what_its_metadata_said_of_its_sessions(tmp_path):
    old = RequestLedger(tmp_path)
    for _ in range(5):  # an older jswim: sent lines naming no session, one never answered
        old.sent(0.1)
    old.close()
    said = {"sessions": 3, "wall_s": 12.0, "requests": 4, "retries": 1, "faults": {"5xx": 1}}
    t = folder_totals(tmp_path, said)
    assert (t["sessions"], t["requests"], t["wall_s"], t["unanswered"]) == (3, 5, 12.0, 5)
    new = RequestLedger(tmp_path)
    assert new.begin_session(said) == 1  # the first named session carries the earlier ones
    new.end_session()
    new.close()
    t = folder_totals(tmp_path, None)  # the metadata is no longer needed
    assert (t["sessions"], t["requests"], t["retries"], t["faults"]) == (4, 5, 1, {"5xx": 1})


@pytest.mark.slow  # two jswim subprocesses killed with SIGKILL, then a resume (~25 s)
def test_show_counts_every_session_after_kill_9_and_a_resume(tmp_path, capsys):
    out = tmp_path / "F"
    with FakeServer(reply=hash_reply, latency=0.2) as srv:
        for k in range(2):
            journaled = len((out / "calls.jsonl").read_text().splitlines()) if k else 0
            proc = start_swim(srv.url, out)
            wait_for_calls(out, journaled + 3, proc)
            wait_in_flight(srv, proc)  # killed while the server holds a request (0.2 s each)
            proc.send_signal(signal.SIGKILL)
            proc.communicate(timeout=60)
            time.sleep(0.3)  # the dead process's requests land at the server
        unanswered = no_outcome(out)
        assert unanswered >= 1  # requests were in flight at the kills
        capsys.readouterr()
        assert cli.main(["show", str(out)]) == 0  # before any session ended normally
        shown = capsys.readouterr().out
        sent = sum("bound_usd" in r for r in ledger_lines(out))
        assert "over 2 session(s) (2 of them not ended" in shown, shown
        assert f"HTTP requests: {sent} sent" in shown and f"{unanswered} got no answer" in shown
        assert cli.main(swim_args(srv.url, out)) == 0
        received = srv.settle()
    capsys.readouterr()
    assert cli.main(["show", str(out)]) == 0
    shown = capsys.readouterr().out
    sent = sum("bound_usd" in r for r in ledger_lines(out))
    # Every request the server got is counted; the ledger may hold a few more (written down just
    # before a kill, never delivered), never more than the requests left unanswered.
    assert received <= sent <= received + unanswered
    assert f"HTTP requests: {sent} sent" in shown, shown
    assert f"{unanswered} got no answer" in shown, shown
    assert "over 3 session(s) (2 of them not ended" in shown, shown
    totals = read_metadata(out)["llm_totals"]  # the report the last session wrote says the same
    assert (totals["sessions"], totals["requests"], totals["unanswered"]) == (3, sent, unanswered)
    answered = len((out / "calls.jsonl").read_text().splitlines())
    assert f"for {answered} answered calls" in shown
    no_traceback(shown)


# -- (b) each study kind records its own success rule --------------------------------------------

#: What each study's rule must name, and what it must not (another study's rule).
RULES = {
    **dict.fromkeys(
        ("curves", "history", "noise", "ablation", "inits", "swim", "competence", "temperature"),
        (
            ["3 consecutive qualifying cycles", "within 50 steps", "jswim.judging.gait.judge"],
            ["target", "swimmer's own moves"],
        ),
    ),
    "continuous": (
        ["consecutive qualifying cycles", "K=1, K=2, K=5, K=10", "jswim.judging.shape_judge"],
        ["target"],
    ),
    "wall": (
        ["each swimmer's own moves", "fate (trapped, escaped, gliding) is measured", "shape"],
        ["target", "every one of its swimmers"],
    ),
    "pair": (["each swimmer's own moves", "every one of its swimmers"], ["target", "fate"]),
    "school": (["each swimmer's own moves", "every one of its swimmers"], ["target", "PPO"]),
    "navigate": (
        ["the target reached", "radius (0.25 a)", "step budget", "times 1.5"],
        ["consecutive qualifying cycles", "within 50 steps"],
    ),
}


@pytest.mark.parametrize("study", sorted(RULES))
def test_each_study_kind_records_the_rule_its_runs_are_judged_by(study):
    from jswim.studies.run import _folder_metadata
    from jswim.studies import build, names
    from jswim.studies.options import StudyOptions

    assert set(RULES) == set(names())  # a new study kind needs its rule here
    plans = build(study, StudyOptions())
    rule = _folder_metadata(study, StudyOptions(), None, plans, {})["success_criterion"]
    names, not_names = RULES[study]
    for text in names:
        assert text in rule, (study, rule)
    for text in not_names:
        assert text not in rule, (study, rule)


def test_a_navigation_rule_names_the_budget_it_ran_under():
    from jswim.studies.options import StudyOptions
    from jswim.studies.specs import build
    from jswim.studies.study import get

    rule_of = get("navigate").success
    o = StudyOptions(flow="shear", flows=(0.0, 0.5), steps=30)
    rule = rule_of(build("navigate", o), o.horizon, o.steps)
    assert "step budget (--steps 30)" in rule and "Zermelo" not in rule
    o = StudyOptions(flow="shear", flows=(0.0, 0.5))
    rule = rule_of(build("navigate", o), o.horizon, o.steps)
    assert "at least 4 times Zermelo's least time" in rule


# -- (c) a resume never narrows what the folder says it holds ------------------------------------


def open_with(folder: Path, study: str, **grid) -> dict:
    """Open ``folder`` as a session of ``study`` with these grid options would, and close it:
    the metadata it records (no run is run)."""
    from jswim.results import StudyStore
    from jswim.studies.options import StudyOptions
    from jswim.studies.run import FolderRecord, identity
    from jswim.studies.specs import build

    o = StudyOptions(**grid)
    record = FolderRecord(study, o, None, build(study, o), {})
    StudyStore(folder, study, identity(study, o, None), extra=record).close()
    return read_metadata(folder)


def test_a_flows_subset_keeps_the_folders_flows_and_runs_planned(tmp_path):
    from jswim.studies.options import StudyOptions
    from jswim.studies.overview import show_text
    from jswim.studies.specs import build

    full = len(build("navigate", StudyOptions(flow="shear", flows=(0.0, 0.5))))
    meta = open_with(tmp_path / "F", "navigate", flow="shear", flows=(0.0, 0.5))
    assert meta["grid"]["flows"] == [0.0, 0.5] and meta["n_planned"] == full
    meta = open_with(tmp_path / "F", "navigate", flow="shear", flows=(0.5,))  # the subset
    assert meta["grid"]["flows"] == [0.0, 0.5] and meta["n_planned"] == full
    assert any("shear 0v" in g for g in meta["group_order"])
    assert "flow shear at 0,0.5 v" in show_text(tmp_path / "F")


@pytest.mark.parametrize(
    "study, first, then, held",
    [
        ("navigate", {"distances": (3.0, 5.0)}, {"distances": (5.0,)}, {"distances": [3.0, 5.0]}),
        ("navigate", {"bearings": (0.0, 90.0)}, {"bearings": (180.0,)}, {"bearings": [0, 90, 180]}),
        ("noise", {"zetas": (0.0, 1.0)}, {"zetas": (0.5,)}, {"zetas": [0.0, 0.5, 1.0]}),
        ("history", {"n_hts": (1, 2, 3)}, {"n_hts": (2,)}, {"n_hts": [1, 2, 3]}),
        ("wall", {"heights": (2.0, 3.0)}, {"heights": (3.0,)}, {"heights": [2.0, 3.0]}),
        ("pair", {"phases": (0, 2)}, {"phases": (1,)}, {"phases": [0, 1, 2]}),
        ("school", {"formations": ("line", "side")}, {"formations": ("side",)}, {}),
        ("swim", {"runs": 4}, {"runs": 2}, {"runs": 4}),
        ("curves", {"temperatures": (0.0, 0.5)}, {"temperatures": (1.0,)}, {}),
    ],
)
def test_a_smaller_grid_on_resume_keeps_the_union_of_every_grid(tmp_path, study, first, then, held):
    from jswim.studies.options import StudyOptions
    from jswim.studies.specs import build

    ids = {p.run_id for o in (first, then) for p in build(study, StudyOptions(**o))}
    open_with(tmp_path / "F", study, **first)
    meta = open_with(tmp_path / "F", study, **then)
    for k, v in held.items():
        assert meta["grid"][k] == v, (k, meta["grid"][k])
    for k in then:  # every value either session ran
        for v in (*first[k], *then[k]) if isinstance(then[k], tuple) else ():
            assert v in meta["grid"][k]
    assert meta["n_planned"] == len(ids)  # the runs of both grids, no grid crossed with another
    assert [g[next(iter(then))] for g in meta["grids"]] == [
        list(x) if isinstance(x, tuple) else x for x in (first[k], then[k])
    ]


def test_a_hand_edited_earlier_grid_is_not_carried_on(tmp_path):
    open_with(tmp_path / "F", "noise", zetas=(0.0, 1.0))
    meta = json.loads((tmp_path / "F" / "metadata.json").read_text())
    meta["grids"] = [{**meta["grids"][0], "zetas": ["fast"]}]
    (tmp_path / "F" / "metadata.json").write_text(json.dumps(meta))
    meta = open_with(tmp_path / "F", "noise", zetas=(0.5,))
    assert meta["grids"] == [meta["grid"]] and meta["grid"]["zetas"] == [0.5]


# -- (d) compare names what differs; the cost line says what is true -----------------------------


@pytest.mark.slow  # two small Q-learning studies and a compare (~10 s)
def test_compare_notes_every_setting_that_differs(tmp_path, capsys):
    base = ["swim", "--runs", "0", "--q-runs", "2", "--swimmer", "purcell", "--no-figures"]
    assert cli.main([*base, "--steps", "12", "--out", str(tmp_path / "a")]) == 0
    assert cli.main([*base, "--steps", "20", "--out", str(tmp_path / "b")]) == 0
    assert cli.main([*base, "--steps", "12", "--out", str(tmp_path / "c")]) == 0
    capsys.readouterr()
    assert cli.main(["compare", str(tmp_path / "a"), str(tmp_path / "b")]) == 0
    out = capsys.readouterr().out
    line = next(ln for ln in out.splitlines() if ln.startswith("settings that differ"))
    assert line.endswith("steps: [1] 12, [2] 20"), line
    assert cli.main(["compare", str(tmp_path / "a"), str(tmp_path / "c")]) == 0
    assert "settings that differ" not in capsys.readouterr().out  # the same settings: no note


def test_a_priced_reference_rule_says_where_its_dollars_come_from(tmp_path, capsys):
    from jswim.llm.reference import completion

    (tmp_path / "p.json").write_text(json.dumps({"reference-rule": [1000.0, 2000.0]}))
    args = ["swim", "--steps", "12", "--runs", "1", "--q-runs", "0", "--swimmer", "purcell"]
    args += ["--direction", "+x", "--no-figures", "--model", "reference-rule"]
    with FakeServer(reply=lambda body: completion(body)["choices"][0]["message"]["content"]) as s:
        for extra in (["--prices", str(tmp_path / "p.json")], []):
            out = tmp_path / ("priced" if extra else "free")
            assert cli.main([*args, *extra, "--base-url", s.url, "--out", str(out)]) == 0
            printed = capsys.readouterr().out
            line = next(ln for ln in printed.splitlines() if ln.startswith("LLM calls:"))
            assert cli.main(["show", str(out)]) == 0
            shown = capsys.readouterr().out
            if extra:  # priced by the user's table: dollars, and where they come from
                assert "for the study (prices of your table p.json)" in line, line
                assert "not priced" not in line and "not priced" not in shown
                assert float(line.split("$")[1].split()[0]) > 0
            else:  # free: said so, with no dollar figure
                assert "not priced (a rule on this machine, not an LLM); $0 counted" in line
                assert "$" not in line.replace("$0 counted", ""), line


@pytest.mark.slow  # two small noise studies of Q-learning and random runs (~10 s)
def test_resuming_with_fewer_noise_levels_keeps_the_folders_record(tmp_path, capsys):
    from jswim.studies.overview import show_text

    out = tmp_path / "N"
    base = ["study", "noise", "--runs", "0", "--q-runs", "2", "--steps", "12", "--no-figures"]
    base += ["--swimmer", "purcell", "--out", str(out)]
    assert cli.main([*base, "--zetas", "0,1"]) == 0
    full = read_metadata(out)["n_planned"]
    assert cli.main([*base, "--zetas", "1"]) == 0  # the subset: nothing left to run
    meta = read_metadata(out)
    assert meta["grid"]["zetas"] == [0.0, 1.0] and meta["n_planned"] == full == 8
    assert {g["group"] for g in meta["summary"]["groups"]} == {"zeta=0", "zeta=1"}
    assert show_text(out).splitlines()[0].endswith(": complete")  # 8 of 8, not "8 of 4"
