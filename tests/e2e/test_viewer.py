"""The live viewer: served at ``/`` by the real server, self-contained, and its WebSocket login works.

No browser runs here (none is installed by the project): the test checks the
page loads, fetches nothing from outside, reads the contract's field names,
and that the way the page authenticates its ``subscribe`` WebSocket — the
subprotocols ``["bearer", token]``, since browsers cannot set headers on an
upgrade — is accepted and delivers results.
"""

from __future__ import annotations

import json
import re

import httpx
import pytest
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from tests.api.conftest import LiveServer
from tests.api.scenario import reports, session_config

RECEIVE_TIMEOUT_S = 20.0


def test_the_viewer_page_loads_and_is_self_contained(live_server: LiveServer) -> None:
    answer = httpx.get(f"{live_server.url}/")
    assert answer.status_code == 200
    assert answer.headers["content-type"].startswith("text/html")
    page = answer.text
    assert "<canvas" in page and "/subscribe" in page
    for field in ("covariance", "pignistic", "fov", "heading_deg", "half_angle_deg", "position"):
        assert field in page, field
    assert not re.search(r"""(src|href)\s*=\s*["']?(https?:)?//""", page), "fetches from outside"
    assert "/" not in httpx.get(f"{live_server.url}/openapi.json").json()["paths"]


def test_the_viewer_login_subscribes_with_the_bearer_subprotocol(live_server: LiveServer) -> None:
    with httpx.Client(base_url=live_server.url, timeout=30) as client:
        created = client.post("/v1/sessions", json=session_config()).json()
        sid, token = created["id"], created["token"]
        url = live_server.url.replace("http://", "ws://") + f"/v1/sessions/{sid}/subscribe"
        with connect(url, subprotocols=["bearer", token]) as viewer:  # type: ignore[list-item]
            assert viewer.subprotocol == "bearer"
            assert json.loads(viewer.recv(timeout=RECEIVE_TIMEOUT_S))["type"] == "ack"
            body = reports(1)[0]
            headers = {"Authorization": f"Bearer {token}"}
            posted = client.post(f"/v1/sessions/{sid}/tracks", json=body, headers=headers)
            message = json.loads(viewer.recv(timeout=RECEIVE_TIMEOUT_S))
            assert message["type"] == "result" and message["result"] == posted.json()
        with (
            pytest.raises(InvalidStatus) as refused,
            connect(url, subprotocols=["bearer", "not-the-token"]),  # type: ignore[list-item]
        ):
            pass
        assert refused.value.response.status_code == 403
