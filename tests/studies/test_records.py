"""Records say what happened: what the server received, the LLM steps as the work, each study's
own defaults in its --help."""

from __future__ import annotations

import json

import pytest

from jswim import cli
from jswim.llm.backend import Backend
from jswim.studies import StudyOptions, run_study
from jswim.studies import get
from tests.fakeserver import FakeServer, hash_reply


def test_the_transcript_records_the_max_tokens_the_server_received(tmp_path):
    opts = StudyOptions(swimmers=("purcell",), directions=(1,), runs=1, q_runs=0, steps=12)
    with FakeServer(reply=hash_reply) as srv:
        run_study(
            "swim",
            opts,
            Backend(base_url=srv.url, model="fake", api_key_env=""),
            tmp_path / "o",
        )
        sent = {b.get("max_tokens") for b in srv.requests}
    (path,) = (tmp_path / "o" / "transcripts").glob("*.jsonl")
    meta = json.loads(path.read_text().splitlines()[0])
    assert (
        sent == {meta["client"]["max_tokens"]} == {10}
    )  # the Purcell swimmer's limit, not a default


def test_progress_counts_llm_steps_as_the_work(tmp_path):
    seen = []
    opts = StudyOptions(swimmers=("purcell",), directions=(1,), runs=2, q_runs=20, steps=12)
    with FakeServer(reply=hash_reply) as srv:
        run_study(
            "swim",
            opts,
            Backend(base_url=srv.url, model="fake", api_key_env=""),
            tmp_path / "o",
            progress=lambda phase, done, total, info: seen.append((phase, done, total)),
        )
    llm = [(d, t) for phase, d, t in seen if phase.startswith("llm")]
    assert llm and all(t == 24 for _, t in llm)  # 2 runs x 12 steps, whatever the 40 baseline runs
    assert llm[0][0] < 24 and llm[-1] == (24, 24)
    base = [(d, t) for phase, d, t in seen if phase in ("qlearning", "random")]
    assert base[-1] == (40, 42)  # runs, while the baselines go


@pytest.mark.parametrize("study", ["noise", "history", "ablation", "curves"])
def test_each_study_help_shows_its_own_defaults(study, capsys):
    with pytest.raises(SystemExit):
        cli.main(["study", study, "--help"])
    text = " ".join(capsys.readouterr().out.split())
    spec = get(study)
    assert f"LLM runs per setting (default {spec.runs})" in text
    assert f"default {','.join(spec.swimmers)})" in text
    if "zetas" not in spec.ignores:
        assert "noise grid (default 0,0.5,1,1.5,2,2.5,3)" in text
    else:
        assert "--zetas" not in text  # an option the study refuses is not offered
    if study == "ablation":
        assert "auto: none in this study" in text


def test_show_reports_decoding_as_the_runs_recorded_it(tmp_path):
    from jswim.studies.overview import show_text
    from jswim.results import StudyStore

    ident = {
        "study": "ablation",
        "backend": {"kind": "remote", "model": "m", "constrain": "auto", "temperature": 0},
    }
    with StudyStore(tmp_path / "s", "ablation", ident) as store:
        store.add_runs(
            [
                {
                    "run_id": "a",
                    "agent": "llm",
                    "swimmer": "purcell",
                    "direction": 1,
                    "group": "full",
                    "constraint": "none",
                    "success": False,
                    "learned": False,
                    "steps_to_learn": None,
                    "signed_final_x": 0.0,
                    "final_x": 0.0,
                    "x": [0.0],
                    "status": "done",
                    "steps": 1,
                    "failed_steps": 0,
                    "calls": 1,
                    "prompt_tokens": 1,
                    "completion_tokens": 1,
                    "cost_usd": 0.0,
                    "zeta": 0.0,
                    "n_ht": 3,
                    "period": 0,
                }
            ]
        )
        store.set_status("complete")
    text = show_text(tmp_path / "s")
    assert "free text (constrain none)" in text and "constrain auto" not in text
