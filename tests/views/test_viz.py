"""Seeing runs: body outlines against the physics, tracks from folders, animations, report.html,
transcripts and calls as DataFrames, `jswim animate` and `jswim report`."""

from __future__ import annotations

import json
import os
import re
import shutil

import jax
import numpy as np
import pytest
from PIL import Image

import jswim

from tests.browser import browser_or_skip
from jswim import cli, env
from jswim.errors import ConfigError
from jswim.results import read_runs, read_transcript
from jswim.studies import Backend, StudyOptions, run_study
from jswim.swimmers import nlink
from jswim.swimmers.models import make_model
from jswim.viz import animate as anim_mod
from tests.views.fitting import captions_outside_their_panel
from jswim.viz.page import report_html, write_report
from jswim.viz.publish import report
from jswim.viz.tracks import outline, place, start_theta, track
from tests.fakeserver import FakeServer, hash_reply

SECRET = "sk-test-SECRET-never-written-0123456789"


@pytest.fixture(scope="module")
def swim_folder(tmp_path_factory):
    """A small swim study against the fake server (2 LLM runs, 3 Q-learning, 3 random), figures drawn,
    with an API key in the environment that must never reach the folder."""
    out = tmp_path_factory.mktemp("viz") / "swim"
    os.environ["JSWIM_TEST_SECRET_KEY"] = SECRET
    try:
        with FakeServer(reply=hash_reply, latency=0.001) as srv:
            rc = cli.main(
                [
                    "swim",
                    "--steps",
                    "14",
                    "--runs",
                    "2",
                    "--q-runs",
                    "3",
                    "--out",
                    str(out),
                    "--base-url",
                    srv.url,
                    "--model",
                    "fake-model",
                    "--api-key-env",
                    "JSWIM_TEST_SECRET_KEY",
                ]
            )
    finally:
        del os.environ["JSWIM_TEST_SECRET_KEY"]
    assert rc == 0
    return out


# -- geometry against the physics ---------------------------------------------------------------


@pytest.mark.parametrize("swimmer", ["purcell", "nlink"])
def test_outline_centroid_and_reference_link_match_the_rft_model(swimmer):
    model = make_model(swimmer)
    rng = np.random.default_rng(1)
    for _ in range(5):
        d = rng.uniform(model.lo, model.hi, model.n_dof)
        pts = outline(model, d)
        m = model.n_dof // 2
        ref_centre = 0.5 * (pts[m] + pts[m + 1])
        # centroid - reference point, from the RFT code's own link centres (independent of outline)
        np.testing.assert_allclose(-ref_centre, np.asarray(nlink.centroid_offset(d)), atol=1e-12)
        np.testing.assert_allclose(
            pts[m + 1] - pts[m], [1.0, 0.0], atol=1e-12
        )  # reference link along +x
        np.testing.assert_allclose(
            np.linalg.norm(np.diff(pts, axis=0), axis=1), 1.0, atol=1e-12
        )  # links of length a
        # hinge angles are the differences of consecutive link directions
        ang = np.arctan2(*np.diff(pts, axis=0)[:, ::-1].T)
        np.testing.assert_allclose(np.diff(ang), d, atol=1e-12)


def test_outline_spheres_sit_at_the_arm_lengths():
    model = make_model("nsphere")
    pts = outline(model, [6.0, 10.0, 7.5])
    np.testing.assert_allclose(np.diff(pts[:, 0]), [6.0, 10.0, 7.5])
    assert abs(pts[:, 0].mean()) < 1e-12 and np.all(pts[:, 1] == 0)


def test_placed_outline_puts_the_middle_link_where_the_environment_has_it():
    params = env.make_params("purcell")
    state = env.reset(jax.random.PRNGKey(0), params)
    for dof, roc in [(2, -1), (1, -1), (2, 1)]:
        state, _ = env.step(jax.random.PRNGKey(1), state, env.encode_action(dof, roc), params)
    x, y = env.position(state)
    pts = place(
        outline(params.model, np.asarray(env.dof_values(state, params))), x, y, float(state.theta)
    )
    np.testing.assert_allclose(
        0.5 * (pts[1] + pts[2]), np.asarray(env.reference_point(state, params)), atol=1e-6
    )


