"""The paper's five-sentence prompt, history records, number encoding and reply parsing.

Text only: this module never imports JAX. The sentences S1..S5, their layouts (paper and cache
orders), every template placeholder, the template file format, the summary sentence, finer ROCs
and scenes are described in docs/api/prompt.md.
"""

from __future__ import annotations

import re
import string
from dataclasses import dataclass, replace
from pathlib import Path
from collections.abc import Iterable, Sequence

from jswim.actions import check_action_set, check_roc_levels
from jswim.errors import ConfigError, check_direction, check_size
from jswim.prompt.numbers import Action, encode_position, format_dof
from jswim.prompt.reply import parse_reply  # noqa: F401  (also read from here)

#: Sentence names, in the paper's order.
SENTENCES = ("S1", "S2", "S3", "S4", "S5")

#: The paper's and the authors' order S1..S5, the history third and the answer instruction last (default).
PAPER_LAYOUT = "{S1} {S2}\n{S3}\n{S4} {S5}"

#: Every fixed sentence before the changing history: the prefix-cache friendly order (``order="cache"``).
CACHE_LAYOUT = "{S1} {S2} {S4} {S5}\n{S3}"

#: What the cache order becomes when S5 or the summary change at every step: per-step text last.
CACHE_LAYOUT_LATE = "{S1} {S2} {S4}\n{S3}\n{summary}\n{S5}"

#: Prompt orders (:attr:`PromptConfig.order`).
ORDERS = ("paper", "cache")

#: A record whose |dX| (in units of a) is below this is flagged stuck (the authors' code).
STUCK_DX = 1e-6

#: The system message of the authors' code: a single space (the paper uses no system prompt).
PAPER_SYSTEM = " "

DEFAULT_SENTENCES = {
    "S1": "Find the sequence of rates of change (ROC) of the degrees of freedom (DOF) {dofs} that gives "
    "the fastest long-term movement in the {direction_words} direction.",
    "S2": "Only one DOF changes at a time, and {dof_ranges}.",
    "S3": "Latest records (step: ({dof_names}) before [changed DOF, ROC] -> ({dof_names}) after, "
    "X before -> after, stuck):\n{history}",
    "S4": "Keep in mind that an action can have long-term consequences.",
    "S5": "Reply with the next action as [changed DOF, ROC], {choices}.",
}

DEFAULT_RECORD = (
    "{step}: ({dofs_before}) {action} -> ({dofs_after}), X {x_before} -> {x_after}, stuck {stuck}"
)


def _join_prose(items: Sequence[str], last: str = "and") -> str:
    if len(items) <= 1:
        return "".join(items)
    return ", ".join(items[:-1]) + f" {last} " + items[-1]


# ---------------------------------------------------------------------------------------------
# Swimmer description (text side)


