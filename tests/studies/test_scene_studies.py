"""Agents and studies on scenes: the prompt's scene records, the parser on joint
DOFs, the fate rule, the joint-state Q-learner, the strokes, and ``jswim study wall`` / ``pair``
end to end against a fake server (folder, figures, show, resume)."""

from __future__ import annotations

import json

import jax
import numpy as np
import pytest

from jswim import cli
import jax.numpy as jnp

from jswim.agents import qlearning
from jswim.env.discretiser import HEIGHT_EDGES, WallCells
from jswim.scenes import decode_scene_action
from jswim.env.scene_world import SceneTask, SceneWorld
from jswim.env.registry import make
from jswim.scenes import Scene, scene_params
from jswim.prompt import (
    DEFAULT_TEMPLATE,
    Action,
    HistoryRecord,
    PromptConfig,
    SceneView,
    SwimmerText,
    allowed_actions,
    parse_reply,
    render_prompt,
    render_record,
    scene_template,
)
from jswim.results import read_metadata, read_runs
from jswim.studies import StudyOptions, run_study
from jswim.studies import scene_studies
from jswim.viz.publish import report
from tests.fakeserver import FakeServer, scene_reply

# -- prompt ---------------------------------------------------------------------------------------


def _wall_text():
    v = SceneView(1, True)
    return SwimmerText(2, 6.0, 10.0, 0, scene=v), PromptConfig(n_ht=3, template=scene_template(v))


def test_wall_record_shows_height_and_tilt():
    sw, cfg = _wall_text()
    rec = HistoryRecord(
        2,
        (10.0, 6.0),
        (10.0, 10.0),
        Action(2, 1),
        0.25,
        0.4129,
        False,
        (0.25,),
        (0.4129,),
        (5.0,),
        (4.98765,),
        (0.0,),
        (-0.01234,),
    )
    assert (
        render_record(rec, sw, cfg)
        == "2: (10, 6) [2, 1] -> (10, 10), X 2750 -> 2912, H 5000 -> 4987, tilt 0.000 -> -0.012, stuck no"
    )


def test_wall_prompt_literal():
    sw, cfg = _wall_text()
    text = render_prompt(sw, cfg, 1, [], (10.0, 6.0), 0.0)
    assert text == (
        "Find the sequence of rates of change (ROC) of the degrees of freedom (DOF) D1 and D2 that gives the fastest "
        "long-term movement in the positive x direction. Only one DOF changes at a time, and D1 and D2 each stay in "
        "[6, 10]. The swimmer moves above a flat wall: H is its height above the wall in thousandths of its sphere "
        "radius and tilt its angle to the wall in radians.\n"
        "Latest records (step: (D1, D2) before [changed DOF, ROC] -> (D1, D2) after, X before -> after, "
        "H before -> after, tilt before -> after, stuck):\nnone yet\n"
        "Keep in mind that an action can have long-term consequences. Reply with the next action as "
        "[changed DOF, ROC], the changed DOF 1 or 2 and the ROC -1, 0 or 1."
    )


def test_pair_record_and_prompt_literal():
    v = SceneView(2, False, 30.0)
    sw = SwimmerText(4, 6.0, 10.0, 0, scene=v)
    cfg = PromptConfig(n_ht=3, template=scene_template(v))
    rec = HistoryRecord(
        1,
        (10.0, 6.0, 10.0, 6.0),
        (10.0, 6.0, 10.0, 10.0),
        Action(4, 1),
        0.0,
        0.0861,
        False,
        (0.0, 0.0),
        (0.0, 0.1722),
    )
    assert (
        render_record(rec, sw, cfg)
        == "1: (10, 6, 10, 6) [4, 1] -> (10, 6, 10, 10), X1 2500 -> 2500, X2 2500 -> 2672, stuck no"
    )
    text = render_prompt(sw, cfg, -1, [rec], (10.0, 6.0, 10.0, 10.0), 0.0861)
    assert (
        "D1 and D2 are the arms of swimmer 1 and D3 and D4 those of swimmer 2, which starts 30 sphere radii "
        "ahead of it on the same axis; X1 and X2 are their positions, and the movement sought is that of their "
        "mean.\n"
    ) in text
    assert (
        "(step: (D1, D2, D3, D4) before [changed DOF, ROC] -> (D1, D2, D3, D4) after, X1 before -> after, "
        "X2 before -> after, stuck):\n1: (10, 6, 10, 6) [4, 1]" in text
    )
    assert text.endswith("the changed DOF 1, 2, 3 or 4 and the ROC -1, 0 or 1.")
    assert "negative x direction" in text


