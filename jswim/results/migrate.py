"""Records of earlier jswim versions in today's form: the one migration step of the readers.

A study folder keeps what it was written with; every record is brought to today's form here, as
it comes off disk (`jswim.results.read`, [`StudyStore`][jswim.results.store.StudyStore] on open)
or as a user's dict becomes a row ([`RunRow.from_dict`][jswim.results.row.RunRow.from_dict]), so
no other reader knows an earlier form. Each translation is idempotent: a record already in
today's form passes through unchanged. What each earlier version wrote and what it becomes:

- ``allowed`` -> ``action_set`` (`RENAMED`): the name of the allowed moves before the
  ``--action-set`` option (folders written before f249a04); in rows, metadata and the
  identity, at any depth.
- A row with no ``plane_height`` (written before the column existed): Purcell's swimmer in a
  wall scene swam in a plane parallel to the wall, at the scene's ``height``; no other world did.
- A navigation row in a flow with ``time_ratio`` and ``zermelo_steps`` but no
  ``optimal_steps`` (written before the swimmer's own optimum was searched): its
  ``time_ratio`` was the ratio to Zermelo's time, today's ``zermelo_ratio``.
- Metadata with one ``grid`` and no ``grids`` (written before a resume could extend a folder's
  grid): that grid is the folder's only one.

The money records (``requests.jsonl``, ``calls.jsonl``) are not translated here: the ledger
reads an earlier jswim's lines itself (`jswim.llm.ledger`), where the cost cap is kept.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from typing import Any

__all__ = ["RENAMED", "migrate_metadata", "migrate_row"]

#: Fields renamed since folders were first written: old name -> today's name.
RENAMED = {"allowed": "action_set"}


def _renamed(obj: Any) -> Any:
    """``obj`` (a row, metadata, an identity; nested dicts and lists) with the old field names of
    `RENAMED` under today's names; a fresh copy of every dict and list."""
    if isinstance(obj, dict):
        return {RENAMED.get(k, k): _renamed(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_renamed(v) for v in obj]
    return obj


def migrate_row(row: Mapping[str, Any]) -> dict[str, Any]:
    """A run record of any jswim version in today's form (a new dict; see the module's list).

    Parameters
    ----------
    row : Mapping
        One record of ``runs.jsonl`` (or a dict a user built like one).

    Returns
    -------
    dict
        The record under today's names, with ``plane_height`` where the old rule gives it and an
        earlier ``time_ratio`` to Zermelo read as ``zermelo_ratio``; unknown fields kept.
    """
    d = _renamed(dict(row))
    if "plane_height" not in d and d.get("swimmer") == "purcell" and d.get("medium") == "wall":
        try:
            scene = json.loads(d["scene"]) if isinstance(d.get("scene"), str) else dict(d["scene"])
            d["plane_height"] = float(scene["height"])
        except (KeyError, TypeError, ValueError, OverflowError):
            pass  # no readable scene height: the row keeps no plane
    if "optimal_steps" not in d and "time_ratio" in d and "zermelo_steps" in d:
        d["zermelo_ratio"] = d.pop("time_ratio")
    return d


def migrate_metadata(meta: Mapping[str, Any]) -> dict[str, Any]:
    """A study's ``metadata.json`` of any jswim version in today's form (a new dict).

    Parameters
    ----------
    meta : Mapping
        The file's object (its fields checked or not).

    Returns
    -------
    dict
        ``meta`` under today's names (identity included), with ``grids`` the one ``grid`` of a
        folder written before a folder recorded each session's grid (or whose ``grids`` is no
        list of grids).
    """
    out = _renamed(dict(meta))
    grids = out.get("grids")
    if not (isinstance(grids, list) and grids and all(isinstance(g, dict) for g in grids)):
        if isinstance(out.get("grid"), dict):
            out["grids"] = [dict(out["grid"])]
        else:
            out.pop("grids", None)
    return out
