"""Replies and bodies real servers send, each a kind with a fake-server mode: a Content-Encoding
header that lies, token counts that are not numbers, answers in non-ASCII brackets or digits."""

from __future__ import annotations

import asyncio
import gzip
import zlib

import pytest

from jswim import cli
from jswim.llm.client import ClientSettings, LLMClient, decode_body
from jswim.llm.usage import Usage
from jswim.prompt import Action, parse_reply
from jswim.results import read_runs
from tests.fakeserver import MODES, FakeServer

MSG = [{"role": "user", "content": "Say [2, -1]"}]


def one_call(url: str):
    async def go():
        async with LLMClient(ClientSettings(base_url=url, model="fake", max_retries=0)) as c:
            return await c.chat(MSG)

    return asyncio.run(go())


def test_a_body_its_content_encoding_misnames_is_read_as_sent():
    with FakeServer(**MODES["lying-encoding"]) as srv:
        res = one_call(srv.url)
        assert srv.n_requests == 1  # read the first time: no retry, no call paid twice
    assert res.text == "[2, -1]" and res.usage.prompt_tokens > 0


@pytest.mark.parametrize(
    "encode, header",
    [
        (gzip.compress, "gzip"),
        (zlib.compress, "deflate"),
        (lambda b: zlib.compress(b)[2:-4], "deflate"),  # raw deflate
        (lambda b: b, "identity"),
        (lambda b: b, "gzip"),
        (lambda b: b, "br"),  # lies and unknowns: as sent
    ],
)
def test_decode_body_undoes_what_it_can_and_keeps_the_rest(encode, header):
    body = b'{"choices": []}'
    assert decode_body(encode(body), header) == body


def test_token_counts_that_are_not_numbers_are_read_as_missing():
    with FakeServer(**MODES["usage-not-numbers"]) as srv:
        res = one_call(srv.url)
    assert res.text == "[2, -1]" and res.usage == Usage(0, 0, 0) and res.cost_usd == 0.0
    got = Usage.from_response(
        {
            "prompt_tokens": "12",
            "completion_tokens": 3.0,
            "prompt_tokens_details": {"cached_tokens": float("nan")},
        }
    )
    assert got == Usage(12, 3, 0)
    assert Usage.from_response({"prompt_tokens": True, "completion_tokens": -4}) == Usage(0, 0, 0)


@pytest.mark.parametrize(
    "text, action",
    [
        ("\uff3b\uff12\uff0c\uff0d\uff11\uff3d", Action(2, -1)),  # fullwidth ［２，－１］
        ("\uff3b1, 1\uff3d", Action(1, 1)),  # fullwidth brackets, ASCII digits
        ("[\uff12, \u22121]", Action(2, -1)),  # fullwidth digit, Unicode minus
        ("answer: \uff12, -1", Action(2, -1)),
        ("[\u0662, -\u0661]", None),  # Arabic-Indic digits: not read
        ("[\u0968, \u0967]", None),  # Devanagari digits: not read
        ("[2, -\u0661]", None),  # one foreign digit makes the pair unreadable, never half read
    ],
)
def test_which_characters_are_read_as_the_answer(text, action):
    assert parse_reply(text) == action


@pytest.mark.parametrize("mode, good", [("fullwidth", True), ("arabic-digits", False)])
def test_swim_reads_fullwidth_answers_and_refuses_other_digits(mode, good, tmp_path, capsys):
    with FakeServer(**MODES[mode]) as srv:
        rc = cli.main(
            [
                "swim",
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
                "--out",
                str(tmp_path / "o"),
                "--base-url",
                srv.url,
                "--model",
                "fake",
                "--constrain",
                "none",
            ]
        )
    assert rc == 0, capsys.readouterr().err
    (row,) = read_runs(tmp_path / "o")
    if good:
        assert row["actions"] == [[2, -1]] * 12 and row["failed_steps"] == 0
    else:
        assert (
            row["failed_steps"] == 12 and row["actions"] == [[1, 0]] * 12
        )  # no-op steps, no misread move
