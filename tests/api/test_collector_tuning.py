"""The serving process's collector settings (app.runtime.tune_garbage_collector), checked in a
fresh interpreter that builds the real app as ``credal-fusion serve`` does, then tuned: what
start-up allocated is frozen, and the middle generation is collected once its count of young
collections exceeds ``threshold1`` (CPython's gc: 3 young collections, then a middle one), so
a middle collection walks a few young collections' survivors at once, not 21 (issue #28: a
65 ms stall at 20)."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

SCRIPT = """
import gc, json
from app.main import create_app
from app.runtime import tune_garbage_collector
from app.settings import Settings

create_app(Settings(), None)
tune_garbage_collector()
frozen = gc.get_freeze_count()
threshold = gc.get_threshold()
order = []
gc.callbacks.append(lambda phase, info: phase == "start" and order.append(info["generation"]))
keep = []
for _ in range(30 * 20_000):  # survivors: 30 young collections' worth, every one kept alive
    keep.append([])
gc.callbacks.clear()
print(json.dumps({"frozen": frozen, "threshold": threshold, "order": order}))
"""


def test_start_up_is_frozen_and_the_middle_generation_is_collected_in_small_pieces() -> None:
    done = subprocess.run(
        [sys.executable, "-c", SCRIPT], cwd=ROOT, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    seen = json.loads(done.stdout.strip().splitlines()[-1])
    assert seen["threshold"] == [20_000, 2, 500]
    assert seen["frozen"] > 10_000  # FastAPI, pydantic, scipy and the routes: never scanned again
    order = seen["order"]
    # 600 000 survivors (plus the list's own growth): 30 collections of 20 000, one in 4 a
    # middle one (which collects the young generation with it), none full (500 middle ones
    # first): young, young, young, middle, young, young, young, middle, ...
    assert 28 <= len(order) <= 32
    assert 2 not in order
    assert order[:4] == [0, 0, 0, 1]
    runs = "".join(map(str, order)).split("1")
    assert len(runs) >= 7
    assert all(run == "000" for run in runs[:-1])
