"""The ``credal-fusion`` command line."""

from __future__ import annotations

import argparse
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path

import uvicorn

from app.commands.replay import export_command, replay_command
from app.commands.scenarios import names as scenario_names
from app.commands.simulate import command as simulate_command
from app.keepalive import server_options
from app.main import create_app
from app.runtime import tune_garbage_collector
from app.settings import get_settings
from app.stores import parse_store_url
from core.evaluation.figures import FIGURES
from core.evaluation.figures import reproduce as reproduce_figure


def _serve(args: argparse.Namespace) -> int:
    parse_store_url(args.store)
    settings = get_settings().model_copy(
        update={
            "host": args.host,
            "port": args.port,
            "store": args.store,
            "access_log": args.access_log,
        }
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
        proxy_headers=False,
        access_log=settings.access_log,
        **server_options(settings),
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
    serve.add_argument(
        "--access-log",
        action=argparse.BooleanOptionalAction,
        default=settings.access_log,
        help="log a line per request (default: on, or CREDAL_ACCESS_LOG)",
    )
    serve.set_defaults(handler=_serve)

    simulate = commands.add_parser(
        "simulate", help="run a paper scenario through the engine (or a running server)"
    )
    simulate.add_argument("scenario", choices=scenario_names())
    simulate.add_argument("--seed", type=int, default=0)
    simulate.add_argument("--server", help="URL of a running service, e.g. http://127.0.0.1:8000")
    simulate.add_argument("--quiet", action="store_true", help="no progress bar")
    simulate.set_defaults(handler=simulate_command)

    reproduce = commands.add_parser("reproduce", help="regenerate one paper figure (PNG)")
    reproduce.add_argument("figure", choices=sorted(FIGURES))
    reproduce.add_argument("--out", default="docs/figures", help="directory (default: %(default)s)")
    reproduce.add_argument("--reduced", action="store_true", help="small sizes, for a quick look")
    reproduce.set_defaults(handler=_reproduce)

    export = commands.add_parser("export", help="write a session's event log as JSON lines")
    export.add_argument("--server", required=True)
    export.add_argument("--session", required=True)
    export.add_argument("--token", required=True, help="the session's token (or the admin token)")
    export.set_defaults(handler=export_command)

    replay = commands.add_parser("replay", help="apply an exported event log, print the results")
    replay.add_argument("events", help="EVENTS.jsonl written by `credal-fusion export`")
    replay.add_argument("--server", help="replay through a running service instead of in process")
    replay.add_argument("--quiet", action="store_true", help="no progress bar")
    replay.set_defaults(handler=replay_command)

    bench = commands.add_parser("bench", help="run the benchmarks of bench/ (from a checkout)")
    bench.add_argument("names", nargs="*", help="benchmarks to run (default: all)")
    bench.set_defaults(handler=_bench)
    return parser


def _reproduce(args: argparse.Namespace) -> int:
    path = reproduce_figure(args.figure, args.out, reduced=args.reduced)
    print(path)
    return 0


def _bench(args: argparse.Namespace) -> int:
    """Each ``bench/NAME.py`` of the checkout, in turn (they print their own tables)."""
    folder = Path(__file__).resolve().parents[1] / "bench"
    available = sorted(p.stem for p in folder.glob("*.py") if p.stem != "machine")
    if not available:
        print(f"no benchmarks found in {folder} (run from a checkout)", file=sys.stderr)
        return 2
    chosen = args.names or available
    unknown = sorted(set(chosen) - set(available))
    if unknown:
        print(f"unknown benchmark(s) {unknown}; choose from {available}", file=sys.stderr)
        return 2
    for name in chosen:
        print(f"== bench/{name}.py", flush=True)
        status = subprocess.run(
            [sys.executable, str(folder / f"{name}.py")], check=False
        ).returncode
        if status != 0:
            return status
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the console script."""
    args = build_parser().parse_args(argv)
    handler = args.handler
    return int(handler(args))


if __name__ == "__main__":
    raise SystemExit(main())
