"""Seeing runs: a swimmer's true shape per step, animations and the study folder's report page.

- `jswim.viz.tracks`: what a run did, step by step, read from what a folder records (the run's
  row in ``runs.jsonl`` and its transcript): pose, DOF values, the body outline in the lab frame,
  actions, stuck and clear events, the LLM's replies, where the success criterion found the stroke.
- `jswim.viz.animate`: runs side by side as a GIF (Pillow) or MP4 (``imageio-ffmpeg``,
  optional), `jswim.viz.animate.animate` (``jswim.animate``) for notebooks.
- `jswim.viz.page`: ``report.html``, one self-contained page per study folder.
- `jswim.viz.publish`: `report` (``jswim.report``), the publish step after a study: its figures and
  its page, drawn from the folder.
"""

from __future__ import annotations

from jswim._exports import lazy_exports

#: Public name -> the module that defines it (loaded on first use).
_EXPORTS = {
    "track": "jswim.viz.tracks",
    "Track": "jswim.viz.tracks",
    "outline": "jswim.viz.tracks",
    "write_report": "jswim.viz.page",
    "report": "jswim.viz.publish",
    "Published": "jswim.viz.publish",
}

__all__ = list(_EXPORTS)

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
