"""Odd input is one line on stderr and exit 2 before any run starts, never a traceback.

Each case is an example of a kind: text that is not UTF-8, a key no HTTP header can carry, a URL
that does not parse, a path the file system refuses, a grid value given twice, a number that is
not finite, a cache that is not one, a prompt file too large to send, an unset key variable.
"""

from __future__ import annotations

import os
import sqlite3

import pytest

from jswim import cli
from jswim.llm.response_cache import ResponseCache, check_cache
from jswim.errors import ConfigError
from jswim.prompt import MAX_TEMPLATE_BYTES
from jswim.results import read_runs
from jswim.studies import StudyOptions
from tests.fakeserver import FakeServer, hash_reply

BASE = [
    "--steps",
    "12",
    "--runs",
    "1",
    "--q-runs",
    "0",
    "--swimmer",
    "purcell",
    "--direction",
    "+x",
    "--no-figures",
    "--model",
    "fake",
]


def refused(capsys, srv, out, *extra: str) -> str:
    rc = cli.main(["swim", *BASE, "--base-url", srv.url, "--out", str(out), *extra])
    err = capsys.readouterr().err
    assert "Traceback" not in err
    lines = [ln for ln in err.splitlines() if ln.startswith("jswim: error:")]
    assert rc == 2 and len(lines) == 1, err
    assert srv.n_requests == 0 and not os.path.exists(out / "runs.jsonl")  # before any run
    return lines[0]


@pytest.fixture
def srv():
    with FakeServer(reply=hash_reply) as s:
        yield s


def test_text_that_is_not_utf8(srv, tmp_path, capsys):
    line = refused(
        capsys, srv, tmp_path / "o", "--model", "m\udcff"
    )  # what Python makes of $'m\xff'
    assert "--model" in line and "UTF-8" in line


@pytest.mark.parametrize("key", ["sk-ü123", "sk-12\x0734", "sk-\u200babc"])
def test_a_key_no_header_can_carry_names_the_variable_never_the_value(
    key, srv, tmp_path, capsys, monkeypatch
):
    monkeypatch.setenv("JSWIM_TEST_BAD_KEY", key)
    line = refused(capsys, srv, tmp_path / "o", "--api-key-env", "JSWIM_TEST_BAD_KEY")
    assert (
        "$JSWIM_TEST_BAD_KEY" in line
        and "abc" not in line
        and "123" not in line
        and "sk-" not in line
    )


@pytest.mark.parametrize("url", ["http://[::1/v1", "http://[zz::1]/v1"])
def test_a_url_that_does_not_parse(url, srv, tmp_path, capsys):
    line = refused(capsys, srv, tmp_path / "o", "--base-url", url)
    assert "base URL" in line


def test_an_out_name_longer_than_the_file_system_allows(srv, tmp_path, capsys):
    line = refused(capsys, srv, tmp_path / ("x" * 300))
    assert "--out" in line and "too long" in line.lower()
    (tmp_path / "file").write_text("x")
    assert "Not a directory" in refused(capsys, srv, tmp_path / "file" / "o")


@pytest.mark.parametrize("value", ["inf", "nan", "-1", "0"])
def test_a_timeout_that_is_not_a_finite_positive_number(value, srv, tmp_path, capsys):
    assert "--timeout" in refused(capsys, srv, tmp_path / "o", "--timeout", value)


@pytest.mark.parametrize(
    "option, value", [("--retries", "-1"), ("--retry-for", "inf"), ("--retry-for", "-2")]
)
def test_a_retry_budget_that_is_not_one(option, value, srv, tmp_path, capsys):
    assert option in refused(capsys, srv, tmp_path / "o", option, value)


def test_a_cache_dir_that_is_a_file_or_not_a_cache(srv, tmp_path, capsys):
    (tmp_path / "afile").write_text("x")
    assert "a file, not a folder" in refused(
        capsys, srv, tmp_path / "o", "--cache-dir", str(tmp_path / "afile")
    )
    (tmp_path / "bad.sqlite").write_text("not a database " * 100)
    assert "not a usable" in refused(
        capsys, srv, tmp_path / "o", "--cache-dir", str(tmp_path / "bad.sqlite")
    )
    (tmp_path / "d").mkdir()
    (tmp_path / "d" / "responses.sqlite").write_bytes(b"\0" * 4096)
    with pytest.raises(ConfigError, match="not a usable"):
        check_cache(tmp_path / "d")
    ResponseCache(tmp_path / "good").close()
    check_cache(tmp_path / "good")  # a real cache is fine


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_a_read_only_cache_dir(srv, tmp_path, capsys):
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        assert "--cache-dir" in refused(
            capsys, srv, tmp_path / "o", "--cache-dir", str(ro / "cache")
        )
    finally:
        ro.chmod(0o755)


