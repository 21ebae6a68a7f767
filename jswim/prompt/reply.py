"""A reply read back as an `Action`: [`parse_reply`][jswim.prompt.parse_reply] (the paper's
``[DOF, ROC]`` and the forms real models write around it)."""

from __future__ import annotations

import re
import unicodedata
from collections.abc import Sequence

from jswim.prompt.numbers import Action


_MINUS = str.maketrans({"\u2212": "-", "\u2013": "-", "\u2014": "-", "\uff0d": "-"})
_INT = r"([+-]?\s*[0-9]+)"  # ASCII digits only (see parse_reply)
_Q = r"[\"']?"  # a JSON key's closing quote
_PATTERNS = (
    # [1, -1]  (2,1)  [D1, -1]  {1, 1}
    re.compile(
        r"[\[\(\{]\s*(?:D\s*)?" + _INT + r"\s*[,;]\s*(?:ROC\s*[:=]?\s*)?" + _INT + r"\s*[\]\)\}]",
        re.I,
    ),
    # DOF 1, ROC -1 / DOF=2 and ROC=+1 / dof: 1 roc: 0 / {"dof": 2, "roc": -1}
    # (a ROC written as a decimal or a fraction, "ROC 0.5" or "ROC 1/2", is no integer: no match)
    re.compile(
        r"\bDOF"
        + _Q
        + r"\s*[:=]?\s*(?:D\s*)?"
        + _INT
        + r"\W{0,4}(?:and\s+)?ROC"
        + _Q
        + r"\s*[:=]?\s*"
        + _INT
        + r"(?!\d|[./]\d)",
        re.I,
    ),
)
# Two bare integers, "2, -1": only as the whole reply or right after an answer marker.
_BARE = re.compile(r"(?:D\s*)?([+-]?[0-9]+)\s*(?:,|;|\s)\s*([+-]?[0-9]+)(?![0-9]|\.[0-9])")
# Words that introduce the answer; the final answer is the first candidate after the last one.
_MARKER = re.compile(
    r"\b(?:final\s+answer|answer|next\s+(?:action|move)|my\s+(?:action|move|choice)|action\s*"
    + _Q
    + r"\s*(?:[:=]|is\b)"
    r"|(?:i\s+(?:will|'ll|would|)\s*)?(?:choose|pick|select|go\s+with|take)|so|therefore|thus|hence)\b",
    re.I,
)
# A candidate right after one of these (in the same clause) is one the reply rejects.
_NEGATION = re.compile(
    r"(?:\b(?:not|never|avoid(?:ing)?|instead\s+of|rather\s+than|except|other\s+than|besides|without)|n't)\b"
    r"(?P<tail>[^\[\(\{\n.;:,]{0,24})$",
    re.I,
)
# ...unless a new clause starts in between ("[1, 1] didn't work, so [2, -1]").
_NEW_CLAUSE = re.compile(r"\b(?:so|but|then|therefore|thus|hence|use|try|choose|pick|take)\b", re.I)
_FILLER = re.compile(
    r"^[\s`'\"*>_]*(?:json|text)?[\s`'\"*:>_]*$", re.I
)  # fences, quotes, bold marks


def parse_reply(text: str, allowed: Sequence[Action] | None = None) -> Action | None:
    """The final answer of a reply, or ``None`` when it names no valid action unambiguously.

    ``text`` is the answer part of a reply (reasoning already split off by the client; see
    `jswim.llm.server_response`). Accepted forms: ``[1, -1]``, ``[1,-1]``, ``(2, 1)``, ``[D1, -1]``,
    ``DOF 1, ROC -1``, ``{"dof": 1, "roc": -1}``, and two bare integers ``1, -1`` when they are
    the whole reply or follow an answer word; code fences, JSON wrappers
    (``{"action": "[1, -1]"}``) and prose may surround them. Which candidate is the answer:

    1. candidates the reply rejects (``not [1, 1]``, ``instead of [1, 1]``, ``avoid [1, 1]``) and
       candidates outside ``allowed`` are skipped;
    2. after an answer word (``answer``, ``final answer``, ``next move``, ``I choose``, ``so``,
       ``therefore``...), the first candidate after the last such word that has one;
    3. otherwise a single distinct candidate; or the candidate the reply opens with
       (``[2, -1] because ...``); or the one it ends with (``... so we go [2, -1].``);
    4. otherwise (several, none in an answer position) ``None``: the caller asks again rather
       than guess.

    Characters: the reply is read after Unicode NFKC normalisation, so fullwidth and other
    compatibility forms of ASCII (``［２，－１］`` from an East Asian input mode) read as the ASCII
    they stand for, and Unicode minus signs and dashes as ``-``. Digits of other scripts
    (Arabic-Indic ``٢``, Devanagari ``२``, ...) are not read: the prompt asks for the ASCII
    format, and a reply in them names no action (the step asks again, as for any unreadable
    reply).

    Parameters
    ----------
    text : str
        The model's answer.
    allowed : sequence of Action, optional
        Valid actions; ``None`` accepts any pair.
    """
    if not text or not text.strip():
        return None
    text = unicodedata.normalize("NFKC", text).translate(_MINUS)
    ok = set(allowed) if allowed is not None else None
    markers = [m.end() for m in _MARKER.finditer(text)]
    found: dict[int, tuple[int, Action]] = {}  # start -> (end, action)
    for pat in _PATTERNS:
        for m in pat.finditer(text):
            dof, roc = (int(g.replace(" ", "")) for g in m.groups())
            found.setdefault(m.start(), (m.end(), Action(dof, roc)))
    for at in [0, *markers]:  # bare pairs: the whole reply, or right after an answer word
        m = _BARE.match(text, at + len(text[at:]) - len(text[at:].lstrip(" \t\n:=*`'\"")))
        if (
            m
            and (at > 0 or _FILLER.match(text[m.end() :].rstrip(".!")))
            and not any(s <= m.start() < e for s, (e, _) in found.items())
        ):
            found.setdefault(m.start(), (m.end(), Action(int(m.group(1)), int(m.group(2)))))
    cands = [
        (start, end, act)
        for start, (end, act) in sorted(found.items())
        if (ok is None or act in ok) and not _rejected(text[max(0, start - 40) : start])
    ]
    if not cands:
        return None
    for at in reversed(markers):
        after = [c for c in cands if c[0] >= at]
        if after:
            return after[0][2]
    if len({c[2] for c in cands}) == 1:
        return cands[0][2]
    first, last = cands[0], cands[-1]
    if _FILLER.match(text[: first[0]]):
        return first[2]
    if _FILLER.match(text[last[1] :].rstrip(".!")):
        return last[2]
    return None


def _rejected(before: str) -> bool:
    """Whether the text right before a candidate rejects it (``not``, ``avoid``, ``instead of``)."""
    m = _NEGATION.search(before)
    return bool(m) and not _NEW_CLAUSE.search(m.group("tail"))
