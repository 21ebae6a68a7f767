"""The text-only prompt layer: sentences, history, number encoding, clearing, reply parsing."""

from __future__ import annotations

import math
import re
import sys

import pytest

from jswim.errors import ConfigError
from jswim.prompt import (
    CACHE_LAYOUT,
    DEFAULT_SENTENCES,
    PAPER_LAYOUT,
    SENTENCES,
    Action,
    HistoryRecord,
    PromptConfig,
    PromptTemplate,
    SwimmerText,
    allowed_actions,
    build_messages,
    encode_position,
    format_dof,
    normalize_mask,
    parse_reply,
    render_prompt,
)

PURCELL = SwimmerText(2, -math.pi / 3, math.pi / 3, dof_decimals=3)
NG = SwimmerText(2, 6.0, 10.0, dof_decimals=0)
HI = (math.pi / 3, math.pi / 3)

# A phrase unique to each default sentence.
MARKERS = {
    "S1": "fastest long-term movement",
    "S2": "Only one DOF changes at a time",
    "S3": "Latest records",
    "S4": "long-term consequences",
    "S5": "Reply with the next action",
}


def rec(
    step: int,
    x0: float = 0.0,
    x1: float = 0.01,
    action: Action = Action(1, -1),
    stuck: bool = False,
) -> HistoryRecord:
    return HistoryRecord(step, HI, (-math.pi / 3, math.pi / 3), action, x0, x1, stuck)


def test_prompt_layer_never_imports_jax():
    import subprocess

    code = "import sys, jswim.prompt, jswim.llm, jswim.llm.local; assert 'jax' not in sys.modules, 'jax imported'"
    subprocess.run(
        [sys.executable, "-c", code],
        check=True,
        cwd=str(__import__("pathlib").Path(__file__).parents[2]),
    )


def test_full_prompt_contents():
    text = render_prompt(PURCELL, PromptConfig(), +1, [rec(1)], HI)
    for phrase in MARKERS.values():
        assert phrase in text
    # fidelity.md: S1 spells out the aliases once and names the direction in words.
    assert text.count("rates of change (ROC)") == 1 and text.count("degrees of freedom (DOF)") == 1
    assert "positive x direction" in text
    assert "D1 and D2 each stay in [-1.047, 1.047]" in text
    # S5: the answer format, then DOF choices and ROC choices given separately.
    assert "[changed DOF, ROC], the changed DOF 1 or 2 and the ROC -1, 0 or 1." in text
    # Every record carries the stuck flag.
    assert "1: (1.047, 1.047) [1, -1] -> (-1.047, 1.047), X 2500 -> 2510, stuck no" in text
    assert "  " not in text


def test_paper_order_is_the_default():
    # fidelity.md: one user message, S1 S2 S3 S4 S5 in that order, the history third, so the
    # answer instruction is the last thing the model reads.
    text = render_prompt(PURCELL, PromptConfig(), 1, [rec(1)], HI)
    pos = [text.index(MARKERS[n]) for n in SENTENCES]
    assert pos == sorted(pos)
    assert text.index("X 2500 -> 2510") < text.index(MARKERS["S4"])
    assert text.rstrip().endswith("the ROC -1, 0 or 1.")
    assert PromptConfig().template.layout == PAPER_LAYOUT


def test_stuck_flag_on_every_record_holds_included():
    # fidelity.md: stuck = |dX| < 1e-6, so a hold (ROC 0) is stuck too.
    hold = HistoryRecord(1, HI, HI, Action(2, 0), 0.2, 0.2)
    tiny = HistoryRecord(2, HI, HI, Action(1, -1), 0.2, 0.2 + 5e-7)
    moved = HistoryRecord(3, HI, HI, Action(1, -1), 0.2, 0.2 + 2e-6)
    text = render_prompt(PURCELL, PromptConfig(), 1, [hold, tiny, moved], HI)
    flags = [ln.rsplit("stuck ", 1)[1] for ln in text.splitlines() if ln[:2] in ("1:", "2:", "3:")]
    assert flags == ["yes", "yes", "no"]


