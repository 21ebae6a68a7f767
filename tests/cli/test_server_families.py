"""Same model, another server: `jswim swim` end to end against servers that differ as real ones do.

One fake-server mode per behaviour (tests/fakeserver.py): a validation error sent as HTTP 500,
a server that runs its one model under any name, a default repeat penalty that changes the
greedy reply, a key refused at the preflight, llama.cpp's /props with its slots.
"""

from __future__ import annotations

import json

import pytest

from jswim import cli
from jswim.results import read_metadata, read_runs
from tests.fakeserver import GGUF_ID, MODES, FakeServer

FAST = [
    "--steps",
    "4",
    "--runs",
    "2",
    "--q-runs",
    "2",
    "--swimmer",
    "purcell",
    "--direction",
    "+x",
    "--no-figures",
]
GOOD = [2, -1]  # what every mode answers when it is asked right
KEY_ENV = "JSWIM_TEST_FAMILY_KEY"


def swim(url: str, out, *extra: str, model: str = "fake") -> int:
    return cli.main(
        [
            "swim",
            *FAST,
            "--out",
            str(out),
            "--base-url",
            url,
            "--model",
            model,
            "--api-key-env",
            KEY_ENV,
            *extra,
        ]
    )


def llm_rows(out):
    return [r for r in read_runs(out) if r["agent"] == "llm"]


def one_line_error(err: str) -> str:
    assert "Traceback" not in err
    lines = [ln for ln in err.splitlines() if ln.startswith("jswim: error:")]
    assert len(lines) == 1, err
    return lines[0]


@pytest.fixture(autouse=True)
def no_key(monkeypatch):
    monkeypatch.delenv(KEY_ENV, raising=False)


# -- a validation error sent as HTTP 500 ---------------------------------------------------------


def test_validation_error_as_500_is_a_rejection_in_one_line(tmp_path, capsys):
    with FakeServer(**MODES["validation-500"]) as srv:
        assert swim(srv.url, tmp_path / "o", "--constrain", "json_schema") == 2
        sent = len(srv.requests)
    line = one_line_error(capsys.readouterr().err)
    assert "response_format.type: Input should be 'text' or 'json_object'" in line
    assert (
        "HTTP 500" in line
        and "--constrain auto" in line
        and "--constrain grammar/json_object" in line
    )
    assert (
        "site-packages" not in line
        and "/opt/venv" not in line
        and "errors.pydantic.dev" not in line
    )
    assert sent <= 2  # one per run at most: never retried (a passing fault would be sent 5 times)
    assert not llm_rows(tmp_path / "o")
    assert "Input should be" in read_metadata(tmp_path / "o")["error"]


def test_constrain_auto_falls_back_to_a_form_the_server_takes(tmp_path, capsys):
    # Told it is vLLM, auto starts with json_schema; the server takes json_object with a schema.
    with FakeServer(**MODES["validation-500"]) as srv:
        assert swim(srv.url, tmp_path / "o", "--server-family", "vllm") == 0, (
            capsys.readouterr().err
        )
        forms = [(b.get("response_format") or {}).get("type") for b in srv.requests]
    out = capsys.readouterr().out
    # Two runs are in flight, so each may send json_schema once before the client has learned the
    # server's form, and in any order (one run's json_schema can arrive after the other's
    # json_object); after that every call is json_object: 4 steps x 2 runs, each answered once.
    assert forms.count("json_schema") <= 2 and forms.count("json_object") == 8  # settled on it
    assert len(forms) == forms.count("json_schema") + 8
    rows = llm_rows(tmp_path / "o")
    assert all(r["actions"] == [GOOD] * 4 and r["constraint"] == "json_object" for r in rows)
    server = read_metadata(tmp_path / "o")["llm_server"]
    assert (
        server["family"] == "vllm" and server["constrain_fallbacks"][0]["rejected"] == "json_schema"
    )
    assert "rejected json_schema" in out and "moved on to json_object" in out