def test_a_read_only_cache_database(tmp_path):
    db = tmp_path / "c.sqlite"
    ResponseCache(db).close()
    con = sqlite3.connect(db)
    con.execute("PRAGMA journal_mode=DELETE")  # a copy without its WAL files, then made read-only
    con.close()
    db.chmod(0o444)
    if os.geteuid() == 0:
        pytest.skip("root writes into read-only files")
    with pytest.raises(ConfigError, match="--cache-dir"):
        check_cache(db)


def test_a_prompt_file_over_the_limit_is_refused_before_any_request(srv, tmp_path, capsys):
    big = tmp_path / "big.txt"
    big.write_text("{history} {allowed}\n" + "x" * (10 * 10**6))
    line = refused(capsys, srv, tmp_path / "o", "--prompt-file", str(big))
    assert "10.0 MB" in line and f"{MAX_TEMPLATE_BYTES // 1000} kB" in line


def test_the_prompt_template_is_stored_once_not_in_every_metadata_rewrite(srv, tmp_path, capsys):
    assert cli.main(["swim", *BASE, "--base-url", srv.url, "--out", str(tmp_path / "o")]) == 0
    meta = (tmp_path / "o" / "metadata.json").read_text()
    assert 'prompt_template"' not in meta and "layout" not in meta
    assert "layout" in (tmp_path / "o" / "prompt_template.json").read_text()


def test_an_unset_key_variable_is_an_error_for_a_remote_server_and_a_warning_here(
    srv, tmp_path, capsys
):
    rc = cli.main(
        [
            "swim",
            *BASE,
            "--base-url",
            "http://example.invalid/v1",
            "--out",
            str(tmp_path / "r"),
            "--api-key-env",
            "JSWIM_SURELY_UNSET",
        ]
    )
    err = capsys.readouterr().err
    assert rc == 2 and "$JSWIM_SURELY_UNSET is not set" in err and "Traceback" not in err
    assert (
        cli.main(
            [
                "swim",
                *BASE,
                "--base-url",
                srv.url,
                "--out",
                str(tmp_path / "l"),
                "--api-key-env",
                "JSWIM_SURELY_UNSET",
            ]
        )
        == 0
    )  # this machine's server may need no key
    warned = [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("jswim: warning:")]
    assert any("$JSWIM_SURELY_UNSET is not set" in ln for ln in warned)


@pytest.mark.parametrize(
    "field, given, merged",
    [
        ("zetas", (0, 0.0, 1), (0, 1)),
        ("swimmers", ("purcell", "purcell"), ("purcell",)),
        ("n_hts", (3, 3, 4), (3, 4)),
        ("directions", (1, 1, -1), (1, -1)),
    ],
)
def test_a_grid_value_given_twice_is_one_setting(field, given, merged):
    assert getattr(StudyOptions(**{field: given}), field) == merged


def test_duplicate_swimmers_run_once(srv, tmp_path, capsys):
    assert (
        cli.main(
            [
                "swim",
                *BASE,
                "--base-url",
                srv.url,
                "--out",
                str(tmp_path / "o"),
                "--swimmer",
                "purcell,purcell",
            ]
        )
        == 0
    )
    assert len(read_runs(tmp_path / "o")) == 1


@pytest.mark.parametrize(
    "field, option",
    [
        ("max_tokens=5000", "--max-tokens"),
        ("temperature=0.7", "--temperature"),
        ("stream=true", "stream"),
        ('model="gpt-4"', "--model"),
        ("messages=[]", "--prompt-file"),
        ("max_completion_tokens=99", "--max-tokens"),
        ("response_format={}", "--constrain"),
    ],
)
def test_an_extra_field_jswim_sets_itself_is_refused_naming_the_real_option(
    field, option, srv, tmp_path, capsys
):
    # It would bypass the cost reservation (max_tokens), the identity (temperature) or be dropped (model).
    line = refused(capsys, srv, tmp_path / "o", "--extra-field", field)
    assert f"--extra-field {field.split('=')[0]}=" in line and option in line


