"""The reference client (``app/commands/resilient.py``) streams through a failover, losing nothing.

Two real instances share a session through the real Redis, with the default
lease (3 s). The client streams its inputs to instance A; A is killed with
SIGKILL halfway; the client reconnects to instance B, which takes the session
over once A's lease lapses. Every input is applied exactly once, in order:
the delivered ``seq`` numbers are 1..N and B's event log holds the N inputs
sent, in the order sent. No time is asserted (the takeover's is printed).
"""

from __future__ import annotations

import signal
import time

import httpx

from app.commands.resilient import ResilientStream
from tests.api.redis_support import REDIS_URL, redis_prefix
from tests.api.scenario import reports, session_config
from tests.e2e.service_process import instance

STEPS = 6
KILL_AFTER = 3


def test_a_client_following_the_protocol_loses_nothing_in_a_failover() -> None:
    with redis_prefix("failover") as prefix:
        environment = {"CREDAL_REDIS_PREFIX": prefix}
        with (
            instance(REDIS_URL, environment) as (url_a, process_a),
            instance(REDIS_URL, environment) as (url_b, _),
        ):
            created = httpx.post(f"{url_a}/v1/sessions", json=session_config(), timeout=30).json()
            client = ResilientStream([url_a, url_b], created["id"], created["token"])
            bodies = reports(STEPS)
            deliveries = []
            try:
                for index, body in enumerate(bodies):
                    if index == KILL_AFTER:
                        process_a.send_signal(signal.SIGKILL)
                        process_a.wait()
                        killed = time.monotonic()
                    deliveries.append(client.send({"type": "tracks", **body}))
                    if index == KILL_AFTER:
                        print(f"taken over in {time.monotonic() - killed:.1f} s")
            finally:
                client.close()
            assert [delivery.seq for delivery in deliveries] == list(range(1, STEPS + 1))
            assert sum(delivery.retries for delivery in deliveries) >= 1  # it did fail over
            headers = {"Authorization": f"Bearer {created['token']}"}
            events = httpx.get(
                f"{url_b}/v1/sessions/{created['id']}/events", headers=headers, timeout=30
            ).json()
            logged = [(event["seq"], event["report"]["time"]) for event in events["events"]]
            assert logged == [(index + 1, body["time"]) for index, body in enumerate(bodies)]
