"""The bottom layer for folder I/O, JAX-free: atomic writes and strict JSON (`atomic`), JSON
lines (`jsonl`), the one-writer folder lock (`folderlock`), file modes (`permissions`), signals
(`interrupts`), path kinds (`paths`) and the XDG cache folder (`xdg`).
"""

from jswim._exports import lazy_exports

#: Public name -> the module that defines it (loaded on first use).
_HOMES = {
    "atomic_write": ".atomic",
    "write_json": ".atomic",
    "dumps": ".atomic",
    "plain_json": ".atomic",
    "FolderLock": ".folderlock",
    "path_kind": ".paths",
}

__all__ = list(_HOMES)

__getattr__, __dir__ = lazy_exports(__name__, _HOMES)