@dataclass(frozen=True)
class SceneView:
    """What the prompt shows of a world beyond the paper's lone swimmer in bulk fluid (walls,
    pairs, schools; an extension; ``None`` on :class:`SwimmerText` is the paper's prompt, unchanged).

    Attributes
    ----------
    swimmers : int
        1 or more. With several, the DOFs are joint (swimmer ``k`` owns D(2k-1), D(2k): a reply
        names the swimmer through its DOF) and every record shows each swimmer's position X1, X2, ...
    wall : bool
        A no-slip wall below: every record shows each swimmer's height H (integer-encoded as X is:
        thousandths of ``a``, :func:`encode_height`) and tilt (rad, three decimals).
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


@dataclass(frozen=True)
class SwimmerText:
    """What the prompt needs to know about a swimmer.

    Attributes
    ----------
    n_dof : int
        Number of DOFs, named D1..Dn.
    lo, hi : float or tuple of float
        DOF range, shared by all DOFs or one value per DOF.
    dof_decimals : int
        Decimals of DOF values in text (angles 3, NG arm lengths 0 on the paper's corners; see
        :func:`jswim.agents.defaults.dof_decimals` for finer ROC lattices).
    rocs : tuple of int
        ROCs an action may carry: ``(-1, 0, 1)`` (paper), ``(-1, 1)`` for 4-DOF swimmers; with
        ``roc_levels = K`` integers in ``-K..K`` (``k`` means ``k/K`` of the range per step).
    roc_levels : int
        ``K`` (1, the paper's set, by default). Above 1, S2 and S5 each get one sentence saying
        what the integer ROC means (:data:`ROC_SCALE_SENTENCE`, :data:`ROC_FORMAT_SENTENCE`).
    scene : SceneView, optional
        A wall and/or a second swimmer (:class:`SceneView`); ``None``: the paper's bulk fluid.
    """

    n_dof: int
    lo: float | tuple[float, ...]
    hi: float | tuple[float, ...]
    dof_decimals: int = 3
    rocs: tuple[int, ...] = (-1, 0, 1)
    roc_levels: int = 1
    scene: SceneView | None = None

    def __post_init__(self) -> None:
        if self.n_dof < 1:
            raise ConfigError(f"n_dof must be >= 1, got {self.n_dof}")
        k = check_roc_levels(self.roc_levels)
        if not self.rocs or any(
            isinstance(r, bool) or not isinstance(r, int) or abs(r) > k for r in self.rocs
        ):
            raise ConfigError(
                f"rocs must be a non-empty set of integers in -{k}..{k} (--roc-levels {k}), "
                f"got {self.rocs}"
            )
        object.__setattr__(self, "rocs", tuple(sorted(set(self.rocs))))

    def bounds(self, k: int) -> tuple[float, float]:
        """``(lo, hi)`` of DOF ``k`` (1-based)."""
        lo = self.lo[k - 1] if isinstance(self.lo, tuple) else self.lo
        hi = self.hi[k - 1] if isinstance(self.hi, tuple) else self.hi
        return float(lo), float(hi)

    @property
    def names(self) -> list[str]:
        return [f"D{k}" for k in range(1, self.n_dof + 1)]


#: S2's extra sentence when ``roc_levels = K > 1`` (the paper's K = 1 prompt has none).
ROC_SCALE_SENTENCE = (
    "In one step a ROC of k changes the DOF by k/{roc_levels} of its range, stopping at its limits."
)

#: S5's extra sentence when ``roc_levels = K > 1``: the reply carries a whole number, as the paper
#: advises (no decimals; the sign is the only non-digit).
ROC_FORMAT_SENTENCE = "The ROC is a whole number from -{roc_levels} to {roc_levels}{except_zero}."


def allowed_actions(
    swimmer: SwimmerText, action_set: str = "all", dof_values: Sequence[float] | None = None
) -> list[Action]:
    """The actions a reply may name, in (dof, roc) order.

    Parameters
    ----------
    swimmer : SwimmerText
        DOF count, ranges and ROC set.
    action_set : {"all", "shape-changing"}
        One of :data:`jswim.actions.ACTION_SETS`. ``"all"``: every (dof, roc) pair (the paper's setting). ``"shape-changing"``: only moves
        that change the shape from ``dof_values``: a positive ROC below ``hi``, a negative one above ``lo``.
    dof_values : sequence of float, optional
        Current DOF values; required for ``"shape-changing"``.
    """
    check_action_set(action_set)
    pairs = [Action(k, r) for k in range(1, swimmer.n_dof + 1) for r in swimmer.rocs]
    if action_set == "all":
        return pairs
    if dof_values is None or len(dof_values) != swimmer.n_dof:
        raise ConfigError("action_set='shape-changing' needs the current value of every DOF")
    out = []
    for a in pairs:
        lo, hi = swimmer.bounds(a.dof)
        v = float(dof_values[a.dof - 1])
        tol = 1e-9 * max(1.0, abs(hi - lo))
        if (a.roc > 0 and v < hi - tol) or (a.roc < 0 and v > lo + tol):
            out.append(a)
    return out


# ---------------------------------------------------------------------------------------------
# History


@dataclass(frozen=True)
class HistoryRecord:
    """One executed step, as shown to the model.

    ``step`` is the record's index as the model sees it (from 1 after each clear; set by
    :meth:`jswim.agents.memory.History.add`). Positions are the raw centroid ``X/a``; they are
    encoded as integers when rendered. ``stuck`` is the environment's flag (the move pushed a DOF
    past its limit); the rendered flag is also on when ``|dX| <`` :data:`STUCK_DX` (holds).
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

    @property
    def dx(self) -> float:
        return self.x_after - self.x_before