@pytest.mark.parametrize("name", SENTENCES)
def test_each_sentence_can_be_removed(name):
    text = render_prompt(PURCELL, PromptConfig(drop={name}), -1, [rec(1)], HI)
    assert MARKERS[name] not in text
    for other, phrase in MARKERS.items():
        if other != name:
            assert phrase in text
    assert "  " not in text and not text.startswith(("\n", " ")) and "\n\n" not in text
    if name == "S3":
        assert "2500 -> 2510" not in text


def test_sentence_masks():
    assert normalize_mask((True, True, False, True, False)) == {"S3", "S5"}
    assert normalize_mask(["s4"]) == {"S4"}
    assert normalize_mask(None) == frozenset()
    with pytest.raises(ConfigError):
        normalize_mask(["S6"])
    with pytest.raises(ConfigError):
        normalize_mask((True, False))
    everything = render_prompt(PURCELL, PromptConfig(drop=SENTENCES), 1, [rec(1)], HI)
    assert everything == ""


def test_history_window_shows_last_n_ht():
    records = [rec(k, 0.01 * (k - 1), 0.01 * k) for k in range(1, 11)]
    text = render_prompt(PURCELL, PromptConfig(n_ht=3), 1, records, HI)
    lines = [ln for ln in text.splitlines() if "->" in ln and ln[0].isdigit()]
    assert [ln.split(":")[0] for ln in lines] == ["8", "9", "10"]
    empty = render_prompt(PURCELL, PromptConfig(n_ht=3), 1, [], HI)
    assert "none yet" in empty
    none = render_prompt(PURCELL, PromptConfig(n_ht=0), 1, records, HI)
    assert "none yet" in none


def test_cache_friendly_order_keeps_fixed_text_first():
    cfg = PromptConfig(n_ht=2, order="cache")
    a = render_prompt(PURCELL, cfg, 1, [rec(1)], HI)
    b = render_prompt(PURCELL, cfg, 1, [rec(1), rec(2, 0.01, 0.03)], HI)
    history_at = a.index("\n1: ")
    assert a[:history_at] == b[:history_at]  # everything before the history is shared
    for name in ("S1", "S2", "S4", "S5"):
        assert a.index(MARKERS[name]) < history_at
    assert cfg.layout == CACHE_LAYOUT
    with pytest.raises(ConfigError):
        PromptConfig(order="fast")


def test_ng_ranges_and_integer_lengths():
    r = HistoryRecord(3, (10.0, 6.0), (6.0, 6.0), Action(1, -1), 0.1, 0.25, False)
    text = render_prompt(NG, PromptConfig(), 1, [r], (6.0, 6.0))
    assert "each stay in [6, 10]" in text
    assert "3: (10, 6) [1, -1] -> (6, 6), X 2600 -> 2750" in text


def test_any_number_of_dofs_and_roc_sets():
    four = SwimmerText(4, 6.0, 10.0, 0, rocs=(-1, 1))
    text = render_prompt(four, PromptConfig(), 1, [], (10.0,) * 4)
    assert "(DOF) D1, D2, D3 and D4" in text
    assert "the changed DOF 1, 2, 3 or 4 and the ROC -1 or 1." in text
    assert "[1, 0]" not in text
    one = SwimmerText(1, 0.0, 1.0, 1)
    assert "D1 stays in [0.0, 1.0]" in render_prompt(one, PromptConfig(), 1, [], (0.0,))
    uneven = SwimmerText(2, (0.0, 1.0), (2.0, 3.0), 0)
    assert "D1 stays in [0, 2] and D2 stays in [1, 3]" in render_prompt(
        uneven, PromptConfig(), 1, [], (0.0, 1.0)
    )


