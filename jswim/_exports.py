"""Lazy package exports (PEP 562): a package names its public names and their modules, and each
module loads on first use, so importing one small module of a package never loads its heavy
siblings (JAX, matplotlib, httpx).

Used as ``__getattr__, __dir__ = lazy_exports(__name__, HOMES)`` in a package's ``__init__``,
beside ``__all__ = list(HOMES)``; ``submodules`` names the package's modules that are reached as
its attributes (``jswim.agents.qlearning``), imported on first use too.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Collection, Mapping
from typing import Any


def lazy_exports(
    package: str, homes: Mapping[str, str], submodules: Collection[str] = ()
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The ``__getattr__`` and ``__dir__`` of ``package`` for the names in ``homes``.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    homes : mapping of str to str
        Public name -> the module that defines it (absolute, or relative to ``package`` when it
        starts with a dot).
    submodules : collection of str, optional
        Names of ``package``'s own modules, each returned as ``package.name``.

    Returns
    -------
    tuple of callables
        ``__getattr__(name)`` imports the name's module and caches the value in the package (a
        submodule: the import binds it there); it raises ``AttributeError`` for any other name.
        ``__dir__()`` lists the module's globals, the exported names and the submodules.
    """
    import sys

    def __getattr__(name: str) -> Any:
        if name in submodules:
            return importlib.import_module(f"{package}.{name}")
        if name not in homes:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(homes[name], package), name)
        setattr(sys.modules[package], name, value)  # later look-ups skip this function
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | set(homes) | set(submodules))

    return __getattr__, __dir__