# ---------------------------------------------------------------------------------------------
# Templates


#: Largest prompt template file read (bytes): the paper's prompt is about 2 kB, and every request
#: carries the template whole (a 10 MB file would send 10 MB per request).
MAX_TEMPLATE_BYTES = 100_000


@dataclass(frozen=True)
class PromptTemplate:
    """Layout, sentence and record templates (placeholders: docs/api/prompt.md)."""

    layout: str = PAPER_LAYOUT
    sentences: tuple[tuple[str, str], ...] = tuple(DEFAULT_SENTENCES.items())
    record: str = DEFAULT_RECORD

    def sentence(self, name: str) -> str:
        return dict(self.sentences)[name]

    def with_sentences(self, **texts: str) -> PromptTemplate:
        """A copy with some sentences replaced, e.g. ``with_sentences(S4="...")``."""
        bad = set(texts) - set(SENTENCES)
        if bad:
            raise ConfigError(f"unknown sentence names {sorted(bad)}; use {SENTENCES}")
        merged = dict(self.sentences) | texts
        return replace(self, sentences=tuple((k, merged[k]) for k in SENTENCES))

    @classmethod
    def from_text(cls, text: str) -> PromptTemplate:
        """Parse template text (whole layout, or ``[layout]``/``[S1]``../``[record]`` sections)."""
        header = re.compile(r"^\[(layout|record|S[1-5])\]\s*$", re.MULTILINE)
        if not header.search(text):
            return cls(layout=text.strip("\n"))
        parts = header.split(text)
        if parts[0].strip():
            raise ConfigError("template text before the first [section] header")
        sections: dict[str, str] = {}
        for name, body in zip(parts[1::2], parts[2::2]):
            if name in sections:
                raise ConfigError(f"template section [{name}] appears twice")
            sections[name] = body.strip("\n")
        tpl = cls()
        tpl = tpl.with_sentences(**{k: v for k, v in sections.items() if k in SENTENCES})
        return replace(
            tpl,
            layout=sections.get("layout", tpl.layout),
            record=sections.get("record", tpl.record),
        )

    @classmethod
    def from_file(cls, path: str | Path) -> PromptTemplate:
        """Read a template file (format: docs/api/prompt.md); at most
        :data:`MAX_TEMPLATE_BYTES` (every request carries the whole prompt)."""
        try:
            size = Path(path).stat().st_size
            if size > MAX_TEMPLATE_BYTES:
                raise ConfigError(
                    f"--prompt-file {path} is {size / 1e6:.1f} MB; a prompt template may be at most "
                    f"{MAX_TEMPLATE_BYTES // 1000} kB (every request sends it whole)"
                )
            text = Path(path).read_text(encoding="utf-8")
        except OSError as exc:
            raise ConfigError(f"cannot read prompt template {path}: {exc.strerror}") from None
        except UnicodeDecodeError as exc:
            raise ConfigError(
                f"--prompt-file {path}: not UTF-8 text (byte {exc.start}); "
                "save the template as UTF-8"
            ) from None
        return cls.from_text(text).check(f"--prompt-file {path}")

    def check(self, where: str = "the prompt template") -> PromptTemplate:
        """``self`` if every placeholder is known and the prompt shows the history and the allowed
        set (the paper's S3 and S5, or ``{history}`` and ``{allowed}``/``{choices}``); else
        :class:`ConfigError` naming what is wrong. Checked when a file is read, so a bad file
        fails before any run.
        """
        prompt_names, record_names = _placeholders()
        parts = [("layout", self.layout, prompt_names)]
        parts += [(name, text, prompt_names) for name, text in self.sentences]
        parts.append(("record", self.record, record_names))
        for what, text, known in parts:
            try:
                names = [f for _, f, _, _ in string.Formatter().parse(text) if f is not None]
            except ValueError as exc:
                raise ConfigError(
                    f"{where}: bad braces in the {what} ({exc}); write literal braces as {{{{ }}}}"
                ) from None
            unknown = sorted({n for n in names if n not in known})
            if unknown:
                raise ConfigError(
                    f"{where}: unknown placeholder {{{unknown[0]}}} in the {what}; known: "
                    + ", ".join("{" + k + "}" for k in known)
                )
        shown = _fields(self.layout)
        for name in SENTENCES:
            if name in shown:
                shown |= _fields(self.sentence(name))
        # Shown means reached from the layout, directly or through a sentence it uses.
        for needs, put, what in (
            (("history",), "{S3} or {history}", "history"),
            (("allowed", "choices"), "{S5} or {allowed}", "allowed set"),
        ):
            if not shown & set(needs):
                raise ConfigError(
                    f"{where}: the prompt never shows the {what}; put {put} in the layout "
                    "(or in a sentence it uses)"
                )
        return self


