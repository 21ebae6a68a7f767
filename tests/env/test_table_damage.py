"""Nothing on disk is trusted (issue 61): a damaged table entry is never used, never blocks and
never crashes; it is rebuilt, written back intact and reported in one line. One case per damage
kind, each on a table's entry that keeps its record (the careful damage: only the arrays
change), checked three ways: a cheap table through `jswim.env.table_cache.cached` (every kind,
fast), the real K = 2 lattice table (fast) and the real flow table of a shear flow, a rollout
equal to a clean one (slow: each kind rebuilds the flow table and recompiles the rollout).
The command end to end is tests/cli/test_table_damage_cli.py."""

from __future__ import annotations

import os
import shutil
import stat
import threading
import warnings
from collections.abc import Callable
from pathlib import Path

import jax
import jax.numpy as jnp
import numpy as np
import pytest

import jswim
from jswim.env import flow_tables, step_tables, table_cache
from jswim.env.flows import Shear
from jswim.env.table_cache import TableCacheWarning, cached
from jswim.swimmers.models import make_model


def _rewrite(change: Callable[[dict[str, np.ndarray], str], dict[str, np.ndarray]]):
    """Damage that rewrites the entry's arrays, keeping every other member (the record too)."""

    def damage(path: Path, table: str) -> None:
        with np.load(path) as data:
            arrays = {k: data[k] for k in data.files}
        arrays = change(arrays, table)
        path.unlink()
        with open(path, "wb") as fh:
            np.savez(fh, **arrays)

    return damage


def _table(change: Callable[[np.ndarray], np.ndarray]):
    return _rewrite(lambda arrays, table: {**arrays, table: change(arrays[table])})


def _renamed(arrays: dict[str, np.ndarray], table: str) -> dict[str, np.ndarray]:
    out = dict(arrays)
    out[table + "_renamed"] = out.pop(table)
    return out


def _fifo(path: Path, table: str) -> None:
    path.unlink()
    os.mkfifo(path)  # np.load of it would wait for a writer forever


#: The issue's damage kinds.
DAMAGE = {
    "cut to its first row": _table(lambda rows: rows[:1]),
    "scaled values, the right shape": _table(lambda rows: rows * 1.001),
    "key renamed": _rewrite(_renamed),
    "shape (1, 1)": _table(lambda rows: rows.reshape(-1)[:1].reshape(1, 1)),
    "transposed": _table(lambda rows: rows.T),
    "shape (0, n)": _table(lambda rows: rows[:0]),
    "1-D": _table(lambda rows: rows.reshape(-1)),
    "a FIFO at its path": _fifo,
}


def _folder(path: Path, table: str) -> None:
    path.unlink()
    path.mkdir()
    (path / "x").write_text("someone's")


def _device_link(path: Path, table: str) -> None:
    path.unlink()
    path.symlink_to("/dev/zero")  # read through, it never ends


def _dangling_link(path: Path, table: str) -> None:
    path.unlink()
    path.symlink_to(path.parent / "nowhere.npz")


def _no_record(path: Path, table: str) -> None:  # an entry as jswim wrote it before issue 61
    with np.load(path) as data:
        arrays = {k: data[k] for k in data.files if k != table_cache.META}
    with open(path, "wb") as fh:
        np.savez(fh, **arrays)


def _nan(path: Path, table: str) -> None:
    _table(lambda rows: np.where(np.arange(rows.size).reshape(rows.shape) == 0, np.nan, rows))(
        path, table
    )


#: More damage, for the cheap table.
MORE = {
    "torn": lambda path, table: path.write_bytes(path.read_bytes()[:100]),
    "empty file": lambda path, table: path.write_bytes(b""),
    "not a zip": lambda path, table: path.write_text("rows = [1, 2, 3]\n"),
    "a folder at its path": _folder,
    "a symlink to a device": _device_link,
    "a dangling symlink": _dangling_link,
    "no record (an older format)": _no_record,
    "a NaN": _nan,
    "a float32 table": _table(lambda rows: rows.astype(np.float32)),
    "another table's record": _rewrite(
        lambda arrays, table: {**arrays, table_cache.META: np.array('{"table": "t"}')}
    ),
}