def test_an_extra_field_jswim_does_not_set_is_sent_and_recorded(srv, tmp_path, capsys):
    out = tmp_path / "o"
    assert (
        cli.main(
            ["swim", *BASE, "--base-url", srv.url, "--out", str(out), "--extra-field", "top_k=5"]
        )
        == 0
    )
    assert srv.requests and all(b["top_k"] == 5 for b in srv.requests)
    import json

    assert json.loads((out / "metadata.json").read_text())["identity"]["backend"][
        "extra_fields"
    ] == {"top_k": 5}


# -- messages that named the wrong cause --------------------------------------------------------


def test_a_fifo_or_a_device_as_prompt_file_says_what_it_is(srv, tmp_path, capsys):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    line = refused(capsys, srv, tmp_path / "o", "--prompt-file", str(fifo))
    assert "a FIFO" in line and "no such file" not in line
    line = refused(capsys, srv, tmp_path / "o", "--prompt-file", "/dev/zero")
    assert "a device" in line and "no such file" not in line
    line = refused(capsys, srv, tmp_path / "o", "--prompt-file", str(tmp_path / "missing.txt"))
    assert "no such file" in line


@pytest.mark.parametrize("command", ["show", "report", "animate"])
def test_a_file_given_as_a_study_folder_is_said_to_be_a_file(command, tmp_path, capsys):
    f = tmp_path / "notes.txt"
    f.write_text("x")
    assert cli.main([command, str(f)]) == 2
    err = capsys.readouterr().err.strip()
    assert (
        len(err.splitlines()) == 1 and "a file, not a study folder" in err and "no such" not in err
    ), err
    assert cli.main([command, str(tmp_path / "nothing")]) == 2
    assert "no such folder" in capsys.readouterr().err


def test_a_transcripts_file_in_the_way_is_not_called_a_full_disk(srv, tmp_path, capsys):
    out = tmp_path / "o"
    assert cli.main(["swim", *BASE, "--base-url", srv.url, "--out", str(out)]) == 0
    meta = (out / "metadata.json").read_bytes()
    for p in (out / "transcripts").iterdir():
        p.unlink()
    (out / "transcripts").rmdir()
    (out / "transcripts").write_text("in the way")
    capsys.readouterr()
    assert cli.main(["swim", *BASE, "--runs", "2", "--base-url", srv.url, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.startswith("jswim: error:")]
    assert len(lines) == 1 and "transcripts is a file where jswim keeps a folder" in lines[0], err
    assert "make room" not in err and "File exists" not in err
    assert (out / "metadata.json").read_bytes() == meta  # status and all left as they were


@pytest.mark.parametrize(
    "argv, named",
    [
        (["swim", "--swimmer", "\udcff"], "--swimmer"),
        (["qlearn", "--swimmer", "\udcff"], "--swimmer"),
        (["swim", "--direction=\udcff"], "--direction"),
        (["show", "\udcff"], "argument 2"),
    ],
)
def test_non_utf8_bytes_are_named_by_their_option_never_shown_as_surrogates(argv, named, capsys):
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"jswim: error: {named} is not valid UTF-8 text; write it in UTF-8"
    assert "udcff" not in err


# -- one check of each value, one message wherever it is given -----------------------------------

BENCH = ["bench", "--model", "base_url=http://127.0.0.1:9/v1,model=fake", "--dry-run"]


def one_error_line(capsys, argv: list[str], out) -> str:
    rc = cli.main([*argv, "--out", str(out)])
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.startswith("jswim: error:")]
    assert rc == 2 and len(lines) == 1 and "Traceback" not in err, err
    assert not out.exists()  # refused before any folder was written
    return lines[0].removeprefix("jswim: error: ")


@pytest.mark.parametrize(
    "option, value, message",
    [
        ("--n-ht", "-1", "--n-ht must be between 0 and 100, got -1"),
        ("--n-ht", "101", "--n-ht must be between 0 and 100, got 101"),
        ("--samples", "0", "--samples must be between 1 and 10000, got 0"),
        ("--samples", "10001", "--samples must be between 1 and 10000, got 10001"),
        ("--steps", "0", "--steps must be between 1 and 10000, got 0"),
        ("--q-runs", "-1", "--q-runs must be between 0 and 100000, got -1"),
    ],
)
def test_a_size_out_of_range_is_one_message_from_study_swim_and_python(
    option, value, message, tmp_path, capsys
):
    field = option.removeprefix("--").replace("-", "_")
    assert one_error_line(capsys, ["study", "curves", option, value], tmp_path / "s") == message
    assert one_error_line(capsys, ["swim", option, value], tmp_path / "w") == message
    with pytest.raises(ConfigError) as exc:
        StudyOptions(**{field: int(value)})
    assert str(exc.value) == message


