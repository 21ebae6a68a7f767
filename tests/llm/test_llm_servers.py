"""The client against servers that behave as real ones do: one fake-server mode per behaviour.

Each test names the real behaviour it stands for (reasoning models, null or list content,
streams sent unasked, rejected fields, base-URL shapes, cold servers, context-length 400s,
caching) and asserts what the client must make of it.
"""

from __future__ import annotations

import asyncio
import json

import pytest

from jswim.errors import ConfigError
from jswim.llm.reasoning import REASONING_MAX_TOKENS
from jswim.llm.response_cache import ResponseCache
from jswim.llm.client import ClientSettings, LLMClient
from jswim.errors import LLMRequestError, LLMResponseError, LLMSetupError, LLMTimeoutError
from jswim.llm.server_response import (
    MalformedReply,
    assemble_sse,
    content_text,
    error_message,
    looks_like_sse,
    read_completion,
    split_reasoning,
)
from jswim.llm.urls import endpoint, normalize_base_url
from tests.fakeserver import MODES, THOUGHT, Answer, FakeServer

MSG = [{"role": "user", "content": "Reply with the next action as [changed DOF, ROC]"}]
REPLIES = ["[1, -1]", "[1, 0]", "[1, 1]", "[2, -1]", "[2, 0]", "[2, 1]"]


def settings(base: str, **kw) -> ClientSettings:
    kw = {
        "model": "fake",
        "backoff_base_s": 0.001,
        "backoff_max_s": 0.01,
        "timeout_s": 5.0,
        "api_key_env": "JSWIM_TEST_NO_KEY",
        **kw,
    }
    return ClientSettings(base_url=base, **kw)


def call(base: str, messages=MSG, chat_kw=None, **kw):
    async def go():
        async with LLMClient(settings(base, **kw)) as c:
            return await c.chat(messages, **(chat_kw or {}))

    return asyncio.run(go())


@pytest.fixture
def mode(request):
    with FakeServer(**MODES[request.param]) as srv:
        yield srv


# -- reasoning models ---------------------------------------------------------------------------


@pytest.mark.parametrize(
    "mode",
    ["think", "think-no-open-tag", "reasoning-field", "parts", "stream-always"],
    indirect=True,
)
def test_reasoning_is_kept_apart_from_the_answer(mode):
    res = call(mode.url)
    assert res.text == "[2, -1]"  # the answer, not the [1, 1] inside the reasoning
    assert THOUGHT in res.reasoning and "[1, 1]" not in res.text
    assert res.as_dict()["reasoning"] == res.reasoning  # kept for the transcript
    assert not res.truncated and mode.n_requests == 1


@pytest.mark.parametrize("mode", ["null-length", "empty-length", "think-length"], indirect=True)
def test_a_cut_off_reply_is_no_answer_and_is_not_resent(mode, tmp_path):
    res = call(mode.url, cache_dir=str(tmp_path))
    assert res.truncated and res.finish_reason == "length" and res.text == ""
    assert mode.n_requests == 1  # a well-formed reply: not retried as if the transport failed
    assert len(ResponseCache(tmp_path)) == 0  # never cached
    again = call(mode.url, cache_dir=str(tmp_path))
    assert not again.cache_hit and mode.n_requests == 2


def test_content_null_keeps_reasoning_field():
    with FakeServer(**MODES["null-length"]) as srv:
        res = call(srv.url)
    assert res.reasoning == THOUGHT and res.raw == ""


# -- streams --------------------------------------------------------------------------------


@pytest.mark.parametrize("mode", ["stream-default"], indirect=True)
def test_stream_false_is_sent(mode):
    res = call(mode.url)
    assert mode.requests[0]["stream"] is False
    assert res.text == "[2, -1]" and res.usage.completion_tokens > 0


@pytest.mark.parametrize("fast", [True, False], ids=["asyncio", "httpx-default"])
def test_a_stream_sent_anyway_is_assembled(fast):
    with FakeServer(**MODES["stream-always"]) as srv:
        res = call(srv.url, fast_transport=fast)
    assert res.text == "[2, -1]" and res.reasoning == THOUGHT
    assert res.finish_reason == "stop" and res.usage.prompt_tokens == 9


def test_stream_with_cut_off_reasoning():
    with FakeServer(
        reply=lambda b: Answer(None, "length", (("reasoning_content", THOUGHT),)), stream="always"
    ) as srv:
        res = call(srv.url)
    assert res.truncated and res.text == "" and res.reasoning == THOUGHT