def _within(seconds: float, fn: Callable):
    """``fn()`` in a thread that must end within ``seconds`` (a blocked read fails the test,
    instead of hanging it)."""
    box: dict = {}

    def run():
        try:
            box["out"] = fn()
        except BaseException as err:  # re-raised in the test's thread
            box["err"] = err

    t = threading.Thread(target=run, daemon=True)
    t.start()
    t.join(seconds)
    assert not t.is_alive(), f"still reading after {seconds} s: it blocked"
    if "err" in box:
        raise box["err"]
    return box["out"]


def _one_warning(record, entry: Path) -> str:
    texts = [str(w.message) for w in record if issubclass(w.category, TableCacheWarning)]
    assert len(texts) == 1, texts
    (text,) = texts
    assert str(entry) in text and "damaged" in text and "not used" in text and "\n" not in text
    return text


# --- a cheap table: every kind --------------------------------------------------------------

ROWS = np.arange(12.0).reshape(4, 3) / 7.0
SHAPES = {"rows": (4, 3)}


def _cheap(tmp_path, monkeypatch):
    monkeypatch.setenv("JSWIM_TABLE_CACHE", str(tmp_path))
    calls = []

    def read():
        return cached("t", "model|K=2", lambda: (calls.append(1), {"rows": ROWS.copy()})[1], SHAPES)

    return read, calls


@pytest.mark.parametrize("kind", [*DAMAGE, *MORE])
def test_a_damaged_entry_is_rebuilt_written_back_and_said_once(kind, tmp_path, monkeypatch):
    read, calls = _cheap(tmp_path, monkeypatch)
    clean = read()
    (entry,) = tmp_path.glob("t-*.npz")
    {**DAMAGE, **MORE}[kind](entry, "rows")
    with pytest.warns(TableCacheWarning) as record:
        got = _within(20, read)
    _one_warning(record, entry)
    np.testing.assert_array_equal(got["rows"], clean["rows"])
    assert list(got) == ["rows"] and len(calls) == 2
    if kind == "a folder at its path":  # someone's folder is kept; the table is not stored
        assert (entry / "x").exists() and "not stored" in str(record[0].message)
        return
    # written back atomically: a regular file, read again without a build or a word
    assert stat.S_ISREG(os.lstat(entry).st_mode) and not list(tmp_path.glob(".*.tmp"))
    with warnings.catch_warnings():
        warnings.simplefilter("error", TableCacheWarning)
        np.testing.assert_array_equal(read()["rows"], clean["rows"])
    assert len(calls) == 2


def test_each_damage_is_said_once_per_process(tmp_path, monkeypatch):
    read, calls = _cheap(tmp_path, monkeypatch)
    read()
    (entry,) = tmp_path.glob("t-*.npz")
    _folder(entry, "rows")  # cannot be replaced: every read rebuilds
    with pytest.warns(TableCacheWarning) as record:
        for _ in range(3):
            np.testing.assert_array_equal(read()["rows"], ROWS)
    assert len([w for w in record if issubclass(w.category, TableCacheWarning)]) == 1
    assert len(calls) == 4


def test_the_record_says_what_the_table_was_built_from(tmp_path, monkeypatch):
    import json

    read, _ = _cheap(tmp_path, monkeypatch)
    read()
    (entry,) = tmp_path.glob("t-*.npz")
    with np.load(entry) as data:
        record = json.loads(str(data[table_cache.META][()]))
    assert record["table"] == "t" and record["key"] == "model|K=2"
    assert record["format"] == table_cache.FORMAT and record["code"] == table_cache.code_version()
    assert record["arrays"] == {"rows": {"shape": [4, 3], "dtype": "<f8"}}
    assert len(record["checksum"]) == 32


