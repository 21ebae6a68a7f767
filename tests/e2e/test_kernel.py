"""A study in a real Jupyter kernel: Stop stops the spending, progress is one output, reprs are short.

A kernel (ipykernel, started through jupyter_client as JupyterLab starts one) runs a noise study
against a slow fake server in this process. The test presses Stop (``interrupt_kernel``: SIGINT
to the kernel, what the toolbar's button sends) while LLM requests are out, then checks what a
user and their bill see: the cell ends within 3 s, the server gets no request after it, the
folder says ``interrupted``, and running the cell again finishes with the very table an
uninterrupted study gives.
"""

from __future__ import annotations

import json
import os
import queue
import time
from pathlib import Path
from typing import Any

import pytest
from jupyter_client.manager import start_new_kernel

from tests.fakeserver import FakeServer, hash_reply

ROOT = Path(__file__).resolve().parents[2]
#: 8 LLM runs of 12 steps; each request waits LATENCY_S, so the study takes about 12 x 0.5 s.
OPTS = "StudyOptions(swimmers=('ng',), runs=4, q_runs=0, steps=12, zetas=(0.0, 0.1))"
LATENCY_S = 0.5
#: What the comparison leaves out: the session's wall time is not part of the study's table.
TIMING = ("wall_s",)


@pytest.fixture
def kernel(tmp_path):
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
    }
    km, kc = start_new_kernel(kernel_name="python3", cwd=str(tmp_path), env=env)
    try:
        yield km, kc
    finally:
        kc.stop_channels()
        km.shutdown_kernel(now=True)


def _run(kc: Any, code: str, timeout: float = 120.0, on_sent: Any = None) -> dict[str, Any]:
    """Execute ``code``; its iopub messages (by type) and the reply, once the kernel is idle."""
    msg_id = kc.execute(code)
    if on_sent is not None:
        on_sent()
    got: dict[str, Any] = {"messages": []}
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            msg = kc.get_iopub_msg(timeout=0.05)
        except queue.Empty:
            continue
        if msg["parent_header"].get("msg_id") != msg_id:
            continue
        got["messages"].append(msg)
        if msg["msg_type"] == "status" and msg["content"]["execution_state"] == "idle":
            got["idle_at"] = time.monotonic()
            while True:  # the reply to this request (not a late one to an earlier request)
                reply = kc.get_shell_msg(timeout=10)
                if reply["parent_header"].get("msg_id") == msg_id:
                    got["reply"] = reply["content"]
                    return got
    raise AssertionError(f"the cell did not finish within {timeout} s: {code}")


def _of(got: dict[str, Any], kind: str) -> list[dict[str, Any]]:
    return [m["content"] for m in got["messages"] if m["msg_type"] == kind]


@pytest.mark.slow
def test_stop_in_a_kernel_stops_the_study_and_a_rerun_resumes(kernel, tmp_path):
    km, kc = kernel
    out = tmp_path / "noise"
    with FakeServer(reply=hash_reply, latency=LATENCY_S) as srv:
        setup = _run(
            kc,
            "import jswim\nfrom jswim.studies import Backend, StudyOptions, run_study\n"
            f"backend = Backend(base_url={srv.url!r}, model='fake', api_key_env='JSWIM_TEST_NO_KEY')\n"
            f"opts = {OPTS}\n",
        )
        assert setup["reply"]["status"] == "ok", setup["reply"]
        cell = f"res = run_study('noise', opts, backend, {str(out)!r})"
        pressed: dict[str, float] = {}

        def press_stop_mid_study() -> None:
            deadline = time.monotonic() + 90
            while srv.n_requests < 16 and time.monotonic() < deadline:  # the second round is out
                time.sleep(0.01)
            time.sleep(0.1)
            pressed["n"] = srv.n_requests
            pressed["t"] = time.monotonic()
            km.interrupt_kernel()

        stopped = _run(kc, cell, on_sent=press_stop_mid_study)
        lag = stopped["idle_at"] - pressed["t"]
        n_back = srv.settle()
        time.sleep(3 * LATENCY_S)  # long enough for several more rounds, had any gone out
        n_later = srv.n_requests
        print(
            f"Stop: cell back {lag:.2f} s after; requests {pressed['n']} at Stop, {n_later} after"
        )
        assert stopped["reply"]["status"] == "error"
        assert stopped["reply"]["ename"] == "KeyboardInterrupt"
        assert lag < 3.0, f"the cell took {lag:.1f} s to end after Stop"
        assert n_later == n_back == pressed["n"], (pressed["n"], n_back, n_later)
        assert n_later < 8 * 12  # far from the study's 96 requests: Stop stopped the spending
        meta = json.loads((out / "metadata.json").read_text())
        assert meta["status"] == "interrupted"
        # Progress: one display, updated in place (never a flood of stream lines).
        assert 1 <= len(_of(stopped, "display_data")) <= 2
        assert not [s for s in _of(stopped, "stream") if s["name"] == "stdout"]

        again = _run(kc, cell + "\nres")
        assert again["reply"]["status"] == "ok", again["reply"]
        shown = _of(again, "execute_result")[0]["data"]
        assert 1 <= len(_of(again, "display_data")) <= 2
        n_total = srv.n_requests
        # The same study, uninterrupted, in the same kernel (the same XLA build and flags).
        whole = _run(
            kc,
            f"run_study('noise', opts, backend, {str(tmp_path / 'whole')!r}, progress=False)\n",
        )
        assert whole["reply"]["status"] == "ok", whole["reply"]
    text = shown["text/plain"]
    assert text.startswith("StudyResult noise: complete; 8 of 8 runs")
    assert len(text.splitlines()) <= 4 and len(text) < 400
    assert "<table" in shown["text/html"]
    resumed = json.loads((out / "metadata.json").read_text())
    assert resumed["status"] == "complete"
    # The resumed folder's table is the uninterrupted study's, to the last digit.
    assert _table(out) == _table(tmp_path / "whole")
    # Nothing paid twice: the rerun asked only what the interrupted session had no answer for.
    assert n_total - n_later <= 8 * 12 - (n_later - 8)


