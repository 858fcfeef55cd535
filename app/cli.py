"""The ``credal-fusion`` command line.

Only the standard library is imported up front: each subcommand imports what
it needs when it runs, so ``--help`` answers at once and ``serve`` loads no
plotting code. Options left out take their value from the settings
(``CREDAL_*`` variables, :mod:`app.settings`).
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import functools
import socket
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

from app.commands.errors import CommandError, one_line
from evaluation.catalogue import CATALOGUE

if TYPE_CHECKING:
    from app.cluster.peers import WorkerGroup
    from app.settings import Settings


def _serve(args: argparse.Namespace) -> int:
    from app.settings import get_settings

    given = {
        name: value
        for name in ("host", "port", "store", "access_log", "workers")
        if (value := getattr(args, name)) is not None
    }
    settings = get_settings().model_copy(update=given)
    listening = _listen(settings.host, settings.port)  # a busy port: one line, no banner
    address = f"http://{settings.host}:{listening.getsockname()[1]}"

    from app.stores import parse_store_url
    from app.workers import serve_workers, worker_count

    if settings.workers > 1 and parse_store_url(settings.store).kind == "memory":
        raise CommandError(
            f"the memory store is one process's: it cannot be shared by {settings.workers} "
            "workers; use --workers 1, or a sqlite or redis store"
        )
    _check_store(settings.store, settings.redis_prefix)
    workers = worker_count(settings)
    print(
        f"credal-fusion on {address}\n"
        f"  live viewer: {address}/\n"
        f"  API docs: {address}/docs\n"
        f"  store: {settings.store}\n"
        f"  workers: {workers}",
        flush=True,
    )
    if workers > 1:
        return serve_workers(settings, listening, workers)
    return serve_socket(settings, listening)


def serve_socket(
    settings: Settings, listening: socket.socket, workers: WorkerGroup | None = None
) -> int:
    """Serve the application on ``listening`` until stopped (one process: the only one, or a
    worker of ``workers``); uvicorn's exit status."""
    import uvicorn

    from app.http.keepalive import server_options
    from app.http.transport import raise_descriptor_limit
    from app.main import create_app
    from app.runtime import tune_garbage_collector

    application = create_app(settings, workers)
    tune_garbage_collector()
    raise_descriptor_limit()  # the connection limits decide, not the descriptor limit
    config = uvicorn.Config(
        application,
        host=settings.host,
        port=settings.port,
        proxy_headers=False,
        access_log=settings.access_log,
        **server_options(settings),
    )
    server = uvicorn.Server(config)
    with contextlib.suppress(KeyboardInterrupt):  # as uvicorn.run: Ctrl-C is a clean stop
        server.run(sockets=[listening])
    return 0 if server.started else 3  # 3: uvicorn's status of a failed start


def _listen(host: str, port: int) -> socket.socket:
    """The service's socket, bound as uvicorn binds it (``SO_REUSEADDR``); uvicorn listens on
    it. An address in use is one line saying what to do (not uvicorn's ``[Errno 98]``)."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    listening = socket.socket(family, socket.SOCK_STREAM)
    listening.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    try:
        listening.bind((host, port))
    except OSError as error:
        listening.close()
        if error.errno == errno.EADDRINUSE:
            raise CommandError(
                f"{host}:{port} is in use (another credal-fusion serve?): stop it, "
                "or choose another port with --port"
            ) from None
        raise CommandError(
            f"cannot listen on {host}:{port} ({error.strerror or error}): check --host and --port"
        ) from None
    listening.set_inheritable(True)
    return listening


def _check_store(url: str, redis_prefix: str) -> None:
    """Open the store once before serving: a store that cannot be used is one line, not a
    traceback from the application's start-up. A Redis server that is only unreachable
    now (not up yet) is a warning: the service starts, ``/readyz`` answers 503 until it is."""
    from app.http.errors import StoreCorrupt, StoreUnavailable
    from app.stores import open_store, parse_store_url

    try:
        store = open_store(url, redis_prefix=redis_prefix)
        try:
            store.count_sessions()
        finally:
            store.close()
    except StoreCorrupt as error:  # serves, not ready (/readyz says why): the operator decides
        print(f"credal-fusion serve: warning: {error.detail}; serving anyway", flush=True)
    except StoreUnavailable as error:
        if parse_store_url(url).kind != "redis":  # a file that cannot be opened: not an outage
            raise _unusable(url, error) from error
        print(f"credal-fusion serve: warning: {error.detail}; serving anyway", flush=True)
    except Exception as error:
        raise _unusable(url, error) from error


def _unusable(url: str, error: Exception) -> CommandError:
    return CommandError(
        f"cannot use the store {url} ({type(error).__name__}: {error}): start it, "
        "or choose another with --store (memory | sqlite[:PATH] | redis://HOST:PORT/DB)"
    )


def _store_url(text: str) -> str:
    from app.stores import parse_store_url

    try:
        parse_store_url(text)
    except ValueError as error:
        raise argparse.ArgumentTypeError(str(error)) from None
    return text


def _server_url(text: str) -> str:
    """A ``--server`` URL: ``HOST:PORT`` without a scheme is read as ``http://HOST:PORT``."""
    url = text.strip().rstrip("/")
    scheme, found, rest = url.partition("://")
    if not found:
        scheme, rest, url = "http", url, f"http://{url}"
    if scheme not in ("http", "https"):
        raise argparse.ArgumentTypeError(
            f"{text!r}: the service's URL starts with http:// or https://, not {scheme}://"
        )
    if not rest or rest.startswith((":", "/")):
        raise argparse.ArgumentTypeError(f"{text!r} names no host, e.g. http://127.0.0.1:8000")
    return url