def test_shape_changing_allowed_set():
    lo, hi = -math.pi / 3, math.pi / 3
    assert allowed_actions(PURCELL, "shape-changing", (hi, lo)) == [Action(1, -1), Action(2, 1)]
    assert allowed_actions(PURCELL, "shape-changing", (lo, lo)) == [Action(1, 1), Action(2, 1)]
    assert len(allowed_actions(PURCELL)) == 6
    text = render_prompt(PURCELL, PromptConfig(action_set="shape-changing"), 1, [], (hi, hi))
    assert "one of [1, -1], [2, -1]." in text
    with pytest.raises(ValueError):
        allowed_actions(PURCELL, "shape-changing")
    with pytest.raises(ConfigError):
        PromptConfig(action_set="some")


@pytest.mark.parametrize(
    "x, x_min, expected",
    [
        (0.0, -2.5, 2500),
        (0.0129, -2.5, 2512),  # truncated, not rounded
        (0.0129999, -2.5, 2512),
        (1.001, -2.5, 3501),  # no float artefact (1.001 * 1000 = 1000.99999...)
        (-0.0005, -2.5, 2500),  # truncation is toward zero
        (-1.2345, -2.5, 1266),
        (-2.5, -2.5, 0),
        (0.4, -1.0, 1400),
    ],
)
def test_position_encoding(x, x_min, expected):
    assert encode_position(x, x_min) == expected


def test_position_below_minimum_is_sent_as_a_negative_number():
    # fidelity.md: a value below X_min is sent as a negative number; runs are never stopped for it.
    assert encode_position(-2.6) == -100
    assert encode_position(-2.5129) == -12  # truncated toward zero: -2.512
    text = render_prompt(PURCELL, PromptConfig(), -1, [rec(1, -2.4, -2.51)], HI)
    assert "X 100 -> -10" in text
    text = render_prompt(PURCELL, PromptConfig(x_min=-5.0), -1, [rec(1, -2.4, -2.51)], HI)
    assert "X 2600 -> 2490" in text


def test_dof_formatting():
    assert format_dof(math.pi / 3, 3) == "1.047"
    assert format_dof(-math.pi / 3, 3) == "-1.047"
    assert format_dof(-1e-9, 3) == "0.000"
    assert format_dof(9.6, 0) == "10"


@pytest.mark.parametrize(
    "reply, expected",
    [
        ("[1, -1]", Action(1, -1)),
        ("[1,-1]", Action(1, -1)),
        ("[ 2 , 1 ]", Action(2, 1)),
        ("(2, 1)", Action(2, 1)),
        ("DOF 1, ROC -1", Action(1, -1)),
        ("dof=2 and roc=+1", Action(2, 1)),
        ("```json\n[2, 0]\n```", Action(2, 0)),
        ('{"action": "[1, 0]"}', Action(1, 0)),
        ("Next: [D2, -1].", Action(2, -1)),
        ("[2, \u22121]", Action(2, -1)),  # unicode minus
        ("The answer is [2, 1]. Previously [1, -1] failed.", Action(2, 1)),  # first valid wins
        ("[3, 1] is impossible, so [1, 1]", Action(1, 1)),  # invalid candidates are skipped
        ("[1, 2] then (2, -1)", Action(2, -1)),
        ("I would move the first joint down.", None),
        ("", None),
        ("[3, 1]", None),
    ],
)
def test_parse_reply(reply, expected):
    assert parse_reply(reply, allowed_actions(PURCELL)) == expected


def test_parse_reply_respects_allowed_set():
    _lo, hi = -math.pi / 3, math.pi / 3
    allowed = allowed_actions(PURCELL, "shape-changing", (hi, hi))
    assert parse_reply("[1, 1]", allowed) is None
    assert parse_reply("[1, 1] or [2, -1]", allowed) == Action(2, -1)
    assert parse_reply("[7, 9]") == Action(7, 9)  # no allowed set: any pair


