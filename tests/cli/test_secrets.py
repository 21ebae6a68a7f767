"""No API key or URL password is ever printed or written, in any encoding of it.

A study runs with a real-looking key and a password in the base URL against a fake server that
echoes both back in its error messages (as proxies and some servers do); then every file of the
study folder and of the response cache, and everything printed, is searched for each secret in
each form a library might write it (raw, repr-escaped, JSON-escaped, percent-encoded, base64).
"""

from __future__ import annotations

import base64
import json
import secrets
from pathlib import Path
from urllib.parse import quote, quote_plus

import pyarrow.parquet as pq
import pytest

from jswim import cli
from jswim.results import read_runs
from tests.fakeserver import Fault, FakeServer

KEY = "sk-proj-" + secrets.token_urlsafe(36)  # looks like an OpenAI project key; new every run
USER, PASSWORD = "alice", "pw-" + secrets.token_hex(8)


def encodings(secret: str) -> set[str]:
    """Written out here, independently of jswim's scrubber."""
    out = set()
    for s in {secret, secret.strip()}:
        out |= {
            s,
            repr(s)[1:-1],
            json.dumps(s)[1:-1],
            quote(s, safe=""),
            quote_plus(s),
            quote(s),
            s.encode("unicode_escape").decode(),
            base64.b64encode(s.encode()).decode(),
            repr(s.encode("utf-8", "replace"))[2:-1],
        }
        if len(s) > 24:
            out.add(s[8:24])  # a good part of it is a leak too
    return out


def leaks(text: str, *found: str) -> list[str]:
    return [f for s in found for f in encodings(s) if f in text]


def folder_text(*folders: Path) -> str:
    """Every file under ``folders`` as text (binary read as latin-1; Parquet tables also decoded)."""
    parts = []
    for folder in folders:
        for path in sorted(folder.rglob("*")):
            if not path.is_file():
                continue
            parts.append(path.read_bytes().decode("latin-1"))
            if path.suffix == ".parquet":
                parts.append(json.dumps(pq.read_table(path).to_pylist(), default=str))
    return "\n".join(parts)


def swim(url: str, out: Path, *extra: str) -> list[str]:
    return [
        "swim",
        "--base-url",
        url,
        "--model",
        "fake",
        "--runs",
        "2",
        "--q-runs",
        "0",
        "--steps",
        "4",
        "--noise",
        "0.5",
        "--no-figures",
        "--out",
        str(out),
        *extra,
    ]


def with_password(url: str) -> str:
    return url.replace("http://", f"http://{USER}:{PASSWORD}@")


def test_a_study_with_a_key_and_url_credentials_writes_and_prints_neither(
    tmp_path, monkeypatch, capsys
):
    monkeypatch.setenv("MYKEY", KEY)
    out, cache = tmp_path / "study", tmp_path / "cache"
    srv: FakeServer

    def reply(body):
        # From the 4th request on the server refuses, with a message that echoes the request's
        # credentials as a server or proxy might: the raw header, JSON-escaped, the URL with its
        # password, the key percent-encoded. The runs it hits end as llm_error, message recorded.
        if srv.n_requests >= 4:
            auth = srv.auth_headers[-1] or ""
            return Fault(
                "status",
                400,
                message=(
                    f"upstream refused {auth!r} ({json.dumps(auth)}) for http://{USER}:{PASSWORD}@gateway/v1 "
                    f"and {quote(KEY, safe='')}"
                ),
            )
        return "[1, 1]"

    srv = FakeServer(reply=reply)
    with srv:
        code = cli.main(
            swim(with_password(srv.url), out, "--api-key-env", "MYKEY", "--cache-dir", str(cache))
        )
        sent = list(srv.auth_headers)
    printed = capsys.readouterr()
    assert sent and all(h == f"Bearer {KEY}" for h in sent)  # the key did reach the server
    assert code == 2  # a run failed (llm_error): reported in one line, the others kept
    rows = read_runs(out)
    assert any(r["status"] == "llm_error" for r in rows)
    failed = next(r for r in rows if r["status"] == "llm_error")
    assert "upstream refused" in json.dumps(failed)  # the server's message is kept, masked
    for where, text in (
        ("stdout", printed.out),
        ("stderr", printed.err),
        ("folder", folder_text(out)),
        ("cache", folder_text(cache) if cache.exists() else ""),
    ):
        assert not leaks(text, KEY, PASSWORD, f"{USER}:{PASSWORD}"), where
    meta = json.loads((out / "metadata.json").read_text())
    assert meta["server"] == srv.url  # the address, without the user info