# -- rejected fields ------------------------------------------------------------------------


def _one_line(err: Exception) -> str:
    msg = str(err)
    assert "\n" not in msg and "Traceback" not in msg
    return msg


@pytest.mark.parametrize("mode", ["reject-grammar"], indirect=True)
def test_rejected_grammar_names_the_server_and_the_option(mode):
    with pytest.raises(LLMSetupError) as err:  # asked for by name: sent as asked, no fallback
        call(mode.url, chat_kw={"replies": REPLIES}, server_kind="llamacpp", constrain="grammar")
    msg = _one_line(err.value)
    assert "Unrecognized request argument supplied: grammar" in msg and "--constrain none" in msg
    assert err.value.field == "grammar" and err.value.status == 400 and mode.n_requests == 1
    res = call(mode.url, chat_kw={"replies": REPLIES}, server_kind="llamacpp", constrain="none")
    assert res.text == "[2, -1]" and "grammar" not in mode.requests[-1]


@pytest.mark.parametrize("mode", ["reject-seed"], indirect=True)
def test_rejected_seed_names_the_option(mode):
    with pytest.raises(LLMSetupError) as err:
        call(mode.url, chat_kw={"temperature": 0.7, "seed": 5})
    msg = _one_line(err.value)
    assert (
        "'seed' is not supported" in msg
        and "--omit-field seed" in msg
        and err.value.field == "seed"
    )
    res = call(mode.url, chat_kw={"temperature": 0.7, "seed": 5}, omit_fields=("seed",))
    assert res.text == "[2, -1]" and "seed" not in mode.requests[-1]


@pytest.mark.parametrize("mode", ["reject-max-tokens"], indirect=True)
def test_rejected_max_tokens_names_the_option(mode):
    res = call(mode.url)  # --reasoning auto (the default): sent again with max_completion_tokens
    assert res.text == "[2, -1]" and "max_tokens" not in mode.requests[-1]
    assert mode.requests[-1]["max_completion_tokens"] == REASONING_MAX_TOKENS
    with pytest.raises(LLMSetupError) as err:
        call(mode.url, reasoning="off")
    msg = _one_line(err.value)
    assert (
        "max_completion_tokens" in msg
        and "--omit-field max_tokens" in msg
        and "--reasoning auto" in msg
    )
    assert call(mode.url, reasoning="off", omit_fields=("max_tokens",)).text == "[2, -1]"
    assert "max_tokens" not in mode.requests[-1]


def test_required_fields_cannot_be_left_out():
    with pytest.raises(ConfigError, match="messages"):
        settings("http://127.0.0.1:1/v1", omit_fields=("messages",))


@pytest.mark.parametrize("mode", ["context-400"], indirect=True)
def test_context_length_400_is_a_per_request_error(mode):
    history = "\n".join(
        f"{k}: (1.047, 1.047) [1, -1] -> (-1.047, 1.047), X 2500 -> 2500" for k in (1, 2)
    )
    with pytest.raises(LLMRequestError) as err:
        call(mode.url, messages=[{"role": "user", "content": "Prompt.\n" + history}])
    assert not isinstance(err.value, LLMSetupError)  # only this run's prompt is too long
    msg = _one_line(err.value)
    assert "maximum context length is 64 tokens" in msg and "--n-ht" in msg
    assert mode.n_requests == 1


def test_auth_and_unknown_model_are_setup_errors(monkeypatch):
    with FakeServer() as srv:
        srv.add_faults(
            srv_fault(401, "Invalid API key"),
            srv_fault(401, "Invalid API key"),
            srv_fault(401, "Invalid API key"),
            srv_fault(404, "The model `gpt-5` does not exist"),
        )
        monkeypatch.delenv("JSWIM_TEST_NO_KEY", raising=False)
        with pytest.raises(
            LLMSetupError, match=r"HTTP 401: Invalid API key; \$JSWIM_TEST_NO_KEY .* is not set"
        ):
            call(srv.url)
        monkeypatch.setenv("JSWIM_TEST_NO_KEY", "")
        with pytest.raises(LLMSetupError, match=r"\$JSWIM_TEST_NO_KEY .* is set but empty"):
            call(srv.url)
        monkeypatch.setenv("JSWIM_TEST_NO_KEY", "sk-wrong")
        with pytest.raises(
            LLMSetupError,
            match=r"HTTP 401: Invalid API key; check the API key in \$JSWIM_TEST_NO_KEY",
        ):
            call(srv.url)
        monkeypatch.delenv("JSWIM_TEST_NO_KEY")
        with pytest.raises(LLMSetupError, match=r"no model 'fake'.*check --model"):
            call(srv.url)