def test_template_from_text_and_file(tmp_path):
    whole = PromptTemplate.from_text("Go {direction}. {S5}\n{history}\n")
    text = render_prompt(PURCELL, PromptConfig(template=whole), -1, [rec(1)], HI)
    assert text.startswith("Go -x. Reply with the next action")
    assert text.endswith("X 2500 -> 2510, stuck no")

    f = tmp_path / "t.txt"
    f.write_text(
        "[S4]\nThink ahead.\n[record]\n#{step} {action} {x_after}{stuck}\n[layout]\n{S4}\n{S3}\n"
    )
    with pytest.raises(ConfigError, match="never shows the allowed set"):  # no S5: refused up front
        PromptTemplate.from_file(f)
    f.write_text(
        "[S4]\nThink ahead.\n[record]\n#{step} {action} {x_after}{stuck}\n[layout]\n{S4}\n{S5}\n{S3}\n"
    )
    tpl = PromptTemplate.from_file(f)
    assert tpl.sentence("S1") == DEFAULT_SENTENCES["S1"]
    text = render_prompt(PURCELL, PromptConfig(template=tpl), 1, [rec(2, stuck=True)], HI)
    assert text.splitlines()[0] == "Think ahead."
    assert text.endswith("#2 [1, -1] 2510yes")

    with pytest.raises(ConfigError, match="nope"):
        render_prompt(PURCELL, PromptConfig(template=PromptTemplate(layout="{nope}")), 1, [], HI)
    with pytest.raises(ConfigError):
        PromptTemplate.from_text("junk\n[S1]\nx")
    with pytest.raises(ConfigError):
        PromptTemplate.from_file(tmp_path / "missing.txt")
    assert "{x}" in render_prompt(
        PURCELL, PromptConfig(template=PromptTemplate(layout="{{x}} {S4}")), 1, [], HI
    )


def test_current_state_placeholder():
    tpl = PromptTemplate(layout="{current}")
    assert (
        render_prompt(PURCELL, PromptConfig(template=tpl), 1, [], HI, x=0.1234)
        == "(D1, D2) = (1.047, 1.047), X = 2623"
    )


def test_build_messages():
    assert build_messages("hi") == [{"role": "user", "content": "hi"}]
    assert build_messages("hi", "sys") == [
        {"role": "system", "content": "sys"},
        {"role": "user", "content": "hi"},
    ]


def test_per_step_text_goes_last_and_the_paper_prompt_is_unchanged():
    lo, hi = -math.pi / 3, math.pi / 3
    rec = HistoryRecord(1, (hi, hi), (lo, hi), Action(1, -1), 0.0, 0.01)
    cache = render_prompt(PURCELL, PromptConfig(order="cache"), 1, [rec], (lo, hi))
    assert PromptConfig(order="cache").layout == CACHE_LAYOUT and cache.index(
        "Reply with"
    ) < cache.index("1: (")
    for cfg in (
        PromptConfig(action_set="shape-changing", order="cache"),
        PromptConfig(shuffle=True, order="cache"),
        PromptConfig(summary=True, order="cache"),
    ):
        text = render_prompt(
            PURCELL, cfg, 1, [rec], (lo, hi), summary="Observed so far: x." if cfg.summary else ""
        )
        lines = text.splitlines()
        assert lines[-1].startswith("Reply with the next action"), text  # S5 last: per-step text
        if cfg.summary:
            assert lines[-2] == "Observed so far: x." and lines[-3].startswith("1: (")
    # The paper's layout (the default) has no {summary} slot: the sentence precedes S3.
    cfg = PromptConfig(summary=True)
    text = render_prompt(PURCELL, cfg, 1, [rec], (lo, hi), summary="Observed so far: x.")
    assert text.index("Observed so far") < text.index("Latest records") < text.index("Reply with")


