"""The paper's protocol by default, element by element (values from ../shared/fidelity.md and the
paper, never from jswim's own output): starts, and the end-to-end request log of `jswim swim`."""

from __future__ import annotations

import math
import re

import jax
import numpy as np
import pytest

from jswim import env
from jswim.studies.plans import initial
from jswim.swimmers import nlink


@pytest.mark.parametrize(
    "swimmer, levels, values",
    [
        ("purcell", (1, 1), (math.pi / 3, math.pi / 3)),  # (pi/3, pi/3)
        ("ng", (1, 0), (10.0, 6.0)),  # NG (10, 6)
        ("nsphere", (0, 1, 1), (6.0, 10.0, 10.0)),  # four-sphere (6, 10, 10)
        ("nlink", (1, 1, 1), (2 * math.pi / 9,) * 3),  # four-link: every hinge at +2pi/9
    ],
)
def test_paper_start_is_the_authors_start(swimmer, levels, values):
    assert initial("paper", 0, swimmer) == levels
    params = env.make_params(swimmer, init=levels)
    state = env.reset(jax.random.PRNGKey(0), params)
    np.testing.assert_allclose(np.asarray(env.dof_values(state, params)), values, rtol=1e-6)


def test_start_orientation_middle_link_along_x_and_four_link_chain_symmetric_about_x():
    # Purcell: the middle link along +x.
    p = env.make_params("purcell", init=(1, 1))
    assert float(env.reset(jax.random.PRNGKey(0), p).theta) == 0.0
    # Four-link, hinges all +2pi/9: links at -pi/3, -pi/9, pi/9, pi/3 (mean direction along x).
    p = env.make_params("nlink", init=(1, 1, 1))
    theta = float(env.reset(jax.random.PRNGKey(0), p).theta)
    angles = np.asarray(nlink.link_angles(np.full(3, 2 * math.pi / 9), theta))
    np.testing.assert_allclose(
        angles, [-math.pi / 3, -math.pi / 9, math.pi / 9, math.pi / 3], atol=1e-6
    )
    # fidelity.md: the best four-link stroke goes 0.3134 per 6-step cycle along x from this start
    # (0.2945 if the middle link started along x instead).
    cycle = [(3, -1), (2, -1), (1, -1), (3, 1), (2, 1), (1, 1)]
    x = np.asarray(env.rollout_moves("nlink", cycle * 2, init=(1, 1, 1)).x)
    assert x[5] == pytest.approx(0.3134, abs=5e-4) and x[11] == pytest.approx(2 * 0.3134, abs=1e-3)


def test_cycle_and_sign_starts_follow_the_swimmer_s_dofs():
    assert {initial("cycle", k, "nlink") for k in range(8)} == set(env.all_inits(3))
    assert initial("+-", 0, "ng") == (1, 0)
    from jswim.errors import ConfigError

    with pytest.raises(ConfigError, match="3 DOFs"):
        initial("++", 0, "nsphere")


# -- end to end: what a server receives from `jswim swim` ---------------------------------------

S_MARKERS = (
    "rates of change (ROC)",
    "Only one DOF changes at a time",
    "Latest records",
    "long-term consequences",
    "Reply with the next action",
)


def test_swim_sends_the_paper_s_prompt_independent_runs_from_the_paper_start(tmp_path):
    from jswim import cli
    from jswim.results import read_runs
    from tests.fakeserver import FakeServer, hash_reply

    with FakeServer(reply=hash_reply) as srv:
        rc = cli.main(
            [
                "swim",
                "--swimmer",
                "ng",
                "--runs",
                "2",
                "--steps",
                "12",
                "--temperature",
                "0",
                "--noise",
                "0",
                "--q-runs",
                "4",
                "--no-figures",
                "--out",
                str(tmp_path / "swim"),
                "--base-url",
                srv.url,
                "--model",
                "fake",
                "--api-key-env",
                "JSWIM_TEST_NO_KEY",
            ]
        )
        bodies = list(srv.requests)
    assert rc == 0
    # Independent runs: 2 runs x 12 steps, every one its own call (no sharing, no cache).
    assert len(bodies) == 24
    for body in bodies:
        # The authors' code: a system message holding a single space, then one user message.
        assert [m["role"] for m in body["messages"]] == ["system", "user"]
        assert body["messages"][0]["content"] == " "
        assert (
            body["temperature"] == 0 and body["max_tokens"] == 10
        )  # fidelity.md: 10 for three-DOF
        assert "grammar" not in body and "response_format" not in body  # no constrained decoding
        text = body["messages"][1]["content"]
        at = [text.index(m) for m in S_MARKERS]
        assert at == sorted(at), text  # S1 S2 S3 S4 S5
        history = text[at[2] : at[3]]  # the history sits third, between S2 and S4
        assert "none yet" in history or re.search(r"\n\d+: \(", history)
        assert text.rstrip().endswith("the ROC -1, 0 or 1.")  # the answer instruction is last
    # NG's first record starts from (10, 6) at X = (0 - X_min) * 1000 = 2500.
    texts = [b["messages"][1]["content"] for b in bodies]
    first_records = [
        t
        for t in texts
        if re.search(r"\n1: \(\d+, \d+\) \[-?\d, -?\d\] -> \(\d+, \d+\), X 2500 -> ", t)
    ]
    assert len(first_records) >= 2  # step 2 of each run
    assert all("\n1: (10, 6) [" in t for t in first_records)
    assert sum("none yet" in t for t in texts) >= 2  # step 1 of each run (and after a clear)
    # The baselines start where the LLM starts.
    rows = read_runs(tmp_path / "swim")
    assert {r["agent"] for r in rows} == {"llm", "qlearning", "random"}
    assert {r["init"] for r in rows} == {"+-"}
    assert all(
        r["constraint"] == "none" and r["share_identical"] is False
        for r in rows
        if r["agent"] == "llm"
    )
    # Deviations from the paper's protocol are recorded with the runs.
    import json

    from jswim.results import read_metadata

    meta = read_metadata(tmp_path / "swim")
    assert any("physics" in d for d in meta["fidelity_deviations"])
    assert meta["summary"]["constrained_decoding"] == ["none"]
    head = json.loads(
        next((tmp_path / "swim" / "transcripts").glob("*.jsonl")).read_text().splitlines()[0]
    )
    assert (
        head["type"] == "meta"
        and head["deviations"]
        and not any("shared" in d for d in head["deviations"])
    )


