"""The session limit holds across instances: two servers on one store never exceed it.

Two real service instances share a store (a private ``redis-server``, or one
SQLite file) with ``CREDAL_MAX_SESSIONS=4``. Twelve clients, six per
instance, create sessions at the same moment: exactly four are created (201)
and eight refused with 429 naming ``max_sessions``, and the store holds four
sessions. Deleting one frees its place for exactly one more creation.
"""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import ExitStack, contextmanager
from pathlib import Path

import httpx
import pytest

from tests.api.conftest import ADMIN_TOKEN
from tests.api.scenario import session_config
from tests.e2e.service_process import instance, private_redis

LIMIT = 4
CLIENTS_PER_INSTANCE = 6
SETTINGS = {"CREDAL_MAX_SESSIONS": str(LIMIT), "CREDAL_RATE_LIMIT": "none"}
ADMIN = {"Authorization": f"Bearer {ADMIN_TOKEN}"}


@contextmanager
def two_instances(store: str, tmp_path: Path) -> Iterator[list[str]]:
    with ExitStack() as stack:
        if store == "redis":
            url = stack.enter_context(private_redis(tmp_path)).url
        else:
            url = f"sqlite:{tmp_path / 'store.db'}"
        urls = [stack.enter_context(instance(url, SETTINGS))[0] for _ in range(2)]
        yield urls


def create_at_once(urls: list[str]) -> list[httpx.Response]:
    """Every client posts a session config when all of them are ready."""
    start = threading.Barrier(len(urls) * CLIENTS_PER_INSTANCE)
    answers: list[httpx.Response] = []
    lock = threading.Lock()

    def create(url: str) -> None:
        with httpx.Client(base_url=url, timeout=30) as client:
            client.get("/healthz")  # connected before the barrier
            start.wait()
            answer = client.post("/v1/sessions", json=session_config())
        with lock:
            answers.append(answer)

    threads = [
        threading.Thread(target=create, args=(url,))
        for url in urls
        for _ in range(CLIENTS_PER_INSTANCE)
    ]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    return answers


@pytest.mark.parametrize("store", ["redis", "sqlite"])
def test_concurrent_creations_on_two_instances_never_exceed_the_limit(
    store: str, tmp_path: Path
) -> None:
    with two_instances(store, tmp_path) as urls:
        answers = create_at_once(urls)
        statuses = sorted(answer.status_code for answer in answers)
        assert statuses == [201] * LIMIT + [429] * (len(answers) - LIMIT), statuses
        for refused in (answer for answer in answers if answer.status_code == 429):
            problem = refused.json()
            assert problem["limit"] == "max_sessions" and problem["maximum"] == LIMIT
            assert problem["errors"][0]["pointer"] == "#"
        listed = httpx.get(f"{urls[1]}/v1/sessions", headers=ADMIN).json()
        created = {answer.json()["id"] for answer in answers if answer.status_code == 201}
        assert {item["id"] for item in listed["sessions"]} == created

        deleted = next(iter(created))
        assert httpx.delete(f"{urls[0]}/v1/sessions/{deleted}", headers=ADMIN).status_code == 204
        again = create_at_once(urls)
        assert sorted(answer.status_code for answer in again) == [201] + [429] * (len(again) - 1)