def _table(folder: Path) -> list[dict[str, Any]]:
    import jswim

    st = jswim.load(folder)
    runs = st.runs.sort_values("run_id").reset_index(drop=True)
    return runs[["run_id", "group", "success", "signed_final_x", "failed_steps"]].to_dict("records")


def _ipython_blocks() -> list[tuple[str, str]]:
    """Each ``ipython`` block of the docs pages (notebook cells: top-level ``await``)."""
    import re

    return [
        (page.name, block)
        for page in sorted((ROOT / "docs").glob("*.md"))
        for block in re.findall(r"```ipython\n(.*?)```", page.read_text(), flags=re.S)
    ]


@pytest.mark.slow
def test_the_docs_notebook_cells_run_in_a_kernel(kernel):
    _, kc = kernel
    blocks = _ipython_blocks()
    assert blocks
    for page, code in blocks:
        got = _run(kc, code)
        assert got["reply"]["status"] == "ok", (page, got["reply"])
        shown = _of(got, "execute_result")
        assert not shown or len(shown[0]["data"]["text/plain"]) < 400  # a short repr


@pytest.mark.slow
def test_stop_in_a_kernel_stops_run_batch(kernel):
    km, kc = kernel
    with FakeServer(reply=hash_reply, latency=LATENCY_S) as srv:
        setup = _run(
            kc,
            "from jswim.agents.llm import LLMAgentConfig, LLMRunSpec, run_batch\n"
            "from jswim.studies import Backend\n"
            f"settings = Backend(base_url={srv.url!r}, model='fake', "
            "api_key_env='JSWIM_TEST_NO_KEY').client_settings()\n"
            "specs = [LLMRunSpec(swimmer='ng', n_steps=40, seed=k) for k in range(8)]\n",
        )
        assert setup["reply"]["status"] == "ok", setup["reply"]
        pressed: dict[str, float] = {}

        def press_stop_mid_batch() -> None:
            deadline = time.monotonic() + 90
            while srv.n_requests < 16 and time.monotonic() < deadline:
                time.sleep(0.01)
            time.sleep(0.1)
            pressed["n"], pressed["t"] = srv.n_requests, time.monotonic()
            km.interrupt_kernel()

        stopped = _run(
            kc, "runs = run_batch(specs, settings, LLMAgentConfig())", on_sent=press_stop_mid_batch
        )
        lag = stopped["idle_at"] - pressed["t"]
        n_back = srv.settle()
        time.sleep(3 * LATENCY_S)
        print(
            f"run_batch Stop: back {lag:.2f} s after; requests {pressed['n']} at Stop, {srv.n_requests} after"
        )
        assert stopped["reply"]["ename"] == "KeyboardInterrupt"
        assert lag < 3.0
        assert srv.n_requests == n_back == pressed["n"]  # of 8 x 40 = 320
