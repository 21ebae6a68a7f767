"""Sampling made explicit: the neutral values of the knobs each server family has.

"Temperature 0" is not one experiment across servers: each carries its own sampling defaults
(llama-cpp-python's ``repeat_penalty`` 1.1 turned a ``[1, 1]`` into ``[1, 0]``), so ``--sampling
neutral`` sends, per family, the value that turns each knob off (`NEUTRAL`). The families'
defaults, the neutral fields, the presets (``auto``, ``neutral``, ``server``) and why ``auto`` sends
the embedded server the neutral penalties only are tabled in docs/servers.md (*Servers*).
"""

from __future__ import annotations

from jswim.errors import ConfigError

#: The ``--sampling`` presets.
PRESETS = ("auto", "neutral", "server")

_LLAMA = (
    ("repeat_penalty", 1.0),
    ("top_k", 0),
    ("top_p", 1.0),
    ("min_p", 0.0),
    ("presence_penalty", 0.0),
    ("frequency_penalty", 0.0),
)
_OPENAI_FIELDS = (("top_p", 1.0), ("presence_penalty", 0.0), ("frequency_penalty", 0.0))

#: Neutral sampling fields per server family (docs/servers.md).
NEUTRAL: dict[str, tuple[tuple[str, float], ...]] = {
    "llamacpp": _LLAMA,
    "llama-cpp-python": _LLAMA,
    "vllm": (
        ("repetition_penalty", 1.0),
        ("top_k", -1),
        ("top_p", 1.0),
        ("min_p", 0.0),
        ("presence_penalty", 0.0),
        ("frequency_penalty", 0.0),
    ),
    "ollama": _OPENAI_FIELDS,
    "generic": _OPENAI_FIELDS,
    "openai": (),
}

#: Families ``auto`` sends the neutral values to.
AUTO_NEUTRAL = ("llamacpp", "llama-cpp-python", "vllm", "ollama")

#: The penalty fields (what ``auto`` sends to the embedded server).
PENALTIES = ("repeat_penalty", "repetition_penalty", "presence_penalty", "frequency_penalty")


def check_preset(name: str) -> str:
    """``name`` if it is a preset, else [`ConfigError`][jswim.errors.ConfigError]."""
    if name not in PRESETS:
        raise ConfigError(f"--sampling must be one of {', '.join(PRESETS)}, got {name!r}")
    return name


def sampling_fields(
    preset: str, family: str, *, embedded: bool = False
) -> tuple[tuple[str, float], ...]:
    """The sampling fields every request carries under ``preset`` for a server of ``family``.

    Parameters
    ----------
    preset : {"auto", "neutral", "server"}
    family : str
        A family of `NEUTRAL` (unknown families are treated as ``"generic"``).
    embedded : bool
        The embedded server (``auto`` then sends the neutral penalties only).

    Returns
    -------
    tuple of (name, value)
        In a fixed order (they are part of each request, hence of its cache key).
    """
    check_preset(preset)
    neutral = NEUTRAL.get(family, NEUTRAL["generic"])
    if preset == "server":
        return ()
    if preset == "neutral":
        return neutral
    if embedded:
        return tuple((k, v) for k, v in neutral if k in PENALTIES)
    return neutral if family in AUTO_NEUTRAL else ()


def describe(preset: str, family: str, fields: tuple[tuple[str, float], ...]) -> str:
    """One line for the output: what was sent for sampling and why."""
    if not fields:
        return (
            f"sampling: {preset} for a {family} server: no sampling fields sent (the server's own defaults"
            f"{'; OpenAI has no penalties or truncation by default' if family == 'openai' else ''})"
        )
    sent = ", ".join(f"{k}={v:g}" for k, v in fields)
    return f"sampling: {preset} for a {family} server: {sent}"