def test_a_build_that_is_not_the_declared_table_is_a_bug_not_a_cache_entry(tmp_path, monkeypatch):
    monkeypatch.setenv("JSWIM_TABLE_CACHE", str(tmp_path))
    with pytest.raises(RuntimeError, match="shape"):
        cached("t", "k", lambda: {"rows": np.zeros((3, 3))}, SHAPES)
    assert not list(tmp_path.iterdir())


# --- real tables -------------------------------------------------------------------------------

PURCELL = make_model("purcell")


@pytest.mark.parametrize("kind", ["cut to its first row", "a FIFO at its path"])
def test_a_damaged_lattice_table_is_rebuilt(kind, tmp_path, monkeypatch):
    monkeypatch.setenv("JSWIM_TABLE_CACHE", str(tmp_path))
    build = step_tables.lattice_table.__wrapped__  # past the in-memory cache: read the disk
    clean = build(PURCELL, 2)
    (entry,) = tmp_path.glob("lattice-*.npz")
    DAMAGE[kind](entry, "rows")
    with pytest.warns(TableCacheWarning) as record:
        got = _within(120, lambda: build(PURCELL, 2))
    _one_warning(record, entry)
    np.testing.assert_array_equal(got, clean)


FLOW = Shear(0.01)
ACTIONS = [1, 3, 0, 2, 4, 1, 5, 3, 0, 2]  # the paper's corner world: every table row in use


def _rollout() -> tuple[np.ndarray, np.ndarray]:
    flow_tables.flow_table.cache_clear()  # the table is read again when the rollout is traced
    jax.clear_caches()
    env, params = jswim.make("purcell", flow=FLOW)
    obs = jswim.rollout(env, params, jax.random.PRNGKey(0), jnp.asarray(ACTIONS)).obs
    return np.asarray(obs.position[..., 0, :]), np.asarray(obs.orientation[..., 0])


@pytest.fixture(scope="module")
def clean_flow(tmp_path_factory):
    folder = tmp_path_factory.mktemp("flow-tables")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("JSWIM_TABLE_CACHE", str(folder))
        clean = _rollout()
    (entry,) = folder.glob("flow-*.npz")
    return folder, entry.name, clean


# slow: each kind rebuilds the flow table (2-10 s) and recompiles the rollout
@pytest.mark.slow
@pytest.mark.parametrize("kind", DAMAGE)
def test_a_damaged_flow_table_is_rebuilt_and_the_rollout_is_the_clean_one(
    kind, clean_flow, tmp_path, monkeypatch
):
    folder, name, clean = clean_flow
    shutil.copytree(folder, tmp_path / "tables")
    monkeypatch.setenv("JSWIM_TABLE_CACHE", str(tmp_path / "tables"))
    entry = tmp_path / "tables" / name
    DAMAGE[kind](entry, "rows")
    with pytest.warns(TableCacheWarning) as record:
        got = _within(300, _rollout)
    _one_warning(record, entry)
    np.testing.assert_array_equal(got[0], clean[0])
    np.testing.assert_array_equal(got[1], clean[1])
    assert not np.allclose(clean[0][-1], clean[0][0])  # it swam: the table was in use


# slow: a flow table rebuild and a rollout compiled in float32
@pytest.mark.slow
def test_the_same_in_the_default_float32(clean_flow, tmp_path, monkeypatch, float32):
    folder, name, _ = clean_flow
    shutil.copytree(folder, tmp_path / "tables")
    monkeypatch.setenv("JSWIM_TABLE_CACHE", str(tmp_path / "tables"))
    clean = _rollout()  # the intact table, read in float32
    entry = tmp_path / "tables" / name
    DAMAGE["cut to its first row"](entry, "rows")
    with pytest.warns(TableCacheWarning) as record:
        got = _rollout()
    _one_warning(record, entry)
    assert got[0].dtype == np.float32
    np.testing.assert_array_equal(got[0], clean[0])
    np.testing.assert_array_equal(got[1], clean[1])
