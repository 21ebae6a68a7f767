"""Size and load time of report.html for a ~1,000-run study; frame rate and size of an animation.

Builds a noise study (both swimmers, the paper's 7 noise levels, 50 steps): Q-learning and random
runs (``--q-runs``, default 36 per level: 1,008 baseline runs) and LLM runs against the fake server
(``--runs``, default 4 per level: 56 runs with transcripts), then measures:

- writing ``report.html`` (figures drawn in memory) and its size;
- in headless Chromium: load to the first run opened, and opening another run (its blob decoded);
- writing a 3-panel, 50-step GIF (frames per second of writing) and its size.

Run: ``.venv/bin/python benchmarks/bench_report.py`` (needs chromium for the page timings).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from jswim.studies import Backend, StudyOptions, run_study
from jswim.viz.animate import build
from jswim.viz.page import write_report
from tests.fakeserver import FakeServer, hash_reply


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--q-runs", type=int, default=36)
    ap.add_argument("--runs", type=int, default=4)
    ap.add_argument("--folder", default=None, help="reuse (or make) the study here")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(args.folder or Path(tmp) / "noise")
        t0 = time.perf_counter()
        with FakeServer(reply=hash_reply, latency=0.0) as srv:
            res = run_study(
                "noise",
                StudyOptions(runs=args.runs, q_runs=args.q_runs, steps=50),
                backend=Backend(base_url=srv.url, model="fake"),
                out=out,
            )
        print(
            f"study: {len(res.rows)} runs ({sum(r['agent'] == 'llm' for r in res.rows)} LLM) in "
            f"{time.perf_counter() - t0:.0f} s"
        )
        t0 = time.perf_counter()
        page = write_report(out, figures="draw")
        print(
            f"report.html: {page.stat().st_size / 2**20:.2f} MiB, written in {time.perf_counter() - t0:.1f} s "
            "(figures drawn in memory)"
        )
        try:
            from tests.browser import Browser, find_browser

            if find_browser() is None:
                raise RuntimeError("no chromium")
            with Browser() as b:
                t0 = time.perf_counter()
                b.open(page.as_uri())
                b.eval("window.jswimReport.opened")
                load = time.perf_counter() - t0
                listed = b.eval("window.jswimReport.listed()")
                t0 = time.perf_counter()
                b.eval("window.jswimReport.select(700)")
                other = time.perf_counter() - t0
                print(
                    f"chromium: loaded with the first run open in {load:.2f} s ({listed} runs listed, the list "
                    f"holds at most 400); another run opened in {other * 1000:.0f} ms; errors: {b.errors or 'none'}"
                )
        except (ImportError, RuntimeError) as exc:
            print(f"chromium: not measured ({exc})")
        anim = build(out)
        t0 = time.perf_counter()
        gif = anim.save(Path(tmp) / "runs.gif")
        dt = time.perf_counter() - t0
        print(
            f"animation: {len(anim.tracks)} panels x {anim.n_frames} frames, {gif.stat().st_size / 1024:.0f} KB GIF, "
            f"written at {anim.n_frames / dt:.1f} frames/s ({dt:.1f} s); plays at {anim.fps:g} steps/s"
        )


if __name__ == "__main__":
    main()
