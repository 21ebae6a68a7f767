"""``--pair-prompt each`` (a variant of the joint pair prompt): each swimmer of a pair its
own LLM conversation, the two taking turns. Its prompt text against hand-written literals, the two
histories kept apart, the option's checks, and a pair study end to end against a fake server."""

from __future__ import annotations

import json

import pytest

from jswim import cli
from jswim.agents import pair_prompt
from jswim.agents.variants import LLMAgentConfig, LLMRunSpec
from jswim.errors import ConfigError
from jswim.prompt import Action, HistoryRecord, SceneView, render_prompt
from jswim.results import read_metadata, read_runs
from jswim.studies import StudyOptions, run_study
from jswim.studies.specs import build
from jswim.studies.run import default_folder, identity
from jswim.studies.scene_grids import pair_scene
from jswim.swimmers.models import make_model
from tests.fakeserver import FakeServer, scene_reply

SPEC = LLMRunSpec(swimmer="ng", scene=pair_scene(30.0), pair_prompt="each", init=(1, 0))


def _convs():
    return pair_prompt.conversations(
        SPEC, make_model("ng"), LLMAgentConfig(), [10.0, 6.0, 10.0, 6.0], SceneView(2, False, 30.0)
    )


def _joint(dofs_before, action, dofs_after, xs_before, xs_after):
    """A joint step's record as the driver builds it (x: the pair's mean)."""
    mean = lambda xs: sum(xs) / 2
    return HistoryRecord(
        0,
        dofs_before,
        dofs_after,
        action,
        mean(xs_before),
        mean(xs_after),
        False,
        xs_before,
        xs_after,
    )


# Swimmer 1 lengthens its second arm (joint [2, 1]), then swimmer 2 its own (joint [4, 1]);
# each move also carries the other swimmer a little (they feel each other).
STEP1 = _joint(
    (10.0, 6.0, 10.0, 6.0), Action(2, 1), (10.0, 10.0, 10.0, 6.0), (0.0, 0.0), (0.1722, 0.0012)
)
STEP2 = _joint(
    (10.0, 10.0, 10.0, 6.0),
    Action(4, 1),
    (10.0, 10.0, 10.0, 10.0),
    (0.1722, 0.0012),
    (0.1734, 0.1740),
)

HEAD = (
    "Find the sequence of rates of change (ROC) of the degrees of freedom (DOF) D1 and D2 that gives the fastest "
    "long-term movement in the positive x direction. Only one DOF changes at a time, and D1 and D2 each stay in "
    "[6, 10]. A second swimmer on the same axis, steered on its own, starts 30 sphere radii {where} this one and "
    "moves its arms between this one's steps; other X is its position, counted from its own start as X is.\n"
    "Latest records (step: (D1, D2) before [changed DOF, ROC] -> (D1, D2) after, X before -> after, "
    "other X before -> after, stuck):\n"
)
TAIL = (
    "\nKeep in mind that an action can have long-term consequences. Reply with the next action as "
    "[changed DOF, ROC], the changed DOF 1 or 2 and the ROC -1, 0 or 1."
)


def _prompt(c):
    return render_prompt(c.text, c.prompt, 1, c.history.records, c.dofs, c.x)


def test_each_swimmer_prompt_literal():
    one, two = _convs()
    assert _prompt(one) == HEAD.format(where="ahead of") + "none yet" + TAIL
    assert _prompt(two) == HEAD.format(where="behind") + "none yet" + TAIL
    pair_prompt.record([one, two], STEP1, 1)
    pair_prompt.record([one, two], STEP2, 1)
    # Each sees its own arms, its own action as [1 or 2, ROC], its own X, and the other's position.
    assert (
        _prompt(one)
        == HEAD.format(where="ahead of")
        + "1: (10, 6) [2, 1] -> (10, 10), X 2500 -> 2672, other X 2500 -> 2501, stuck no"
        + TAIL
    )
    assert (
        _prompt(two)
        == HEAD.format(where="behind")
        + "1: (10, 6) [2, 1] -> (10, 10), X 2501 -> 2674, other X 2672 -> 2673, stuck no"
        + TAIL
    )
    assert list(one.dofs) == [10.0, 10.0] and list(two.dofs) == [10.0, 10.0]
    assert one.x == 0.1734 and two.x == 0.1740  # the other's move carried swimmer 1 too


def test_above_a_wall_each_swimmer_sees_its_own_height_and_tilt():
    from jswim.prompt import (
        PromptConfig,
        SceneView,
        SwimmerText,
        render_record,
        scene_sentence,
        scene_template,
    )

    v = SceneView(2, True, 40.0, own=2)
    rec = HistoryRecord(
        1,
        (10.0, 6.0),
        (10.0, 10.0),
        Action(2, 1),
        0.0,
        0.1722,
        False,
        (0.0, 0.0),
        (0.0012, 0.1722),
        (5.0, 5.5),
        (5.001, 5.49),
        (0.0, 0.1),
        (0.002, 0.099),
    )
    line = render_record(
        rec, SwimmerText(2, 6.0, 10.0, 0, scene=v), PromptConfig(template=scene_template(v))
    )
    assert (
        line
        == "1: (10, 6) [2, 1] -> (10, 10), X 2500 -> 2672, other X 2500 -> 2501, H 5500 -> 5490, "
        "tilt 0.100 -> 0.099, stuck no"
    )
    assert scene_sentence(v).endswith(
        "counted from its own start as X is. The swimmer moves above a flat wall: H "
        "is its height above the wall in thousandths of its sphere radius and tilt its "
        "angle to the wall in radians."
    )
    with pytest.raises(ConfigError):
        SceneView(1, True, own=1)  # a lone swimmer has no other


