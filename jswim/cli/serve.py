"""``jswim serve reference``: the prompt-only reference agent behind an OpenAI-compatible server."""

from __future__ import annotations

import argparse
import sys

from jswim.errors import ConfigError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "serve",
        help="serve the prompt-only reference agent (not an LLM) on 127.0.0.1",
        description="Start an OpenAI-compatible server on 127.0.0.1 whose 'model' "
        "(reference-rule) is a plain rule that reads only the prompt text it is sent "
        "and repeats the move that went furthest toward the target from the current "
        "shape among the records shown, else tries a move not yet shown from it "
        "(jswim.llm.reference). It is not a language model. Point --base-url at it.",
    )
    p.add_argument("what", choices=("reference",), help="reference: the reference agent")
    p.add_argument(
        "--port",
        type=int,
        default=8099,
        help="port on 127.0.0.1 (default 8099; 0 picks a free one)",
    )
    p.set_defaults(command_main=main)


def main(args: argparse.Namespace) -> int:
    from jswim.llm.reference import (
        MODEL,
        ReferenceServer,
    )  # lazy: start-up (the reference rule loads only for a run)

    if not 0 <= args.port <= 65535:
        raise ConfigError(f"--port must be between 0 and 65535, got {args.port}")
    try:
        srv = ReferenceServer(port=args.port)
    except OSError as exc:
        raise ConfigError(
            f"cannot listen on 127.0.0.1:{args.port} ({exc.strerror or exc}); try another --port"
        ) from None
    print(
        f"reference agent (a plain rule, not an LLM) at {srv.url}, model {MODEL!r}; Ctrl-C stops it",
        flush=True,
    )
    print(f"  jswim swim --base-url {srv.url} --model {MODEL}", flush=True)
    try:
        srv.serve_forever()
    except KeyboardInterrupt:
        print("stopped", file=sys.stderr)
    return 0
