"""Running studies (jswim.studies.run) against the fake server: the competence study, LLM speed,
variants of the swim job."""

from __future__ import annotations

import json
from collections import Counter

import pytest

from jswim import cli
from jswim.results import read_metadata, read_runs
from jswim.studies import StudyOptions, run_study, summarize
from tests.fakeserver import FakeServer, hash_reply


@pytest.mark.slow  # jswim study competence end to end (27 s under load 8)
def test_competence_study_end_to_end(tmp_path, capsys):
    out = tmp_path / "competence"
    with FakeServer(reply=hash_reply, latency=0.002) as srv:
        rc = cli.main(
            [
                "study",
                "competence",
                "--swimmer",
                "purcell",
                "--runs",
                "2",
                "--q-runs",
                "4",
                "--steps",
                "8",
                "--variant",
                "paper,shape-changing+shuffle",
                "--out",
                str(out),
                "--base-url",
                srv.url,
                "--model",
                "fake",
                "--api-key-env",
                "JSWIM_TEST_NO_KEY",
            ]
        )
    assert rc == 0
    rows = read_runs(out)
    assert Counter((r["agent"], r["group"]) for r in rows) == {
        ("llm", "paper"): 2,
        ("llm", "shape-changing+shuffle"): 2,
        ("random", "all"): 4,
        ("random", "shape-changing"): 4,
        ("qlearning", "all"): 4,
        ("qlearning", "shape-changing"): 4,
    }
    llm = [r for r in rows if r["agent"] == "llm"]
    assert {(r["variant"], r["action_set"], r["shuffle"]) for r in llm} == {
        ("paper", "all", False),
        ("shape-changing+shuffle", "shape-changing", True),
    }
    meta = read_metadata(out)
    assert meta["identity"]["variants"]["shape-changing+shuffle"] == {
        "action_set": "shape-changing",
        "shuffle": True,
    }
    assert meta["llm_variants"] == ["paper", "shape-changing+shuffle"]
    summary = {(s["agent"], s["group"]): s for s in summarize(rows)}
    s = summary[("llm", "shape-changing+shuffle")]
    mine = [r for r in llm if r["group"] == "shape-changing+shuffle"]
    assert s["n"] == 2 and s["distinct"] == 2 and s["tokens_per_step"] > 0
    assert s["failed_steps"] == sum(
        r["failed_steps"] for r in mine
    )  # the fake picks outside the set
    assert (out / "figures" / "competence.png").is_file()
    # The random baseline on the shape-changing set never wastes a step.
    for r in rows:
        if r["agent"] == "random" and r["action_set"] == "shape-changing":
            assert all(roc != 0 for _, roc in r["actions"])
    spec = json.loads((out / "metadata.json").read_text())
    assert spec["status"] == "complete"


def test_study_reports_llm_calls_per_second(tmp_path):
    with FakeServer(reply=hash_reply) as srv:
        res = run_study(
            "competence",
            StudyOptions(swimmers=("ng",), runs=1, q_runs=0, steps=4, variants=("paper",)),
            srv.backend(),
            tmp_path / "c",
        )
    sp = res.llm_speed
    assert sp["calls"] == 4 and sp["billed_calls"] == 4 and sp["calls_per_s"] > 0


def test_swim_takes_a_variant_and_records_it(tmp_path):
    out = tmp_path / "swim"
    with FakeServer(reply=hash_reply) as srv:
        rc = cli.main(
            [
                "swim",
                "--variant",
                "shuffle",
                "--runs",
                "1",
                "--q-runs",
                "2",
                "--steps",
                "4",
                "--no-figures",
                "--out",
                str(out),
                "--base-url",
                srv.url,
                "--model",
                "fake",
                "--api-key-env",
                "JSWIM_TEST_NO_KEY",
            ]
        )
        assert rc == 0
        assert (
            cli.main(
                [
                    "swim",
                    "--variant",
                    "a,b",
                    "--out",
                    str(tmp_path / "x"),
                    "--base-url",
                    srv.url,
                    "--model",
                    "fake",
                ]
            )
            == 2
        )
    (llm,) = [r for r in read_runs(out) if r["agent"] == "llm"]
    assert (llm["variant"], llm["shuffle"]) == ("shuffle", True)
    meta = read_metadata(out)
    assert (
        meta["llm_variants"] == ["shuffle"] and meta["identity"]["options"]["variant"] == "shuffle"
    )
