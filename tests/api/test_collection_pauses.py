"""Garbage collection paused for heavy work in worker threads, resumed after the last one."""

from __future__ import annotations

import gc
import threading

import pytest

from app.runtime import collection_paused, without_collection


def test_collection_resumes_only_when_the_last_overlapping_job_ends() -> None:
    assert gc.isenabled()
    first_in, first_may_end = threading.Event(), threading.Event()
    seen: list[bool] = []

    def first() -> None:
        with collection_paused():
            first_in.set()
            first_may_end.wait(10)
            seen.append(gc.isenabled())

    worker = threading.Thread(target=first)
    worker.start()
    first_in.wait(10)
    without_collection(lambda: seen.append(gc.isenabled()))()
    assert gc.isenabled() is False  # the first job still runs
    first_may_end.set()
    worker.join(10)
    assert seen == [False, False]
    assert gc.isenabled()


def test_a_failing_job_resumes_collection_and_a_disabled_collector_stays_disabled() -> None:
    with pytest.raises(ZeroDivisionError), collection_paused():
        _ = 1 / 0
    assert gc.isenabled()
    gc.disable()
    try:
        with collection_paused():
            pass
        assert not gc.isenabled()
    finally:
        gc.enable()