def srv_fault(status, message):
    from tests.fakeserver import Fault

    return Fault.server_error(status, message)


def test_html_body_is_reported_with_its_type():
    with FakeServer() as srv:
        from tests.fakeserver import Fault

        srv.add_faults(*[Fault.malformed()] * 3)
        with pytest.raises(LLMResponseError, match="not a chat completion") as err:
            call(srv.url, max_retries=2)
        _one_line(err.value)


# -- base URLs ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "shape",
    [
        "http://127.0.0.1:{port}/v1",
        "http://127.0.0.1:{port}",  # no /v1
        "http://127.0.0.1:{port}/",
        "http://127.0.0.1:{port}/v1/chat/completions",  # the full endpoint
        "127.0.0.1:{port}/v1",  # no scheme
        "localhost:{port}",
    ],
)
def test_base_url_shapes_are_accepted(shape):
    with FakeServer(**MODES["plain"]) as srv:
        res = call(shape.format(port=srv.port))
        assert res.text == "[2, -1]" and srv.n_requests == 1


def test_wrong_path_names_the_url_tried():
    with FakeServer(**MODES["plain"]) as srv:
        with pytest.raises(LLMSetupError) as err:
            call(f"http://127.0.0.1:{srv.port}/api")
    msg = _one_line(err.value)
    assert (
        f"http://127.0.0.1:{srv.port}/api/chat/completions" in msg
        and "HTTP 404" in msg
        and "/v1" in msg
    )


@pytest.mark.parametrize(
    "written, used",
    [
        ("http://localhost:8080/v1", "http://localhost:8080/v1"),
        ("http://localhost:8080", "http://localhost:8080/v1"),
        ("http://host:8000/v1/chat/completions/", "http://host:8000/v1"),
        ("localhost:11434/v1", "http://localhost:11434/v1"),
        ("192.168.1.20:8000", "http://192.168.1.20:8000/v1"),
        ("gpu-box:8000/v1", "http://gpu-box:8000/v1"),
        ("api.openai.com/v1", "https://api.openai.com/v1"),
        ("HTTPS://Example.com/openai/v1", "https://Example.com/openai/v1"),
        (
            "https://r.example.com/openai/deployments/x?api-version=2024-06-01",
            "https://r.example.com/openai/deployments/x?api-version=2024-06-01",
        ),
    ],
)
def test_normalize_base_url(written, used):
    assert normalize_base_url(written) == used


def test_endpoint_keeps_the_query():
    assert (
        endpoint("https://r.example.com/dep?api-version=1")
        == "https://r.example.com/dep/chat/completions?api-version=1"
    )


@pytest.mark.parametrize("bad", ["", "   ", "ftp://host/v1", "http:///v1", "http://host:99999/v1"])
def test_bad_base_urls_say_what_to_write(bad):
    with pytest.raises(ConfigError, match="http://localhost:8080/v1"):
        normalize_base_url(bad)


# -- slow servers ---------------------------------------------------------------------------


@pytest.mark.parametrize("mode", ["cold"], indirect=True)
def test_cold_server_timeouts_are_bounded_by_the_retry_budget_and_say_slow(mode):
    with pytest.raises(LLMTimeoutError) as err:
        call(mode.url, timeout_s=0.3, max_retries=2)
    msg = _one_line(err.value)
    assert "slow" in msg and "--timeout" in msg and "0.3 s" in msg and "--retries 2" in msg
    assert "gave up after 3 attempts" in msg
    assert mode.n_requests == 3  # timeouts count against --retries like any transient failure
    assert mode.n_answered == 0  # gave up before the server warmed up (it never got to answer)


@pytest.mark.parametrize("mode", ["cold"], indirect=True)
def test_cold_server_timeouts_are_ridden_out_within_the_retry_budget(mode):
    # The server answers nothing for its first 1.5 s; 0.3 s timeouts are retried at once.
    res = call(mode.url, timeout_s=0.3, max_retries=20)
    assert res.text == "[2, -1]" and res.retries >= 3 and mode.n_requests == res.retries + 1