DEFAULT_TEMPLATE = PromptTemplate()


def _fill(template: str, values: dict[str, str], what: str) -> str:
    try:
        return template.format_map(values)
    except KeyError as exc:
        raise ConfigError(
            f"unknown placeholder {{{exc.args[0]}}} in the {what} template; known: "
            + ", ".join(sorted(values))
        ) from None
    except (ValueError, IndexError) as exc:
        raise ConfigError(
            f"bad {what} template ({exc}); write literal braces as {{{{ }}}}"
        ) from None


def _tidy(text: str) -> str:
    # Masked sentences leave doubled spaces and empty lines behind; remove them.
    lines = [re.sub(r"[ \t]{2,}", " ", ln).strip() for ln in text.split("\n")]
    return "\n".join(ln for ln in lines if ln)


def normalize_mask(mask: Iterable[str] | Sequence[bool] | None) -> frozenset[str]:
    """Sentence names to drop, from names (``{"S4"}``) or five keep-flags (``(1, 1, 1, 0, 1)``)."""
    if mask is None:
        return frozenset()
    items = list(mask)
    if items and all(isinstance(v, (bool, int)) and not isinstance(v, str) for v in items):
        if len(items) != len(SENTENCES):
            raise ConfigError(
                f"a keep-mask needs {len(SENTENCES)} flags (S1..S5), got {len(items)}"
            )
        return frozenset(n for n, keep in zip(SENTENCES, items) if not keep)
    names = frozenset(str(v).upper() for v in items)
    bad = names - set(SENTENCES)
    if bad:
        raise ConfigError(f"unknown sentence names {sorted(bad)} in the mask; use {SENTENCES}")
    return names


@dataclass(frozen=True)
class PromptConfig:
    """Prompt knobs (the paper's values are the defaults, ``n_ht`` aside, which it tunes).

    Attributes
    ----------
    n_ht : int
        History records shown.
    x_min : float
        Lower bound of X for the integer encoding.
    drop : frozenset of str
        Sentences to leave out (see :func:`normalize_mask`).
    action_set : {"all", "shape-changing"}
        Which actions S5 (and constrained decoding) offers (:data:`jswim.actions.ACTION_SETS`).
    template : PromptTemplate
        The text.
    system : str, optional
        A system message (the authors' code sends a single space, :data:`PAPER_SYSTEM`).
    summary : bool
        Add the observed-progress sentence (:func:`jswim.agents.memory.render_summary`); off in the paper.
    shuffle : bool
        S5 lists the options in an order that changes per step (set by the caller through
        ``options``); in the cache order, moves S5 behind the history.
    order : {"paper", "cache"}
        Sentence order when the template keeps the default layout: the paper's S1..S5 (history
        third), or every fixed sentence first for prefix caching (:data:`ORDERS`).
    """

    n_ht: int = 3
    x_min: float = -2.5
    drop: frozenset[str] = frozenset()
    action_set: str = "all"
    template: PromptTemplate = DEFAULT_TEMPLATE
    system: str | None = None
    summary: bool = False
    shuffle: bool = False
    order: str = "paper"

    def __post_init__(self) -> None:
        object.__setattr__(self, "drop", normalize_mask(self.drop))
        if self.order not in ORDERS:
            raise ConfigError(f"order must be one of {', '.join(ORDERS)}, got {self.order!r}")
        check_size("n_ht", self.n_ht)
        check_action_set(self.action_set)

    @property
    def layout(self) -> str:
        """The layout used: the template's; with ``order="cache"`` and the default layout,
        :data:`CACHE_LAYOUT`, or :data:`CACHE_LAYOUT_LATE` when S5 or the summary change from
        step to step."""
        layout = self.template.layout
        if self.order == "cache" and layout == PAPER_LAYOUT:
            layout = CACHE_LAYOUT
        if layout == CACHE_LAYOUT and (self.action_set != "all" or self.shuffle or self.summary):
            return CACHE_LAYOUT_LATE
        return layout


