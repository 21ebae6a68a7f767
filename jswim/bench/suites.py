"""Bench suites: named lists of study parts, each a study and its options, with a seed.

A suite's definition (parts, options, seed, sizes) is recorded in the bench folder
(``bench.json``), so two labs running ``core`` get comparable rows; a folder made with another
definition is refused, not mixed. The suites ``core`` and ``paper`` (their parts, sizes and
cost) are described in docs/bench.md (*Suites*); ``navigate`` runs the navigation study
(docs/navigation.md), ``navigate-flow`` the same in a background flow (``--flow uniform``).
"""

from __future__ import annotations

import functools
import types
from dataclasses import dataclass, field
from typing import Any
from collections.abc import Mapping

from jswim.errors import ConfigError
from jswim.studies.flags import FLAGS


@functools.cache
def part_options() -> Mapping[str, str]:
    """The options a suite part may set (a models file's ``options`` keys) -> the flag each becomes.

    Read from the options' one definition: each run option a part may set
    (`jswim.studies.flags.Flag.part`) under its argparse dest (``noise`` -> ``--noise``), and
    every study's own options (`jswim.studies.study.Study.flags`) under their field.
    """
    from jswim.studies.study import get, names  # lazy: the study kinds load JAX

    out = {f.dest: f.names[0] for f in FLAGS if f.part}
    for study in map(get, names()):
        out.update(zip(study.own_options, (flag for flag, _ in study.flags)))
    return types.MappingProxyType(out)  # cached: read-only


#: Sizes a bench command may override for every part (``--runs``, ``--q-runs``, ``--steps``);
#: recorded in the definition (rows then say they are not the suite's own sizes).
SIZE_OPTIONS = ("runs", "q_runs", "steps")


@dataclass(frozen=True)
class Part:
    """One study of a suite: ``study`` (a ``jswim study`` name, or ``swim``) and its options."""

    name: str
    study: str
    options: tuple[tuple[str, Any], ...] = ()

    def args(
        self, seed: int, sizes: Mapping[str, Any] | None = None, samples: int | None = None
    ) -> list[str]:
        """The command line of this part (``jswim study NAME ...``), options then size overrides
        and the bench's ``--samples`` (which replaces a part's own)."""
        opts = dict(self.options)
        opts.setdefault("seed", seed)
        opts.update({k: v for k, v in (sizes or {}).items() if v is not None})
        if samples is not None:
            opts["samples"] = samples
        from jswim.studies.study import get  # lazy: the study kinds load JAX

        command = get(self.study).command  # "study" (jswim study NAME) or its own ("swim")
        out = ["study", self.study] if command == "study" else [command]
        for key, value in opts.items():
            flag = part_options()[key]
            if isinstance(value, (list, tuple)):
                value = ",".join(str(v) for v in value)
            out += [flag, str(value)]
        return out

    def describe(self) -> dict[str, Any]:
        return {"name": self.name, "study": self.study, "options": dict(self.options)}


@dataclass(frozen=True)
class Suite:
    """A named list of parts and the seed of every study in it."""

    name: str
    parts: tuple[Part, ...]
    seed: int = 0
    about: str = ""
    sizes: tuple[tuple[str, Any], ...] = field(default=())  # overrides of SIZE_OPTIONS
    # ``jswim bench --samples N``: independent samples of every LLM run. Not part of the compared
    # definition (recorded beside it in bench.json): like --zetas for a study, it grows a folder.
    samples: int | None = None

    def describe(self) -> dict[str, Any]:
        """The definition recorded in ``bench.json`` (compared when a bench folder is resumed;
        ``samples`` is recorded beside it, not compared)."""
        return {
            "name": self.name,
            "seed": self.seed,
            "parts": [p.describe() for p in self.parts],
            "size_overrides": dict(self.sizes),
        }


CORE = Suite(
    "core",
    (
        Part("curves", "curves", (("direction", "both"), ("runs", 10), ("init", "paper"))),
        Part("noise", "noise", (("zetas", (1.0,)), ("runs", 10), ("init", "paper"))),
    ),
    seed=0,
    about="the paper's headline results: p and steps to learn, both swimmers and directions; zeta = 1",
)

PAPER = Suite(
    "paper",
    (
        Part("curves", "curves", (("direction", "both"),)),
        Part("history", "history", ()),
        Part("noise", "noise", ()),
        Part("ablation", "ablation", ()),
        Part("inits", "inits", ()),
    ),
    seed=0,
    about="every figure of the paper, each study at its own defaults",
)

NAVIGATE = Suite(
    "navigate",
    (Part("navigate", "navigate", (("runs", 1),)),),
    seed=0,
    about="navigation (an extension): targets 3 a away at 0, 90 and 180 degrees, a path and a moving "
    "target; success = the target reached within its budget, steps to it",
)