@pytest.mark.parametrize(
    "value, what",
    [
        (KEY + "\r", "carriage return"),  # pasted from a Windows file
        (KEY + "\n", "line feed"),
        (" " + KEY, "space"),
        (KEY[:10] + "é" + KEY[10:], "non-ASCII"),
        (KEY[:10] + "\x1b" + KEY[10:], "control character"),
    ],
    ids=["cr", "lf", "space", "non-ascii", "escape"],
)
def test_a_key_no_header_can_carry_is_one_line_naming_the_variable(
    value, what, tmp_path, monkeypatch, capsys
):
    monkeypatch.setenv("MYKEY", value)
    with FakeServer() as srv:
        code = cli.main(swim(srv.url, tmp_path / "o", "--api-key-env", "MYKEY"))
        assert srv.n_requests == 0  # refused before any request: no retry loop
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1, err
    assert "$MYKEY" in err and what in err
    assert not leaks(err, value)
    assert not (tmp_path / "o").exists()


def test_an_unset_key_variable_is_an_error_for_a_remote_server_and_a_warning_here(
    tmp_path, monkeypatch, capsys
):
    monkeypatch.delenv("NO_SUCH_KEY", raising=False)
    code = cli.main(
        swim("https://api.example.invalid/v1", tmp_path / "r", "--api-key-env", "NO_SUCH_KEY")
    )
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "$NO_SUCH_KEY is not set" in err
    with FakeServer() as srv:
        assert cli.main(swim(srv.url, tmp_path / "l", "--api-key-env", "NO_SUCH_KEY")) == 0
        assert srv.n_requests > 0 and set(srv.auth_headers) == {None}
    err = capsys.readouterr().err
    assert "warning" in err and "$NO_SUCH_KEY is not set" in err


@pytest.mark.parametrize(
    "url",
    [
        f"ftp://{USER}:{PASSWORD}@host/v1",  # not http(s)
        f"http://{USER}:{PASSWORD}@host:99999/v1",  # bad port
        f"http://{USER}:{PASSWORD}@127.0.0.1:9/v1",  # nothing listens there
    ],
    ids=["not-http", "bad-port", "nothing-listens"],
)  # fixed ids: the password is new every run (xdist)
def test_a_password_in_the_base_url_is_never_echoed(url, tmp_path, capsys):
    code = cli.main(swim(url, tmp_path / "o"))
    printed = capsys.readouterr()
    assert code == 2
    assert not leaks(printed.out + printed.err, PASSWORD, f"{USER}:{PASSWORD}")
    assert not leaks(folder_text(tmp_path), PASSWORD, f"{USER}:{PASSWORD}")


def test_a_key_echoed_in_a_200_reply_is_scrubbed_before_anything_is_written(
    tmp_path, monkeypatch, capsys
):
    # A server (or proxy) quoting the request's credentials inside a normal answer.
    monkeypatch.setenv("MYKEY", KEY)
    out, cache = tmp_path / "study", tmp_path / "cache"
    srv: FakeServer

    def reply(body):
        return (
            f"[1, 1] (your key: {srv.auth_headers[-1]}, {json.dumps(KEY)}, {quote(KEY, safe='')})"
        )

    srv = FakeServer(reply=reply)
    with srv:
        code = cli.main(swim(srv.url, out, "--api-key-env", "MYKEY", "--cache-dir", str(cache)))
    printed = capsys.readouterr()
    assert code == 0, printed.err
    calls = [json.loads(ln) for ln in (out / "calls.jsonl").read_text().splitlines()]
    assert calls and all(
        c["raw"].startswith("[1, 1] (your key: Bearer") and "***" in c["raw"] for c in calls
    )
    for where, text in (
        ("stdout", printed.out),
        ("stderr", printed.err),
        ("folder", folder_text(out)),
        ("cache", folder_text(cache) if cache.exists() else ""),
    ):
        assert not leaks(text, KEY), where


