"""The ``credal-fusion`` command line."""

from __future__ import annotations

import argparse
from collections.abc import Sequence

import uvicorn

from app.settings import get_settings


def _serve(args: argparse.Namespace) -> int:
    print(f"credal-fusion on http://{args.host}:{args.port}  (API docs: /docs)", flush=True)
    uvicorn.run("app.main:create_app", factory=True, host=args.host, port=args.port)
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand."""
    settings = get_settings()
    parser = argparse.ArgumentParser(prog="credal-fusion", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    serve = commands.add_parser("serve", help="start the HTTP/WebSocket service")
    serve.add_argument("--host", default=settings.host)
    serve.add_argument("--port", type=int, default=settings.port)
    serve.set_defaults(handler=_serve)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the console script."""
    args = build_parser().parse_args(argv)
    handler = args.handler
    return int(handler(args))


if __name__ == "__main__":
    raise SystemExit(main())