def test_start_orientation_is_the_environments():
    for swimmer in ("purcell", "nlink"):
        model = make_model(swimmer)
        for levels in ([1] * model.n_dof, [0] + [1] * (model.n_dof - 1)):
            d0 = np.array([model.lo + (model.hi - model.lo) * v for v in levels])
            assert start_theta(model, d0) == pytest.approx(
                float(env.start_orientation(model, np.array(levels), xp=np))
            )


# -- tracks from a folder ---------------------------------------------------------------------------


def test_tracks_follow_the_recorded_runs(swim_folder):
    rows = read_runs(swim_folder)
    for r in rows:
        t = track(r, read_transcript(swim_folder, r["run_id"]))
        n = len(r["x"])
        assert t.points.shape == (n + 1, 4, 2) and len(t.actions) == n
        np.testing.assert_allclose(t.x[1:], r["x"])
        # the body's centroid (mean of the link centres) is the recorded position
        centres = 0.5 * (t.points[:, 1:] + t.points[:, :-1])
        np.testing.assert_allclose(centres.mean(axis=1), np.stack([t.x, t.y], 1), atol=1e-9)
        # DOF values: an independent noiseless rollout of the same actions from the same start
        ro = env.rollout_moves(
            "purcell", [tuple(a) for a in r["actions"]], init=[1, 1], direction=r["direction"]
        )
        np.testing.assert_allclose(t.dofs[1:], np.asarray(ro.dofs), atol=1e-6)
        if r["agent"] == "llm":
            assert all(isinstance(x, str) for x in t.replies) and not t.replayed
            assert t.label == "LLM (fake-model)" or t.label == "LLM"
        else:
            assert t.replies == [None] * n


def test_track_of_an_old_folder_replays_the_missing_pose(swim_folder):
    """Folders written before y/orientation were recorded, with the old field name `allowed`."""
    r = next(r for r in read_runs(swim_folder) if r["agent"] == "qlearning")
    old = {
        ("allowed" if k == "action_set" else k): v
        for k, v in r.items()
        if k not in ("y", "orientation")
    }
    t_new, t_old = track(r), track(old)
    assert t_old.replayed and not t_new.replayed
    np.testing.assert_allclose(t_old.y, t_new.y, atol=1e-6)
    np.testing.assert_allclose(t_old.theta, t_new.theta, atol=1e-6)


def test_track_accepts_real_valued_rocs_and_recorded_dofs():
    """Continuous strokes: a ROC of 0.5 moves half the range and stops at the limit; a row's own
    per-step `dofs` win over the replay."""
    model = make_model("purcell")
    row = {
        "run_id": "x",
        "agent": "random",
        "swimmer": "purcell",
        "direction": 1,
        "init": "--",
        "x": [0.0, 0.01, 0.02],
        "y": [0.0, 0.0, 0.0],
        "orientation": [0.0, 0.1, 0.1],
        "actions": [[1, 0.5], [1, 0.75], [2, -0.25]],
    }
    t = track(row)
    span = model.hi - model.lo
    np.testing.assert_allclose(t.dofs[:, 0], [model.lo, model.lo + 0.5 * span, model.hi, model.hi])
    np.testing.assert_allclose(t.dofs[:, 1], [model.lo] * 4)  # pushed past the lower limit: stays
    lattice = dict(row, roc_levels=4, actions=[[1, 1], [1, 2], [2, -3]])  # k / K of the range
    np.testing.assert_allclose(
        track(lattice).dofs[:, 0],
        [model.lo, model.lo + span / 4, model.lo + 3 * span / 4, model.lo + 3 * span / 4],
    )
    row["dofs"] = [[0.1, 0.2], [0.3, 0.4], [0.5, 0.6]]
    np.testing.assert_allclose(track(row).dofs[1:], row["dofs"])
    assert anim_mod.Animation([t]).n_frames == 4 + 4


# -- jswim.load: transcripts and calls ---------------------------------------------------------------


def test_load_gives_transcripts_and_calls(swim_folder):
    study = jswim.load(swim_folder)
    llm = study.runs[study.runs.agent == "llm"]
    calls = study.calls
    assert len(calls) == int(llm.calls.sum()) and set(calls.run) == set(llm.run_id)
    rid = llm.run_id.iloc[0]
    tr = study.transcript(rid)
    assert list(tr.step) == list(range(1, 15))
    assert tr.prompt.str.contains("Reply with the next action").all()
    mine = calls[calls.run == rid].sort_values("n")
    assert list(tr.reply) == list(mine.text)  # one call per step here (no parse retries)
    assert tr.prompt_tokens.sum() == mine.prompt_tokens.sum() == int(llm.prompt_tokens.iloc[0])
    assert study.transcript("qlearning-purcell-px-i++-z0-r0").empty
    assert study.transcript("../metadata").empty  # not a path out of the folder