def test_pair_above_a_wall_shows_both_heights():
    v = SceneView(2, True, 40.0)
    rec = HistoryRecord(
        1,
        (10.0,) * 4,
        (6.0,) + (10.0,) * 3,
        Action(1, -1),
        0.0,
        -0.01,
        False,
        (0.0, 0.0),
        (-0.02, 0.0),
        (5.0, 5.5),
        (5.001, 5.5),
        (0.0, 0.1),
        (0.002, 0.1),
    )
    line = render_record(
        rec, SwimmerText(4, 6.0, 10.0, 0, scene=v), PromptConfig(template=scene_template(v))
    )
    assert line == (
        "1: (10, 10, 10, 10) [1, -1] -> (6, 10, 10, 10), X1 2500 -> 2480, X2 2500 -> 2500, "
        "H1 5000 -> 5001, tilt1 0.000 -> 0.002, H2 5500 -> 5500, tilt2 0.100 -> 0.100, stuck no"
    )


def test_bulk_prompt_is_untouched_by_scenes():
    # No scene: the paper's template and record (the literal tests in test_prompt.py hold the text).
    sw = SwimmerText(2, 6.0, 10.0, 0)
    rec = HistoryRecord(1, (10.0, 6.0), (10.0, 10.0), Action(2, 1), 0.0, 0.1)
    assert (
        render_record(rec, sw, PromptConfig())
        == "1: (10, 6) [2, 1] -> (10, 10), X 2500 -> 2600, stuck no"
    )


def test_a_user_template_is_kept_for_a_scene():
    tpl = DEFAULT_TEMPLATE.with_sentences(S4="Think.")
    assert scene_template(SceneView(2, True, 30.0), tpl) is tpl


def test_parser_takes_exactly_the_joint_actions():
    pair = allowed_actions(SwimmerText(4, 6.0, 10.0, 0, scene=SceneView(2, False, 30.0)))
    assert parse_reply("[3, 1]", pair) == Action(3, 1)
    assert parse_reply("I choose [4, -1].", pair) == Action(4, -1)
    for bad in ("[5, 1]", "[0, 1]", "[3, 2]", "[3, 0.5]", "swimmer 2"):
        assert parse_reply(bad, pair) is None, bad
    alone = allowed_actions(SwimmerText(2, 6.0, 10.0, 0, scene=SceneView(1, True)))
    assert parse_reply("[3, 1]", alone) is None and parse_reply("[2, -1]", alone) == Action(2, -1)


# -- fates, strokes, joint actions ------------------------------------------------------------------


@pytest.mark.parametrize(
    "heights, contact, expected",
    [
        ([5.0, 4.0, 3.0, 2.0, 1.4, 1.2], None, "trapped"),  # below 1.5 a in the second half
        (
            [5.0, 4.8, 4.7, 4.7, 4.7, 4.7],
            [False, False, False, False, True, False],
            "trapped",
        ),  # touched
        ([5.0, 6.0, 7.5, 8.0, 9.0, 10.2], None, "escaped"),  # twice the start
        (
            [5.0, 5.0, 5.1, 5.3, 5.6, 5.9],
            None,
            "gliding",
        ),  # rising, not yet at twice the start: a gliding orbit's rising limb looks the same
        ([5.0, 5.1, 4.9, 5.05, 4.95, 5.0], None, "gliding"),
        (
            [20.0, 19.0, 18.0, 17.5, 17.2, 17.0],
            None,
            "gliding",
        ),  # sinking slowly, far from the wall
    ],
)
def test_fate_rule(heights, contact, expected):
    f, mean = scene_studies.fate(heights, heights[0], contact)
    assert f == expected
    assert mean == pytest.approx(np.mean(heights[3:]))


def test_stroke_codes_and_per_cycle():
    assert scene_studies.stroke_codes("square", 1, 6, 1).tolist() == [5, 0, 3, 2, 5, 0]
    assert scene_studies.stroke_codes("square", -1, 4, 1).tolist() == [0, 5, 2, 3]
    # Swimmer 2 (codes + 6) two moves ahead, then alternating, swimmer 1 first.
    assert scene_studies.stroke_codes("phase2", 1, 8, 2).tolist() == [11, 6, 5, 9, 0, 8, 3, 11]
    x = np.arange(1, 13) * 0.25  # 0.25 per step: 1.0 per four-step cycle
    assert scene_studies.per_cycle(x, "square", 1) == pytest.approx(1.0)
    assert scene_studies.per_cycle(
        np.r_[0.5, 0.5 + np.arange(1, 17) * 0.25], "phase1", 2
    ) == pytest.approx(2.0)
    # Speed over whole cycles of the second half: a big back-and-forth move outside them is left out.
    moves = np.tile([1.0, -0.9, 1.0, -0.9], 5)  # 0.2 per four-step cycle
    x = np.cumsum(np.r_[moves, 1.0])  # 21 steps: the last one a lone +1
    assert scene_studies.late_speed(x[:-1], 1, 1) == pytest.approx(0.05)
    assert scene_studies.late_speed(x, 1, 1) == pytest.approx((x[-1] - x[-9]) / 8)