NAVIGATE_FLOW = Suite(
    "navigate-flow",
    (
        Part(
            "navigate-flow",
            "navigate",
            # the speeds written out (the study's defaults today): the recorded definition then
            # stays this suite's if the study's defaults move
            (("runs", 1), ("flow", "uniform"), ("flows", (0.0, 0.5, 0.9))),
        ),
    ),
    seed=0,
    about="navigation in a uniform stream across the start heading at 0, 0.5 and 0.9 of the "
    "swimming speed: navigate's targets at each; success = the target reached within its budget, "
    "steps to it; Zermelo's time-optimal steerer as the yardstick",
)

SUITES = {"core": CORE, "paper": PAPER, "navigate": NAVIGATE, "navigate-flow": NAVIGATE_FLOW}


def check_name(name: str, what: str) -> str:
    import re

    if not re.fullmatch(r"[A-Za-z0-9][A-Za-z0-9._-]{0,63}", str(name)):
        raise ConfigError(
            f"{what} {name!r}: use letters, digits, '.', '_' or '-' (it names a folder)"
        )
    return str(name)


def _check_part_options(study: str, opts: Mapping[str, Any], where: str) -> None:
    """Refuse, when the models file is read, an option the part's study would refuse at run time
    (every model's process would fail on it)."""
    from jswim.env.flows import FLOWS  # lazy: JAX
    from jswim.studies.specs import ignored_options, own_options, owners  # lazy: kinds load JAX
    from jswim.studies.study import get  # lazy: as above

    spec = get(study)
    if spec.command != "study":
        # a grid axis: only ``jswim study`` takes it
        axes = {f.dest: f.names[0] for f in FLAGS if f.study_only}
        axis = next((k for k in opts if k in axes), None)
        if axis is not None:
            raise ConfigError(
                f"{where}: jswim {spec.command} takes no {axes[axis]} (a study's grid "
                'axis); use a study, e.g. study = "curves"'
            )
    only = next((k for k in opts if k in own_options() and k not in spec.own_options), None)
    if only is not None:
        who = " and ".join(f"the {n} study" for n in owners(only))
        raise ConfigError(
            f"{where}: the {study} study has no use for {only} (only {who} reads it); leave it out"
        )
    if "flow" in opts and (not isinstance(opts["flow"], str) or opts["flow"] not in FLOWS):
        raise ConfigError(f"{where}: flow must be one of {', '.join(FLOWS)}, got {opts['flow']!r}")
    elif "flows" in opts and not opts.get("flow"):
        raise ConfigError(
            f'{where}: flows sets the speeds of a flow: give its kind too (flow = "uniform")'
        )
    fields = {f.dest: f.field for f in FLAGS if f.part and f.field}  # a key -> the field it sets
    for name, why in ignored_options(study, [fields.get(k, k) for k in opts]).items():
        option = next(k for k in opts if fields.get(k, k) == name)
        raise ConfigError(
            f"{where}: the {study} study has no use for {option} ({why}); leave it out"
        )


def user_suite(name: str, table: Any, where: str) -> Suite:
    """A suite from a models file's ``[suites.NAME]`` table.

    Either one study (``study = "history"`` and an ``options`` table) or a list of parts
    (``[[suites.NAME.parts]]`` each with ``name``, ``study``, ``options``); ``seed`` optional.

    Raises
    ------
    ConfigError
        For an unknown study or option (one line, naming the file).
    """
    from jswim.studies.study import names  # lazy: the study kinds load JAX

    studies = names()

    if not isinstance(table, Mapping):
        raise ConfigError(f"{where}: [suites.{name}] must be a table")
    parts_in = table.get("parts")
    if parts_in is None:
        parts_in = [
            {
                "name": table.get("study", name),
                "study": table.get("study"),
                "options": table.get("options", {}),
            }
        ]
    if not isinstance(parts_in, list):
        raise ConfigError(f"{where}: suite {name!r}: parts must be an array of tables")
    parts = []
    for i, p in enumerate(parts_in):
        if (
            not isinstance(p, Mapping)
            or not isinstance(p.get("study"), str)
            or p["study"] not in studies
        ):
            raise ConfigError(
                f"{where}: suite {name!r} part {i + 1}: study must be one of {', '.join(studies)}"
            )
        opts = p.get("options") or {}
        if not isinstance(opts, Mapping):
            raise ConfigError(f"{where}: suite {name!r} part {i + 1}: options must be a table")
        bad = sorted(set(opts) - set(part_options()))
        if bad:
            raise ConfigError(
                f"{where}: suite {name!r}: unknown option {bad[0]!r}; choose from "
                f"{', '.join(sorted(part_options()))}"
            )
        _check_part_options(p["study"], opts, f"{where}: suite {name!r} part {i + 1}")
        parts.append(
            Part(
                check_name(p.get("name") or p["study"], "suite part"),
                p["study"],
                tuple((k, tuple(v) if isinstance(v, list) else v) for k, v in opts.items()),
            )
        )
    if len({p.name for p in parts}) != len(parts):
        raise ConfigError(f"{where}: suite {name!r} has two parts of the same name")
    try:
        seed = int(table.get("seed", 0))
    except (TypeError, ValueError):
        raise ConfigError(f"{where}: suite {name!r}: seed must be an integer") from None
    return Suite(check_name(name, "suite"), tuple(parts), seed, str(table.get("about", "")))
