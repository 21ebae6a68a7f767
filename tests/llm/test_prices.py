"""--prices FILE: the user's price table, its date printed, and a model without a price said so."""

from __future__ import annotations

import json

import pytest

from jswim import cli
from jswim.errors import ConfigError
from jswim.llm.prices import load_prices
from jswim.results import read_metadata, read_runs
from tests.fakeserver import MODES, FakeServer

FAST = [
    "--steps",
    "4",
    "--runs",
    "1",
    "--q-runs",
    "0",
    "--swimmer",
    "purcell",
    "--direction",
    "+x",
    "--no-figures",
]


def test_price_files_toml_and_json(tmp_path):
    (tmp_path / "p.toml").write_text(
        'as_of = "2026-11"\n[prices]\n"gpt-5" = [1.25, 10.0]\n"m" = { input = 0.5, output = 2 }\n'
    )
    assert load_prices(tmp_path / "p.toml") == ({"gpt-5": (1.25, 10.0), "m": (0.5, 2.0)}, "2026-11")
    (tmp_path / "p.json").write_text(json.dumps({"gpt-5": [1, 2]}))
    assert load_prices(tmp_path / "p.json") == ({"gpt-5": (1.0, 2.0)}, "your table p.json")
    for bad in ('[prices]\n"x" = [1]\n', '[prices]\n"x" = [-1, 2]\n', "not toml ["):
        (tmp_path / "b.toml").write_text(bad)
        with pytest.raises(ConfigError, match="--prices"):
            load_prices(tmp_path / "b.toml")
    with pytest.raises(ConfigError, match="no such file"):
        load_prices(tmp_path / "missing.toml")


def test_swim_prices_from_a_file_on_any_host_with_its_date(tmp_path, capsys):
    (tmp_path / "p.toml").write_text('as_of = "2026-11"\n[prices]\n"gpt-5" = [1000000, 2000000]\n')
    with FakeServer(**MODES["openai-reasoning"]) as srv:
        assert (
            cli.main(
                [
                    "swim",
                    *FAST,
                    "--out",
                    str(tmp_path / "o"),
                    "--base-url",
                    srv.url,
                    "--model",
                    "gpt-5",
                    "--prices",
                    str(tmp_path / "p.toml"),
                ]
            )
            == 0
        )
    out = capsys.readouterr().out
    (row,) = read_runs(tmp_path / "o")
    # $1 per prompt token, $2 per completion token (reasoning included): the rows' own tokens priced
    assert row["cost_usd"] == pytest.approx(
        row["prompt_tokens"] * 1.0 + row["completion_tokens"] * 2.0
    )
    assert row["reasoning_tokens"] > 0 and row["completion_tokens"] > row["reasoning_tokens"]
    assert "prices of 2026-11" in out and read_metadata(tmp_path / "o")["prices_as_of"] == "2026-11"


def test_a_model_without_a_price_says_so_in_every_cost_line(tmp_path, capsys):
    (tmp_path / "p.json").write_text(json.dumps({"other": [1, 2]}))
    with FakeServer(**MODES["plain"]) as srv:
        args = [
            *FAST,
            "--out",
            str(tmp_path / "o"),
            "--base-url",
            srv.url,
            "--model",
            "fake",
            "--prices",
            str(tmp_path / "p.json"),
        ]
        assert cli.main(["swim", *args, "--dry-run"]) == 0
        dry = capsys.readouterr().out
        assert cli.main(["swim", *args]) == 0
        out = capsys.readouterr().out
    assert "not priced: no price for 'fake'" in dry and "--prices FILE" in dry
    assert "not priced (no price for 'fake'" in out and "$0 counted" in out


def test_a_local_server_without_a_list_price_says_why_it_is_not_priced(tmp_path, capsys):
    for model, why in (
        ("llama-local", "a server on this machine or the LAN, with no list price for its model"),
        ("reference-rule", "a rule on this machine, not an LLM"),
    ):
        with FakeServer(
            **MODES["plain"]
        ) as srv:  # a llama.cpp box, the reference rule: on this machine
            assert (
                cli.main(
                    [
                        "swim",
                        *FAST,
                        "--out",
                        str(tmp_path / model),
                        "--base-url",
                        srv.url,
                        "--model",
                        model,
                    ]
                )
                == 0
            )
        out = capsys.readouterr().out
        line = next(ln for ln in out.splitlines() if ln.startswith("LLM calls:"))
        # One wording, with the reason, in the study's line and in jswim show.
        assert (
            f"not priced ({why}); $0 counted" in line
            and "free" not in line
            and "--prices FILE" not in line
        )
        assert cli.main(["show", str(tmp_path / model)]) == 0
        assert f"not priced ({why}); $0 counted" in capsys.readouterr().out
