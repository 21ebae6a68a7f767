"""The exact tables' disk cache: keyed, atomic, and never a reason for a step to fail."""

import os

import numpy as np

from jswim.env import table_cache


def _build(calls):
    def build():
        calls.append(1)
        return {"rows": np.arange(6, dtype=np.float64).reshape(2, 3)}

    return build


def test_a_table_is_built_once_then_read_back(tmp_path, monkeypatch):
    monkeypatch.setenv("JSWIM_TABLE_CACHE", str(tmp_path))
    calls = []
    a = table_cache.cached("t", "model-a", _build(calls))
    b = table_cache.cached("t", "model-a", _build(calls))
    np.testing.assert_array_equal(a["rows"], b["rows"])
    assert len(calls) == 1 and len(list(tmp_path.glob("t-*.npz"))) == 1
    table_cache.cached("t", "model-b", _build(calls))  # another key: another entry
    assert len(calls) == 2 and not list(tmp_path.glob(".*.tmp"))


def test_a_corrupt_or_foreign_entry_is_rebuilt(tmp_path, monkeypatch):
    monkeypatch.setenv("JSWIM_TABLE_CACHE", str(tmp_path))
    calls = []
    table_cache.cached("t", "k", _build(calls))
    (entry,) = tmp_path.glob("t-*.npz")
    entry.write_bytes(entry.read_bytes()[:40])  # torn
    assert table_cache.cached("t", "k", _build(calls))["rows"].shape == (2, 3) and len(calls) == 2
    np.savez(entry, rows=np.array([np.nan]))  # valid file, not a table
    assert table_cache.cached("t", "k", _build(calls))["rows"].shape == (2, 3) and len(calls) == 3


def test_an_unusable_folder_falls_back_to_building(tmp_path, monkeypatch):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    monkeypatch.setenv("JSWIM_TABLE_CACHE", str(blocker / "sub"))
    calls = []
    assert table_cache.cached("t", "k", _build(calls))["rows"].shape == (2, 3)
    monkeypatch.setenv("JSWIM_TABLE_CACHE", "off")
    assert table_cache.cache_dir() is None and table_cache.cached("t", "k", _build(calls))[
        "rows"
    ].shape == (
        2,
        3,
    )
    assert len(calls) == 2


def test_the_folder_follows_xdg_cache_home(tmp_path, monkeypatch):
    monkeypatch.delenv("JSWIM_TABLE_CACHE", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert table_cache.cache_dir() == tmp_path / "jswim" / "tables"
    monkeypatch.delenv("XDG_CACHE_HOME")
    assert (
        table_cache.cache_dir()
        == __import__("pathlib").Path(os.path.expanduser("~")) / ".cache" / "jswim" / "tables"
    )


def test_the_key_includes_the_code_version(tmp_path, monkeypatch):
    monkeypatch.setenv("JSWIM_TABLE_CACHE", str(tmp_path))
    calls = []
    table_cache.cached("t", "k", _build(calls))
    monkeypatch.setattr(table_cache, "code_version", lambda: "another-version")
    table_cache.cached("t", "k", _build(calls))
    assert len(calls) == 2