def test_constrain_auto_uses_grammar_on_llama_cpp_python(tmp_path, capsys):
    with FakeServer(**MODES["validation-500"]) as srv:
        assert swim(srv.url, tmp_path / "o") == 0, capsys.readouterr().err
        assert all("grammar" in b and "response_format" not in b for b in srv.requests)
    meta = read_metadata(tmp_path / "o")
    assert (
        meta["llm_server"]["family"] == "llama-cpp-python"
        and "owned_by 'me'" in meta["llm_server"]["detected_by"]
    )
    assert {r["constraint"] for r in llm_rows(tmp_path / "o")} == {"grammar"}


# -- a server that runs its one model under any name --------------------------------------------


def test_a_model_the_server_does_not_list_is_a_warning_and_is_not_priced(tmp_path, capsys):
    with FakeServer(**MODES["echo-any-model"]) as srv:
        # --price-local: as if this were a gateway to a paid API; still not priced as gpt-4.
        assert swim(srv.url, tmp_path / "o", "--price-local", model="gpt-4") == 0
    cap = capsys.readouterr()
    warning = [ln for ln in cap.err.splitlines() if ln.startswith("jswim: warning:")]
    assert any(
        "does not list the model 'gpt-4'" in ln and GGUF_ID in ln and "--strict-model" in ln
        for ln in warning
    )
    meta = read_metadata(tmp_path / "o")
    assert meta["summary"]["llm_speed"]["study_cost_usd"] == 0.0
    assert (
        "does not list 'gpt-4'" in meta["llm_server"]["unpriced"]
        and "cost: the server does not list" in cap.out
    )
    assert meta["llm_server"]["models"] == [GGUF_ID]


def test_a_local_server_is_not_priced_at_a_cloud_list_price(tmp_path, capsys):
    with FakeServer(**{**MODES["echo-any-model"], "models": ("gpt-4",)}) as srv:
        assert swim(srv.url, tmp_path / "o", model="gpt-4") == 0
        assert read_metadata(tmp_path / "o")["summary"]["llm_speed"]["study_cost_usd"] == 0.0
        assert "--price-local" in capsys.readouterr().out
        assert swim(srv.url, tmp_path / "o2", "--price-local", model="gpt-4") == 0  # asked: priced
        assert read_metadata(tmp_path / "o2")["summary"]["llm_speed"]["study_cost_usd"] > 0


def test_strict_model_stops_before_the_baselines(tmp_path, capsys):
    with FakeServer(**MODES["echo-any-model"]) as srv:
        assert swim(srv.url, tmp_path / "o", "--strict-model", model="gpt-4") == 2
        assert srv.n_requests == 0
    line = one_line_error(capsys.readouterr().err)
    assert "does not list the model 'gpt-4'" in line and GGUF_ID in line
    assert read_runs(tmp_path / "o") == []  # no baseline ran either


# -- a default repeat penalty that changes the greedy reply --------------------------------------


