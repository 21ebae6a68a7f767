"""What the prompt says of a scene (walls, pairs, schools; an extension of the paper):
[`SceneView`][jswim.prompt.SceneView], S2's scene sentences and the scene's template.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from jswim.errors import ConfigError
from jswim.prompt.prose import join_prose
from jswim.prompt.template import DEFAULT_TEMPLATE, PromptTemplate


@dataclass(frozen=True)
class SceneView:
    """What the prompt shows of a world beyond the paper's lone swimmer in bulk fluid (walls,
    pairs, schools; an extension; ``None`` on [`SwimmerText`][jswim.prompt.SwimmerText] is the paper's prompt, unchanged).

    Attributes
    ----------
    swimmers : int
        1 or more. With several, the DOFs are joint (swimmer ``k`` owns D(2k-1), D(2k): a reply
        names the swimmer through its DOF) and every record shows each swimmer's position X1, X2, ...
    wall : bool
        A no-slip wall below: every record shows each swimmer's height H (integer-encoded as X is:
        thousandths of ``a``, [`encode_height`][jswim.prompt.encode_height]) and tilt (rad, three decimals).
    separation : float
        The starting distance D (sphere radii) of swimmer 2 ahead of swimmer 1, said once in S2.
    own : int
        0: the joint prompt (one conversation steers every swimmer). ``k`` >= 1: the prompt of
        swimmer ``k`` alone (``--pair-prompt each``, a variant): its own arms D1, D2 and position
        X, and the others' positions (a pair's: ``other X``; more: ``X1``, ``X2``, ... of the
        others), encoded as X is; with a wall, its own H and tilt.
    starts : tuple of (x, z)
        Three or more swimmers: each one's start relative to swimmer 1 (sphere radii), said in S2.
    """

    swimmers: int = 1
    wall: bool = False
    separation: float = 0.0
    own: int = 0
    starts: tuple[tuple[float, float], ...] = ()

    def __post_init__(self) -> None:
        if (
            isinstance(self.swimmers, bool)
            or not isinstance(self.swimmers, int)
            or self.swimmers < 1
        ):
            raise ConfigError(f"a scene holds 1 or more swimmers, got {self.swimmers}")
        if self.own not in (range(self.swimmers + 1) if self.swimmers > 1 else (0,)):
            raise ConfigError(
                f"a per-swimmer prompt needs several swimmers and one of them, got swimmer {self.own} "
                f"of {self.swimmers}"
            )


#: S2's extra sentence for a wall (one swimmer), for a pair, and for a pair above a wall.
WALL_SENTENCE = (
    "The swimmer moves above a flat wall: H is its height above the wall in thousandths of its sphere "
    "radius and tilt its angle to the wall in radians."
)


PAIR_SENTENCE = (
    "D1 and D2 are the arms of swimmer 1 and D3 and D4 those of swimmer 2, which starts {separation} "
    "sphere radii ahead of it on the same axis; X1 and X2 are their positions, and the movement sought is "
    "that of their mean."
)


#: S2's extra sentence of one swimmer's own prompt in a pair (``--pair-prompt each``): where the
#: other starts (``{where}``: ``ahead of`` for swimmer 1, ``behind`` for swimmer 2), that it moves
#: between this one's steps, and what ``other X`` is; with a wall, `WALL_SENTENCE` follows.
OWN_PAIR_SENTENCE = (
    "A second swimmer on the same axis, steered on its own, starts {separation} sphere radii {where} "
    "this one and moves its arms between this one's steps; other X is its position, counted from its "
    "own start as X is."
)


#: With several swimmers above a wall (``{all}``: Both or All; ``{to}``: and, or to for three or more).
SEVERAL_WALL_SENTENCE = (
    "{all} swim above a flat wall: H1 {to} H{n} are their heights above it in thousandths of the "
    "sphere radius, tilt1 {to} tilt{n} their angles to it in radians."
)


#: S2's extra sentence of a school (three or more swimmers; ``{starts}``: where each starts from
#: swimmer 1, or from this one in one swimmer's own prompt, ``--pair-prompt each``).
SCHOOL_SENTENCE = (
    "Swimmer k has the arms D(2k-1) and D(2k), up to D{last} of swimmer {n}; they start with {starts} "
    "from swimmer 1; X1 to X{n} are their positions, and the movement sought is that of their mean."
)


OWN_SCHOOL_SENTENCE = (
    "This is swimmer {own} of {n}, steered on its own; the others start with {starts} from it and "
    "move their arms between this one's steps; Xk is swimmer k's position, counted from its own "
    "start as X is."
)


def _starts(view: SceneView) -> str:
    """``swimmer 1 at (0, 0), ... sphere radii (x, z)``: each start from swimmer ``own`` (or 1)."""
    ox, oz = view.starts[max(view.own, 1) - 1]
    return (
        join_prose(
            [
                f"swimmer {k} at ({x - ox:g}, {z - oz:g})"
                for k, (x, z) in enumerate(view.starts, 1)
                if k != view.own
            ]
        )
        + " sphere radii (x, z)"
    )


def scene_sentence(view: SceneView | None) -> str:
    """What S2 gains for a scene (empty for none)."""
    if view is None:
        return ""
    parts = []
    n = view.swimmers
    if view.own and n == 2:
        where = "ahead of" if view.own == 1 else "behind"
        parts.append(OWN_PAIR_SENTENCE.format(separation=f"{view.separation:g}", where=where))
    elif n == 2:
        parts.append(PAIR_SENTENCE.format(separation=f"{view.separation:g}"))
    elif n > 2:
        parts.append(
            (OWN_SCHOOL_SENTENCE if view.own else SCHOOL_SENTENCE).format(
                own=view.own, n=n, last=2 * n, starts=_starts(view)
            )
        )
    if view.wall:
        parts.append(
            WALL_SENTENCE
            if n == 1 or view.own
            else SEVERAL_WALL_SENTENCE.format(
                all="Both" if n == 2 else "All", to="and" if n == 2 else "to", n=n
            )
        )
    return " ".join(parts)


def scene_template(view: SceneView, base: PromptTemplate | None = None) -> PromptTemplate:
    """The default template for a scene: S3's legend and the record line gain what
    [`SceneView`][jswim.prompt.SceneView] says each record shows. A template other than the default (a
    ``--prompt-file``) is returned as given: its author chose what to show."""
    base = DEFAULT_TEMPLATE if base is None else base
    if base != DEFAULT_TEMPLATE:
        return base
    n, me = view.swimmers, view.own
    legend, line = [], []

    def show(label: str, key: str) -> None:
        legend.append(f"{label} before -> after")
        line.append(f"{label} {{{key}_before}} -> {{{key}_after}}")

    if me:  # one swimmer of several: the lone swimmer's record, then the others' positions
        show("X", f"x{me}")
        for k in range(1, n + 1):
            if k != me:
                show("other X" if n == 2 else f"X{k}", f"x{k}")
        if view.wall:
            show("H", f"h{me}")
            show("tilt", f"tilt{me}")
    else:
        for k in range(1, n + 1):
            show("X" if n == 1 else f"X{k}", "x" if n == 1 else f"x{k}")
        for k in range(1, n + 1) if view.wall else ():
            show("H" if n == 1 else f"H{k}", f"h{k}")
            show("tilt" if n == 1 else f"tilt{k}", f"tilt{k}")
    s3 = (
        "Latest records (step: ({dof_names}) before [changed DOF, ROC] -> ({dof_names}) after, "
        + ", ".join(legend)
        + ", stuck):\n{history}"
    )
    record = (
        "{step}: ({dofs_before}) {action} -> ({dofs_after}), " + ", ".join(line) + ", stuck {stuck}"
    )
    return replace(base.with_sentences(S3=s3), record=record)