def test_turns_and_joint_actions():
    assert [pair_prompt.turn(t) for t in range(1, 6)] == [0, 1, 0, 1, 0]
    assert pair_prompt.to_joint(1, Action(2, -1)) == Action(4, -1)
    assert pair_prompt.to_joint(0, Action(1, 0)) == Action(1, 0)  # swimmer 1's hold stays [1, 0]
    assert [pair_prompt.swimmer_of(Action(d, 1)) for d in (1, 2, 3, 4)] == [0, 0, 1, 1]


def test_the_two_histories_and_clearings_are_separate():
    one, two = _convs()
    dofs = [10.0, 6.0, 10.0, 6.0]
    xs = [0.0, 0.0]
    for t in range(12):  # swimmer 1 holds (no own progress); swimmer 2 moves on by 0.05 a a step
        if t % 2 == 0:
            rec = _joint(tuple(dofs), Action(1, 0), tuple(dofs), tuple(xs), (xs[0], xs[1] + 0.001))
        else:
            rec = _joint(
                tuple(dofs),
                Action(3 + t // 2 % 2, 1),
                tuple(dofs),
                tuple(xs),
                (xs[0] + 0.001, xs[1] + 0.05),
            )
        pair_prompt.record([one, two], rec, 1)
        xs = list(rec.xs_after)
    # Swimmer 1's rule saw six own steps summing to nothing: it cleared; swimmer 2's saw progress.
    assert (one.history.n_clears, two.history.n_clears) == (1, 0)
    assert one.history.records == [] and len(two.history.records) == 6
    assert [r.action for r in two.history.records] == [Action(1 + k % 2, 1) for k in range(6)]
    assert [r.step for r in two.history.records] == [1, 2, 3, 4, 5, 6]
    assert two.history.progress == pytest.approx([0.05] * 6)  # its own X, not the pair's mean


def test_the_option_is_checked():
    with pytest.raises(ConfigError, match="--pair-prompt must be one of joint, each"):
        LLMRunSpec(swimmer="ng", scene=pair_scene(30.0), pair_prompt="both")
    with pytest.raises(ConfigError, match="two or more swimmers"):
        LLMRunSpec(swimmer="ng", scene=pair_scene(), pair_prompt="each")
    # A school: the per-swimmer prompt takes any number of swimmers.
    school = json.dumps({"medium": "free", "separation": 30.0, "swimmers": 3})
    assert LLMRunSpec(swimmer="ng", scene=school, pair_prompt="each").pair_prompt == "each"
    with pytest.raises(ConfigError, match="--pair-prompt"):
        StudyOptions(pair_prompt="separate")
    assert SPEC.label() == "llm-ng-px-i+--z0-each-s0"


def test_bad_value_is_one_line(tmp_path, capsys):
    with pytest.raises(SystemExit) as stop:  # argparse's choices: a usage error, exit 2
        cli.main(["study", "pair", "--pair-prompt", "both", "--out", str(tmp_path / "x")])
    assert stop.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1 and "--pair-prompt" in err
    from jswim.cli import options as cli_options

    args = cli.build_parser().parse_args(["study", "pair", "--pair-prompt", "each"])
    assert cli_options.options(args, "pair").pair_prompt == "each"


def test_each_is_refused_where_no_llm_run_steers_a_pair(tmp_path):
    # It names the folder (identity), so dropping it silently would split one study into two folders.
    grid = dict(separations=(30.0,), phases=(0,), steps=4, q_runs=1)
    for study, extra in (("wall", {}), ("curves", {}), ("pair", {"agents": ("stroke", "ppo")})):
        with pytest.raises(ConfigError, match="has no use for --pair-prompt each") as err:
            run_study(
                study,
                StudyOptions(**grid, **extra, pair_prompt="each"),
                None,
                tmp_path / study,
            )
        assert "\n" not in str(err.value)
        assert not (tmp_path / study).exists()
    assert build(
        "pair", StudyOptions(**grid, agents=("llm",), pair_prompt="each")
    )  # the one place it applies
    # The scene grids likewise: another study would drop them.
    for study, kw in (
        ("wall", {"separations": (60.0,)}),
        ("curves", {"heights": (3.0,)}),
        ("pair", {"heights": [5.0]}),
    ):
        with pytest.raises(
            ConfigError, match=f"the {study} study has no use for --{next(iter(kw))}"
        ):
            build(study, StudyOptions(**kw))
    assert build(
        "wall", StudyOptions(heights=[3, 5], phases=[0, 1, 2, 3])
    )  # the defaults, as a list: fine


def test_plans_tag_the_variant_and_the_identity_keeps_old_folders():
    grid = dict(separations=(30.0,), phases=(0,))
    joint, each = (
        build("pair", StudyOptions(**grid)),
        build("pair", StudyOptions(**grid, pair_prompt="each")),
    )
    llm = [p for p in each if p.agent == "llm"]
    assert llm and all("-each-" in p.run_id and p.pair_prompt == "each" for p in llm)
    assert not any("each" in p.run_id for p in joint)
    # The baselines steer both swimmers whatever the LLM's prompt: the same runs.
    assert [p for p in joint if p.agent != "llm"] == [p for p in each if p.agent != "llm"]
    assert "pair_prompt" not in identity("pair", StudyOptions(**grid), None)["options"]
    assert default_folder("pair", StudyOptions(**grid), None) != default_folder(
        "pair", StudyOptions(**grid, pair_prompt="each"), None
    )


@pytest.mark.slow  # the pair's scene step compiles once per session (~10-20 s under load)
def test_each_pair_study_end_to_end_and_resume(tmp_path, monkeypatch):
    from jswim.llm import client as client_module

    opts = StudyOptions(
        agents=("llm",), separations=(30.0,), phases=(0,), runs=1, steps=8, pair_prompt="each"
    )
    out = tmp_path / "pair"
    real_chat = client_module.LLMClient.chat
    answered = {"n": 0}

    async def chat(
        self, *a, **kw
    ):  # Ctrl-C before the 6th call: mid-run, after both swimmers spoke
        if answered["n"] >= 5:
            raise KeyboardInterrupt
        res = await real_chat(self, *a, **kw)
        answered["n"] += 1
        return res

    with FakeServer(reply=scene_reply) as srv:
        monkeypatch.setattr(client_module.LLMClient, "chat", chat)
        with pytest.raises(KeyboardInterrupt):
            run_study("pair", opts, srv.backend(), out)
        monkeypatch.setattr(client_module.LLMClient, "chat", real_chat)
        assert srv.settle() == 5 and read_runs(out) == []
        run_study("pair", opts, srv.backend(), out)
        sent = srv.settle()
        (row,) = read_runs(out)
        # The five answered calls were replayed from the journal, not asked again.
        assert row["replayed_calls"] == 5 and sent == row["calls"]
        assert row["run_id"] == "llm-ng-px-i+--z0-each-D30-r0" and row["pair_prompt"] == "each"
        assert row["steps"] == 8 and row["failed_steps"] == 0 and row["parse_retries"] >= 1
        # Swimmer 1 (D1, D2) moves at odd steps, swimmer 2 (D3, D4) at even ones.
        assert [(a[0] - 1) // 2 for a in row["actions"]] == [0, 1] * 4
        lines = [
            json.loads(x)
            for x in (out / "transcripts" / f"{row['run_id']}.jsonl").read_text().splitlines()
        ]
        assert lines[0]["pair_prompt"] == "each" and len(lines[0]["conversations"]) == 2
        steps = [x for x in lines if x["type"] == "step"]
        assert [s["swimmer"] for s in steps] == [1, 2] * 4
        for s in steps:
            assert "the changed DOF 1 or 2 and" in s["prompt"]
            assert ("ahead of this one" if s["swimmer"] == 1 else "behind this one") in s["prompt"]
            own = s["own_action"]
            assert s["action"] == [own[0] + 2 * (s["swimmer"] - 1), own[1]]
        # Swimmer 2's last prompt lists its own earlier moves only, in its own numbering.
        mine = [tuple(s["own_action"]) for s in steps if s["swimmer"] == 2][:3]
        shown = [
            ln.split(" ")[3] + " " + ln.split(" ")[4]
            for ln in steps[-1]["prompt"].splitlines()
            if ln[:2] in ("1:", "2:", "3:")
        ]
        assert shown == [f"[{d}, {r}]" for d, r in mine]
        meta = read_metadata(out)
        assert any("--pair-prompt each" in line for line in meta["fidelity_deviations"])
        # Resumed once more: nothing is asked again.
        again = run_study("pair", opts, srv.backend(), out)
        assert srv.settle() == sent and [r["actions"] for r in again.rows] == [row["actions"]]


def test_the_fidelity_line_names_every_swimmer():
    from types import SimpleNamespace

    from jswim.agents.fidelity import EACH_PAIR_PROMPT, scene_deviation

    def scene(n):
        return SimpleNamespace(medium="free", swimmers=n, separation=30.0, obstacles=())

    assert scene_deviation(scene(1)) == "scene (an extension): medium 'free'"
    pair = scene_deviation(scene(2))
    assert "two coaxial NG swimmers 30 a apart" in pair and "D1..D4 (swimmer 2 owns D3, D4)" in pair
    assert scene_deviation(scene(2), "each").endswith(EACH_PAIR_PROMPT)
    four = scene_deviation(scene(4))
    assert "4 NG swimmers 30 a apart" in four and "D1..D8" in four and "X1..X4" in four
    each = scene_deviation(scene(4), "each")
    assert "swimmer k decides at steps k, k + 4" in each and "D1..D8" not in each
