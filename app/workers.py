"""``credal-fusion serve --workers N``: N worker processes on one listening socket.

The parent binds the socket (:func:`app.cli._listen`) and starts N workers, each
a fresh interpreter (``python -m app.workers``: nothing is pickled) that
inherits the socket and serves the whole application on it; the kernel hands
each accepted connection to one of them, so every core takes its share. The
workers share the sessions through the store (:mod:`app.cluster.peers`): a
session's inputs are applied by the worker holding its lease, one at a time,
whichever worker a client reaches. The memory store lives in one process: it
runs one worker.

The parent supervises: a worker that exits is started again, unless it failed
within :data:`START_GRACE_S` of its start (a store it cannot use: then every
worker is stopped and ``serve`` exits with its status). SIGTERM or SIGINT stop
every worker gracefully (uvicorn's shutdown: open requests are answered).
"""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from types import FrameType

from app.settings import Settings

START_GRACE_S = 10.0
"""A worker that exits sooner after its start failed to start (not restarted)."""
STOP_TIMEOUT_S = 30.0
POLL_S = 0.2
PR_SET_PDEATHSIG = 1


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity, not the machine's count)."""
    return len(os.sched_getaffinity(0))


def worker_count(settings: Settings) -> int:
    """How many workers ``serve`` runs: ``settings.workers`` (0: one per usable core); one for
    the memory store, which is one process's memory."""
    from app.stores import parse_store_url

    if parse_store_url(settings.store).kind == "memory":
        return 1
    return settings.workers or usable_cores()


def _environment(settings: Settings) -> dict[str, str]:
    """The workers' environment: the parent's, with the settings ``serve`` was given on its
    command line (the workers read them from ``CREDAL_*`` as any setting)."""
    given = {
        "CREDAL_HOST": settings.host,
        "CREDAL_PORT": str(settings.port),
        "CREDAL_STORE": settings.store,
        "CREDAL_ACCESS_LOG": "true" if settings.access_log else "false",
    }
    return os.environ | given


def serve_workers(settings: Settings, listening: socket.socket, count: int) -> int:
    """Run ``count`` workers on ``listening`` until SIGTERM/SIGINT; the exit status."""
    directory = Path(tempfile.mkdtemp(prefix="credal-fusion-workers-"))
    command = [sys.executable, "-m", "app.workers", str(listening.fileno()), str(directory)]
    command.append(str(os.getpid()))
    environment = _environment(settings)
    stopping = False

    def start() -> tuple[subprocess.Popen[bytes], float]:
        process = subprocess.Popen(command, pass_fds=[listening.fileno()], env=environment)
        return process, time.monotonic()

    def stop(signum: int, frame: FrameType | None) -> None:
        nonlocal stopping
        stopping = True

    previous = {sig: signal.signal(sig, stop) for sig in (signal.SIGTERM, signal.SIGINT)}
    workers = [start() for _ in range(count)]
    status = 0
    try:
        while not stopping:
            time.sleep(POLL_S)
            for index, (process, started) in enumerate(workers):
                code = process.poll()
                if code is None or stopping:
                    continue
                if time.monotonic() - started < START_GRACE_S:
                    print(f"credal-fusion serve: worker {process.pid} failed to start", flush=True)
                    stopping, status = True, code or 1
                    break
                print(f"credal-fusion serve: worker {process.pid} exited ({code}); restarting")
                workers[index] = start()
    finally:
        for process, _ in workers:  # SIGTERM: uvicorn answers what is open, then stops
            if process.poll() is None:
                process.send_signal(signal.SIGTERM)
        deadline = time.monotonic() + STOP_TIMEOUT_S
        for process, _ in workers:
            try:
                process.wait(timeout=max(0.1, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        for sig, handler in previous.items():
            signal.signal(sig, handler)
        shutil.rmtree(directory, ignore_errors=True)
    return status


def _end_with_parent(parent: int) -> None:
    """Have the kernel send this worker SIGTERM when its ``serve`` dies, even by SIGKILL (Linux
    ``prctl(PR_SET_PDEATHSIG)``): no worker outlives it, serving on a socket nobody supervises."""
    import ctypes

    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(PR_SET_PDEATHSIG, signal.SIGTERM)
    if os.getppid() != parent:  # it died before the request (this one was adopted)
        os.kill(os.getpid(), signal.SIGTERM)


def main(argv: list[str]) -> int:
    """A worker: serve the application on the inherited socket ``argv[0]`` (a descriptor),
    sharing the store with the workers meeting in the directory ``argv[1]``, for as long as
    its ``serve``, process ``argv[2]``, lives."""
    from app.cli import serve_socket
    from app.cluster.peers import WorkerGroup
    from app.settings import get_settings

    descriptor, directory, parent = argv
    _end_with_parent(int(parent))
    listening = socket.socket(fileno=int(descriptor))
    return serve_socket(get_settings(), listening, WorkerGroup(Path(directory)))


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