def test_a_key_nobody_named_never_goes_to_another_host(tmp_path, monkeypatch, capsys):
    # $OPENAI_API_KEY is read when --api-key-env is left out only for api.openai.com.
    monkeypatch.setenv("OPENAI_API_KEY", KEY)
    with FakeServer() as srv:
        assert cli.main(swim(srv.url, tmp_path / "a")) == 0
        assert srv.n_requests > 0 and set(srv.auth_headers) == {None}
        # Named, it is sent.
        assert cli.main(swim(srv.url, tmp_path / "b", "--api-key-env", "OPENAI_API_KEY")) == 0
        assert f"Bearer {KEY}" in srv.auth_headers
        srv.reset_counts()
        capsys.readouterr()
        # --api-key-env '' names nothing: one line, nothing sent (it used to fall back to $OPENAI_API_KEY).
        assert cli.main(swim(srv.url, tmp_path / "c", "--api-key-env", "")) == 2
        assert srv.n_requests == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--api-key-env ''" in err[0]
    from jswim.cli.options import default_key_env

    assert default_key_env("https://api.openai.com/v1") == "OPENAI_API_KEY"
    assert default_key_env("https://openrouter.ai/api/v1") == ""


def test_a_key_variable_set_to_empty_is_said_to_be_empty(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("EMPTY_KEY", "")
    code = cli.main(
        swim("https://api.example.invalid/v1", tmp_path / "r", "--api-key-env", "EMPTY_KEY")
    )
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and "$EMPTY_KEY is set but empty" in err


def test_a_credential_given_as_a_request_field_is_sent_but_never_written(tmp_path, capsys):
    field_key = "sk-live-" + secrets.token_hex(12)
    out = tmp_path / "study"
    with FakeServer(reply=lambda body: "[1, 1]") as srv:
        args = swim(with_password(srv.url), out, "--extra-field", f"user={field_key}")
        args += ["--extra-field", "top_k=40"]
        assert cli.main(args) == 0
        got = [b.get("user") for b in srv.requests]
    printed = capsys.readouterr()
    assert got and all(u == field_key for u in got)  # the server still gets it
    for where, text in (
        ("stdout", printed.out),
        ("stderr", printed.err),
        ("folder", folder_text(out)),
    ):
        assert not leaks(text, field_key, PASSWORD), where
    meta = json.loads((out / "metadata.json").read_text())
    assert "top_k" in json.dumps(meta)  # ordinary fields are recorded as given


def test_encoded_and_partial_echoes_of_a_secret_are_scrubbed(monkeypatch):
    import asyncio

    from jswim.errors import LLMRequestError
    from jswim.llm.client import ClientSettings, LLMClient

    key = "sk-proj-abcdefghijklmn789XyZ"  # 27 characters; the echo keeps 14 of them
    monkeypatch.setenv("ECHOKEY", key)
    basic = "Basic " + base64.b64encode(f"{USER}:{PASSWORD}".encode()).decode()

    def refuse(body):
        return Fault(
            "status",
            401,
            message=f"Incorrect API key provided: sk-proj-****789XyZ. Sent: {quote(basic, safe='')}",
        )

    async def go(url: str, env: str):
        s = ClientSettings(base_url=url, model="fake", api_key_env=env)
        async with LLMClient(s) as c:
            await c.chat([{"role": "user", "content": "x"}])

    with FakeServer(reply=refuse) as srv:
        with pytest.raises(LLMRequestError) as err:
            asyncio.run(go(with_password(srv.url), "ECHOKEY"))
    text = str(err.value)
    assert "Incorrect API key" in text
    assert "789XyZ" not in text and "sk-proj-" not in text
    b64 = base64.b64encode(f"{USER}:{PASSWORD}".encode()).decode()
    assert quote(b64, safe="") not in text and b64.rstrip("=") not in text


def test_a_nan_request_field_is_one_line(capsys):
    code = cli.main(swim("http://127.0.0.1:9/v1", Path("/nonexistent"), "--extra-field", "x=NaN"))
    err = capsys.readouterr().err
    assert code == 2 and "x=" in err and "Traceback" not in err


def test_request_fields_are_masked_by_credential_name_or_key_shape_only():
    from jswim.llm.credentials import mask_fields

    fields = {
        "user": "alice-account",
        "api_key": "x1y2",
        "nested": {"password": "hunter2!"},
        "tokenizer": "llama",  # a word containing 'token' is no credential's name
        "keep_alive": "5m",
        "top_k": 40,
        "opaque": "tok_3f9a8b7c6d5e4f3a2b1c",  # shaped like a key, whatever its name
    }
    got = mask_fields(fields)
    assert got["user"] == got["api_key"] == got["nested"]["password"] == got["opaque"] == "***"
    assert got["tokenizer"] == "llama" and got["keep_alive"] == "5m" and got["top_k"] == 40