@pytest.mark.parametrize("mode", ["cold"], indirect=True)
def test_cold_server_with_a_longer_timeout_works(mode):
    res = call(mode.url, timeout_s=5.0)
    assert res.text == "[2, -1]" and res.retries == 0


def test_timeout_settings_are_recorded():
    meta = settings("http://127.0.0.1:1/v1", timeout_s=120, omit_fields=("seed",)).metadata()
    assert (
        meta["timeout_s"] == 120 and meta["omit_fields"] == ["seed"] and meta["max_retries"] == 20
    )


# -- caching only answers -------------------------------------------------------------------


def test_cache_keeps_only_replies_the_caller_accepts(tmp_path):
    with FakeServer(reply=lambda b: "no idea") as srv:
        call(srv.url, cache_dir=str(tmp_path), chat_kw={"cache_if": lambda r: "[" in r.text})
        assert len(ResponseCache(tmp_path)) == 0
        srv.reply = lambda b: "[2, -1]"
        first = call(
            srv.url, cache_dir=str(tmp_path), chat_kw={"cache_if": lambda r: "[" in r.text}
        )
        assert first.text == "[2, -1]" and not first.cache_hit
        second = call(srv.url, cache_dir=str(tmp_path))
        assert second.cache_hit and second.text == "[2, -1]" and srv.n_requests == 2


def test_cache_restores_reasoning(tmp_path):
    with FakeServer(**MODES["think"]) as srv:
        call(srv.url, cache_dir=str(tmp_path))
        hit = call(srv.url, cache_dir=str(tmp_path))
    assert (
        hit.cache_hit
        and hit.text == "[2, -1]"
        and THOUGHT in hit.reasoning
        and "<think>" in hit.raw
    )


def test_json_schema_answer_after_reasoning():
    with FakeServer(reply=lambda b: "<think>" + THOUGHT + '</think>{"action": "[2, 0]"}') as srv:
        res = call(srv.url, chat_kw={"replies": REPLIES}, constrain="json_schema")
    assert res.text == "[2, 0]" and THOUGHT in res.reasoning


# -- the pure readers -----------------------------------------------------------------------


@pytest.mark.parametrize(
    "content, reasoning, answer",
    [
        ("[2, -1]", "", "[2, -1]"),
        ("<think>no [1, 1]</think>\n[2, -1]", "no [1, 1]", "[2, -1]"),
        ("<THINKING>no [1, 1]</THINKING> [2, -1]", "no [1, 1]", "[2, -1]"),
        ("no [1, 1]</think>[2, -1]", "no [1, 1]", "[2, -1]"),  # opening tag was in the template
        ("<think>no [1, 1], maybe", "no [1, 1], maybe", ""),  # cut off while thinking
        (
            "<think>a</think>[1, 1]<think>b</think>[2, -1]",
            "a\n\n[1, 1]\n\nb",
            "[2, -1]",
        ),  # the last block
        ("<reasoning>r</reasoning>[2, 0]", "r", "[2, 0]"),
        (
            "<|channel|>analysis<|message|>not [1, 1]<|end|><|start|>assistant<|channel|>final<|message|>[2, 1]",
            "analysis not [1, 1] assistant",
            "[2, 1]",
        ),
    ],
)
def test_split_reasoning(content, reasoning, answer):
    got_reasoning, got_answer = split_reasoning(content)
    assert got_answer == answer
    assert " ".join(got_reasoning.split()) == " ".join(reasoning.split())


def test_content_shapes():
    assert content_text(None) == ("", "")
    assert content_text([{"type": "text", "text": "[1, "}, {"type": "text", "text": "1]"}]) == (
        "[1, 1]",
        "",
    )
    assert content_text(
        [{"type": "thinking", "thinking": "hm"}, {"type": "output_text", "text": "x"}]
    ) == ("x", "hm")
    assert content_text([{"type": "image_url", "image_url": {}}, "y"]) == ("y", "")
    with pytest.raises(MalformedReply):
        content_text(3)


def test_read_completion_shapes():
    legacy = read_completion({"choices": [{"text": "[1, 0]", "finish_reason": "stop"}]})
    assert legacy.answer == "[1, 0]"
    refusal = read_completion({"choices": [{"message": {"content": None, "refusal": "I can't"}}]})
    assert refusal.answer == "I can't" and refusal.finish_reason is None
    both = read_completion(
        {"choices": [{"message": {"content": "<think>b</think>[2, 1]", "reasoning": "a"}}]}
    )
    assert both.reasoning == "a\n\nb" and both.answer == "[2, 1]"
    for bad in ({}, {"choices": []}, {"choices": [{}]}, [], {"error": {"message": "overloaded"}}):
        with pytest.raises(MalformedReply):
            read_completion(bad)


