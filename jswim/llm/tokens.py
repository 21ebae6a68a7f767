"""Token counts estimated from text, without a tokenizer or a server.

Used for the dry run's cost estimate, for budget reservations and for tokens-per-minute pacing.
The estimate counts the pieces a byte-pair tokenizer first cuts text into, scaled by
`CALIBRATION`; docs/paid-apis.md gives the rule and its measured accuracy.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence

#: Scale from counted pieces to tokens (docs/paid-apis.md).
CALIBRATION = 1.06

#: Chat-format overhead: tokens per message (role, separators) and to prime the reply.
PER_MESSAGE = 4
PER_REQUEST = 3

_PIECES = re.compile(r" ?[^\W\d_]+|\d{1,3}| ?[^\s\w]+|_+|\s+")


def estimate_tokens(text: str) -> int:
    """Estimated tokens of ``text`` (rule and accuracy: docs/paid-apis.md)."""
    n = 0
    for m in _PIECES.finditer(text):
        s = m.group()
        last = s[-1]
        if last.isalpha():
            n += 1 + (len(s.strip()) - 1) // 9
        elif last.isdigit():
            n += 1
        elif s.isspace():
            n += 1 if ("\n" in s or len(s) > 1) else 0
        else:
            n += max(1, len(s.strip()) // 2)
    return round(n * CALIBRATION)


def estimate_prompt_tokens(messages: Sequence[Mapping[str, object]]) -> int:
    """Estimated ``prompt_tokens`` a chat-completions server reports for ``messages``."""
    return PER_REQUEST + sum(
        PER_MESSAGE + estimate_tokens(str(m.get("content") or "")) for m in messages
    )
