"""Latency and throughput of the embedded local model (llama.cpp via xllamacpp).

Measures, for a prompt of about ``--tokens`` tokens (grammar-constrained reply):

- server start (model load) time;
- cold latency: first request, nothing cached;
- identical repeat: the server reuses its KV cache for the whole prompt;
- next step: the history changed, only the fixed prefix (S1, S2, S4, S5) is reused;
- throughput: ``--batch`` distinct prompts in flight at once over ``--slots`` slots.

Run: ``python -m benchmarks.bench_local_model [--tokens 420] [--slots 4] [--batch 16]``.
Numbers depend heavily on free CPU cores; close other work first.
"""

from __future__ import annotations

import argparse
import asyncio
import math
import time

import httpx

from jswim.llm import LLMClient, LocalServer
from jswim.prompt import (
    Action,
    HistoryRecord,
    PromptConfig,
    SwimmerText,
    allowed_actions,
    build_messages,
    render_prompt,
)

LO, HI = -math.pi / 3, math.pi / 3
SWIMMER = SwimmerText(2, LO, HI, dof_decimals=3)
CYCLE = [Action(1, -1), Action(2, -1), Action(1, 1), Action(2, 1)]


def history(n: int, offset: int = 0) -> list[HistoryRecord]:
    """A plausible square-gait history of ``n`` steps starting after step ``offset``."""
    out, dofs, x = [], [HI, HI], 0.0
    for k in range(offset + n):
        a = CYCLE[k % 4]
        new = list(dofs)
        new[a.dof - 1] = HI if a.roc == 1 else LO
        rec = HistoryRecord(k + 1, tuple(dofs), tuple(new), a, x, x + 0.048, False)
        dofs, x = new, x + 0.048
        if k >= offset:
            out.append(rec)
    return out


def prompt_for(n_ht: int, offset: int = 0) -> str:
    records = history(n_ht, offset)
    return render_prompt(
        SWIMMER, PromptConfig(n_ht=n_ht), 1, records, records[-1].dofs_after, records[-1].x_after
    )


async def timed(client: LLMClient, prompt: str, replies: list[str]) -> tuple[float, int, int, str]:
    t0 = time.perf_counter()
    res = await client.chat(build_messages(prompt), replies=replies, use_cache=False)
    return time.perf_counter() - t0, res.usage.prompt_tokens, res.usage.cached_tokens, res.text


async def main_async(args: argparse.Namespace, srv: LocalServer) -> None:
    replies = [a.text() for a in allowed_actions(SWIMMER)]
    async with LLMClient(srv.client_settings(max_tokens=12)) as client:
        # Pick n_ht so the prompt is about --tokens long; /tokenize touches no KV cache, so the
        # first chat request below is truly cold. The chat template adds ~10 tokens.
        root = srv.base_url.removesuffix("/v1")
        n_ht = 1
        async with httpx.AsyncClient(trust_env=False) as http:
            while n_ht < 60:
                r = await http.post(f"{root}/tokenize", json={"content": prompt_for(n_ht)})
                if len(r.json()["tokens"]) + 10 >= args.tokens:
                    break
                n_ht += 1
        p = prompt_for(n_ht)
        cold = await timed(client, p, replies)
        again = await timed(client, p, replies)
        nxt = await timed(client, prompt_for(n_ht, offset=1), replies)
        print(f"prompt: n_ht={n_ht}, {cold[1]} tokens; reply {cold[3]!r}")
        print(f"cold latency       {cold[0]:7.3f} s  (cached tokens {cold[2]})")
        print(f"identical repeat   {again[0]:7.3f} s  (cached tokens {again[2]})")
        print(f"next step (shared prefix) {nxt[0]:7.3f} s  (cached tokens {nxt[2]})")
        prompts = [prompt_for(n_ht, offset=10 + k) for k in range(args.batch)]
        t0 = time.perf_counter()
        await asyncio.gather(*[timed(client, q, replies) for q in prompts])
        wall = time.perf_counter() - t0
        print(
            f"throughput: {args.batch} distinct prompts over {args.slots} slots in {wall:.2f} s "
            f"= {args.batch / wall:.2f} calls/s"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tokens", type=int, default=420, help="target prompt length in tokens")
    ap.add_argument("--slots", type=int, default=4, help="server slots (n_parallel)")
    ap.add_argument("--batch", type=int, default=16, help="prompts in the throughput burst")
    ap.add_argument(
        "--threads", type=int, default=None, help="decoding threads (default: llama.cpp's)"
    )
    args = ap.parse_args()
    t0 = time.perf_counter()
    with LocalServer(n_parallel=args.slots, n_ctx_per_slot=1024, n_threads=args.threads) as srv:
        print(f"server start       {time.perf_counter() - t0:7.3f} s  ({srv.model_name})")
        asyncio.run(main_async(args, srv))


if __name__ == "__main__":
    main()