def test_assemble_sse():
    events = [
        {"choices": [{"index": 0, "delta": {"role": "assistant", "reasoning_content": "thin"}}]},
        {"choices": [{"index": 0, "delta": {"reasoning_content": "king"}}]},
        {"choices": [{"index": 0, "delta": {"content": "[2, "}}]},
        {"choices": [{"index": 0, "delta": {"content": "-1]"}, "finish_reason": "stop"}]},
        {"choices": [], "usage": {"prompt_tokens": 3, "completion_tokens": 4}},
    ]
    text = ": ping\n\n" + "".join(f"data: {json.dumps(e)}\n\n" for e in events) + "data: [DONE]\n\n"
    assert looks_like_sse("text/event-stream; charset=utf-8", "") and looks_like_sse("", text)
    done = read_completion(assemble_sse(text), streamed=True)
    assert (
        done.answer == "[2, -1]" and done.reasoning == "thinking" and done.finish_reason == "stop"
    )
    assert done.usage == {"prompt_tokens": 3, "completion_tokens": 4} and done.streamed
    with pytest.raises(MalformedReply, match="overloaded"):
        assemble_sse('data: {"error": {"message": "overloaded"}}\n\n')
    with pytest.raises(MalformedReply):
        assemble_sse("data: [DONE]\n\n")


def test_error_message_shapes():
    assert error_message({"error": {"message": "bad  field\n grammar"}}) == "bad field grammar"
    assert error_message(
        {"detail": [{"loc": ["body", "seed"], "msg": "extra inputs are not permitted"}]}
    ) == ("seed: extra inputs are not permitted")
    assert error_message({"detail": "Not Found"}) == "Not Found"
    assert error_message({"error": "model not loaded"}) == "model not loaded"


# -- backend settings -----------------------------------------------------------------------


def test_backend_checks_its_settings_up_front(tmp_path):
    from jswim.llm.backend import Backend

    not_gguf = tmp_path / "model.gguf"
    not_gguf.write_text("<html>a download page</html>")
    with pytest.raises(ConfigError, match="not a GGUF model file"):
        Backend(gguf=str(not_gguf))
    real = tmp_path / "ok.gguf"
    real.write_bytes(b"GGUF\x03\x00\x00\x00")
    assert Backend(gguf=str(real)).gguf == str(real)  # only the header is read here
    b = Backend(base_url="localhost:8080", model="m", timeout_s=300, omit_fields=("seed", "seed"))
    assert b.base_url == "http://localhost:8080/v1" and b.omit_fields == ("seed",)
    s = b.client_settings()
    assert (s.timeout_s, s.omit_fields) == (300, ("seed",))
    # defaults add nothing to the identity; the address is not part of it (Backend.address)
    assert Backend(base_url="http://h/v1", model="m").describe().keys() == {
        "kind",
        "model",
        "constrain",
        "temperature",
    }
    with pytest.raises(ConfigError, match="--timeout"):
        Backend(base_url="http://h/v1", model="m", timeout_s=0)
    with pytest.raises(ConfigError, match="--omit-field model"):
        Backend(base_url="http://h/v1", model="m", omit_fields=("model",))


def test_preflight_says_slow_when_the_server_does_not_answer():
    import socket

    from jswim.llm.backend import check_server

    with socket.socket() as s:  # accepts connections (backlog) but never answers
        s.bind(("127.0.0.1", 0))
        s.listen(4)
        port = s.getsockname()[1]
        with pytest.raises(LLMTimeoutError, match="slow.*--timeout") as err:
            check_server(f"127.0.0.1:{port}", 0.3)
    assert f"http://127.0.0.1:{port}/v1/models" in str(err.value)


# -- server families, validation errors, sampling ----------------------------------------------


