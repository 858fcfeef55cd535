"""No stale reads: an instance that does not apply a session's inputs still answers its
current state, and a session deleted through one instance is gone on every instance.

Two real instances (uvicorn subprocesses) share the real Redis under a prefix
of this test. A applies every input (it holds the lease); B has the session
in memory from an earlier read. B's answers must equal A's after every input,
with the log compacted behind snapshots meanwhile (so B catches up both from
the log and from a snapshot), and after a delete through A, B answers 404.
"""

from __future__ import annotations

from contextlib import ExitStack

import httpx

from tests.api.redis_support import REDIS_URL, redis_prefix
from tests.api.scenario import reports, session_config
from tests.e2e.service_process import instance

STEPS = 12


def test_a_non_leasing_instance_answers_the_current_state_and_forgets_a_deleted_session() -> None:
    bodies = reports(STEPS)
    with redis_prefix("fresh-reads") as prefix, ExitStack() as stack:
        settings = {
            "CREDAL_REDIS_PREFIX": prefix,
            "CREDAL_SNAPSHOT_EVERY": "3",
            "CREDAL_LOG_RETENTION": "1",
        }
        a_url, _ = stack.enter_context(instance(REDIS_URL, settings))
        b_url, _ = stack.enter_context(instance(REDIS_URL, settings))
        a = stack.enter_context(httpx.Client(base_url=a_url, timeout=30))
        b = stack.enter_context(httpx.Client(base_url=b_url, timeout=30))
        created = a.post("/v1/sessions", json=session_config()).json()
        sid, headers = created["id"], {"Authorization": f"Bearer {created['token']}"}
        summary, picture = f"/v1/sessions/{sid}", f"/v1/sessions/{sid}/tracks"
        assert b.get(summary, headers=headers).json()["seq"] == 0  # B holds it in memory now
        for index, body in enumerate(bodies):
            result = a.post(picture, json=body, headers=headers)
            assert result.status_code == 200, result.text
            if index % 5 == 4:
                continue  # B falls behind by two inputs, then one snapshot, now and then
            on_a = a.get(summary, headers=headers).json()
            on_b = b.get(summary, headers=headers).json()
            assert on_b["seq"] == on_a["seq"] == index + 1
            assert on_b == on_a
            assert b.get(picture, headers=headers).json() == a.get(picture, headers=headers).json()
        tracks = a.get(picture, headers=headers).json()["tracks"]
        assert tracks, "the scene has fused tracks"
        detail = f"{picture}/{tracks[0]['id']}"
        assert b.get(detail, headers=headers).json() == a.get(detail, headers=headers).json()

        assert a.delete(summary, headers=headers).status_code == 204
        for path in (summary, picture, detail, f"{summary}/events"):
            gone = b.get(path, headers=headers)
            assert gone.status_code == 404, (path, gone.text)
            assert gone.json()["type"] == "urn:credal-fusion:problem:session-not-found"
        refused = b.post(picture, json=bodies[0], headers=headers)
        assert refused.status_code == 404, refused.text
