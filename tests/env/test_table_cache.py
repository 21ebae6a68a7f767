"""The exact tables' disk cache: keyed, atomic, and never a reason for a step to fail."""

import os
import tempfile
from pathlib import Path

import numpy as np
import pytest

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
    with pytest.warns(table_cache.TableCacheWarning, match="damaged"):
        assert table_cache.cached("t", "k", _build(calls))["rows"].shape == (2, 3)
    assert len(calls) == 2
    np.savez(entry, rows=np.array([np.nan]))  # valid file, not a table
    with pytest.warns(table_cache.TableCacheWarning, match="damaged"):
        assert table_cache.cached("t", "k", _build(calls))["rows"].shape == (2, 3)
    assert len(calls) == 3


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


def test_another_entry_copied_over_is_not_used(tmp_path, monkeypatch):
    monkeypatch.setenv("JSWIM_TABLE_CACHE", str(tmp_path))
    calls = []
    table_cache.cached("t", "k", _build(calls))
    (mine,) = tmp_path.glob("t-*.npz")
    other = table_cache.cached("t", "k2", lambda: {"rows": np.ones((2, 3))})
    (theirs,) = set(tmp_path.glob("t-*.npz")) - {mine}
    mine.write_bytes(theirs.read_bytes())  # intact, checksum and all, but another model's
    with pytest.warns(table_cache.TableCacheWarning, match="built from another key"):
        got = table_cache.cached("t", "k", _build(calls))
    assert len(calls) == 2 and not np.array_equal(got["rows"], other["rows"])


def test_without_declared_shapes_the_record_decides(tmp_path, monkeypatch):
    monkeypatch.setenv("JSWIM_TABLE_CACHE", str(tmp_path))
    calls = []
    table_cache.cached("t", "k", _build(calls))
    (entry,) = tmp_path.glob("t-*.npz")
    with np.load(entry) as data:
        arrays = {k: data[k] for k in data.files}
    entry.unlink()
    np.savez(entry, **{**arrays, "rows": arrays["rows"][:1]})  # cut, its record kept
    with pytest.warns(table_cache.TableCacheWarning, match="not the ones it records"):
        assert table_cache.cached("t", "k", _build(calls))["rows"].shape == (2, 3)


# --- the folder: the XDG Base Directory spec ---------------------------------------------------


@pytest.fixture
def no_cache_env(monkeypatch):
    """No JSWIM_TABLE_CACHE, no XDG_CACHE_HOME, and a fresh temporary folder and warnings."""
    monkeypatch.delenv("JSWIM_TABLE_CACHE", raising=False)
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.setattr(table_cache, "_warned", set())
    table_cache._temporary_dir.cache_clear()
    yield monkeypatch
    table_cache._temporary_dir.cache_clear()


def test_a_relative_xdg_cache_home_is_ignored(tmp_path, no_cache_env):
    no_cache_env.setenv("HOME", str(tmp_path))
    for relative in ("cache", "./cache", "~/cache"):
        no_cache_env.setenv("XDG_CACHE_HOME", relative)
        assert table_cache.cache_dir() == tmp_path / ".cache" / "jswim" / "tables"
    no_cache_env.setenv("XDG_CACHE_HOME", "")  # empty: unset, says the spec
    assert table_cache.cache_dir() == tmp_path / ".cache" / "jswim" / "tables"


@pytest.mark.parametrize("home", ["", "relative/home"])
def test_no_usable_home_gives_a_temporary_folder_and_one_warning(home, tmp_path, no_cache_env):
    no_cache_env.setenv("HOME", home)
    no_cache_env.chdir(tmp_path)
    with pytest.warns(table_cache.TableCacheWarning) as record:
        folder = table_cache.cache_dir()
        assert table_cache.cache_dir() == folder  # one folder per process
        table_cache.cached("t", "k", _build([]))
    (w,) = record
    assert "no usable home folder" in str(w.message) and str(folder) in str(w.message)
    assert folder.is_absolute() and str(folder).startswith(tempfile.gettempdir())
    assert len(list(folder.glob("t-*.npz"))) == 1
    assert not list(tmp_path.iterdir())  # nothing in the working folder (nor in /.cache)
    # a relative XDG_CACHE_HOME does not rescue it; an absolute one does, silently
    no_cache_env.setenv("XDG_CACHE_HOME", "rel")
    assert table_cache.cache_dir() == folder
    no_cache_env.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    assert table_cache.cache_dir() == tmp_path / "xdg" / "jswim" / "tables"


def test_a_tilde_in_jswim_table_cache_is_the_home_folder(tmp_path, no_cache_env):
    no_cache_env.setenv("HOME", str(tmp_path / "home"))
    no_cache_env.chdir(tmp_path)
    no_cache_env.setenv("JSWIM_TABLE_CACHE", "~/x")
    assert table_cache.cache_dir() == tmp_path / "home" / "x"
    table_cache.cached("t", "k", _build([]))
    assert len(list((tmp_path / "home" / "x").glob("t-*.npz"))) == 1
    assert not (tmp_path / "~").exists()  # no folder literally named ~
    no_cache_env.setenv("JSWIM_TABLE_CACHE", "~")
    assert table_cache.cache_dir() == tmp_path / "home"
    no_cache_env.setenv("JSWIM_TABLE_CACHE", "~root/x")  # another user's: the password database
    assert table_cache.cache_dir() == Path(os.path.expanduser("~root")) / "x"
    no_cache_env.setenv("JSWIM_TABLE_CACHE", "~no-such-user-here/x")
    with pytest.warns(table_cache.TableCacheWarning, match="no usable home"):
        assert table_cache.cache_dir() == table_cache._temporary_dir()
    no_cache_env.setenv("JSWIM_TABLE_CACHE", "a~b")  # only a leading ~ is the home
    assert table_cache.cache_dir() == Path("a~b")


def test_a_tilde_without_a_usable_home_is_the_temporary_folder(tmp_path, no_cache_env):
    no_cache_env.setenv("HOME", "")
    no_cache_env.setenv("JSWIM_TABLE_CACHE", "~/x")
    with pytest.warns(table_cache.TableCacheWarning, match="no usable home"):
        folder = table_cache.cache_dir()
    assert folder == table_cache._temporary_dir() and not str(folder).startswith("/x")


@pytest.mark.parametrize("home", ["", "relative/home"])
def test_the_compilation_cache_never_goes_to_the_root_folder(home, tmp_path, no_cache_env):
    from jswim import compile_cache

    no_cache_env.delenv("JAX_COMPILATION_CACHE_DIR", raising=False)
    no_cache_env.delenv("JSWIM_COMPILATION_CACHE", raising=False)
    no_cache_env.setenv("HOME", home)
    no_cache_env.setenv("XDG_CACHE_HOME", "cache")  # relative: ignored
    no_cache_env.chdir(tmp_path)
    assert compile_cache.cache_folder() is None and compile_cache.enable() is None
    assert not list(tmp_path.iterdir())
    no_cache_env.setenv("HOME", str(tmp_path))
    assert compile_cache.cache_folder() == tmp_path / ".cache" / "jswim" / "jax"