def test_joint_decode_matches_the_scene_codes():
    sw, dof, roc = decode_scene_action(np.array([0, 5, 6, 11]))
    assert (
        sw.tolist() == [0, 0, 1, 1]
        and dof.tolist() == [0, 1, 0, 1]
        and roc.tolist() == [-1, 1, -1, 1]
    )


def test_scene_discretisers_are_the_joint_corner_and_the_height_bin():
    # A pair's 16 joint corners (bit i: arm i long); with a wall, times 7 height bins of swimmer 1.
    pair, pair_task = make(
        "ng", Scene(medium="free", swimmers=2, separation=30.0), init=(1, 0)
    )  # both (10, 6)
    cells = pair.cells()
    state = pair.reset(None, pair_task)
    j = cells.positions(state, pair_task)
    assert (
        cells.n_cells == 16
        and j.tolist() == [1, 0, 1, 0]
        and int(cells.cell(state, j, pair_task)) == 5
    )
    wall, wall_task = make("ng", Scene(medium="wall", height=5.0), init=(0, 1))
    cells = wall.cells()
    assert isinstance(cells, WallCells) and cells.n_cells == 4 * (len(HEIGHT_EDGES) + 1)
    state = wall.reset(None, wall_task)
    assert (
        int(cells.cell(state, cells.positions(state, wall_task), wall_task)) == 2 * 7 + 2
    )  # 5 a: bin (3.5, 6]
    # Shape-changing moves of a pair at (long, short, short, long): D1 -1, D2 +1, D3 +1, D4 -1.
    mask = pair.cells().mask(jnp.array([1, 0, 0, 1]), pair_task, "shape-changing")
    assert np.flatnonzero(mask).tolist() == [0, 5, 8, 9]


@pytest.mark.slow  # compiles joint-state Q-learning on a pair scene (23 s under load 8)
def test_q_learning_joint_state_shapes():
    sc = Scene(medium="bulk", swimmers=2, separation=30.0)
    world, task = make("ng", sc, init=(1, 0))
    run = qlearning.train(
        world,
        task,
        jax.random.split(jax.random.PRNGKey(0), 3),
        qlearning.QConfig(steps=20, action_set="shape-changing"),
        trace=True,
    )
    assert run.actions.shape == (3, 20) and run.trace.obs.position.shape == (3, 20, 2, 2)
    assert run.q.shape == (3, 16, 12) and np.asarray(run.actions).max() < 12
    assert np.allclose(run.x, np.asarray(run.trace.obs.position[..., 0]).mean(axis=-1))


@pytest.mark.slow  # compiles and trains Q-learning on a scene (20 s under load 8)
def test_q_learning_learns_the_square_alone_in_the_bulk_scene():
    # One untilted bulk swimmer is the paper's world for jswim.make; the scene world itself here.
    world = SceneWorld(Scene(medium="bulk"))
    task = SceneTask(scene_params("ng", Scene(medium="bulk"), init=(1, 0)), 1.0)
    run = qlearning.train(
        world,
        task,
        jax.random.split(jax.random.PRNGKey(1), 16),
        qlearning.QConfig(steps=120, action_set="shape-changing"),
    )
    tail = np.asarray(run.actions)[:, -8:]
    # The +x square gait from (10, 6) as a cycle of the four shape-changing moves, in some rotation.
    cycles = {tuple(np.roll([5, 0, 3, 2], k)) for k in range(4)}
    assert sum(tuple(t[:4]) in cycles and tuple(t[4:]) == tuple(t[:4]) for t in tail) >= 12


# -- studies end to end ----------------------------------------------------------------------------


@pytest.fixture(scope="module")
def server():
    with FakeServer(reply=scene_reply) as srv:
        yield srv


WALL = dict(heights=(3.0,), runs=1, q_runs=2, steps=12)
PAIR = dict(separations=(30.0,), phases=(1,), runs=1, q_runs=2, steps=12)