def test_ablation_study_decodes_free_text_unless_told_otherwise():
    from jswim.llm.backend import Backend
    from jswim.studies.run import identity, study_backend

    # fidelity.md: no constrained decoding. With a grammar, removing S5 would remove nothing.
    auto = Backend(base_url="http://127.0.0.1:9/v1", model="m")
    assert study_backend("ablation", auto).constrain == "none"
    assert study_backend("swim", auto).constrain == "auto"
    assert (
        study_backend(
            "ablation", Backend(base_url="http://127.0.0.1:9/v1", model="m", constrain="grammar")
        ).constrain
        == "grammar"
    )
    from jswim.studies import StudyOptions

    assert identity("ablation", StudyOptions(), auto)["backend"]["constrain"] == "none"


def test_swim_options_share_identical_max_tokens_and_x_min_reach_the_server(tmp_path, capsys):
    from jswim import cli
    from tests.fakeserver import FakeServer

    with FakeServer(reply=lambda body: "[1, -1]") as srv:  # Purcell from (+, +): moves toward -x
        rc = cli.main(
            [
                "swim",
                "--runs",
                "3",
                "--steps",
                "6",
                "--q-runs",
                "0",
                "--no-figures",
                "--share-identical",
                "--max-tokens",
                "7",
                "--x-min",
                "-0.001",
                "--out",
                str(tmp_path / "s"),
                "--base-url",
                srv.url,
                "--model",
                "fake",
                "--api-key-env",
                "JSWIM_TEST_NO_KEY",
            ]
        )
        bodies = list(srv.requests)
    assert rc == 0
    out = capsys.readouterr().out
    assert len(bodies) == 6  # three identical runs share every call: copies of one run
    assert "copies of one run" in out and "free text" in out
    assert {b["max_tokens"] for b in bodies} == {7}
    assert re.search(
        r"X 1 -> -\d+, stuck no", bodies[1]["messages"][1]["content"]
    )  # below X_min: sent negative


@pytest.mark.slow  # jswim swim end to end on the four-DOF swimmers (35 s for both under load 8)
@pytest.mark.parametrize("swimmer, start", [("nlink", "+++"), ("nsphere", "-++")])
def test_swim_runs_four_dof_swimmers_from_their_paper_start(swimmer, start, tmp_path):
    from jswim import cli
    from jswim.results import read_runs
    from tests.fakeserver import FakeServer

    with FakeServer(reply=lambda body: "[3, -1]") as srv:
        rc = cli.main(
            [
                "swim",
                "--swimmer",
                swimmer,
                "--runs",
                "1",
                "--steps",
                "4",
                "--q-runs",
                "2",
                "--no-figures",
                "--out",
                str(tmp_path / swimmer),
                "--base-url",
                srv.url,
                "--model",
                "fake",
                "--api-key-env",
                "JSWIM_TEST_NO_KEY",
            ]
        )
        first = srv.requests[0]
    assert rc == 0
    assert {r["init"] for r in read_runs(tmp_path / swimmer)} == {start}  # LLM and baselines alike
    assert first["max_tokens"] == 20  # fidelity.md: 20 for four-DOF
    assert "the changed DOF 1, 2 or 3 and the ROC -1 or 1." in first["messages"][-1]["content"]
