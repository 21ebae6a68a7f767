"""The prompt's text as data: sentence names, layouts, the default sentences and record line, and
[`PromptTemplate`][jswim.prompt.PromptTemplate] (read from text or a file, and checked).

Placeholders and the template file format: docs/api/prompt.md.
"""

from __future__ import annotations

import re
import string
from dataclasses import dataclass, replace
from pathlib import Path

from jswim.errors import ConfigError
from jswim.prompt.prose import placeholder_names


#: Sentence names, in the paper's order.
SENTENCES = ("S1", "S2", "S3", "S4", "S5")


#: The paper's and the authors' order S1..S5, the history third and the answer instruction last (default).
PAPER_LAYOUT = "{S1} {S2}\n{S3}\n{S4} {S5}"


#: Every fixed sentence before the changing history: the prefix-cache friendly order (``order="cache"``).
CACHE_LAYOUT = "{S1} {S2} {S4} {S5}\n{S3}"


#: What the cache order becomes when S5 or the summary change at every step: per-step text last.
CACHE_LAYOUT_LATE = "{S1} {S2} {S4}\n{S3}\n{summary}\n{S5}"


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


#: Placeholders a layout or sentence may use: the prompt's values (filled by
#: [`render_prompt`][jswim.prompt.render_prompt]), then the sentences S1..S5.
PROMPT_FIELDS = (
    "direction",
    "direction_words",
    "dofs",
    "dof_names",
    "n_dof",
    "dof_ranges",
    "dof_choices",
    "roc_choices",
    "allowed",
    "choices",
    "n_ht",
    "n_records",
    "history",
    "current",
    "summary",
    "roc_levels",
    "except_zero",
    "target",
    "target_x",
    "target_y",
    "waypoint",
    *SENTENCES,
)

#: Placeholders a record line may use ([`render_record`][jswim.prompt.render_record]): the
#: paper's, then each swimmer's position, height and tilt in a scene (names up to swimmer 2 are
#: always known), swimmer 1's height and tilt under their short names, and a navigation task's Y
#: (encoded as X) and heading (rad), and in a flow the local flow before the step (thousandths
#: per step).
RECORD_FIELDS = (
    "step",
    "dofs_before",
    "dofs_after",
    "action",
    "x_before",
    "x_after",
    "stuck",
    *(f"{n}{k}_{when}" for k in (1, 2) for when in ("before", "after") for n in ("x", "h", "tilt")),
    *(f"{n}_{when}" for when in ("before", "after") for n in ("h", "tilt")),
    *(f"{n}_{when}" for n in ("y", "heading") for when in ("before", "after")),
    "flow_x",
    "flow_y",
)


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
        `MAX_TEMPLATE_BYTES` (every request carries the whole prompt)."""
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
        [`ConfigError`][jswim.errors.ConfigError] naming what is wrong. Checked when a file is read, so a bad file
        fails before any run.
        """
        prompt_names, record_names = PROMPT_FIELDS, RECORD_FIELDS
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
        shown = placeholder_names(self.layout)
        for name in SENTENCES:
            if name in shown:
                shown |= placeholder_names(self.sentence(name))
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