# -- animations ---------------------------------------------------------------------------------


@pytest.mark.slow  # renders a 19-frame GIF (6 CPU-s); `jswim animate` writes one in the fast tier
def test_animation_gif_has_a_frame_per_step_and_names_the_model(swim_folder, tmp_path):
    a = jswim.animate(jswim.load(swim_folder))
    assert [t.agent for t in a.tracks] == ["llm", "qlearning", "random"]
    assert len({t.row["init"] for t in a.tracks}) == 1  # the same start
    assert "fake-model" in a.title
    path = a.save(tmp_path / "runs.gif")
    assert a.n_frames == 14 + 1 + 4  # step 0, 14 steps, a 1 s hold on the last
    with Image.open(path) as im:  # Pillow merges identical frames (the hold) into longer ones
        durations = []
        for i in range(im.n_frames):
            im.seek(i)
            durations.append(im.info["duration"])
    assert im.n_frames >= 15 and sum(durations) == pytest.approx(a.n_frames * 1000 / a.fps, abs=20)
    html = a._repr_html_()
    assert html.startswith('<img src="data:image/gif;base64,')
    one = anim_mod.animate(swim_folder, "llm-purcell-px-i++-z0-r1")
    assert [t.run_id for t in one.tracks] == ["llm-purcell-px-i++-z0-r1"]
    with pytest.raises(ConfigError, match="no run 'nope'"):
        anim_mod.animate(swim_folder, ["nope"])
    with pytest.raises(ConfigError, match=r"\.gif or \.mp4"):
        a.save(tmp_path / "runs.avi")


def test_animation_frames_differ_as_the_swimmer_moves(swim_folder):
    a = anim_mod.build(swim_folder, ["qlearning-purcell-px-i++-z0-r0"])
    first, later = a.frame_png(0), a.frame_png(6)
    assert first[:8] == b"\x89PNG\r\n\x1a\n" and first != later


def test_animation_captions_stay_in_their_panels(swim_folder):
    # four panels side by side, each with the LLM's reply and the step's events under it
    a = anim_mod.build(swim_folder, most=4)
    assert len(a.tracks) >= 3
    assert captions_outside_their_panel(a, range(0, a.n_frames, 3)) == []
    # The longest lines a step can have: every event at once and a long reply (wrapped, not cut
    # off at the next panel)
    t = a.tracks[0]
    t.stuck[:], t.cleared[:], t.failed[:] = True, True, True
    t.replies[:] = ["I shall now rotate the first link by one level, then hold " * 3] * len(
        t.replies
    )
    assert captions_outside_their_panel(a, [1, a.n_frames - 1]) == []


@pytest.mark.skipif(
    anim_mod.ffmpeg_exe() is None, reason="no ffmpeg (pip install 'jswim[video]' ships one)"
)
def test_animation_mp4(swim_folder, tmp_path):
    path = anim_mod.build(swim_folder, ["random-purcell-px-i++-z0-r0"]).save(tmp_path / "run.mp4")
    assert path.stat().st_size > 1000 and b"ftyp" in path.read_bytes()[:64]