@pytest.mark.slow  # the scene solver compiles once per scene and agent (~20 s each under load)
def test_wall_study_end_to_end(server, tmp_path):
    out = tmp_path / "wall"
    # PPO's wall rows: tests/studies/test_scene_ppo_rows.py (its compilation is paid there once).
    run_study(
        "wall",
        StudyOptions(**WALL, agents=("stroke", "llm", "qlearning", "random")),
        server.backend(),
        out,
    )
    report(out)  # the publish step: figures and report.html from the folder
    rows = read_runs(out)
    assert {(r["agent"], r["group"]) for r in rows} == {("stroke", "free")} | {
        (a, "h=3") for a in ("stroke", "llm", "qlearning", "random")
    }
    meta = read_metadata(out)
    assert any(
        "scene (an extension): medium 'wall'" in line for line in meta["fidelity_deviations"]
    )
    table = meta["summary"]["scenes"]
    stroke = {r["group"]: r for r in table if r["agent"] == "stroke"}
    assert stroke["h=3"]["per_cycle"] > 0.1 and stroke["free"]["medium"] == "free"
    for r in rows:
        assert json.loads(r["scene"])["medium"] in ("wall", "free")
        if r["group"] != "free":
            assert (
                r["fate"] in scene_studies.FATES
                and len(r["heights"]) == 12
                and r["start_height"] == 3.0
            )
    llm = next(r for r in rows if r["agent"] == "llm")
    meta_line = json.loads(
        (out / "transcripts" / f"{llm['run_id']}.jsonl").read_text().splitlines()[0]
    )
    assert meta_line["scene"]["medium"] == "wall"
    step = json.loads((out / "transcripts" / f"{llm['run_id']}.jsonl").read_text().splitlines()[1])
    assert ", H " in step["prompt"] and len(step["heights_after"]) == 1
    assert llm["parse_retries"] >= 0 and llm["failed_steps"] == 0
    assert {p.name for p in (out / "figures").glob("*.png")} == {"wall.png", "wall-track.png"}


@pytest.mark.slow  # the scene solver compiles once per scene and agent (~20 s each under load)
def test_show_prints_the_scene_table(server, tmp_path, capsys):
    out = tmp_path / "pair"
    rc = cli.main(
        [
            "study",
            "pair",
            "--separations",
            "30",
            "--phases",
            "2",
            "--runs",
            "1",
            "--q-runs",
            "2",
            "--steps",
            "12",
            "--no-figures",
            "--out",
            str(out),
            "--base-url",
            server.url,
            "--model",
            "fake",
        ]
    )
    assert rc == 0
    printed = capsys.readouterr().out
    assert "scenes: displacement per stroke cycle" in printed and "D=30, phase 2" in printed
    assert cli.main(["show", str(out)]) == 0
    shown = capsys.readouterr().out
    assert "X/a per cycle" in shown and "alone" in shown
    rows = read_runs(out)
    llm = next(r for r in rows if r["agent"] == "llm")
    assert max(a[0] for a in llm["actions"]) <= 4 and len(llm["xs"][0]) == 2
    assert llm["separation"] == 30.0
    assert (
        llm["pair_prompt"] == "joint" and "-each-" not in llm["run_id"]
    )  # the default: one joint prompt
    meta_line = json.loads(
        (out / "transcripts" / f"{llm['run_id']}.jsonl").read_text().splitlines()[0]
    )
    assert meta_line["pair_prompt"] == "joint" and "conversations" not in meta_line
    # The continuous RL baseline steers both swimmers next to the others, judged on both swimmers' moves.
    learners = [r for r in rows if r["agent"] == "ppo"]
    assert len(learners) == 2 and {r["group"] for r in learners} == {"D=30"} and "ppo" in printed
    for r in learners:
        assert isinstance(r["success"], bool) and r["fate"] is None and r["separation"] == 30.0
        assert (
            {d for d, _ in r["actions"]} <= {1, 2, 3, 4}
            and len(r["xs"][0]) == 2
            and r["speed"] is not None
        )


