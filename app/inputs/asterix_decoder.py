"""``asterix-decoder`` in a child process: a crash of its C code costs one block, not the server.

The decoder's C code crashes the process on some malformed blocks (a corrupted
CAT205 block does). The service hands it each block through a pipe to one
child process per server process: length-prefixed bytes in, the records as
JSON out (no pickle). A child that dies, or does not answer within
:data:`DECODE_TIMEOUT_S`, is replaced, and that block is reported as one the
decoder could not read (``None``); the next block goes to a fresh child.
"""

from __future__ import annotations

import json
import os
import select
import struct
import subprocess
import sys
import threading
import time
from typing import Any

DECODE_TIMEOUT_S = 5.0
"""A block the child has not decoded by then is given up (the child is replaced)."""

WORKER = """
import json, struct, sys
import asterix
read, write = sys.stdin.buffer, sys.stdout.buffer
while True:
    header = read.read(4)
    if len(header) < 4:
        break
    block = read.read(struct.unpack(">I", header)[0])
    text = json.dumps(asterix.parse(block, verbose=False)).encode()
    write.write(struct.pack(">I", len(text)) + text)
    write.flush()
"""
"""The child's loop (run with ``-c``: it imports nothing of the service)."""


class IsolatedDecoder:
    """One child process decoding blocks, one block at a time (thread-safe)."""

    def __init__(self, timeout_s: float = DECODE_TIMEOUT_S) -> None:
        self.timeout_s = timeout_s
        self._lock = threading.Lock()
        self._child: subprocess.Popen[bytes] | None = None

    def parse(self, block: bytes) -> list[dict[str, Any]] | None:
        """The decoder's records of one data block, or ``None`` if it failed on it."""
        with self._lock:
            child = self._child if self._child is not None else self._start()
            try:
                assert child.stdin is not None and child.stdout is not None
                child.stdin.write(struct.pack(">I", len(block)) + block)
                child.stdin.flush()
                deadline = time.monotonic() + self.timeout_s
                size = struct.unpack(">I", self._read(child, 4, deadline))[0]
                decoded: list[dict[str, Any]] = json.loads(self._read(child, size, deadline))
            except (OSError, EOFError, TimeoutError, ValueError):
                self._stop()
                return None
            return decoded

    def _start(self) -> subprocess.Popen[bytes]:
        self._child = subprocess.Popen(
            [sys.executable, "-c", WORKER],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
        )
        return self._child

    @staticmethod
    def _read(child: subprocess.Popen[bytes], size: int, deadline: float) -> bytes:
        assert child.stdout is not None
        stream = child.stdout.fileno()
        chunks: list[bytes] = []
        while size:
            left = deadline - time.monotonic()
            if left <= 0 or not select.select([stream], [], [], left)[0]:
                raise TimeoutError("the decoder did not answer")
            chunk = os.read(stream, size)
            if not chunk:
                raise EOFError("the decoder exited")
            chunks.append(chunk)
            size -= len(chunk)
        return b"".join(chunks)

    def _stop(self) -> None:
        child, self._child = self._child, None
        if child is not None:
            child.kill()
            child.wait()

    def close(self) -> None:
        """Stop the child (it also stops by itself when this process's end of the pipe closes)."""
        with self._lock:
            self._stop()