def test_animate_and_report_commands(swim_folder, tmp_path, capsys):
    out = tmp_path / "a.gif"
    assert (
        cli.main(
            [
                "animate",
                str(swim_folder),
                "--run",
                "llm-purcell-px-i++-z0-r0",
                "--run",
                "random-purcell-px-i++-z0-r1",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    assert out.is_file() and "2 runs" in capsys.readouterr().out
    assert cli.main(["animate", str(swim_folder), "--run", "nope"]) == 2
    assert "no run 'nope'" in capsys.readouterr().err
    assert cli.main(["animate", str(tmp_path / "missing")]) == 2
    assert cli.main(["report", str(tmp_path / "missing")]) == 2
    assert "no such folder" in capsys.readouterr().err


# -- the report page ------------------------------------------------------------------------------


def _snapshot(folder):
    return {p.relative_to(folder): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def test_study_writes_report_with_table_figures_and_every_run(swim_folder):
    page = (swim_folder / "report.html").read_text()
    assert SECRET not in page and "SECRET" not in page
    assert "fake-model" in page and "complete: 8 runs" in page
    assert page.count('<script type="text/plain" id="run-') == 8
    assert '<img alt="swim" src="data:image/png;base64,' in page
    assert '<table class="summary" id="summary-table">' in page and "qlearning" in page
    assert not re.search(r"""(src|href)=["']https?:""", page)  # nothing fetched from a network


def test_report_command_writes_only_the_page(swim_folder, tmp_path, capsys):
    folder = tmp_path / "copy"
    shutil.copytree(swim_folder, folder)
    (folder / "report.html").unlink()
    before = _snapshot(folder)
    assert cli.main(["report", str(folder)]) == 0
    after = _snapshot(folder)
    assert set(after) - set(before) == {__import__("pathlib").Path("report.html")}
    assert all(after[k] == v for k, v in before.items())
    assert "report:" in capsys.readouterr().out


def test_report_of_an_unfinished_study_says_so(swim_folder, tmp_path):
    folder = tmp_path / "unfinished"
    shutil.copytree(swim_folder, folder)
    lines = (folder / "runs.jsonl").read_text().splitlines()
    (folder / "runs.jsonl").write_text(
        "\n".join(lines[:5]) + "\n" + lines[5][:40]
    )  # torn last line
    meta = json.loads((folder / "metadata.json").read_text())
    meta["status"] = "interrupted"
    (folder / "metadata.json").write_text(json.dumps(meta))
    page = report_html(folder)
    assert "UNFINISHED STUDY: 5 of 8 runs done (status interrupted)" in page
    assert page.count('<script type="text/plain" id="run-') == 5


def _blob(page, i):
    import base64
    import gzip

    blob = re.search(rf'<script type="text/plain" id="run-{i}">([^<]+)</script>', page).group(1)
    return json.loads(gzip.decompress(base64.b64decode(blob)))


def test_report_page_data_decodes(swim_folder):
    """The per-run blobs are gzip+base64 JSON with a frame per step (what the page's script reads)."""
    page = (swim_folder / "report.html").read_text()
    index = json.loads(
        re.search(
            r'<script type="application/json" id="report-data">(.+?)</script>', page, re.S
        ).group(1)
    )
    runs = {r["run_id"]: r for r in read_runs(swim_folder)}
    data = _blob(page, 0)
    assert len(data["pts"]) == len(runs[index["runs"][0]["run_id"]]["x"]) + 1 and data["planar"]
    # Every run once, listed by the study's axes (agent, then replicate), not in finishing order.
    ids = [r["run_id"] for r in index["runs"]]
    assert sorted(ids) == sorted(runs)
    assert ids == ["llm-purcell-px-i++-z0-r0", "llm-purcell-px-i++-z0-r1"] + [
        f"qlearning-purcell-px-i++-z0-r{i}" for i in range(3)
    ] + [f"random-purcell-px-i++-z0-r{i}" for i in range(3)]


# -- every study and swimmer ---------------------------------------------------------------------------


@pytest.mark.slow
@pytest.mark.parametrize("study", ["curves", "history", "noise", "ablation", "inits", "competence"])
def test_report_and_animation_of_every_study(study, tmp_path):
    opts = dict(swimmers=("purcell",), directions=(1,), runs=1, steps=6)
    if study in ("curves", "noise", "competence"):
        opts["q_runs"] = 2
    if study == "noise":
        opts["zetas"] = (0.0, 1.0)
    if study == "history":
        opts["n_hts"] = (1, 3)
    if study == "competence":
        opts["variants"] = ("paper",)
    with FakeServer(reply=hash_reply, latency=0.0) as srv:
        run_study(
            study,
            StudyOptions(**opts),
            backend=Backend(base_url=srv.url, model="fake"),
            out=tmp_path / study,
        )
    report(tmp_path / study, figures=False)  # the publish step: the page alone
    page = (tmp_path / study / "report.html").read_text()
    n = len(read_runs(tmp_path / study))
    assert page.count('<script type="text/plain" id="run-') == n and "complete" in page
    by = {"noise": "zeta", "history": "n_ht", "ablation": "group", "inits": "init"}.get(
        study, "agent"
    )
    a = anim_mod.build(tmp_path / study, by=by)
    assert len(a.tracks) >= 2
    assert a.frame_png(a.n_frames - 1)[:4] == b"\x89PNG"


@pytest.mark.slow  # four-DOF studies, animations and a report end to end (60 s under load 8)
def test_four_dof_swimmers_animate_and_report(tmp_path):
    out = tmp_path / "four"
    run_study(
        "curves",
        StudyOptions(
            swimmers=("nlink", "nsphere"),
            directions=(1,),
            q_runs=2,
            steps=8,
            agents=("qlearning", "random"),
        ),
        backend=None,
        out=out,
    )
    rows = read_runs(out)
    for r in rows:
        t = track(r)
        assert t.points.shape[1] == (5 if r["swimmer"] == "nlink" else 4)
        if r["swimmer"] == "nlink":  # five link ends, links of length a, centroid at the recorded x
            np.testing.assert_allclose(
                np.linalg.norm(np.diff(t.points, axis=1), axis=2), 1.0, atol=1e-9
            )
        centres = (
            0.5 * (t.points[:, 1:] + t.points[:, :-1]) if r["swimmer"] == "nlink" else t.points
        )
        np.testing.assert_allclose(centres.mean(axis=1)[:, 0], t.x, atol=1e-6)
    for sw in ("nlink", "nsphere"):
        ids = [r["run_id"] for r in rows if r["swimmer"] == sw][:2]
        assert anim_mod.build(out, ids).frame_png(5)[:4] == b"\x89PNG"
    page = write_report(out, figures="none").read_text()
    models = {_blob(page, i)["model"] for i in range(len(rows))}
    assert models == {"4-link", "4-sphere"}


# -- in a real browser ----------------------------------------------------------------------------------


def _browser():
    return browser_or_skip()


ARTIFACTS = os.environ.get("JSWIM_TEST_ARTIFACTS", "test-artifacts")


def _check_page(path, shot):
    with _browser() as b:
        b.open(path.resolve().as_uri())
        listed = b.eval("window.jswimReport.opened.then(() => window.jswimReport.listed())")
        steps = b.eval("window.jswimReport.steps()")
        status = b.eval("document.getElementById('status').textContent")
        title = b.eval("document.getElementById('run-title').textContent")
        assert b.eval("window.jswimReport.step()") == 0
        b.eval("window.jswimReport.play()")
        b.pump(1.5)  # 4 steps/s
        moved = b.eval("window.jswimReport.step()")
        b.eval("window.jswimReport.pause()")
        prompt = b.eval(
            "(document.querySelector('pre.prompt') || {}).textContent || ''"
        )  # of the step shown
        b.eval("document.getElementById('browser').scrollIntoView()")
        b.screenshot(shot)
        figures = b.eval(
            "Array.from(document.querySelectorAll('#figures img')).filter(i => i.naturalWidth > 0).length"
        )
        foreign = [u for u in b.requests if not u.startswith(("file:", "data:"))]
        return dict(
            listed=listed,
            steps=steps,
            status=status,
            title=title,
            prompt=prompt,
            moved=moved,
            figures=figures,
            errors=b.errors,
            foreign=foreign,
        )


@pytest.mark.slow  # a real browser (Chromium start, page load, screenshots)
def test_report_in_chromium(swim_folder):
    got = _check_page(swim_folder / "report.html", os.path.join(ARTIFACTS, "report-swim.png"))
    assert got["errors"] == [] and got["foreign"] == []
    assert got["listed"] == 8 and got["steps"] == 14
    assert got["title"].startswith("llm-")  # an LLM run opens first, with its prompt
    assert "Reply with the next action" in got["prompt"]
    assert 2 <= got["moved"] <= 14  # the animation advanced when played
    assert got["figures"] == 1 and got["status"].startswith("complete")


@pytest.mark.slow  # a real browser (Chromium start, page load, screenshots)
def test_unfinished_report_in_chromium(swim_folder, tmp_path):
    folder = tmp_path / "unfinished"
    shutil.copytree(swim_folder, folder)
    lines = (folder / "runs.jsonl").read_text().splitlines()
    (folder / "runs.jsonl").write_text("\n".join(lines[:7]) + "\n")
    meta = json.loads((folder / "metadata.json").read_text())
    meta["status"] = "interrupted"
    (folder / "metadata.json").write_text(json.dumps(meta))
    got = _check_page(write_report(folder), os.path.join(ARTIFACTS, "report-unfinished.png"))
    assert got["errors"] == [] and got["foreign"] == []
    assert got["status"].startswith("UNFINISHED STUDY: 7 of 8 runs") and got["listed"] == 7
    assert got["moved"] >= 2


# -- figures of jswim qlearn and jswim ensemble -------------------------------------------------------


def test_ensemble_table_rows_sit_at_regular_steps():
    from jswim.studies.ensemble import regular_rows

    steps = np.arange(1, 51)
    assert list(steps[regular_rows(steps, 12)]) == [5, 10, 15, 20, 25, 30, 35, 40, 45, 50]
    assert list(steps[regular_rows(steps[:49], 10)]) == [
        5,
        10,
        15,
        20,
        25,
        30,
        35,
        40,
        45,
        49,
    ]  # the last step
    every10 = np.arange(10, 1001, 10)
    assert list(every10[regular_rows(every10, 12)]) == list(range(100, 1001, 100))
    assert list(regular_rows(np.arange(1, 8), 12)) == list(range(7))


def test_qlearn_out_writes_a_histogram_that_names_the_agent(tmp_path, capsys):
    out = tmp_path / "ql"
    assert (
        cli.main(
            [
                "qlearn",
                "--swimmer",
                "purcell",
                "--direction",
                "+x",
                "--seeds",
                "48",
                "--steps",
                "60",
                "--action-set",
                "all",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    text = capsys.readouterr().out
    assert (out / "qlearn.png").is_file() and (out / "qlearn.pdf").is_file() and "figure:" in text
    import csv

    rows = list(csv.DictReader((out / "qlearn.csv").open()))
    assert (
        len(rows) == 1 and rows[0]["swimmer"] == "purcell" and int(rows[0]["n"]) == 48
    )  # the 48 learners of the next test: one program
    (tmp_path / "file").write_text("x")
    assert cli.main(["qlearn", "--seeds", "4", "--out", str(tmp_path / "file")]) == 2


def test_qlearn_histogram_counts_every_learner_that_learned():
    from jswim.agents.qlearning import QConfig
    from jswim.studies import qlearn

    rows = qlearn.study(QConfig(steps=60), swimmers=("purcell",), directions=(1,), n_seeds=48)
    (r,) = rows
    assert sum(r.hist) == r.n_learned and r.hist[0] == 0
    med = np.median(np.repeat(np.arange(len(r.hist)), r.hist))
    assert med == r.median
    from jswim.viz.charts import qlearn_figure

    fig = qlearn_figure(rows, "Q-learning baseline: test")
    assert fig._suptitle.get_text() == "Q-learning baseline: test"
    assert "never learned" in fig.axes[0].get_legend().get_texts()[0].get_text()


def test_ensemble_out_writes_the_table_and_a_figure(tmp_path, capsys):
    # the same small program both times (n and steps are compiled in): one compile
    assert (
        cli.main(
            [
                "ensemble",
                "--n",
                "300",
                "--zetas",
                "0,1",
                "--steps",
                "8",
                "--out",
                str(tmp_path / "e"),
            ]
        )
        == 0
    )
    assert (tmp_path / "e" / "ensemble.csv").is_file() and (
        tmp_path / "e" / "ensemble.png"
    ).is_file()
    assert (
        cli.main(
            [
                "ensemble",
                "--n",
                "300",
                "--zetas",
                "1",
                "--steps",
                "8",
                "--out",
                str(tmp_path / "t.csv"),
            ]
        )
        == 0
    )
    assert (
        (tmp_path / "t.csv").is_file()
        and (tmp_path / "t.png").is_file()
        and (tmp_path / "t.pdf").is_file()
    )
    assert "figure:" in capsys.readouterr().out


def test_report_and_animation_of_a_folder_an_earlier_version_wrote(tmp_path):
    """tests/data/folder-54c2edb: `jswim swim` of commit 54c2edb (before y, orientation, n_planned and
    the call journal were recorded)."""
    folder = tmp_path / "old"
    shutil.copytree(
        os.path.join(os.path.dirname(os.path.dirname(__file__)), "data", "folder-54c2edb"), folder
    )
    rows = read_runs(folder)
    assert rows and all("orientation" not in r for r in rows)
    a = anim_mod.build(folder)
    assert [t.agent for t in a.tracks] == ["llm", "qlearning", "random"] and all(
        t.replayed for t in a.tracks
    )
    assert a.frame_png(5)[:4] == b"\x89PNG"
    page = write_report(folder, figures="none").read_text()
    assert "complete: 5 runs" in page and page.count('<script type="text/plain" id="run-') == 5
    study = jswim.load(folder)
    assert study.calls.empty and len(study.transcript("llm-purcell-px-i++-z0-r0")) == 12
