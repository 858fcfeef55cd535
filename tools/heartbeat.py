#!/usr/bin/env python3
"""Run a command, pass its output through, and say it is still working during long silences.

    tools/heartbeat.py COMMAND [ARG ...]

pip prints nothing while it builds a C extension from source (asterix-decoder: ~40 s)
or unpacks the packages it downloaded (~30-90 s): after SILENCE_S seconds without a
line, one line says what is still running and for how long. The exit status is the
command's.
"""

from __future__ import annotations

import queue
import subprocess
import sys
import threading
import time

SILENCE_S = 8.0


def main(command: list[str]) -> int:
    process = subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, bufsize=1
    )
    assert process.stdout is not None
    lines: queue.Queue[str | None] = queue.Queue()

    def read() -> None:
        assert process.stdout is not None
        for line in process.stdout:
            lines.put(line)
        lines.put(None)

    threading.Thread(target=read, daemon=True).start()
    last, since = "starting", time.monotonic()
    while True:
        try:
            line = lines.get(timeout=SILENCE_S)
        except queue.Empty:
            what = last if len(last) <= 70 else last[:67] + "..."
            silent = time.monotonic() - since
            print(f"    ... still working, {silent:.0f} s since: {what}", flush=True)
            continue
        if line is None:
            return process.wait()
        sys.stdout.write(line)
        sys.stdout.flush()
        if line.strip():
            last, since = line.strip(), time.monotonic()


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    sys.exit(main(sys.argv[1:]))
