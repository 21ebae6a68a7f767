"""Warnings that name the user's line: the call into jswim, not a line inside it.

``warnings.warn(..., stacklevel=N)`` names a fixed frame, which is wrong as soon as the warning
is reached through another path, and names nothing of the user's from a worker thread (the study's
event loop in a notebook: `jswim.llm.sync.run_sync`), whose stack ends in ``threading``.
`warn_user` walks out of jswim's own frames instead, and from a worker thread uses the
call site that ``run_sync`` recorded in `CALL_SITE` before it started the thread.
"""

from __future__ import annotations

import contextlib
import os
import sys
import warnings
from contextvars import ContextVar
from typing import Any

#: Where the user's call into jswim is, for warnings raised where the stack does not reach it
#: (the worker thread of `jswim.llm.sync.run_sync`): ``(filename, lineno, module globals)``.
CALL_SITE: ContextVar[tuple[str, int, dict[str, Any]] | None] = ContextVar(
    "jswim_call_site", default=None
)
_PACKAGE_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__))) + os.sep
_STDLIB = os.path.dirname(os.path.abspath(contextlib.__file__)) + os.sep
#: Frames that are neither jswim's nor the user's: the event loop's and the context managers'.
_PLUMBING = tuple(
    _STDLIB + name
    for name in ("asyncio" + os.sep, "concurrent" + os.sep, "contextlib.py", "warnings.py")
)
_THREAD_BOTTOM = _STDLIB + "threading.py"


def user_call_site(frame: Any = None) -> tuple[str, int, dict[str, Any]] | None:
    """``(filename, lineno, globals)`` of the innermost frame outside jswim and the event loop's
    plumbing; ``None`` in a worker thread, whose stack ends before any user code."""
    f = frame or sys._getframe(1)
    while f is not None:
        name = f.f_code.co_filename
        path = name if name.startswith("<") else os.path.abspath(name)
        if path == _THREAD_BOTTOM:
            return None
        if not path.startswith(_PACKAGE_DIR) and not path.startswith(_PLUMBING):
            return name, f.f_lineno, f.f_globals
        f = f.f_back
    return None


def warn_user(message: str | Warning, category: type[Warning] | None = None) -> None:
    """``warnings.warn`` pointed at the user's line that called into jswim, not at jswim's own.

    From a worker thread (whose stack never reaches the user's code) the call site recorded by
    `jswim.llm.sync.run_sync` is used.
    """
    if category is None:
        category = type(message) if isinstance(message, Warning) else UserWarning
    site = user_call_site(sys._getframe(1)) or CALL_SITE.get()
    if site is None:
        warnings.warn(message, category, stacklevel=2)
        return
    filename, lineno, module_globals = site
    warnings.warn_explicit(
        message,
        category,
        filename,
        lineno,
        module=module_globals.get("__name__", "__main__"),
        registry=module_globals.setdefault("__warningregistry__", {}),
        module_globals=module_globals,
    )