def test_essential_message_drops_tracebacks_and_paths():
    from jswim.llm.rejection import essential_message

    # llama-cpp-python 0.3.36's real 500 body for --constrain json_schema (error.message as sent).
    real = (
        "1 validation error:\n  {'type': 'literal_error', 'loc': ('body', 'response_format', 'type'), "
        "'msg': \"Input should be 'text' or 'json_object'\", 'input': 'json_schema', 'ctx': {'expected': "
        "\"'text' or 'json_object'\"}}\n\n  File \"/tmp/venv/lib/python3.11/site-packages/llama_cpp/server/"
        'app.py", line 376, in create_chat_completion\n    POST /v1/chat/completions'
    )
    assert (
        essential_message(real) == "response_format.type: Input should be 'text' or 'json_object'"
    )
    from tests.fakeserver import VALIDATION_500

    assert (
        essential_message(VALIDATION_500)
        == "response_format.type: Input should be 'text' or 'json_object'"
    )
    bare = (
        'Traceback (most recent call last):\n  File "/srv/app/main.py", line 3, in f\n    x()\n'
        "ValueError: top_k is not supported by /srv/app/models/x.py"
    )
    assert essential_message(bare) == "ValueError: top_k is not supported by <path>"
    assert essential_message("Unrecognized request argument supplied: grammar") == (
        "Unrecognized request argument supplied: grammar"
    )


@pytest.mark.parametrize(
    "status, body, words",
    [
        (
            500,
            {
                "error": {
                    "message": "1 validation error for X\nresponse_format.type\n  Input should be 'text' "
                    "[type=literal_error]",
                    "type": "internal_server_error",
                }
            },
            "response_format.type: Input should be 'text'",
        ),
        (
            422,
            {
                "detail": [
                    {
                        "type": "extra_forbidden",
                        "loc": ["body", "top_k"],
                        "msg": "Extra inputs are not permitted",
                    }
                ]
            },
            "top_k: Extra inputs are not permitted",
        ),
        (
            503,
            {"error": {"message": "min_p is not supported by this backend"}},
            "min_p is not supported",
        ),
    ],
)
def test_a_validation_body_is_a_rejection_whatever_its_status(status, body, words):
    from tests.fakeserver import Fault

    with FakeServer(reply=lambda b: Fault("status", status, body=body)) as srv:
        with pytest.raises(LLMSetupError) as err:
            call(srv.url, sampling=(("top_k", 0), ("min_p", 0.0)))
        assert srv.n_requests == 1  # not retried (a 5xx fault would be sent 5 times)
    msg = _one_line(err.value)
    assert words in msg and err.value.status == status


def test_probe_tells_server_families_apart():
    from jswim.llm.probe import probe
    from tests.fakeserver import LLAMACPP_PROPS

    cases = [
        ({"owned_by": "vllm"}, "vllm"),
        ({"owned_by": "library"}, "ollama"),
        ({"owned_by": "me"}, "llama-cpp-python"),
        ({"props": LLAMACPP_PROPS}, "llamacpp"),
        ({"owned_by": "organization_owner"}, "generic"),
        ({}, "generic"),
    ]
    for kw, family in cases:
        with FakeServer(**kw) as srv:
            info = probe(srv.url, api_key_env="JSWIM_TEST_NO_KEY")
        assert info.family == family, (kw, info)
    with FakeServer(owned_by="vllm") as srv:
        assert probe(srv.url, family="llamacpp").family == "llamacpp"  # forced
    with FakeServer(props=LLAMACPP_PROPS) as srv:
        info = probe(srv.url)
    assert info.total_slots == 2 and info.slots == 2 and info.settings["min_p"] == 0.05
    assert "samplers" not in info.settings  # scalars only


def test_sampling_fields_per_family():
    from jswim.llm.sampling import sampling_fields

    llama = dict(sampling_fields("auto", "llama-cpp-python"))
    assert llama == {
        "repeat_penalty": 1.0,
        "top_k": 0,
        "top_p": 1.0,
        "min_p": 0.0,
        "presence_penalty": 0.0,
        "frequency_penalty": 0.0,
    }
    assert dict(sampling_fields("auto", "vllm"))["repetition_penalty"] == 1.0
    assert dict(sampling_fields("auto", "vllm"))["top_k"] == -1  # vLLM's "off"
    assert sampling_fields("auto", "openai") == () and sampling_fields("neutral", "openai") == ()
    assert sampling_fields("auto", "generic") == () and sampling_fields("server", "llamacpp") == ()
    # The embedded server: its own penalty defaults are the neutral ones; truncations kept.
    assert dict(sampling_fields("auto", "llamacpp", embedded=True)) == {
        "repeat_penalty": 1.0,
        "presence_penalty": 0.0,
        "frequency_penalty": 0.0,
    }
