"""A check shared by the animation tests: every caption of every panel stays inside its panel
and on the figure (no caption runs into the next panel or off the figure's edge)."""

from __future__ import annotations

from collections.abc import Iterable


def captions_outside_their_panel(anim, frames: Iterable[int]) -> list[str]:
    """The captions of ``anim`` that leave their panel at any of ``frames`` (empty: all fit)."""
    import matplotlib.pyplot as plt

    fig, draw = anim.figure()
    n = len(anim.tracks)
    bad = []
    try:
        for frame in frames:
            draw(frame)
            fig.canvas.draw()
            renderer = fig.canvas.get_renderer()
            w, h = fig.bbox.width, fig.bbox.height
            panel_texts = fig.texts[1:]  # fig.texts[0] is the figure's title
            for i, ax in enumerate(fig.axes):
                lo, hi = i / n * w - 1.0, (i + 1) / n * w + 1.0
                for what, text in (("title", ax.title), ("lines", panel_texts[i])):
                    box = text.get_window_extent(renderer)
                    if box.x0 < lo or box.x1 > hi or box.y0 < -1.0 or box.y1 > h + 1.0:
                        bad.append(f"frame {frame}, panel {i} {what}: {text.get_text()!r}")
    finally:
        plt.close(fig)
    return bad
