"""The prompt for the next decision ([`render_prompt`][jswim.prompt.render_prompt]) and the chat
messages that carry it ([`build_messages`][jswim.prompt.build_messages]).
"""

from __future__ import annotations

from collections.abc import Sequence

from jswim.errors import ConfigError, check_direction
from jswim.prompt.config import PromptConfig
from jswim.prompt.nav_text import nav_sentence, target_phrase
from jswim.prompt.numbers import Action, encode_position, format_dof
from jswim.prompt.prose import fill, join_prose, placeholder_names, tidy_lines
from jswim.prompt.records import HistoryRecord, render_record
from jswim.prompt.scene_text import scene_sentence
from jswim.prompt.swimmer_text import (
    ROC_FORMAT_SENTENCE,
    ROC_SCALE_SENTENCE,
    SwimmerText,
    allowed_actions,
)
from jswim.prompt.template import SENTENCES


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
    target: tuple[float, float] | None = None,
    waypoint: int = 1,
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
        default [`allowed_actions`][jswim.prompt.allowed_actions] in (dof, roc) order.
    summary : str
        The summary sentence ([`jswim.agents.memory.render_summary`][jswim.agents.memory.render_summary]), or empty.
    target : tuple of float, optional
        A navigation task's target now, ``(x, y)`` in link lengths (``sw.nav`` set): S1 names
        it, encoded as X is.
    waypoint : int
        Which waypoint of a path the target is (1-based).

    Raises
    ------
    ConfigError
        A navigation task (``sw.nav``) without a ``target``.
    """
    check_direction(direction)
    shown = list(records[-cfg.n_ht :]) if cfg.n_ht > 0 else []
    allowed = (
        list(options) if options is not None else allowed_actions(sw, cfg.action_set, dof_values)
    )
    values = _prompt_values(
        sw, cfg, direction, shown, allowed, dof_values, x, summary, target=target, waypoint=waypoint
    )
    for name in SENTENCES:
        text = "" if name in cfg.drop else fill(cfg.template.sentence(name), values, name)
        if text and sw.roc_levels > 1 and name in _ROC_SENTENCES:
            text += " " + _ROC_SENTENCES[name].format_map(values)
        if text and name == "S2" and sw.scene is not None:
            text += " " + scene_sentence(sw.scene)
        if text and name == "S2" and sw.nav is not None:
            text += " " + nav_sentence(sw.nav)
        values[name] = text
    layout = cfg.layout
    if summary and "summary" not in placeholder_names(layout):
        # No slot in the layout: the sentence goes right before the history (or last without it).
        if values["S3"]:
            values["S3"] = summary + "\n" + values["S3"]
        else:
            layout = layout + "\n{summary}"
    return tidy_lines(fill(layout, values, "layout"))


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
    *,
    target: tuple[float, float] | None = None,
    waypoint: int = 1,
) -> dict[str, str]:
    """The placeholders of layouts and sentences (one place: rendering and [`PromptTemplate.check`][jswim.prompt.PromptTemplate.check])."""
    d = sw.dof_decimals
    return {
        "direction": "+x" if direction == 1 else "-x",
        "direction_words": "positive x" if direction == 1 else "negative x",
        "dofs": join_prose(sw.names),
        "dof_names": ", ".join(sw.names),
        "n_dof": str(sw.n_dof),
        "dof_ranges": _dof_ranges(sw),
        "dof_choices": join_prose([str(k) for k in range(1, sw.n_dof + 1)], "or"),
        "roc_choices": join_prose([str(r) for r in sw.rocs], "or"),
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
        **_nav_values(sw, cfg, target, waypoint),
    }


def _nav_values(
    sw: SwimmerText, cfg: PromptConfig, target: tuple[float, float] | None, waypoint: int
) -> dict[str, str]:
    """A navigation task's placeholders: ``target`` (S1's phrase), ``target_x``, ``target_y``
    (encoded as X) and ``waypoint``; empty strings for the paper's task."""
    if sw.nav is None:
        return dict.fromkeys(("target", "target_x", "target_y", "waypoint"), "")
    if target is None:
        raise ConfigError("a navigation prompt needs the target's position")
    return {
        "target": target_phrase(sw.nav, target, cfg.x_min, waypoint),
        "target_x": str(encode_position(target[0], cfg.x_min)),
        "target_y": str(encode_position(target[1], cfg.x_min)),
        "waypoint": str(waypoint),
    }


def _dof_ranges(sw: SwimmerText) -> str:
    d = sw.dof_decimals
    spans = [sw.bounds(k) for k in range(1, sw.n_dof + 1)]
    text = [f"[{format_dof(lo, d)}, {format_dof(hi, d)}]" for lo, hi in spans]
    if len(set(text)) == 1:
        verb = "each stay in" if sw.n_dof > 1 else "stays in"
        return f"{join_prose(sw.names)} {verb} {text[0]}"
    return join_prose([f"{n} stays in {t}" for n, t in zip(sw.names, text)])


def _choices(sw: SwimmerText, allowed: Sequence[Action]) -> str:
    """S5's choices: DOF and ROC choices separately when every action is offered in (DOF, ROC)
    order (the authors' code), else the allowed replies listed."""
    if list(allowed) == allowed_actions(sw, "all"):
        dofs = join_prose([str(k) for k in range(1, sw.n_dof + 1)], "or")
        rocs = join_prose([str(r) for r in sw.rocs], "or")
        return f"the changed DOF {dofs} and the ROC {rocs}"
    return "one of " + ", ".join(a.text() for a in allowed)


def build_messages(prompt: str, system: str | None = None) -> list[dict[str, str]]:
    """Chat messages: one user message, preceded by a system message only when given."""
    msgs = [{"role": "system", "content": system}] if system else []
    msgs.append({"role": "user", "content": prompt})
    return msgs
