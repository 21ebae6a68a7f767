"""What the prompt says of a navigation task (an extension: the paper's task is "swim along +x"):
[`NavView`][jswim.prompt.NavView], S1's target phrase, S2's navigation sentence and the
navigation template (records with X, Y and heading).

The paper's five sentences stay five: S1 names the target's position, integer-encoded as the
paper encodes X (``(X - X_min) 1000``, truncated; Y with the same offset), S2 gains one sentence
saying what X, Y and the heading are, how close counts as reached and, for a moving target or a
path, how the target changes; S3's records give X, Y and the heading before and after each step;
S4 and S5 are the paper's. A ROC lattice finer than the paper's adds its sentence to S2 and S5 as
for any task.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

from jswim.errors import ConfigError
from jswim.prompt.numbers import encode_position
from jswim.prompt.template import DEFAULT_TEMPLATE, PromptTemplate

#: Target kinds (`NavView.kind`): a fixed point, a path of waypoints, a point moving at a
#: constant velocity.
NAV_KINDS = ("fixed", "waypoints", "moving")


@dataclass(frozen=True)
class NavView:
    """What the prompt shows of a navigation task (``None`` on
    [`SwimmerText`][jswim.prompt.SwimmerText]: the paper's +x/-x task).

    Attributes
    ----------
    kind : {"fixed", "waypoints", "moving"}
        The target's kind (`NAV_KINDS`).
    radius : float
        Success radius (link lengths): the target counts as reached once the swimmer's centre is
        this close to it; said in S2 in thousandths, as positions are.
    waypoints : int
        Targets in the path (1 for a point or a moving target).
    velocity : tuple of float
        A moving target's velocity ``(vx, vy)`` in link lengths per step; said in S2 in
        thousandths per step.
    flow : bool
        The fluid flows (an extension, docs/navigation.md *Flows*): S2 says so (`FLOW_SENTENCE`)
        and each record gives the local flow before the step (`NAV_FLOW_RECORD`).
    """

    kind: str = "fixed"
    radius: float = 0.25
    waypoints: int = 1
    velocity: tuple[float, float] = (0.0, 0.0)
    flow: bool = False

    def __post_init__(self) -> None:
        if self.kind not in NAV_KINDS:
            raise ConfigError(f"a navigation target is one of {NAV_KINDS}, got {self.kind!r}")
        if not (self.radius > 0 and math.isfinite(self.radius)):
            raise ConfigError(f"a success radius must be > 0, got {self.radius}")
        if self.waypoints < 1:
            raise ConfigError(f"a path holds one or more waypoints, got {self.waypoints}")


#: S1 of a navigation task: ``{target}`` is [`target_phrase`][jswim.prompt.nav_text.target_phrase].
NAV_S1 = (
    "Find the sequence of rates of change (ROC) of the degrees of freedom (DOF) {dofs} that brings "
    "the swimmer to {target} in the fewest steps."
)

#: S2's navigation sentence (``{radius}`` in thousandths of a link length).
NAV_SENTENCE = (
    "X and Y are positions in the plane in thousandths of a link length; heading is the angle of "
    "the swimmer's middle link to the x axis in radians, counterclockwise; the target counts as "
    "reached within {radius} of it."
)

#: What S2 adds for a moving target (``{vx}``, ``{vy}``: thousandths per step, signed).
MOVING_SENTENCE = "The target moves by ({vx}, {vy}) in (X, Y) every step."

#: What S2 adds for a path of waypoints.
PATH_SENTENCE = (
    "The path has {waypoints} waypoints; when one is reached, the next becomes the target."
)

#: What S2 adds in a background flow.
FLOW_SENTENCE = (
    "The fluid flows and carries the swimmer: each record's flow (X, Y) is the fluid's velocity "
    "at the swimmer's centre before the step, in thousandths of a link length per step."
)

#: S3 and the record line of the navigation template.
NAV_S3 = (
    "Latest records (step: ({dof_names}) before [changed DOF, ROC] -> ({dof_names}) after, X before "
    "-> after, Y before -> after, heading before -> after, stuck):\n{history}"
)
NAV_RECORD = (
    "{step}: ({dofs_before}) {action} -> ({dofs_after}), X {x_before} -> {x_after}, Y {y_before} -> "
    "{y_after}, heading {heading_before} -> {heading_after}, stuck {stuck}"
)


#: S3 and the record line of the navigation template in a flow: the records gain the local flow.
NAV_FLOW_S3 = (
    "Latest records (step: ({dof_names}) before [changed DOF, ROC] -> ({dof_names}) after, X before "
    "-> after, Y before -> after, heading before -> after, flow (X, Y), stuck):\n{history}"
)
NAV_FLOW_RECORD = (
    "{step}: ({dofs_before}) {action} -> ({dofs_after}), X {x_before} -> {x_after}, Y {y_before} -> "
    "{y_after}, heading {heading_before} -> {heading_after}, flow ({flow_x}, {flow_y}), stuck {stuck}"
)


def target_phrase(
    view: NavView, target: tuple[float, float], x_min: float, waypoint: int = 1
) -> str:
    """S1's ``{target}``: where the target is now, X and Y encoded as the paper encodes X
    ([`encode_position`][jswim.prompt.encode_position] with ``x_min`` for both)."""
    at = f"(X, Y) = ({encode_position(target[0], x_min)}, {encode_position(target[1], x_min)})"
    if view.kind == "moving":
        return f"the moving target, now at {at},"
    if view.kind == "waypoints":
        return f"waypoint {waypoint} of {view.waypoints} at {at}, then along the path,"
    return f"the target at {at}"


def per_step(v: float) -> str:
    """A velocity component in thousandths per step, signed, truncated as positions are."""
    return str(math.trunc(v * 1000))


def nav_sentence(view: NavView | None) -> str:
    """What S2 gains for a navigation task (empty for none)."""
    if view is None:
        return ""
    parts = [NAV_SENTENCE.format(radius=math.trunc(view.radius * 1000))]
    if view.kind == "moving":
        parts.append(
            MOVING_SENTENCE.format(vx=per_step(view.velocity[0]), vy=per_step(view.velocity[1]))
        )
    if view.flow:
        parts.append(FLOW_SENTENCE)
    if view.kind == "waypoints":
        parts.append(PATH_SENTENCE.format(waypoints=view.waypoints))
    return " ".join(parts)


def nav_template(base: PromptTemplate | None = None, flow: bool = False) -> PromptTemplate:
    """The default template of a navigation task: S1 names the target (`NAV_S1`), S3's legend
    and the record line give X, Y and the heading (`NAV_S3`, `NAV_RECORD`; in a flow also the
    local flow, `NAV_FLOW_S3`, `NAV_FLOW_RECORD`). A template other than the default (a
    ``--prompt-file``) is returned as given: its author chose the text (its S1 may name
    ``{target}``, its records ``{y_before}`` .. ``{heading_after}``, ``{flow_x}``, ``{flow_y}``)."""
    base = DEFAULT_TEMPLATE if base is None else base
    if base != DEFAULT_TEMPLATE:
        return base
    s3, record = (NAV_FLOW_S3, NAV_FLOW_RECORD) if flow else (NAV_S3, NAV_RECORD)
    return replace(base.with_sentences(S1=NAV_S1, S3=s3), record=record)


__all__ = [
    "FLOW_SENTENCE",
    "MOVING_SENTENCE",
    "NAV_FLOW_RECORD",
    "NAV_FLOW_S3",
    "NAV_KINDS",
    "NAV_RECORD",
    "NAV_S1",
    "NAV_S3",
    "NAV_SENTENCE",
    "PATH_SENTENCE",
    "NavView",
    "nav_sentence",
    "nav_template",
    "per_step",
    "target_phrase",
]
