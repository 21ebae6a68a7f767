"""ROC lattices (``--roc-levels K``): the prompt's text, the reply parser and the agent defaults.

K = 1 is the paper's prompt byte for byte; K > 1 adds one sentence to S2 and one to S5 and offers
every integer ROC in -K..K.
"""

from __future__ import annotations

import math

import pytest

from jswim.errors import ConfigError
from jswim.prompt import (
    Action,
    HistoryRecord,
    PromptConfig,
    SwimmerText,
    allowed_actions,
    parse_reply,
    render_prompt,
)

HI = (math.pi / 3, math.pi / 3)


def purcell(k: int = 1) -> SwimmerText:
    return SwimmerText(2, -math.pi / 3, math.pi / 3, 3, tuple(range(-k, k + 1)), k)


def test_k1_prompt_is_byte_identical_to_the_paper_prompt():
    rec = HistoryRecord(1, HI, (-math.pi / 3, math.pi / 3), Action(1, -1), 0.0, 0.01)
    # The K = 1 swimmer text is the default one: nothing about ROC levels reaches the prompt.
    old = SwimmerText(2, -math.pi / 3, math.pi / 3, dof_decimals=3)
    assert purcell(1) == old
    text = render_prompt(purcell(1), PromptConfig(), +1, [rec], HI, 0.0)
    assert text == (
        "Find the sequence of rates of change (ROC) of the degrees of freedom (DOF) D1 and D2 that gives the fastest "
        "long-term movement in the positive x direction. Only one DOF changes at a time, and D1 and D2 each stay in "
        "[-1.047, 1.047].\nLatest records (step: (D1, D2) before [changed DOF, ROC] -> (D1, D2) after, X before -> "
        "after, stuck):\n1: (1.047, 1.047) [1, -1] -> (-1.047, 1.047), X 2500 -> 2510, stuck no\nKeep in mind that an "
        "action can have long-term consequences. Reply with the next action as [changed DOF, ROC], the changed DOF 1 "
        "or 2 and the ROC -1, 0 or 1."
    )


def test_k_levels_add_one_sentence_to_s2_and_one_to_s5():
    text = render_prompt(purcell(5), PromptConfig(), -1, [], HI, 0.0)
    s2 = (
        "Only one DOF changes at a time, and D1 and D2 each stay in [-1.047, 1.047]. In one step a ROC of k "
        "changes the DOF by k/5 of its range, stopping at its limits."
    )
    s5 = (
        "Reply with the next action as [changed DOF, ROC], the changed DOF 1 or 2 and the ROC -5, -4, -3, -2, -1, "
        "0, 1, 2, 3, 4 or 5. The ROC is a whole number from -5 to 5."
    )
    assert s2 in text and s5 in text
    assert text.count("k/5") == 1 and text.count("whole number") == 1
    # A dropped sentence takes its extra sentence with it.
    short = render_prompt(purcell(5), PromptConfig(drop=frozenset({"S2", "S5"})), -1, [], HI, 0.0)
    assert "k/5" not in short and "whole number" not in short


def test_four_dof_rocs_leave_out_zero_and_say_so():
    from jswim.agents.defaults import default_rocs, swimmer_text
    from jswim.swimmers.models import make_model

    model = make_model("nsphere")
    assert default_rocs(model) == (-1, 1)
    assert default_rocs(model, 3) == (-3, -2, -1, 1, 2, 3)
    text = render_prompt(
        swimmer_text(model, roc_levels=3), PromptConfig(), 1, [], (6.0, 10.0, 10.0), 0.0
    )
    assert "The ROC is a whole number from -3 to 3, not 0." in text


def test_allowed_set_at_k_levels_and_shape_changing_moves():
    sw = purcell(2)
    assert [a.roc for a in allowed_actions(sw) if a.dof == 1] == [-2, -1, 0, 1, 2]
    assert len(allowed_actions(sw)) == 2 * (2 * 2 + 1)
    # From D1 at its upper limit and D2 in the middle: D1 may only go down, D2 either way.
    moves = allowed_actions(sw, "shape-changing", (math.pi / 3, 0.0))
    assert moves == [
        Action(1, -2),
        Action(1, -1),
        Action(2, -2),
        Action(2, -1),
        Action(2, 1),
        Action(2, 2),
    ]


