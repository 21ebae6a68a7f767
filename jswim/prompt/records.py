"""History records: [`HistoryRecord`][jswim.prompt.HistoryRecord] (one executed step) and its
line in S3, with the integer encoding of positions and heights.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from jswim.prompt.config import PromptConfig
from jswim.prompt.nav_text import per_step
from jswim.prompt.numbers import Action, encode_position, format_dof
from jswim.prompt.prose import fill
from jswim.prompt.swimmer_text import SwimmerText


#: A record whose |dX| (in units of a) is below this is flagged stuck (the authors' code).
STUCK_DX = 1e-6


@dataclass(frozen=True)
class HistoryRecord:
    """One executed step, as shown to the model.

    A navigation task's record also holds the centre's ``y`` and the heading (``None``
    elsewhere); then the stuck flag reads the displacement in the plane.

    ``step`` is the record's index as the model sees it (from 1 after each clear; set by
    [`jswim.agents.memory.History.add`][jswim.agents.memory.History.add]). Positions are the raw centroid ``X/a``; they are
    encoded as integers when rendered. ``stuck`` is the environment's flag (the move pushed a DOF
    past its limit); the rendered flag is also on when ``|dX| <`` `STUCK_DX` (holds).
    """

    step: int
    dofs_before: tuple[float, ...]
    dofs_after: tuple[float, ...]
    action: Action
    x_before: float
    x_after: float
    stuck: bool = False
    # Scenes only (empty in the paper's bulk fluid): per swimmer, positions (X1, X2), heights
    # above the wall and tilts (rad), before and after the step.
    xs_before: tuple[float, ...] = ()
    xs_after: tuple[float, ...] = ()
    heights_before: tuple[float, ...] = ()
    heights_after: tuple[float, ...] = ()
    tilts_before: tuple[float, ...] = ()
    tilts_after: tuple[float, ...] = ()
    # Navigation (an extension): the centre's y and the heading (rad), before and after the step.
    y_before: float | None = None
    y_after: float | None = None
    heading_before: float | None = None
    heading_after: float | None = None
    # Navigation in a background flow (an extension): the flow's (ux, uy) at the centre before
    # the step (a / step, lab frame).
    flow: tuple[float, float] | None = None

    @property
    def dx(self) -> float:
        return self.x_after - self.x_before

    @property
    def moved(self) -> float:
        """How far the centre moved: ``|dX|``, or ``|(dX, dY)|`` where the record has Y."""
        if self.y_before is None or self.y_after is None:
            return abs(self.dx)
        return math.hypot(self.dx, self.y_after - self.y_before)


def render_record(rec: HistoryRecord, sw: SwimmerText, cfg: PromptConfig) -> str:
    """One history line."""
    return fill(cfg.template.record, _record_values(rec, sw, cfg), "record")


def _record_values(rec: HistoryRecord, sw: SwimmerText, cfg: PromptConfig) -> dict[str, str]:
    """The placeholders of a record line (one place: rendering and [`PromptTemplate.check`][jswim.prompt.PromptTemplate.check])."""
    d = sw.dof_decimals
    return {
        "step": str(rec.step),
        "dofs_before": ", ".join(format_dof(v, d) for v in rec.dofs_before),
        "dofs_after": ", ".join(format_dof(v, d) for v in rec.dofs_after),
        "action": rec.action.text(),
        "x_before": str(encode_position(rec.x_before, cfg.x_min)),
        "x_after": str(encode_position(rec.x_after, cfg.x_min)),
        "stuck": "yes" if rec.stuck or rec.moved < STUCK_DX else "no",
        **_scene_record_values(rec, cfg),
        **_nav_record_values(rec, cfg),
    }


def _nav_record_values(rec: HistoryRecord, cfg: PromptConfig) -> dict[str, str]:
    """A record's navigation placeholders (empty where the record has none): ``y_before``,
    ``y_after`` (encoded as X, with the same ``X_min``) and ``heading_before``,
    ``heading_after`` (rad in ``(-pi, pi]``, three decimals); in a flow ``flow_x``,
    ``flow_y`` (thousandths of a link length per step, truncated, signed:
    [`per_step`][jswim.prompt.nav_text.per_step])."""
    out = {}
    for when in ("before", "after"):
        y = getattr(rec, f"y_{when}")
        out[f"y_{when}"] = "" if y is None else str(encode_position(y, cfg.x_min))
    for when in ("before", "after"):
        h = getattr(rec, f"heading_{when}")
        out[f"heading_{when}"] = "" if h is None else format_dof(wrap_angle(h), 3)
    for k, name in enumerate(("flow_x", "flow_y")):
        out[name] = "" if rec.flow is None else per_step(rec.flow[k])
    return out


def wrap_angle(angle: float) -> float:
    """``angle`` (rad) in ``(-pi, pi]``."""
    return math.pi - math.fmod(math.fmod(math.pi - angle, 2 * math.pi) + 2 * math.pi, 2 * math.pi)


def encode_height(h: float) -> int:
    """A height above the wall as the prompt shows it: thousandths of ``a``, truncated, as X is
    ([`encode_position`][jswim.prompt.encode_position] with ``X_min = 0``: heights are positive)."""
    return encode_position(h, 0.0)


def _scene_record_values(rec: HistoryRecord, cfg: PromptConfig) -> dict[str, str]:
    """A record's scene placeholders (empty where the record has no scene): ``x1_before`` ..
    ``x2_after`` (encoded as X), ``h1_before`` .. ``h2_after`` ([`encode_height`][jswim.prompt.encode_height]),
    ``tilt1_before`` .. ``tilt2_after`` (rad, 3 decimals), and ``h_*``/``tilt_*`` for swimmer 1;
    a school's ``x3_*``, ``h3_*``, ... likewise (names up to swimmer 2 are always known)."""
    out: dict[str, str] = {}
    for k in range(1, max(2, len(rec.xs_before), len(rec.xs_after)) + 1):
        for when in ("before", "after"):
            xs, hs, ts = (getattr(rec, f"{n}_{when}") for n in ("xs", "heights", "tilts"))
            out[f"x{k}_{when}"] = str(encode_position(xs[k - 1], cfg.x_min)) if k <= len(xs) else ""
            out[f"h{k}_{when}"] = str(encode_height(hs[k - 1])) if k <= len(hs) else ""
            out[f"tilt{k}_{when}"] = format_dof(ts[k - 1], 3) if k <= len(ts) else ""
    for when in ("before", "after"):
        out[f"h_{when}"], out[f"tilt_{when}"] = out[f"h1_{when}"], out[f"tilt1_{when}"]
    return out