def test_neutral_sampling_makes_greedy_mean_greedy(tmp_path, capsys):
    with FakeServer(**MODES["repeat-penalty"]) as srv:
        assert swim(srv.url, tmp_path / "o") == 0
        sent = srv.requests[-1]
        assert swim(srv.url, tmp_path / "s", "--sampling", "server") == 0
        assert not any(
            "repeat_penalty" in b or "top_k" in b
            for b in srv.requests[len(srv.requests) // 2 + 1 :]
        )
    out = capsys.readouterr().out
    assert (sent["repeat_penalty"], sent["top_k"], sent["top_p"], sent["min_p"]) == (
        1.0,
        0,
        1.0,
        0.0,
    )
    assert sent["presence_penalty"] == 0.0 and sent["frequency_penalty"] == 0.0
    assert all(r["actions"] == [GOOD] * 4 for r in llm_rows(tmp_path / "o"))
    assert all(
        r["actions"] == [[1, 0]] * 4 for r in llm_rows(tmp_path / "s")
    )  # the server's own default
    meta = read_metadata(tmp_path / "o")["llm_server"]
    assert meta["sampling"] == {
        "preset": "auto",
        "sent": {
            "repeat_penalty": 1.0,
            "top_k": 0,
            "top_p": 1.0,
            "min_p": 0.0,
            "presence_penalty": 0.0,
            "frequency_penalty": 0.0,
        },
    }
    assert "sampling: auto for a llama-cpp-python server: repeat_penalty=1" in out
    assert read_metadata(tmp_path / "s")["llm_server"]["sampling"]["sent"] == {}
    transcript = (
        (tmp_path / "o" / "transcripts").glob("*.jsonl").__next__().read_text().splitlines()
    )
    assert (
        json.loads(transcript[0])["client"]["sampling"]["repeat_penalty"] == 1.0
    )  # in every run's record


def test_nothing_extra_for_an_unknown_server(tmp_path):
    with FakeServer(**MODES["plain"]) as srv:
        assert swim(srv.url, tmp_path / "o") == 0
        assert not any(k in srv.requests[0] for k in ("repeat_penalty", "top_k", "top_p", "min_p"))
        assert (
            swim(srv.url, tmp_path / "n", "--sampling", "neutral") == 0
        )  # the OpenAI API's own fields
        assert srv.requests[-1]["top_p"] == 1.0 and "repeat_penalty" not in srv.requests[-1]


# -- a key refused at the preflight --------------------------------------------------------------


def test_refused_key_stops_at_the_preflight_naming_the_variable(tmp_path, capsys, monkeypatch):
    with FakeServer(**MODES["auth-401"]) as srv:
        assert swim(srv.url, tmp_path / "o") == 2
        line = one_line_error(capsys.readouterr().err)
        assert (
            "HTTP 401" in line
            and "preflight" in line
            and f"${KEY_ENV}" in line
            and "is not set" in line
        )
        assert srv.n_requests == 0 and read_runs(tmp_path / "o") == []  # before any baseline ran
        monkeypatch.setenv(KEY_ENV, "")
        assert swim(srv.url, tmp_path / "e") == 2
        assert "is set but empty" in one_line_error(capsys.readouterr().err)
        monkeypatch.setenv(KEY_ENV, "sk-wrong-key")
        assert swim(srv.url, tmp_path / "w") == 2
        line = one_line_error(capsys.readouterr().err)
        assert f"check the API key in ${KEY_ENV}" in line and "sk-wrong-key" not in line
        monkeypatch.setenv(KEY_ENV, "sk-right-key")
        assert swim(srv.url, tmp_path / "r") == 0
    assert all(r["actions"] == [GOOD] * 4 for r in llm_rows(tmp_path / "r"))


# -- llama.cpp's /props: slots and sampling defaults ---------------------------------------------


def test_concurrency_fits_the_servers_slots(tmp_path, capsys):
    with FakeServer(**MODES["props-slots"]) as srv:
        assert swim(srv.url, tmp_path / "o", "--runs", "6") == 0
        assert srv.max_in_flight == 2  # total_slots, not 16
        assert all("grammar" in b and b["repeat_penalty"] == 1.0 for b in srv.requests)
    meta = read_metadata(tmp_path / "o")["llm_server"]
    assert (
        meta["family"] == "llamacpp"
        and "/props" in meta["detected_by"]
        and meta["total_slots"] == 2
    )
    assert meta["max_concurrency"] == 2
    assert (
        meta["server_sampling_defaults"]["top_k"] == 40
        and meta["server_sampling_defaults"]["repeat_penalty"] == 1.0
    )
    with FakeServer(**MODES["props-slots"]) as srv:
        assert swim(srv.url, tmp_path / "c", "--runs", "6", "--concurrency", "4") == 0
        assert 2 < srv.max_in_flight <= 4
    err = capsys.readouterr().err
    assert (
        "--concurrency 4 on a server that serves 2 request(s) at once" in err and "--timeout" in err
    )


def test_single_slot_server_gets_one_request_at_a_time(tmp_path):
    with FakeServer(
        **{**MODES["repeat-penalty"], "latency": 0.05}
    ) as srv:  # llama-cpp-python: one at a time
        assert swim(srv.url, tmp_path / "o", "--runs", "4") == 0
        assert srv.max_in_flight == 1