@pytest.mark.parametrize(
    "reply, expected",
    [
        # Bare pairs: the whole reply, or after an answer word.
        ("1, 1", Action(1, 1)),
        ("2, -1", Action(2, -1)),
        ("2,-1.", Action(2, -1)),
        ("`2, -1`", Action(2, -1)),
        ("Answer: 2, -1", Action(2, -1)),
        ("I pick 2, 1", Action(2, 1)),
        ("2, 1.5", None),  # not two integers
        ("Step 3: 1, 1", None),  # a step number, not an answer
        # The final answer, not the first pair mentioned.
        ("not [1, 1]; answer [2, -1]", Action(2, -1)),
        ("Not [1, 1] again. [2, -1]", Action(2, -1)),
        ("Instead of [1, 1], use [2, -1].", Action(2, -1)),
        ("not [1, 1] but [2, -1]", Action(2, -1)),
        ("Don't repeat [1, 1]; [2, 0] instead", Action(2, 0)),
        ("[1, 1] didn't work so [2, -1]", Action(2, -1)),
        ("Since [1, 1] was stuck, I'd go with [2, -1].", Action(2, -1)),
        ("The move [1, 1] failed; next move: [2, -1]", Action(2, -1)),
        ("Final answer: [2, 1]", Action(2, 1)),
        # Several answer words: the last one decides (a model that changes its mind).
        ("I choose [1, 1]. On second thought, the answer is [2, -1]", Action(2, -1)),
        ("Answer: [1, 1]... wait, that is stuck. Final answer: [2, 1]", Action(2, 1)),
        ("[2, -1] because [1, 1] was stuck.", Action(2, -1)),  # answer first
        ('{"dof": 2, "roc": -1}', Action(2, -1)),
        # Two pairs, neither in an answer position: ambiguous, ask again.
        ("Either [1, 1] or [2, -1] could work here", None),
        ("not [1, 1]", None),  # only a rejected pair
    ],
)
def test_parse_reply_takes_the_final_answer(reply, expected):
    assert parse_reply(reply, allowed_actions(PURCELL)) == expected


@pytest.mark.parametrize(
    "text, words",
    [
        ("Go {direction}. {S5}\n{S3}\n{bogus}", "unknown placeholder {bogus} in the layout"),
        ("[record]\n#{step} {nope}\n", "unknown placeholder {nope} in the record"),
        ("Go {direction}. Answer with one of {allowed}.", "never shows the history"),
        (
            "[S3]\nno records here\n[layout]\n{S3} {S5}",
            "never shows the history",
        ),  # S3 without {history}
        ("Go {direction}.\n{history}", "never shows the allowed set"),
        ("Go {direction {S3} {S5}", "bad braces"),
    ],
)
def test_template_check_refuses_what_cannot_work(text, words):
    with pytest.raises(ConfigError, match=re.escape(words)):
        PromptTemplate.from_text(text).check()


def test_template_check_accepts_every_placeholder_the_prompt_fills():
    from jswim.prompt import PROMPT_FIELDS as names, RECORD_FIELDS as record

    layout = " ".join("{" + n + "}" for n in names)
    assert PromptTemplate.from_text(layout).check().layout == layout
    assert PromptTemplate(record=" ".join("{" + n + "}" for n in record)).check()
    # The default template passes and is the paper's order: S1 S2 / S3 / S4 S5, records as in Fig. 1.
    default = PromptTemplate()
    assert default.check() is default
    assert default.layout == "{S1} {S2}\n{S3}\n{S4} {S5}"
    assert default.record.startswith("{step}: ({dofs_before}) {action} -> ({dofs_after})")


def test_the_declared_placeholders_are_the_ones_rendering_fills():
    # PromptTemplate.check reads PROMPT_FIELDS and RECORD_FIELDS; rendering fills its own dicts.
    from jswim.prompt import PROMPT_FIELDS, RECORD_FIELDS, SENTENCES, allowed_actions
    from jswim.prompt.records import _record_values
    from jswim.prompt.render import _prompt_values

    sw = SwimmerText(2, -1.0, 1.0, 3, (-1, 0, 1))
    cfg = PromptConfig()
    rec = HistoryRecord(1, (1.0, 1.0), (-1.0, 1.0), Action(1, -1), 0.0, 0.0)
    values = _prompt_values(sw, cfg, 1, [], allowed_actions(sw), (1.0, 1.0), 0.0, "")
    assert (*values, *SENTENCES) == PROMPT_FIELDS
    assert tuple(_record_values(rec, sw, cfg)) == RECORD_FIELDS
    school = HistoryRecord(1, (1.0,), (1.0,), Action(1, 1), 0.0, 0.0, xs_before=(0.0,) * 3)
    assert set(RECORD_FIELDS) < set(_record_values(school, sw, cfg))