def _dof_ranges(sw: SwimmerText) -> str:
    d = sw.dof_decimals
    spans = [sw.bounds(k) for k in range(1, sw.n_dof + 1)]
    text = [f"[{format_dof(lo, d)}, {format_dof(hi, d)}]" for lo, hi in spans]
    if len(set(text)) == 1:
        verb = "each stay in" if sw.n_dof > 1 else "stays in"
        return f"{_join_prose(sw.names)} {verb} {text[0]}"
    return _join_prose([f"{n} stays in {t}" for n, t in zip(sw.names, text)])


def render_record(rec: HistoryRecord, sw: SwimmerText, cfg: PromptConfig) -> str:
    """One history line."""
    return _fill(cfg.template.record, _record_values(rec, sw, cfg), "record")


def _record_values(rec: HistoryRecord, sw: SwimmerText, cfg: PromptConfig) -> dict[str, str]:
    """The placeholders of a record line (one place: rendering and :meth:`PromptTemplate.check`)."""
    d = sw.dof_decimals
    return {
        "step": str(rec.step),
        "dofs_before": ", ".join(format_dof(v, d) for v in rec.dofs_before),
        "dofs_after": ", ".join(format_dof(v, d) for v in rec.dofs_after),
        "action": rec.action.text(),
        "x_before": str(encode_position(rec.x_before, cfg.x_min)),
        "x_after": str(encode_position(rec.x_after, cfg.x_min)),
        "stuck": "yes" if rec.stuck or abs(rec.dx) < STUCK_DX else "no",
        **_scene_record_values(rec, cfg),
    }


def encode_height(h: float) -> int:
    """A height above the wall as the prompt shows it: thousandths of ``a``, truncated, as X is
    (:func:`encode_position` with ``X_min = 0``: heights are positive)."""
    return encode_position(h, 0.0)