@pytest.mark.parametrize(
    "option, value, message",
    [
        ("--samples", "0", "--samples must be between 1 and 10000, got 0"),
        ("--samples", "10001", "--samples must be between 1 and 10000, got 10001"),
        ("--steps", "0", "--steps must be between 1 and 10000, got 0"),
        ("--steps", "10001", "--steps must be between 1 and 10000, got 10001"),
        ("--runs", "-1", "--runs must be between 0 and 100000, got -1"),
    ],
)
def test_a_size_out_of_range_is_the_same_message_from_bench(
    option, value, message, tmp_path, capsys
):
    assert one_error_line(capsys, [*BENCH, option, value], tmp_path / "b") == message


@pytest.mark.parametrize("n_ht", [-1, 101])
def test_the_prompt_refuses_the_n_ht_the_study_refuses(n_ht):
    from jswim.prompt import PromptConfig

    with pytest.raises(ConfigError, match=f"^--n-ht must be between 0 and 100, got {n_ht}$"):
        PromptConfig(n_ht=n_ht)
    PromptConfig(n_ht=0), PromptConfig(n_ht=100)  # the ends are in range for both


def test_an_n_ht_grid_is_checked_value_by_value(tmp_path, capsys):
    line = one_error_line(capsys, ["study", "history", "--n-hts", "1,200"], tmp_path / "h")
    assert line == "--n-hts must be between 0 and 100, got 200"


@pytest.mark.parametrize(
    "argv, least",
    [
        (["study", "pair", "--separations", "20"], "22.1"),
        (["study", "school", "--separations", "30,20"], "22.1"),
        (["study", "school", "--separations", "1.5", "--formations", "side"], "2.1"),
    ],
)
def test_swimmers_that_would_overlap_are_refused_when_the_options_are_checked(
    argv, least, tmp_path, capsys
):
    # Arms at d_max = 10: a line needs D >= 2 * 10 + 2 radii + the contact gap 0.1; side by side, 2 + 0.1.
    line = one_error_line(capsys, argv, tmp_path / "o")
    assert line.startswith("--separations ") and f"raise separation above {least}" in line


def test_separations_that_fit_pass_and_a_lone_swimmer_needs_none():
    StudyOptions(separations=(22.2, 30.0))
    StudyOptions(separations=(2.2,), formations=("side",))
    StudyOptions(separations=(5.0,), school_sizes=(1,))  # nobody to overlap
    with pytest.raises(ConfigError, match=r"^--separations 22 \(line\)"):
        StudyOptions(separations=(22.0,))


def test_a_report_interval_longer_than_the_run_is_one_message_from_the_command_and_python(
    tmp_path, capsys
):
    from jswim.studies import ensemble

    line = one_error_line(
        capsys,
        ["ensemble", "--n", "4", "--steps", "3", "--every", "5", "--zetas", "0"],
        tmp_path / "e.csv",
    )
    assert line == "--every (5) must not exceed --steps (3)"
    with pytest.raises(ConfigError, match=r"^--every \(5\) must not exceed --steps \(3\)$"):
        ensemble.run(None, None, n=4, zetas=[0.0], steps=3, every=5)


@pytest.mark.parametrize(
    "seeds, chunk, message",
    [
        (0, 10, "--seeds must be >= 1, got 0"),
        (5, 0, "--chunk must be >= 1, got 0"),
        (2**31, 10, "--seeds must be at most 2,147,483,647, got 2147483648"),
    ],
)
def test_a_count_out_of_range_is_one_message_from_qlearn_and_python(
    seeds, chunk, message, tmp_path, capsys
):
    from jswim.studies import qlearn

    argv = ["qlearn", "--seeds", str(seeds), "--chunk", str(chunk), "--steps", "10"]
    assert one_error_line(capsys, argv, tmp_path / "q.csv") == message
    with pytest.raises(ConfigError, match="^" + message.replace("+", r"\+") + "$"):
        qlearn.study(["purcell"], n_seeds=seeds, chunk=chunk)
