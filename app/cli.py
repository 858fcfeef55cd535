"""The ``credal-fusion`` command line."""

from __future__ import annotations

import argparse
from collections.abc import Sequence

import uvicorn

from app.main import create_app
from app.runtime import tune_garbage_collector
from app.settings import get_settings
from app.stores import parse_store_url


def _serve(args: argparse.Namespace) -> int:
    parse_store_url(args.store)
    settings = get_settings().model_copy(
        update={"host": args.host, "port": args.port, "store": args.store}
    )
    print(
        f"credal-fusion on http://{args.host}:{args.port}\n"
        f"  live viewer: http://{args.host}:{args.port}/\n"
        f"  API docs: http://{args.host}:{args.port}/docs\n"
        f"  store: {args.store}",
        flush=True,
    )
    application = create_app(settings)
    tune_garbage_collector()
    uvicorn.run(
        application,
        host=args.host,
        port=args.port,
        ws_max_size=settings.max_body_bytes,
        ws_ping_interval=settings.ws_ping_interval,
        ws_ping_timeout=settings.ws_ping_timeout,
        proxy_headers=False,
    )
    return 0


def _store_url(text: str) -> str:
    try:
        parse_store_url(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None
    return text


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand."""
    settings = get_settings()
    parser = argparse.ArgumentParser(prog="credal-fusion", description=__doc__)
    commands = parser.add_subparsers(dest="command", required=True)
    serve = commands.add_parser("serve", help="start the HTTP/WebSocket service")
    serve.add_argument("--host", default=settings.host)
    serve.add_argument("--port", type=int, default=settings.port)
    serve.add_argument(
        "--store",
        type=_store_url,
        default=settings.store,
        help="memory | sqlite[:PATH] | redis[s]://HOST:PORT/DB (default: %(default)s, or CREDAL_STORE)",
    )
    serve.set_defaults(handler=_serve)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the console script."""
    args = build_parser().parse_args(argv)
    handler = args.handler
    return int(handler(args))


if __name__ == "__main__":
    raise SystemExit(main())
