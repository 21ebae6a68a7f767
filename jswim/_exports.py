"""Lazy package exports (PEP 562): a package names its public names and their modules, and each
module loads on first use, so importing one small module of a package never loads its heavy
siblings (JAX, matplotlib, httpx).

Used as ``__getattr__, __dir__ = lazy_exports(__name__, HOMES)`` in a package's ``__init__``,
beside ``__all__ = list(HOMES)``.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Mapping
from typing import Any


def lazy_exports(
    package: str, homes: Mapping[str, str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The ``__getattr__`` and ``__dir__`` of ``package`` for the names in ``homes``.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    homes : mapping of str to str
        Public name -> the module that defines it (absolute, or relative to ``package`` when it
        starts with a dot).

    Returns
    -------
    tuple of callables
        ``__getattr__(name)`` imports the name's module and caches the value in the package;
        it raises ``AttributeError`` for any other name. ``__dir__()`` lists the module's globals
        and the exported names.
    """
    import sys

    def __getattr__(name: str) -> Any:
        if name not in homes:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(homes[name], package), name)
        setattr(sys.modules[package], name, value)  # later look-ups skip this function
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(homes))

    return __getattr__, __dir__
