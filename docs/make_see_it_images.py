"""Make README's pictures of `jswim animate` and `report.html` with the code as it is.

A swim study (50 steps) whose "LLM" is jswim's prompt-only reference rule (`jswim serve reference`,
model "reference-rule": a plain rule reading the prompt text, not a language model, chosen so the
picture shows a run that swims), next to Q-learning and the random policy; then one frame of its
animation, the animation itself, and a screenshot of its report page in headless Chromium.
Prints sizes and timings. Run: .venv/bin/python docs/make_see_it_images.py
"""

from __future__ import annotations

import io
import sys
import tempfile
import time
from pathlib import Path

from PIL import Image

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from jswim.llm.reference import MODEL, ReferenceServer  # noqa: E402
from jswim.studies import Backend, StudyOptions, run_study  # noqa: E402
from jswim.viz.animate import build  # noqa: E402
from tests.browser import Browser  # noqa: E402

IMAGES = ROOT / "docs" / "images"


def small_png(data: bytes, path: Path, width: int, colors: int = 256) -> None:
    im = Image.open(io.BytesIO(data)).convert("RGB")
    if im.width > width:
        im = im.resize((width, round(im.height * width / im.width)), Image.LANCZOS)
    im.quantize(colors=colors, method=Image.Quantize.MEDIANCUT).save(path, optimize=True)
    print(f"{path.relative_to(ROOT)}: {path.stat().st_size / 1024:.0f} KB, {im.width}x{im.height}")


def main() -> None:
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "swim"
        with ReferenceServer() as srv:
            run_study(
                "swim",
                StudyOptions(runs=2, q_runs=10, steps=50),
                backend=Backend(base_url=srv.url, model=MODEL),
                out=out,
                figures=True,
            )
        t0 = time.perf_counter()
        anim = build(out, fps=6, dpi=64)
        gif = anim.save(Path(tmp) / "swim.gif")
        dt = time.perf_counter() - t0
        print(
            f"animation: {len(anim.tracks)} panels, {anim.frames_written} frames in the GIF ({anim.n_frames} drawn), "
            f"{gif.stat().st_size / 1024:.0f} KB, "
            f"written in {dt:.1f} s ({anim.n_frames / dt:.1f} frames/s)"
        )
        small_png(anim.frame_png(33, dpi=130), IMAGES / "animation-frame.png", 1000)
        if (
            gif.stat().st_size < 450 * 1024
        ):  # legible text makes the frames richer: 334 KB at 64 dpi
            (IMAGES / "swim.gif").write_bytes(gif.read_bytes())
            print(f"docs/images/swim.gif: {gif.stat().st_size / 1024:.0f} KB")
        page = out / "report.html"
        with Browser(width=1280, height=1000) as b:
            t0 = time.perf_counter()
            b.open(page.as_uri())
            b.eval("window.jswimReport.opened")
            print(
                f"report: {page.stat().st_size / 1024:.0f} KB, loaded and first run open in "
                f"{time.perf_counter() - t0:.2f} s; console errors: {b.errors or 'none'}"
            )
            b.eval(
                "(() => { const r = Array.from(document.querySelectorAll('#run-list tr[data-i]'))"
                ".find(tr => tr.textContent.startsWith('llm-')); return window.jswimReport.select(+r.dataset.i); })()"
            )
            b.eval("window.jswimReport.play()")
            b.pump(33 / 4 + 0.1)
            b.eval("window.jswimReport.pause()")
            b.eval("document.getElementById('browser').scrollIntoView()")
            with tempfile.NamedTemporaryFile(suffix=".png") as f:
                b.screenshot(f.name)
                small_png(Path(f.name).read_bytes(), IMAGES / "report.png", 1100)


if __name__ == "__main__":
    main()
