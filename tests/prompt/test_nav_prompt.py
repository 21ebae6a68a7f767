"""The navigation prompt (an extension): S1 names the target encoded as X is, S2 states the ROC
levels and what X, Y and the heading are, records give X, Y and the heading, S4 and S5 are the
paper's; the reference rule steers a navigation prompt with the controller's cycles."""

from __future__ import annotations

import math

import pytest

from jswim.errors import ConfigError
from jswim.llm.reference import decide, nav_decide
from jswim.prompt import (
    DEFAULT_SENTENCES,
    Action,
    HistoryRecord,
    NavView,
    PromptConfig,
    PromptTemplate,
    SwimmerText,
    nav_template,
    render_prompt,
)

HI = math.pi / 3


def _text(kind: str = "fixed", k: int = 2, **kw) -> SwimmerText:
    rocs = tuple(range(-k, k + 1))
    return SwimmerText(2, -HI, HI, rocs=rocs, roc_levels=k, nav=NavView(kind, **kw))


def _cfg(x_min: float = -5.0) -> PromptConfig:
    return PromptConfig(n_ht=3, x_min=x_min, template=nav_template())


def _rec(step, before, action, after, x0, x1, y0, y1, h0, h1) -> HistoryRecord:
    return HistoryRecord(
        step,
        before,
        after,
        Action(*action),
        x0,
        x1,
        y_before=y0,
        y_after=y1,
        heading_before=h0,
        heading_after=h1,
    )


def test_s1_names_the_target_encoded_as_x_and_s4_s5_are_the_papers():
    # X_min = -5: (3, -1.2345) -> ((3 + 5) 1000, (-1.234 + 5) 1000) = (8000, 3766), truncated as X is.
    text = render_prompt(_text(), _cfg(), 1, [], (HI, HI), 0.0, target=(3.0, -1.2345))
    assert "brings the swimmer to the target at (X, Y) = (8000, 3766) in the fewest steps" in text
    assert DEFAULT_SENTENCES["S4"] in text
    assert "Reply with the next action as [changed DOF, ROC]" in text
    # S2: the ROC levels (K = 2) and what X, Y, the heading and the radius are (radius 0.25 a: 250).
    assert "In one step a ROC of k changes the DOF by k/2 of its range" in text
    assert "heading is the angle of the swimmer's middle link" in text
    assert "reached within 250 of it" in text
    assert "positive x" not in text  # the paper's direction is not the task


def test_records_give_x_y_and_heading_and_stuck_reads_the_plane():
    moved_in_y = _rec(1, (HI, HI), (2, -1), (HI, 0.0), 0.0, 0.0, 0.0, 0.01, 0.0, 7.0)
    text = render_prompt(_text(), _cfg(), 1, [moved_in_y], (HI, 0.0), 0.0, target=(3.0, 0.0))
    line = next(ln for ln in text.splitlines() if ln.startswith("1:"))
    # heading 7 rad is wrapped into (-pi, pi]: 7 - 2 pi = 0.717
    assert line == (
        "1: (1.047, 1.047) [2, -1] -> (1.047, 0.000), X 5000 -> 5000, Y 5000 -> 5010, "
        "heading 0.000 -> 0.717, stuck no"
    )
    still = _rec(1, (HI, HI), (1, 1), (HI, HI), 0.5, 0.5, 0.2, 0.2, 0.0, 0.0)
    text = render_prompt(_text(), _cfg(), 1, [still], (HI, HI), 0.5, target=(3.0, 0.0))
    assert "stuck yes" in text


@pytest.mark.parametrize(
    "kind, kw, want",
    [
        (
            "moving",
            {"velocity": (0.0, 0.005)},
            [
                "the moving target, now at (X, Y) =",
                "The target moves by (0, 5) in (X, Y) every step.",
            ],
        ),
        (
            "waypoints",
            {"waypoints": 3},
            ["waypoint 2 of 3 at (X, Y) =", "The path has 3 waypoints"],
        ),
    ],
)
def test_moving_targets_and_paths_say_so(kind, kw, want):
    text = render_prompt(
        _text(kind, **kw), _cfg(), 1, [], (HI, HI), 0.0, target=(1.0, 1.0), waypoint=2
    )
    for piece in want:
        assert piece in text


def test_a_navigation_prompt_needs_its_target_and_a_bad_view_is_one_line():
    with pytest.raises(ConfigError, match="target's position"):
        render_prompt(_text(), _cfg(), 1, [], (HI, HI), 0.0)
    with pytest.raises(ConfigError, match="navigation target"):
        NavView("circle")
    with pytest.raises(ConfigError, match="success radius"):
        NavView(radius=0.0)


def test_a_template_file_may_use_the_navigation_placeholders():
    tpl = PromptTemplate.from_text(
        "[S1]\nGo to ({target_x}, {target_y}).\n"
        "[record]\n{step}: {action} X {x_after} Y {y_after} h {heading_after}\n"
    ).check()
    assert nav_template(tpl) is tpl  # an author's template is kept as given
    cfg = PromptConfig(n_ht=3, x_min=-5.0, template=tpl)
    rec = _rec(1, (HI, HI), (2, -2), (HI, -HI), 0.0, 0.1, 0.0, 0.0, 0.0, 0.0)
    text = render_prompt(_text(), cfg, 1, [rec], (HI, -HI), 0.1, target=(3.0, 0.0))
    assert "Go to (8000, 5000)." in text and "1: [2, -2] X 5100 Y 5000 h 0.000" in text


def _prompt(records, target=(3.0, 0.0), k=2):
    return render_prompt(_text(k=k), _cfg(), 1, records, records[-1].dofs_after, 0.0, target=target)


def test_reference_rule_turns_toward_the_target_with_the_quarter_loop_else_swims_the_gait():
    # On hub (hi, hi), having just closed a gait cycle forward ((0, K) -> (K, K): D1 up).
    at_hub = [_rec(4, (-HI, HI), (1, 2), (HI, HI), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)]
    assert nav_decide(_prompt(at_hub, (3.0, 0.0))) == (2, -2)  # ahead: the gait, D2 down
    assert nav_decide(_prompt(at_hub, (0.0, 3.0))) == (2, -1)  # left: the upper quarter loop
    assert nav_decide(_prompt(at_hub, (-3.0, 0.0))) == (1, -2)  # behind: the reversed gait
    # Between hubs it plays on its cycle: after (K, K) -> (K, K/2), on to (K/2, K/2).
    mid = [_rec(5, (HI, HI), (2, -1), (HI, 0.0), 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)]
    assert nav_decide(_prompt(mid, (0.0, 3.0))) == (1, -1)
    # Any other prompt: not the navigation rule's.
    assert nav_decide("Find ... in the positive x direction.") is None
    assert decide(_prompt(at_hub, (0.0, 3.0))) == (2, -1)