@pytest.mark.parametrize("k", [2, 5, 10])
def test_parser_accepts_exactly_the_offered_integers(k):
    allowed = allowed_actions(purcell(k))
    for roc in range(-k, k + 1):
        assert parse_reply(f"[2, {roc}]", allowed) == Action(2, roc)
        assert parse_reply(f"DOF 1, ROC {roc}", allowed) == Action(1, roc)
    for bad in (
        f"[1, {k + 1}]",
        f"[1, -{k + 1}]",
        "[1, 0.5]",
        "[1, 1/2]",
        "[1, 1.0]",
        "DOF 1, ROC 0.5",
        "DOF 1, ROC 1/2",
        f"DOF 1, ROC {k + 1}",
        "[3, 1]",
        "[1, 1.5]",
    ):
        assert parse_reply(bad, allowed) is None, bad


def test_parser_at_k1_still_refuses_rocs_beyond_one():
    allowed = allowed_actions(purcell(1))
    assert parse_reply("[1, 2]", allowed) is None
    assert parse_reply("DOF 1, ROC 1.5", allowed) is None  # used to read as ROC 1
    assert parse_reply("DOF 2, ROC -1", allowed) == Action(2, -1)


def test_the_driver_asks_again_for_a_roc_outside_the_lattice():
    from jswim.agents import protocol
    from jswim.agents.variants import LLMAgentConfig

    cfg = LLMAgentConfig()
    sw = purcell(2)
    req = protocol.request(
        cfg,
        sw,
        PromptConfig(),
        direction=1,
        seed=0,
        step=1,
        records=[],
        dofs=HI,
        x=0.0,
        stats=__import__("jswim.agents.memory", fromlist=["MoveStats"]).MoveStats(),
    )
    reply = protocol.read_reply(req, req.messages, "[1, 3]", 0, cfg)
    assert reply.action is None and reply.follow_up is not None
    assert (
        "[1, -2]" in reply.follow_up[-1]["content"]
        and "[1, 3]" not in reply.follow_up[-1]["content"]
    )
    assert protocol.read_reply(req, req.messages, "[1, -2]", 0, cfg).action == Action(1, -2)


def test_roc_levels_are_checked():
    for bad in (0, -1, 1001, 2.5, True):
        with pytest.raises(ConfigError, match="--roc-levels"):
            SwimmerText(2, -1.0, 1.0, 3, (-1, 0, 1), bad)
    with pytest.raises(ConfigError, match="rocs"):
        SwimmerText(2, -1.0, 1.0, 3, (-3, 0, 3), 2)


def test_arm_lengths_get_the_decimals_the_lattice_needs():
    from jswim.agents.defaults import dof_decimals
    from jswim.swimmers.models import make_model

    ng, purcell_model = make_model("ng"), make_model("purcell")
    # Arms 6..10: steps of 4, 2, 1 are whole numbers; 0.8 and 0.4 need one decimal; 4/3 never ends.
    assert [dof_decimals(ng, k) for k in (1, 2, 4, 5, 10, 3)] == [0, 0, 0, 1, 1, 3]
    assert {dof_decimals(purcell_model, k) for k in (1, 2, 5, 10)} == {3}


def test_run_id_and_fidelity_record_k():
    from jswim.agents.fidelity import deviations, roc_levels_deviation
    from jswim.agents.variants import LLMAgentConfig, LLMRunSpec

    assert LLMRunSpec(seed=3).label() == "llm-purcell-px-idefault-z0-s3"
    assert LLMRunSpec(seed=3, roc_levels=5).label() == "llm-purcell-px-idefault-z0-K5-s3"
    kw = dict(temperature=0.0, constraint="none", max_tokens=10, default_max_tokens=10)
    assert roc_levels_deviation(1) is None
    assert not any("--roc-levels" in d for d in deviations(LLMAgentConfig(), **kw))
    assert any("--roc-levels 5" in d for d in deviations(LLMAgentConfig(), roc_levels=5, **kw))
    with pytest.raises(ConfigError, match="--roc-levels"):
        LLMRunSpec(roc_levels=0)
