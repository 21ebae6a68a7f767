"""The paper's five-sentence prompt, history records, number encoding and reply parsing.

Text only: this package never imports JAX. One concept a module:

- `jswim.prompt.template`: sentence names, layouts, the default text, `PromptTemplate`;
- `jswim.prompt.config`: `PromptConfig` (n_ht, X_min, the sentence mask, the allowed set);
- `jswim.prompt.swimmer_text`: `SwimmerText`, `allowed_actions`, the finer-ROC sentences;
- `jswim.prompt.scene_text`: `SceneView`, S2's scene sentences, `scene_template`;
- `jswim.prompt.nav_text`: `NavView`, a navigation task's S1, S2 sentence and records;
- `jswim.prompt.records`: `HistoryRecord` and its line in S3;
- `jswim.prompt.render`: `render_prompt`, `build_messages`;
- `jswim.prompt.numbers`: `Action`, the integer encoding of X, DOF values in text;
- `jswim.prompt.reply`: `parse_reply`;
- `jswim.prompt.prose`: prose lists and template filling.

The sentences S1..S5, their layouts (paper and cache orders), every template placeholder, the
template file format, the summary sentence, finer ROCs and scenes are described in
docs/api/prompt.md. Every public name is importable from `jswim.prompt`.
"""

from jswim.prompt.config import ORDERS, PAPER_SYSTEM, PromptConfig, normalize_mask
from jswim.prompt.nav_text import NAV_KINDS, NavView, nav_sentence, nav_template, target_phrase
from jswim.prompt.numbers import Action, encode_position, format_dof
from jswim.prompt.records import STUCK_DX, HistoryRecord, encode_height, render_record
from jswim.prompt.render import build_messages, render_prompt
from jswim.prompt.reply import parse_reply
from jswim.prompt.scene_text import (
    OWN_PAIR_SENTENCE,
    OWN_SCHOOL_SENTENCE,
    PAIR_SENTENCE,
    SCHOOL_SENTENCE,
    SEVERAL_WALL_SENTENCE,
    WALL_SENTENCE,
    SceneView,
    scene_sentence,
    scene_template,
)
from jswim.prompt.swimmer_text import (
    ROC_FORMAT_SENTENCE,
    ROC_SCALE_SENTENCE,
    SwimmerText,
    allowed_actions,
)
from jswim.prompt.template import (
    CACHE_LAYOUT,
    CACHE_LAYOUT_LATE,
    DEFAULT_RECORD,
    DEFAULT_SENTENCES,
    DEFAULT_TEMPLATE,
    MAX_TEMPLATE_BYTES,
    PAPER_LAYOUT,
    PROMPT_FIELDS,
    RECORD_FIELDS,
    SENTENCES,
    PromptTemplate,
)

__all__ = [
    "CACHE_LAYOUT",
    "CACHE_LAYOUT_LATE",
    "DEFAULT_RECORD",
    "DEFAULT_SENTENCES",
    "DEFAULT_TEMPLATE",
    "MAX_TEMPLATE_BYTES",
    "NAV_KINDS",
    "ORDERS",
    "OWN_PAIR_SENTENCE",
    "OWN_SCHOOL_SENTENCE",
    "PAIR_SENTENCE",
    "PAPER_LAYOUT",
    "PAPER_SYSTEM",
    "PROMPT_FIELDS",
    "RECORD_FIELDS",
    "ROC_FORMAT_SENTENCE",
    "ROC_SCALE_SENTENCE",
    "SCHOOL_SENTENCE",
    "SENTENCES",
    "SEVERAL_WALL_SENTENCE",
    "STUCK_DX",
    "WALL_SENTENCE",
    "Action",
    "HistoryRecord",
    "NavView",
    "PromptConfig",
    "PromptTemplate",
    "SceneView",
    "SwimmerText",
    "allowed_actions",
    "build_messages",
    "encode_height",
    "encode_position",
    "format_dof",
    "nav_sentence",
    "nav_template",
    "normalize_mask",
    "parse_reply",
    "render_prompt",
    "render_record",
    "scene_sentence",
    "scene_template",
    "target_phrase",
]
