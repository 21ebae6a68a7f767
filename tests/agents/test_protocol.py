"""The protocol as pure functions (jswim.agents.protocol): no server, no event loop, no env."""

from __future__ import annotations

import math


from jswim.agents import protocol
from jswim.agents.memory import MoveStats
from jswim.agents.variants import LLMAgentConfig, LLMRunSpec, variant_config
from jswim.prompt import Action, HistoryRecord
from jswim.swimmers.models import make_model

LO, HI = -math.pi / 3, math.pi / 3
ALL = [Action(d, r) for d in (1, 2) for r in (-1, 0, 1)]


def first_request(
    cfg: LLMAgentConfig,
    spec: LLMRunSpec = LLMRunSpec(),
    step: int = 1,
    records=(),
    x=0.0,
    dofs=(HI, HI),
):
    _, text, prompt = protocol.setup(spec, make_model(spec.swimmer), cfg)
    return protocol.request(
        cfg,
        text,
        prompt,
        direction=spec.direction,
        seed=spec.seed,
        step=step,
        records=list(records),
        dofs=dofs,
        x=x,
        stats=MoveStats(),
    )


def test_setup_takes_the_swimmer_s_agent_defaults_unless_the_spec_sets_them():
    cfg = LLMAgentConfig()
    assert (
        protocol.setup(LLMRunSpec("purcell"), make_model("purcell"), cfg)[0] == 3
    )  # the authors' default
    assert protocol.setup(LLMRunSpec("ng"), make_model("ng"), cfg)[0] == 3  # paper: NG +x
    assert (
        protocol.setup(LLMRunSpec("ng", direction=-1), make_model("ng"), cfg)[0] == 6
    )  # paper: NG -x
    n_ht, text, prompt = protocol.setup(LLMRunSpec("nlink", n_ht=2), make_model("nlink"), cfg)
    assert n_ht == prompt.n_ht == 2 and text.rocs == (-1, 1) and text.n_dof == 3
    assert protocol.setup(LLMRunSpec("ng"), make_model("ng"), cfg)[1].dof_decimals == 0


def test_request_is_one_user_message_offering_every_action():
    req = first_request(LLMAgentConfig())
    # fidelity.md: a system message holding a single space, then one user message.
    assert req.messages == [
        {"role": "system", "content": " "},
        {"role": "user", "content": req.prompt},
    ]
    assert req.allowed == req.options == ALL
    assert req.replies == ["[1, -1]", "[1, 0]", "[1, 1]", "[2, -1]", "[2, 0]", "[2, 1]"]
    assert "Reply with the next action" in req.prompt and "none yet" in req.prompt
    sys_req = first_request(LLMAgentConfig(system="You steer a swimmer."))
    assert sys_req.messages[0] == {"role": "system", "content": "You steer a swimmer."}


def test_history_records_reach_the_prompt():
    recs = [HistoryRecord(1, (HI, HI), (LO, HI), Action(1, -1), 0.0, 0.1234)]
    req = first_request(LLMAgentConfig(), step=2, records=recs, x=0.1234, dofs=(LO, HI))
    # X encoded as (X - X_min) * 1000 with X truncated to 3 decimals: 0.123 + 2.5 -> 2623.
    assert "1: (1.047, 1.047) [1, -1] -> (-1.047, 1.047), X 2500 -> 2623" in req.prompt


def test_shape_changing_offers_only_moves_that_change_the_shape():
    req = first_request(variant_config("shape-changing"), dofs=(HI, LO))
    assert req.allowed == [Action(1, -1), Action(2, 1)]


def test_shuffle_reorders_per_step_and_replays_but_never_changes_the_set_or_the_grammar():
    cfg = variant_config("shuffle")
    orders = [first_request(cfg, LLMRunSpec(seed=5), step=s).options for s in range(1, 9)]
    assert all(sorted(o) == ALL for o in orders) and len({tuple(o) for o in orders}) > 2
    assert orders == [first_request(cfg, LLMRunSpec(seed=5), step=s).options for s in range(1, 9)]
    assert orders != [first_request(cfg, LLMRunSpec(seed=6), step=s).options for s in range(1, 9)]
    assert all(first_request(cfg, step=s).allowed == ALL for s in range(1, 9))  # grammar order


