"""The models of a bench: a TOML models file or repeated ``--model`` options.

A models file has one ``[[models]]`` entry per row (``name``, ``base_url``, ``model``,
``api_key_env`` and per-model options), an optional ``[prices]`` table and ``[suites.NAME]``
tables; ``--model base_url=URL,model=NAME[,KEY=VALUE...]`` gives the same keys on the command
line. docs/bench.md (*The models file*) lists every key, with an example.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from collections.abc import Mapping

from jswim.bench.suites import Suite, check_name, user_suite
from jswim.errors import ConfigError
from jswim.llm.prices import parse_prices, read_small_text
from jswim.llm.urls import safe_url

#: Keys of a model entry -> the ``jswim study`` flag each becomes (``None``: handled apart).
MODEL_KEYS = {
    "name": None,
    "base_url": "--base-url",
    "model": "--model",
    "api_key_env": "--api-key-env",
    "concurrency": "--concurrency",
    "rpm": "--rpm",
    "tpm": "--tpm",
    "max_cost": None,
    "temperature": "--temperature",
    "max_tokens": "--max-tokens",
    "timeout": "--timeout",
    "reasoning": "--reasoning",
    "reasoning_effort": "--reasoning-effort",
    "constrain": "--constrain",
    "omit_fields": "--omit-field",
    "price_local": "--price-local",
    "extra": "--extra-field",
}

#: The type each key's value must have, as TOML writes it: text, a whole number, a number
#: (whole or not), true/false; never a bool for a number ("max_cost = true" is no $1) nor text
#: for a bool ("price_local = 'false'" is no switch).
TEXT_KEYS = (
    "name",
    "base_url",
    "model",
    "api_key_env",
    "reasoning",
    "reasoning_effort",
    "constrain",
)
INT_KEYS = ("concurrency", "max_tokens")
NUMBER_KEYS = ("rpm", "tpm", "max_cost", "temperature", "timeout")


def _check_types(table: Mapping[str, Any], where: str) -> None:
    """One line naming the first key whose value has the wrong type."""
    for key, value in table.items():
        if key in TEXT_KEYS:
            ok, want = isinstance(value, str), "text"
        elif key in INT_KEYS:
            ok, want = isinstance(value, int) and not isinstance(value, bool), "a whole number"
        elif key in NUMBER_KEYS:
            ok = (
                isinstance(value, (int, float))
                and not isinstance(value, bool)
                and math.isfinite(value)
            )
            want = "a number"
        elif key == "price_local":
            ok, want = isinstance(value, bool), "true or false"
        elif key == "omit_fields":
            ok = isinstance(value, list) and all(isinstance(v, str) for v in value)
            want = "a list of field names"
        elif key == "extra":
            ok, want = isinstance(value, Mapping), "a table of request fields"
        else:
            continue
        if not ok:
            raise ConfigError(f"{where}: {key} must be {want}, got {value!r}")


#: Names a user's model may not take: the bench's own rows and folders.
RESERVED = ("baselines", "reference")


@dataclass(frozen=True)
class ModelEntry:
    """One model of a bench (its settings as given, checked)."""

    name: str
    settings: tuple[tuple[str, Any], ...]

    def get(self, key: str, default: Any = None) -> Any:
        return dict(self.settings).get(key, default)

    @property
    def max_cost(self) -> float | None:
        v = self.get("max_cost")
        return None if v is None else float(v)

    def args(self) -> list[str]:
        """The backend flags of this model for ``jswim study`` (no secret: the key's variable name)."""
        import json

        out: list[str] = []
        for key, value in self.settings:
            flag = MODEL_KEYS[key]
            if flag is None:
                continue
            if key == "price_local":
                out += [flag] if value else []
            elif key == "omit_fields":
                for v in value:
                    out += [flag, str(v)]
            elif key == "extra":
                for k, v in value.items():
                    out += [flag, f"{k}={json.dumps(v)}"]
            else:
                out += [flag, str(value)]
        return out

    def describe(self) -> dict[str, Any]:
        """The entry as recorded in ``bench.json`` and the leaderboard: the base URL without
        user info, and request fields by name only (either may hold a credential)."""
        out: dict[str, Any] = {"name": self.name}
        for k, v in self.settings:
            if k == "base_url":
                v = safe_url(v)
            elif k == "extra":
                v = dict.fromkeys(v, "...")
            out[k] = v
        return out


def model_entry(table: Any, where: str) -> ModelEntry:
    """One checked model entry from a table (file entry or ``--model`` option).

    Raises
    ------
    ConfigError
        Unknown keys, a missing ``base_url``/``model``, a bad name.
    """
    if not isinstance(table, Mapping):
        raise ConfigError(f"{where}: each [[models]] entry must be a table")
    bad = sorted(str(k) for k in set(table) - set(MODEL_KEYS))
    if bad:
        raise ConfigError(
            f"{where}: unknown key {bad[0]!r} in a model entry; use {', '.join(MODEL_KEYS)}"
        )
    _check_types(table, where)
    for key in ("base_url", "model"):
        if not table.get(key):
            raise ConfigError(
                f"{where}: a model entry needs {key} (every entry has base_url and model; name is "
                "optional)"
            )
    name = check_name(table.get("name") or table["model"], "model name")
    if name in RESERVED:
        raise ConfigError(
            f"{where}: the model name {name!r} is the bench's own row; choose another"
        )
    if "omit_fields" in table and not isinstance(table["omit_fields"], list):
        raise ConfigError(f"{where}: omit_fields must be a list of field names")
    if "extra" in table and not isinstance(table["extra"], Mapping):
        raise ConfigError(f"{where}: extra must be a table of request fields")
    if table.get("max_cost") is not None:
        try:
            if not float(table["max_cost"]) >= 0:
                raise ValueError
        except (TypeError, ValueError):
            raise ConfigError(
                f"{where}: max_cost of {name!r} must be a number of dollars >= 0"
            ) from None
    settings = tuple((k, table[k]) for k in MODEL_KEYS if k in table and k != "name")
    return ModelEntry(name, settings)


def parse_model_option(text: str) -> ModelEntry:
    """A ``--model key=value,key=value`` option."""
    table: dict[str, Any] = {}
    for item in text.split(","):
        key, sep, value = item.partition("=")
        if not sep:
            raise ConfigError(
                f"--model expects key=value pairs such as base_url=URL,model=NAME, got {text!r}"
            )
        key = key.strip()
        if key in ("concurrency", "max_tokens"):
            try:
                table[key] = int(value)
            except ValueError:
                raise ConfigError(f"--model {key}={value}: expected an integer") from None
        elif key in ("rpm", "tpm", "max_cost", "temperature", "timeout"):
            try:
                table[key] = float(value)
            except ValueError:
                raise ConfigError(f"--model {key}={value}: expected a number") from None
        elif key == "omit_fields":
            table[key] = [v for v in value.split("+") if v]
        elif key == "price_local":
            flag = value.strip().lower()
            if flag not in ("1", "true", "yes", "0", "false", "no"):
                raise ConfigError(f"--model price_local={value}: expected true or false")
            table[key] = flag in ("1", "true", "yes")
        else:
            table[key] = value.strip()
    return model_entry(table, "--model")


@dataclass(frozen=True)
class ModelsFile:
    """What a models file holds: the models, an optional price table and user suites."""

    models: tuple[ModelEntry, ...]
    prices: dict[str, tuple[float, float]] | None = None
    prices_as_of: str | None = None
    suites: tuple[Suite, ...] = ()


def load_models_file(path: str | Path) -> ModelsFile:
    """Read and check a models file (TOML).

    Raises
    ------
    ConfigError
        A missing or invalid file, or any bad entry (one line, naming the file).
    """
    p = Path(path)
    where = str(path)
    try:
        data = tomllib.loads(read_small_text(p, "models file"))
    except FileNotFoundError:
        raise ConfigError(f"models file {where}: no such file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError(
            f"models file {where}: cannot read it ({getattr(exc, 'strerror', None) or exc})"
        ) from None
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(
            f"models file {where}: not valid TOML ({str(exc).splitlines()[0]})"
        ) from None
    unknown = sorted(set(data) - {"models", "prices", "suites"})
    if unknown:
        raise ConfigError(
            f"models file {where}: unknown table {unknown[0]!r}; use [[models]], [prices], [suites.NAME]"
        )
    entries = data.get("models") or []
    if not isinstance(entries, list):
        raise ConfigError(f"models file {where}: models must be an array of tables ([[models]])")
    models = tuple(model_entry(t, where) for t in entries)
    prices = as_of = None
    if not isinstance(data.get("suites", {}), Mapping):
        raise ConfigError(f"models file {where}: suites must be tables ([suites.NAME])")
    if "prices" in data:
        if not isinstance(data["prices"], Mapping):
            raise ConfigError(
                f"models file {where}: prices must be a table of model = [prompt, completion]"
            )
        raw = dict(data["prices"])
        as_of = str(raw.pop("as_of", f"the prices of {p.name}"))
        prices = parse_prices(raw, f"models file {where}")
    suites = tuple(
        user_suite(name, table, f"models file {where}")
        for name, table in (data.get("suites") or {}).items()
    )
    return ModelsFile(models, prices, as_of, suites)


def check_unique(models: tuple[ModelEntry, ...]) -> None:
    names = [m.name for m in models]
    dupes = sorted({n for n in names if names.count(n) > 1})
    if dupes:
        raise ConfigError(
            f"two models are named {dupes[0]!r}; give each its own name (it names its folder)"
        )
    if not models:
        raise ConfigError(
            "no models: give a models file with [[models]] entries or --model base_url=URL,model=NAME"
        )