def test_wall_study_crosses_heights_with_the_tilts_that_clear_the_wall():
    from jswim.errors import ConfigError
    from jswim.studies.scene_grids import wall_start_clears
    from jswim.studies.specs import build

    opts = dict(agents=("stroke", "qlearning"), q_runs=1)
    tilted = build("wall", StudyOptions(**opts))
    level = build("wall", StudyOptions(tilts=(0.0,), **opts))
    # the level runs are the same runs with or without the tilt axis (ids, seeds, scenes)
    assert [p for p in tilted if json.loads(p.scene)["tilt"] == 0.0] == level
    extra = [p for p in tilted if json.loads(p.scene)["tilt"] != 0.0]
    assert {(p.group, p.run_id.split("-z0-")[1]) for p in extra if p.agent == "stroke"} == {
        ("h=10, tilt=0.8", "h10-t0.8-r0"),
        ("h=50, tilt=0.8", "h50-t0.8-r0"),
    }
    # the rear sphere (arm 10 a behind the middle one) of a start tilted 0.8 rad sits
    # 10 sin(0.8) = 7.17 a below the middle sphere: it needs h >= 1.1 + 7.17 a
    need = 1.1 + 10.0 * np.sin(0.8)
    assert wall_start_clears(need + 0.01, 0.8) and not wall_start_clears(need - 0.01, 0.8)
    nose_down = 1.1 + 6.0 * np.sin(0.8)  # nose down the front sphere, 6 a ahead, is the low one
    assert wall_start_clears(nose_down + 0.01, -0.8) and not wall_start_clears(
        nose_down - 0.01, -0.8
    )
    # Purcell's swimmer starts level only
    purcell = build("wall", StudyOptions(swimmers=("purcell",), **opts))
    assert all(json.loads(p.scene).get("tilt", 0.0) == 0.0 for p in purcell)
    with pytest.raises(ConfigError, match="clears the wall"):
        build("wall", StudyOptions(heights=(2.0,), tilts=(0.8,), **opts))
    for bad in ((0.0, 2.0), (0.3, 0.3)):
        with pytest.raises(ConfigError, match="--tilts"):
            StudyOptions(tilts=bad)
    with pytest.raises(ConfigError, match="--tilts"):  # a grid another study would drop
        build("pair", StudyOptions(tilts=(0.0,)))


def test_scene_options_are_checked(tmp_path, capsys):
    for argv in (
        ["study", "wall", "--tilts", "1.6"],
        ["study", "wall", "--heights", "0.5"],
        ["study", "pair", "--phases", "5"],
        ["study", "pair", "--separations", "30,30"],
    ):
        assert cli.main(argv + ["--out", str(tmp_path / "x")]) == 2
        assert "Traceback" not in capsys.readouterr().err
    # An empty list ("," or "") is a mistake, not the defaults.
    for argv in (
        ["study", "wall", "--heights", ","],
        ["study", "pair", "--separations", ""],
        ["study", "pair", "--phases", ",,"],
    ):
        with pytest.raises(SystemExit) as stop:
            cli.main(argv + ["--dry-run", "--out", str(tmp_path / "x")])
        err = capsys.readouterr().err
        assert (
            stop.value.code == 2
            and len(err.strip().splitlines()) == 1
            and "expected comma-separated" in err
        )
    assert not (tmp_path / "x").exists()


@pytest.mark.slow  # the scene solver compiles once per scene and agent (~20 s each under load)
def test_interrupted_pair_study_resumes(server, tmp_path):
    opts = StudyOptions(**PAIR)
    whole = run_study("pair", opts, server.backend(), tmp_path / "whole")
    seen = {"n": 0}

    def interrupt(phase, done, total, info=""):
        if phase in ("stroke", "qlearning", "random"):
            seen["n"] += 1
            if seen["n"] == 3:
                raise KeyboardInterrupt

    part = tmp_path / "part"
    with pytest.raises(KeyboardInterrupt):
        run_study("pair", opts, server.backend(), part, progress=interrupt)
    assert read_metadata(part)["status"] == "interrupted"
    assert 0 < len(read_runs(part)) < len(whole.rows)
    again = run_study("pair", opts, server.backend(), part)
    key = lambda r: r["run_id"]
    assert [(r["run_id"], r["actions"], r["x"]) for r in sorted(again.rows, key=key)] == [
        (r["run_id"], r["actions"], r["x"]) for r in sorted(whole.rows, key=key)
    ]


def test_a_pair_s_scene_table_has_no_wall_columns_and_its_note_names_only_its_own():
    from jswim.studies.scene_studies import columns_note, table

    row = dict(agent="stroke", direction=1, group="D=30", medium="free", n=1, per_cycle=0.17,
               speed=0.02, vs_stroke=1.0, separation=30.0)  # fmt: skip
    cols, cells = table([row])
    headers = [c.header for c in cols]
    assert "fates" not in headers and "mean height" not in headers
    assert len(cells[0]) == len(headers)
    note = columns_note(cols)
    assert "fates" not in note and "mean height" not in note and "x stroke" in note
    wall = dict(row, medium="wall", fates="trapped 1", mean_height=1.2, start_height=1.2)
    cols, _ = table([wall])
    assert {"fates", "mean height"} <= {c.header for c in cols}
    assert "fates: trapped, escaped or gliding" in columns_note(cols)
