"""The navigation prompt in a background flow (an extension): S2 says the fluid flows, each
record gives the local flow before the step in thousandths per step (truncated and signed, as
a moving target's velocity is), and a still-fluid prompt is unchanged."""

from __future__ import annotations

import math

from jswim.prompt import (
    Action,
    HistoryRecord,
    NavView,
    PromptConfig,
    PromptTemplate,
    SwimmerText,
    nav_template,
    render_prompt,
)
from jswim.prompt.nav_text import FLOW_SENTENCE, NAV_RECORD

HI = math.pi / 3


def _text(flow: bool) -> SwimmerText:
    return SwimmerText(2, -HI, HI, rocs=(-2, -1, 0, 1, 2), roc_levels=2, nav=NavView(flow=flow))


def _rec(flow) -> HistoryRecord:
    return HistoryRecord(
        1,
        (HI, HI),
        (HI, 0.0),
        Action(2, -1),
        0.0,
        0.01,
        y_before=0.0,
        y_after=0.03,
        heading_before=0.0,
        heading_after=0.1,
        flow=flow,
    )


def _render(flow_on: bool, flow) -> str:
    cfg = PromptConfig(n_ht=3, x_min=-5.0, template=nav_template(flow=flow_on))
    return render_prompt(_text(flow_on), cfg, 1, [_rec(flow)], (HI, 0.0), 0.0, target=(3.0, 0.0))


def test_records_in_a_flow_give_the_local_flow_in_thousandths_per_step():
    # u = (0.0239, -0.0071) a per step: 23.9 -> 23 and -7.1 -> -7 (truncated toward zero)
    text = _render(True, (0.0239059, -0.0071))
    line = next(ln for ln in text.splitlines() if ln.startswith("1:"))
    assert line == (
        "1: (1.047, 1.047) [2, -1] -> (1.047, 0.000), X 5000 -> 5010, Y 5000 -> 5030, "
        "heading 0.000 -> 0.100, flow (23, -7), stuck no"
    )
    assert FLOW_SENTENCE in text
    assert "flow (X, Y), stuck" in text  # S3's legend names the new field


def test_a_still_fluid_prompt_is_unchanged():
    text = _render(False, None)
    assert FLOW_SENTENCE not in text and "flow (" not in text
    assert nav_template() == nav_template(flow=False)
    assert nav_template().record == NAV_RECORD


def test_a_template_file_may_use_the_flow_placeholders():
    tpl = PromptTemplate(record="{step}: {action} flow {flow_x},{flow_y}")
    assert tpl.check() is tpl
