"""Pictures of every world (jswim.viz.worlds): a pair shows both swimmers and D1..D4, a wall run starts at
its height and the wall is drawn, the view always holds the whole swimmer (an NG swimmer at arms
(10, 10) is 22 a long), and a wall study's page has its scenes table; on the page (Chromium) and in
the GIF. Screenshots go to test-artifacts/."""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np
import pytest

from tests.browser import browser_or_skip, open_report_run
from jswim.studies.options import StudyOptions
from jswim.studies.run import run_study
from jswim.viz import animate as anim_mod
from jswim.viz.page import write_report
from jswim.viz.tracks import track

ARTIFACTS = os.environ.get("JSWIM_TEST_ARTIFACTS", "test-artifacts")
H, D = 3.0, 24.0


def rows(folder: Path) -> list[dict]:
    return [json.loads(ln) for ln in (folder / "runs.jsonl").read_text().splitlines() if ln.strip()]


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    root = tmp_path_factory.mktemp("worlds")
    run_study(
        "wall",
        StudyOptions(heights=(H,), runs=0, q_runs=1, steps=8, agents=("random",)),
        backend=None,
        out=root / "wall",
    )
    run_study(
        "pair",
        StudyOptions(separations=(D,), phases=(0,), runs=0, q_runs=1, steps=8, agents=("random",)),
        backend=None,
        out=root / "pair",
    )
    return root


@pytest.fixture(scope="module")
def far_ng(tmp_path_factory):
    """A folder holding an NG run at arms (10, 10) (start ``++``) that swims 40 a: a following view."""
    out = tmp_path_factory.mktemp("ng") / "ng"
    run_study(
        "curves",
        StudyOptions(swimmers=("ng",), directions=(1,), q_runs=1, steps=6, agents=("random",)),
        backend=None,
        out=out,
    )
    r = dict(rows(out)[0])
    n = 20
    r.update(
        run_id="random-ng-far",
        init="++",
        x=list(np.linspace(2.0, 40.0, n)),
        y=[0.0] * n,
        orientation=[0.0] * n,
        actions=[[1, 0]] * n,
        steps=n,
        stuck=[False] * n,
        dofs=[[10.0, 10.0]] * n,
    )
    r.pop("progress", None)
    with open(out / "runs.jsonl", "a") as fh:
        fh.write(json.dumps(r) + "\n")
    return out


@pytest.mark.slow  # the scenes fixture compiles a wall and a pair scene study (17 CPU-s)
def test_pair_track_has_both_swimmers_their_dofs_and_the_start(scenes):
    r = next(r for r in rows(scenes / "pair") if r.get("n_swimmers") == 2)
    t = track(r)
    n = len(r["x"])
    assert t.bodies.shape == (n + 1, 2, 3, 2) and t.dof_names == ["D1", "D2", "D3", "D4"]
    # Step 0: both middle spheres at height 10 (the scene's start), swimmer 2 at x = D.
    np.testing.assert_allclose(t.positions[0], [[0.0, 10.0], [D, 10.0]])
    np.testing.assert_allclose(
        t.bodies[0, :, 1], t.positions[0]
    )  # the middle sphere is the position
    # Arms (10, 6) for each (start +-): the spheres 10 behind and 6 ahead of the middle one.
    np.testing.assert_allclose(t.bodies[0, 1, :, 0], [D - 10.0, D, D + 6.0])
    # An action [j, roc] moves joint DOF j by roc x (10 - 6) a, stopping at 6 or 10; the others stay:
    # D3 and D4 are swimmer 2's arms.
    for k, (dof, roc) in enumerate(r["actions"]):
        want = t.dofs[k].copy()
        want[dof - 1] = min(10.0, max(6.0, want[dof - 1] + 4.0 * roc))
        np.testing.assert_allclose(t.dofs[k + 1], want)
    assert any(dof >= 3 for dof, _ in r["actions"]) and np.ptp(t.dofs[:, 2:]) > 0


@pytest.mark.slow  # the scenes fixture compiles a wall and a pair scene study (17 CPU-s)
def test_wall_track_starts_at_its_height_and_the_view_holds_the_wall(scenes):
    from jswim.viz.tracks import view_box

    for r in rows(scenes / "wall"):
        t = track(r)
        if r.get("medium") == "wall":
            assert (
                t.world.wall and t.y[0] == H and t.positions[0, 0, 1] == H
            )  # not 0: no false jump at step 1
            assert abs(t.y[1] - H) < 0.5
            assert view_box([t])[2] < 0.0  # the wall (y = 0) is in view