def _scene_record_values(rec: HistoryRecord, cfg: PromptConfig) -> dict[str, str]:
    """A record's scene placeholders (empty where the record has no scene): ``x1_before`` ..
    ``x2_after`` (encoded as X), ``h1_before`` .. ``h2_after`` (:func:`encode_height`),
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


def scene_template(view: SceneView, base: PromptTemplate | None = None) -> PromptTemplate:
    """The default template for a scene: S3's legend and the record line gain what
    :class:`SceneView` says each record shows. A template other than the default (a
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
#: between this one's steps, and what ``other X`` is; with a wall, :data:`WALL_SENTENCE` follows.
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
        _join_prose(
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


def render_prompt(
    sw: SwimmerText,
    cfg: PromptConfig,
    direction: int,
    records: Sequence[HistoryRecord],
    dof_values: Sequence[float],
    x: float = 0.0,
    *,
    options: Sequence[Action] | None = None,
    summary: str = "",
) -> str:
    """The prompt text for the next decision.

    Parameters
    ----------
    sw : SwimmerText
        The swimmer.
    cfg : PromptConfig
        Knobs and template.
    direction : {+1, -1}
        Target direction.
    records : sequence of HistoryRecord
        Records since the last clear; the last ``cfg.n_ht`` are shown.
    dof_values : sequence of float
        Current DOF values (for the allowed set and ``{current}``).
    x : float
        Current X (for ``{current}``).
    options : sequence of Action, optional
        The allowed actions in the order S5 lists them (the shuffle variant reorders them);
        default :func:`allowed_actions` in (dof, roc) order.
    summary : str
        The summary sentence (:func:`jswim.agents.memory.render_summary`), or empty.

    """
    check_direction(direction)
    shown = list(records[-cfg.n_ht :]) if cfg.n_ht > 0 else []
    allowed = (
        list(options) if options is not None else allowed_actions(sw, cfg.action_set, dof_values)
    )
    values = _prompt_values(sw, cfg, direction, shown, allowed, dof_values, x, summary)
    for name in SENTENCES:
        text = "" if name in cfg.drop else _fill(cfg.template.sentence(name), values, name)
        if text and sw.roc_levels > 1 and name in _ROC_SENTENCES:
            text += " " + _ROC_SENTENCES[name].format_map(values)
        if text and name == "S2" and sw.scene is not None:
            text += " " + scene_sentence(sw.scene)
        values[name] = text
    layout = cfg.layout
    if summary and "summary" not in _fields(layout):
        # No slot in the layout: the sentence goes right before the history (or last without it).
        if values["S3"]:
            values["S3"] = summary + "\n" + values["S3"]
        else:
            layout = layout + "\n{summary}"
    return _tidy(_fill(layout, values, "layout"))


#: The sentence each of S2 and S5 gains when ``roc_levels > 1`` (appended, so templates stay as given).
_ROC_SENTENCES = {"S2": ROC_SCALE_SENTENCE, "S5": ROC_FORMAT_SENTENCE}


def _prompt_values(
    sw: SwimmerText,
    cfg: PromptConfig,
    direction: int,
    shown: Sequence[HistoryRecord],
    allowed: Sequence[Action],
    dof_values: Sequence[float],
    x: float,
    summary: str,
) -> dict[str, str]:
    """The placeholders of layouts and sentences (one place: rendering and :meth:`PromptTemplate.check`)."""
    d = sw.dof_decimals
    return {
        "direction": "+x" if direction == 1 else "-x",
        "direction_words": "positive x" if direction == 1 else "negative x",
        "dofs": _join_prose(sw.names),
        "dof_names": ", ".join(sw.names),
        "n_dof": str(sw.n_dof),
        "dof_ranges": _dof_ranges(sw),
        "dof_choices": _join_prose([str(k) for k in range(1, sw.n_dof + 1)], "or"),
        "roc_choices": _join_prose([str(r) for r in sw.rocs], "or"),
        "allowed": ", ".join(a.text() for a in allowed),
        "choices": _choices(sw, allowed),
        "n_ht": str(cfg.n_ht),
        "n_records": str(len(shown)),
        "history": "\n".join(render_record(r, sw, cfg) for r in shown) or "none yet",
        "current": f"({', '.join(sw.names)}) = ({', '.join(format_dof(v, d) for v in dof_values)}),"
        f" X = {encode_position(x, cfg.x_min)}",
        "summary": summary,
        "roc_levels": str(sw.roc_levels),
        "except_zero": "" if 0 in sw.rocs else ", not 0",
    }


def _placeholders() -> tuple[tuple[str, ...], tuple[str, ...]]:
    """Names a layout or sentence may use (the variables and S1..S5), and a record line's."""
    sw = SwimmerText(2, -1.0, 1.0, 3, (-1, 0, 1))  # any swimmer: only the names count
    cfg = PromptConfig()
    rec = HistoryRecord(
        1, (1.0, 1.0), (-1.0, 1.0), Action(1, -1), 0.0, 0.0
    )  # scene names are always listed
    prompt = (
        tuple(_prompt_values(sw, cfg, 1, [], allowed_actions(sw), (1.0, 1.0), 0.0, "")) + SENTENCES
    )
    return prompt, tuple(_record_values(rec, sw, cfg))


def _choices(sw: SwimmerText, allowed: Sequence[Action]) -> str:
    """S5's choices: DOF and ROC choices separately when every action is offered in (DOF, ROC)
    order (the authors' code), else the allowed replies listed."""
    if list(allowed) == allowed_actions(sw, "all"):
        dofs = _join_prose([str(k) for k in range(1, sw.n_dof + 1)], "or")
        rocs = _join_prose([str(r) for r in sw.rocs], "or")
        return f"the changed DOF {dofs} and the ROC {rocs}"
    return "one of " + ", ".join(a.text() for a in allowed)


def _fields(template: str) -> set[str]:
    """Placeholder names used by a format string (escaped braces are not placeholders)."""
    try:
        return {name for _, name, _, _ in string.Formatter().parse(template) if name}
    except ValueError:
        return set()  # malformed: _fill reports it


def build_messages(prompt: str, system: str | None = None) -> list[dict[str, str]]:
    """Chat messages: one user message, preceded by a system message only when given."""
    msgs = [{"role": "system", "content": system}] if system else []
    msgs.append({"role": "user", "content": prompt})
    return msgs