SERVER_HELP = "URL of a running service, e.g. http://127.0.0.1:8000 (or 127.0.0.1:8000: http)"


def _workers(text: str) -> int:
    if not text.isdigit():
        raise argparse.ArgumentTypeError(f"a number of processes (0: one per core), not {text!r}")
    return int(text)


def _positive(text: str) -> float:
    value = float(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be > 0, not {text}")
    return value


DEBUG_HELP = "on failure, show the Python traceback (default: one line saying what to do)"


def _preset_name(text: str) -> str:
    from app.commands.scenarios import PRESETS

    if text not in PRESETS:
        raise argparse.ArgumentTypeError(f"unknown preset {text!r}; choose from {list(PRESETS)}")
    return text


def _scenario_name(text: str) -> str:
    from app.commands.scenarios import names

    if text not in names():
        raise argparse.ArgumentTypeError(f"unknown scenario {text!r}; choose from {names()}")
    return text


def _simulate(args: argparse.Namespace) -> int:
    from app.commands.simulate import command

    return command(args)


def _export(args: argparse.Namespace) -> int:
    from app.commands.export import export_command  # httpx only: no engine for a few GETs

    return export_command(args)


def _replay(args: argparse.Namespace) -> int:
    from app.commands.replay import replay_command

    return replay_command(args)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand (``--debug`` before or after it)."""
    parser = argparse.ArgumentParser(
        prog="credal-fusion",
        description="Fuse multi-sensor tracks and classify them with belief functions.",
    )
    parser.add_argument("--debug", action="store_true", help=DEBUG_HELP)
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=DEBUG_HELP)
    commands = parser.add_subparsers(dest="command", required=True)
    add_parser = functools.partial(commands.add_parser, parents=[common])
    serve = add_parser("serve", help="start the HTTP/WebSocket service")
    serve.add_argument("--host", help="default: 127.0.0.1, or CREDAL_HOST")
    serve.add_argument("--port", type=int, help="default: 8000, or CREDAL_PORT")
    serve.add_argument(
        "--store",
        type=_store_url,
        help="memory | sqlite[:PATH] | redis[s]://HOST:PORT/DB (default: sqlite:data/credal-fusion.db, or CREDAL_STORE)",
    )
    serve.add_argument(
        "--workers",
        type=_workers,
        help="worker processes sharing the sessions through the store, 0: one per usable "
        "core (default: 1, or CREDAL_WORKERS; the memory store runs one)",
    )
    serve.add_argument(
        "--access-log",
        action=argparse.BooleanOptionalAction,
        help="log a line per request (default: on, or CREDAL_ACCESS_LOG)",
    )
    serve.set_defaults(handler=_serve)

    simulate = add_parser(
        "simulate", help="run a paper scenario through the engine (or a running server)"
    )
    simulate.add_argument(
        "scenario", type=_scenario_name, help="e.g. aircraft, crossing (a wrong name lists them)"
    )
    simulate.add_argument("--seed", type=int, default=0)
    simulate.add_argument(
        "--preset",
        type=_preset_name,
        help="track a detection scenario with this preset instead of its own ('none': one CV model)",
    )
    simulate.add_argument(
        "--server",
        type=_server_url,
        help=f"{SERVER_HELP}: prints the session, its token and the viewer URL first",
    )
    simulate.add_argument(
        "--keep",
        action="store_true",
        help="with --server: leave the session open at the end (default: delete it)",
    )
    simulate.add_argument(
        "--speed",
        type=_positive,
        help="with --server: play the inputs at SPEED times the scenario's clock (1: real "
        "time, to watch in the viewer; default: as fast as possible)",
    )
    simulate.add_argument("--quiet", action="store_true", help="no progress bar")
    simulate.set_defaults(handler=_simulate)

    reproduce = add_parser("reproduce", help="regenerate one paper figure (PNG)")
    reproduce.add_argument("figure", choices=sorted(CATALOGUE))
    reproduce.add_argument(
        "--out",
        default="out/figures",
        help="directory (default: %(default)s, ignored by git; docs/figures replaces the "
        "committed figure)",
    )
    reproduce.add_argument("--reduced", action="store_true", help="small sizes, for a quick look")
    reproduce.set_defaults(handler=_reproduce)

    export = add_parser("export", help="write a session's event log as JSON lines")
    export.add_argument("--server", type=_server_url, required=True, help=SERVER_HELP)
    export.add_argument("--session", required=True)
    export.add_argument("--token", required=True, help="the session's token (or the admin token)")
    export.set_defaults(handler=_export)

    replay = add_parser("replay", help="apply an exported event log, print the results")
    replay.add_argument("events", help="EVENTS.jsonl written by `credal-fusion export`")
    replay.add_argument(
        "--server",
        type=_server_url,
        help=f"replay through a running service instead of in process ({SERVER_HELP})",
    )
    replay.add_argument("--quiet", action="store_true", help="no progress bar")
    replay.set_defaults(handler=_replay)

    bench = add_parser("bench", help="run the benchmarks of bench/ (from a checkout)")
    bench.add_argument("names", nargs="*", help="benchmarks to run (default: all)")
    bench.set_defaults(handler=_bench)
    return parser


def _reproduce(args: argparse.Namespace) -> int:
    """One figure; the plotting code is imported here only (the ``figures`` extra)."""
    try:
        from evaluation.figures import reproduce as reproduce_figure
    except ModuleNotFoundError as missing:
        if (missing.name or "").partition(".")[0] != "matplotlib":
            raise
        print(
            f"reproduce needs the figures extra ({missing.name} is missing): "
            "pip install 'credal-fusion[figures]'",
            file=sys.stderr,
        )
        return 2
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


def _idle_flag(args: argparse.Namespace) -> str | None:
    """Why a flag given would do nothing in this command line (it is then refused), or None."""
    if args.command != "simulate":
        return None
    if args.server is None:
        if args.keep:
            return "--keep leaves the server's session open: it needs --server"
        if args.speed is not None:
            return "--speed paces the inputs for a server's live viewer: it needs --server"
    if args.preset is not None:
        from app.commands.scenarios import tracks_locally

        if not tracks_locally(args.scenario):
            return (
                f"--preset sets the local tracking of a detection scenario; {args.scenario} "
                "is a track-list scenario (no local tracking): leave --preset out"
            )
    return None


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the console script: a failure is one line on stderr and exit status 1;
    a flag that would do nothing is one line and exit status 2."""
    args = build_parser().parse_args(argv)
    idle = _idle_flag(args)
    if idle is not None:
        print(f"credal-fusion {args.command}: {idle}", file=sys.stderr)
        return 2
    try:
        return int(args.handler(args))
    except KeyboardInterrupt:
        if args.debug:
            raise
        print("credal-fusion: interrupted", file=sys.stderr)
        return 130
    except Exception as error:  # every failure is told in one line, unless --debug
        if args.debug:
            raise
        print(f"credal-fusion {args.command}: {one_line(error)}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    raise SystemExit(main())