def test_gif_view_always_holds_the_whole_ng_swimmer_at_10_10(far_ng):
    (r,) = [r for r in rows(far_ng) if r["run_id"] == "random-ng-far"]
    t = track(r)
    assert np.ptp(t.bodies[0, 0, :, 0]) == pytest.approx(20.0)  # 22 a long with the end spheres
    a = anim_mod.Animation([t])
    fig, draw = a.figure()
    ax = fig.axes[0]
    for k in range(t.n_steps + 1):
        draw(k)
        x0, x1 = ax.get_xlim()
        xs = t.bodies[k, 0, :, 0]
        assert x0 <= xs.min() - 1.0 and xs.max() + 1.0 <= x1, (k, x0, x1, xs)
    import matplotlib.pyplot as plt

    plt.close(fig)
    path = a.save(Path(ARTIFACTS) / "anim-ng-10-10.gif")
    assert a.frames_written is not None and 1 <= a.frames_written <= a.n_frames
    from PIL import Image

    with Image.open(path) as im:
        assert im.n_frames == a.frames_written  # the count reported is the file's


@pytest.mark.slow  # the scenes fixture compiles a wall and a pair scene study (17 CPU-s)
def test_wall_page_has_the_scenes_table_and_only_its_own_settings(scenes):
    page = write_report(scenes / "wall", figures="none").read_text()
    assert 'id="scenes"' in page and "mean height" in page and "fates" in page
    block = page[page.index('id="settings-table"') : page.index('id="full-record"')]
    assert "<th>heights</th><td>3.0</td>" in block
    for other in (
        "separations",
        "phases",
        "zetas",
        "n_hts",
        "horizon",
        "model",
    ):  # other studies', or no LLM run
        assert f"<th>{other}</th>" not in block
    assert (
        "&quot;separations&quot;" in page[page.index('id="full-record"') :]
    )  # the full record one click away


# -- in a real browser ----------------------------------------------------------------------------


def _browser():
    return browser_or_skip(height=1100)


def _open(b, page: Path, run_id: str) -> None:
    open_report_run(b, page, run_id)


@pytest.mark.slow
def test_world_pictures_in_chromium(scenes, far_ng):
    pair = next(r["run_id"] for r in rows(scenes / "pair") if r.get("n_swimmers") == 2)
    wall = next(r["run_id"] for r in rows(scenes / "wall") if r.get("medium") == "wall")
    with _browser() as b:
        _open(b, write_report(scenes / "pair", figures="none"), pair)
        drawn = b.eval("window.jswimReport.drawn()")
        start = b.eval("document.getElementById('step').textContent")
        b.screenshot(os.path.join(ARTIFACTS, "report-pair.png"))

        _open(b, write_report(scenes / "wall", figures="none"), wall)
        # The pixel just below y = 0 is the wall's fill; the swimmer's middle sphere sits at y = h.
        below = b.eval(
            "(() => { var p = window.jswimReport.toCanvas(0.5, -0.3), c = document.getElementById('swim');"
            "return Array.from(c.getContext('2d').getImageData(p[0], p[1], 1, 1).data).slice(0, 3); })()"
        )
        mid_y = b.eval(f"window.jswimReport.toCanvas(0, {H})[1]")
        wall_y = b.eval("window.jswimReport.toCanvas(0, 0)[1]")
        b.screenshot(os.path.join(ARTIFACTS, "report-wall.png"))
        settings = b.eval("document.getElementById('settings-table').innerText")
        closed = b.eval("!document.getElementById('full-record').open")
        b.eval("document.getElementById('settings').scrollIntoView()")
        b.screenshot(os.path.join(ARTIFACTS, "report-wall-settings.png"))

        _open(b, write_report(far_ng, figures="none"), "random-ng-far")
        inside = []
        for k in (0, 5, 10, 20):
            b.eval(
                f"window.jswimReport.pause(); document.getElementById('scrub').value = {k};"
                "document.getElementById('scrub').dispatchEvent(new Event('input'))"
            )
            inside.append(
                b.eval(
                    "(() => { var d = window.jswimReport.data(), k = window.jswimReport.step(),"
                    "W = document.getElementById('swim').width;"
                    "return d.bodies[k][0].every(q => { var l = window.jswimReport.toCanvas(q[0] - 1, 0)[0],"
                    "r = window.jswimReport.toCanvas(q[0] + 1, 0)[0]; return l >= 0 && r <= W; }); })()"
                )
            )
        b.screenshot(os.path.join(ARTIFACTS, "report-ng-10-10.png"))
        assert b.errors == []
    assert drawn == 2 and "D1" in start and "D4" in start
    assert (
        below == [217, 207, 194] and wall_y > mid_y
    )  # the wall drawn, below the swimmer (canvas y grows down)
    assert inside == [True] * 4
    assert "heights" in settings and "separations" not in settings and closed
