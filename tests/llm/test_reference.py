"""The prompt-only reference agent (jswim.llm.reference): its rule on prompt text, and the real
HTTP loop against its server."""

from __future__ import annotations

import httpx

from jswim import cli
from jswim.agents import protocol
from jswim.agents.memory import MoveStats
from jswim.agents.variants import LLMAgentConfig, LLMRunSpec
from jswim.llm.reference import MODEL, ReferenceServer, decide, read_prompt
from jswim.prompt import Action, HistoryRecord
from jswim.results import read_runs
from jswim.swimmers.models import make_model

UP, DOWN = 1.0471975511965976, -1.0471975511965976


def prompt(records, dofs, direction=1, swimmer="purcell", action_set="all"):
    cfg = LLMAgentConfig(action_set=action_set)
    _, text, p = protocol.setup(
        LLMRunSpec(swimmer, direction=direction, n_ht=8), make_model(swimmer), cfg
    )
    req = protocol.request(
        cfg,
        text,
        p,
        direction=direction,
        seed=0,
        step=len(records) + 1,
        records=records,
        dofs=dofs,
        x=0.0,
        stats=MoveStats(),
    )
    return req.messages[-1]["content"]


def test_rule_reads_records_and_offers_from_the_text():
    recs = [
        HistoryRecord(1, (UP, UP), (DOWN, UP), Action(1, -1), 0.0, 0.05),
        HistoryRecord(2, (DOWN, UP), (UP, UP), Action(1, 1), 0.05, 0.0),
    ]
    text = prompt(recs, (UP, UP), direction=-1)
    direction, records, offered = read_prompt(text)
    assert direction == -1 and [r.action for r in records] == [(1, -1), (1, 1)]
    assert [r.progress for r in records] == [-50, 50]  # thousandths of a, toward -x
    assert offered == [(d, r) for d in (1, 2) for r in (-1, 0, 1)]
    # Back at (+, +): [1, -1] went away from -x from here, so try a move not yet shown from it;
    # D2 at its upper limit cannot go up, so the first is [2, -1].
    assert decide(text) == (2, -1)
    # Toward +x the same record went forward: repeat it.
    assert decide(prompt(recs, (UP, UP), direction=1)) == (1, -1)


def test_rule_skips_holds_and_moves_a_limit_blocks():
    assert decide(prompt([], (UP, UP))) == (1, -1)  # no record: the first offered move
    recs = [HistoryRecord(1, (UP, UP), (DOWN, UP), Action(1, -1), 0.0, -0.02)]
    assert decide(prompt(recs, (DOWN, UP))) == (1, 1)  # [1, -1] at D1's lower limit is a hold
    only = prompt(recs, (DOWN, UP), action_set="shape-changing")  # S5 lists the pairs
    assert set(read_prompt(only)[2]) == {(1, 1), (2, -1)}


def test_server_answers_the_openai_shape_and_names_itself():
    with ReferenceServer() as srv:
        models = httpx.get(srv.url + "/models").json()
        assert [m["id"] for m in models["data"]] == [MODEL]
        body = {"model": MODEL, "messages": [{"role": "user", "content": prompt([], (UP, UP))}]}
        got = httpx.post(srv.url + "/chat/completions", json=body).json()
        assert (
            got["choices"][0]["message"]["content"] == "[1, -1]"
            and got["usage"]["prompt_tokens"] > 0
        )
        assert httpx.post(srv.url + "/chat/completions", content=b"[").status_code == 400


def test_swim_against_the_reference_server_learns_purcell_at_n_ht_6(tmp_path, capsys):
    with ReferenceServer() as srv:
        assert (
            cli.main(
                [
                    "swim",
                    "--base-url",
                    srv.url,
                    "--model",
                    MODEL,
                    "--n-ht",
                    "6",
                    "--runs",
                    "1",
                    "--q-runs",
                    "0",
                    "--out",
                    str(tmp_path / "o"),
                    "--no-figures",
                ]
            )
            == 0
        )
    (row,) = read_runs(tmp_path / "o")
    assert row["success"] and row["steps_to_learn"] == 6 and row["failed_steps"] == 0