def test_read_reply_gives_an_action_a_follow_up_or_up():
    cfg = LLMAgentConfig(parse_retries=1)
    req = first_request(cfg)
    assert protocol.read_reply(req, req.messages, "Sure: [2, 1].", 0, cfg) == protocol.Reply(
        Action(2, 1)
    )
    retry = protocol.read_reply(req, req.messages, "I am not sure.", 0, cfg)
    assert retry.action is None and retry.follow_up[:2] == req.messages
    assert retry.follow_up[2] == {"role": "assistant", "content": "I am not sure."}
    assert (
        retry.follow_up[3]["role"] == "user" and "[1, -1], [1, 0]" in retry.follow_up[3]["content"]
    )
    assert protocol.read_reply(req, retry.follow_up, "still no", 1, cfg) == protocol.Reply(
        None
    )  # retries used up
    # A pair outside the offered set is not an action.
    sc = first_request(variant_config("shape-changing"), dofs=(HI, LO))
    assert protocol.read_reply(sc, sc.messages, "[1, 1]", 0, cfg).action is None


def test_sampling_seeds_exist_only_above_temperature_zero_and_differ_per_attempt():
    assert protocol.sample_seed(1, 3, 0, 0.0) is None
    seeds = {protocol.sample_seed(1, 3, k, 0.7) for k in range(3)} | {
        protocol.sample_seed(2, 3, 0, 0.7)
    }
    assert len(seeds) == 4 and all(0 <= s < 2**31 for s in seeds)
    assert protocol.sample_seed(1, 3, 0, 0.7) == protocol.sample_seed(1, 3, 0, 0.2)  # stable


def test_max_tokens_per_swimmer_raised_only_for_a_constrained_format():
    # fidelity.md: max_tokens 10 (three-DOF), 20 (four-DOF); no constrained decoding.
    cfg = LLMAgentConfig()
    assert protocol.max_tokens(cfg, make_model("purcell")) == 10
    assert protocol.max_tokens(cfg, make_model("ng")) == 10
    assert protocol.max_tokens(cfg, make_model("nlink")) == 20
    assert protocol.max_tokens(cfg, make_model("nsphere")) == 20
    assert (
        protocol.max_tokens(cfg, make_model("purcell"), "json_schema") > 10
    )  # {"action": "[1, -1]"}
    assert protocol.max_tokens(LLMAgentConfig(max_tokens=50), make_model("purcell")) == 50


def test_the_paper_protocol_shares_nothing_between_runs_by_default():
    cfg = LLMAgentConfig()
    assert cfg.share_identical is False and cfg.system == " " and cfg.order == "paper"
    assert protocol.clearing_rule(cfg, make_model("nlink")).window == 40


def test_a_cut_off_reply_is_no_answer_and_says_so():
    cfg = LLMAgentConfig(parse_retries=1)
    req = first_request(cfg)
    # A reply stopped at max_tokens may end mid-sentence ("[1, 1] would fail, so"): never executed.
    cut = protocol.read_reply(req, req.messages, "[1, 1] would fail, so", 0, cfg, truncated=True)
    assert cut.action is None and "cut off" in cut.follow_up[-1]["content"]
    assert cut.follow_up[-2] == {"role": "assistant", "content": "[1, 1] would fail, so"}
    empty = protocol.read_reply(req, req.messages, "", 0, cfg, truncated=True)
    assert empty.follow_up[-2]["content"] == protocol.CUTOFF_TURN  # never an empty assistant turn
    assert empty.follow_up != req.messages  # a deterministic server is never asked the same again
    assert protocol.valid_reply(req, "[2, -1]") and not protocol.valid_reply(req, "no idea")
