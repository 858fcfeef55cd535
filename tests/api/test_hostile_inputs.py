"""Hostile inputs against a live uvicorn server: never a 5xx, every refusal a problem, nothing changes.

One session holds one accepted track list. Each case sends something hostile
— sizes past every limit, deep nesting, numbers at the edges of float64,
broken encodings, broken HTTP framing, WebSocket abuse — and then:

- no answer is a 5xx; every refusal is ``application/problem+json`` (a 422
  lists ``errors`` with a JSON ``pointer`` and a ``detail`` free of library
  prefixes); a refusal's body stays small (at most :data:`MAX_REFUSAL_BYTES`);
- the session's ``seq``, fused tracks, event log and the number of sessions
  are what they were.

Framing errors that the HTTP server itself refuses (before the application)
must get a 4xx or a closed connection, never a hang. After every case the
server is healthy, ``/metrics`` counts no internal error, and a valid input
is still accepted.
"""

from __future__ import annotations

import contextlib
import copy
import gzip
import http.client
import json
import socket
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import httpx
import pytest
from websockets.exceptions import ConnectionClosed
from websockets.sync.client import ClientConnection, connect

from tests.api.conftest import ADMIN_TOKEN, LiveServer, make_settings, serving
from tests.api.scenario import CLASSES, track_report

Body = dict[str, Any]
MAX_BODY = 64 * 1024
MAX_TRACKS = 20
MAX_FOCAL_SETS = 8
WS_RATE = 20
MAX_WORK = 60  # a track list of 20 on the scene's 3 fused tracks is 20 × 4 = 80 work units
MAX_EXPLAIN_CELLS = 30  # 8 tracks on 3 explained: (3 + 8) × 8 = 88 cells
MAX_REFUSAL_BYTES = 16 * 1024
GOOD = track_report("radar-1", 12.5, seed=1)
LATER = track_report("radar-1", 13.0, seed=2)
CONFIG: Body = {
    "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
    "classes": CLASSES,
    "sensors": [{"id": "radar-1"}, {"id": "radar-2"}],
}
ADMIN = {"Authorization": f"Bearer {ADMIN_TOKEN}"}


@dataclass
class Scene:
    server: LiveServer
    http: httpx.Client
    sid: str
    headers: dict[str, str]

    @property
    def tracks_path(self) -> str:
        return f"/v1/sessions/{self.sid}/tracks"

    @property
    def ws_url(self) -> str:
        return self.server.url.replace("http://", "ws://") + f"/v1/sessions/{self.sid}/stream"

    def state(self) -> tuple[object, ...]:
        """What no refusal may change: seq, fused tracks, event log, number of sessions."""
        summary = self.http.get(f"/v1/sessions/{self.sid}", headers=self.headers).json()
        picture = self.http.get(self.tracks_path, headers=self.headers).json()
        events = self.http.get(f"/v1/sessions/{self.sid}/events", headers=self.headers).json()
        sessions = self.http.get("/v1/sessions", headers=ADMIN).json()["sessions"]
        return summary["seq"], picture, events, len(sessions)


@pytest.fixture(scope="module")
def scene() -> Iterator[Scene]:
    settings = make_settings(
        max_body_bytes=MAX_BODY,
        max_tracks_per_input=MAX_TRACKS,
        max_focal_sets=MAX_FOCAL_SETS,
        ws_messages_per_second=WS_RATE,
        body_read_timeout=0.5,
        request_head_timeout=1.0,
        max_input_work=MAX_WORK,
        max_explain_cells=MAX_EXPLAIN_CELLS,
        rate_limit="none",
    )
    with serving(settings) as server, httpx.Client(base_url=server.url, timeout=30.0) as http:
        created = http.post("/v1/sessions", json=CONFIG).json()
        headers = {"Authorization": f"Bearer {created['token']}"}
        accepted = http.post(f"/v1/sessions/{created['id']}/tracks", json=GOOD, headers=headers)
        assert accepted.status_code == 200, accepted.text
        yield Scene(server, http, created["id"], headers)


# ------------------------------------------------------------------ how cases send
@dataclass(frozen=True)
class Answer:
    """One answer: HTTP status, content type and body (a WebSocket error: its problem)."""

    status: int
    content_type: str
    body: bytes


def post(scene: Scene, path: str, content: bytes | str, **headers: str) -> Answer:
    sent = {"Content-Type": "application/json", **scene.headers, **headers}
    response = scene.http.post(path, content=content, headers=sent)
    return Answer(response.status_code, response.headers.get("content-type", ""), response.content)


def tracks(text: bytes | str, **headers: str) -> Callable[[Scene], list[Answer]]:
    return lambda scene: [post(scene, scene.tracks_path, text, **headers)]


def later(change: Callable[[Body], object]) -> str:
    body = copy.deepcopy(LATER)
    change(body)
    return json.dumps(body)


def raw_later(old: str, new: str) -> str:
    text = json.dumps(LATER)
    assert old in text
    return text.replace(old, new, 1)


def first_track(body: Body) -> Body:
    track: Body = body["tracks"][0]
    return track


def get(path: str, **params: str) -> Callable[[Scene], list[Answer]]:
    def send(scene: Scene) -> list[Answer]:
        response = scene.http.get(path.format(sid=scene.sid), params=params, headers=scene.headers)
        content_type = response.headers.get("content-type", "")
        return [Answer(response.status_code, content_type, response.content)]

    return send


def _whole(received: bytes) -> bool:
    """Whether ``received`` holds an answer's head and all the body its Content-Length
    declares (the head and the body may come in separate segments)."""
    head, found, body = received.partition(b"\r\n\r\n")
    if not found:
        return False
    for line in head.split(b"\r\n")[1:]:
        name, _, value = line.partition(b":")
        if name.strip().lower() == b"content-length":
            return len(body) >= int(value.strip())
    return True


def raw_http(request: bytes, *, wait: float = 2.0) -> Callable[[Scene], list[Answer]]:
    """Bytes written on a raw socket; the status line read back (or a closed connection)."""

    def send(scene: Scene) -> list[Answer]:
        port = int(scene.server.url.rsplit(":", 1)[1])
        with socket.create_connection(("127.0.0.1", port), timeout=wait + 5.0) as connection:
            connection.sendall(request.replace(b"{sid}", scene.sid.encode()))
            received = b""
            deadline = time.monotonic() + wait + 5.0
            while not _whole(received) and time.monotonic() < deadline:
                chunk = connection.recv(65536)
                if not chunk:
                    break
                received += chunk
        if not received:
            return [Answer(499, "closed", b"")]  # closed without an answer: allowed
        head, _, body = received.partition(b"\r\n\r\n")
        status = int(head.split(b" ", 2)[1])
        content_type = ""
        for line in head.split(b"\r\n")[1:]:
            name, _, value = line.partition(b":")
            if name.strip().lower() == b"content-type":
                content_type = value.strip().decode()
        return [Answer(status, content_type, body)]

    return send


def raw_head(head: bytes, *, chunk: int = 65536) -> Callable[[Scene], list[Answer]]:
    """A request head written in pieces until the server answers or closes (a refusal of a
    head too large comes before the head ends); the answer's status read back."""

    def send(scene: Scene) -> list[Answer]:
        port = int(scene.server.url.rsplit(":", 1)[1])
        with socket.create_connection(("127.0.0.1", port), timeout=10.0) as connection:
            with contextlib.suppress(OSError):  # closed by the server mid-way: read its answer
                for start in range(0, len(head), chunk):
                    connection.sendall(head[start : start + chunk])
            received = b""
            with contextlib.suppress(OSError):
                while chunk_in := connection.recv(65536):
                    received += chunk_in
        return [_parsed(received)]

    return send


def _parsed(received: bytes) -> Answer:
    if not received:
        return Answer(499, "closed", b"")
    head, _, body = received.partition(b"\r\n\r\n")
    content_type = ""
    for line in head.split(b"\r\n")[1:]:
        name, _, value = line.partition(b":")
        if name.strip().lower() == b"content-type":
            content_type = value.strip().decode()
    return Answer(int(head.split(b" ", 2)[1]), content_type, body)


def naming(limit: str, send: Callable[[Scene], list[Answer]]) -> Callable[[Scene], list[Answer]]:
    """``send``, whose first answer must be the refusal that names ``limit`` (``""``: a 415)."""

    def checked(scene: Scene) -> list[Answer]:
        answers = send(scene)
        if limit:
            assert json.loads(answers[0].body).get("limit") == limit, answers[0]
        else:
            assert answers[0].status == 415, answers[0]
        return answers

    return checked


def ws_messages(*frames: str | bytes) -> Callable[[Scene], list[Answer]]:
    """Frames sent on the ``stream`` channel; each must be answered by an ``error`` message."""

    def send(scene: Scene) -> list[Answer]:
        with connect(
            scene.ws_url, additional_headers=scene.headers, max_size=None, open_timeout=10
        ) as ws:
            assert json.loads(ws.recv(timeout=10))["type"] == "ack"
            answers = []
            for frame in frames:
                ws.send(frame)
                answers.append(ws_error(ws))
            ws.send("{}")  # the connection is still open and answering
            answers.append(ws_error(ws))
        return answers

    return send


def ws_error(ws: ClientConnection) -> Answer:
    message = json.loads(ws.recv(timeout=10))
    assert message["type"] == "error", message
    problem = message["problem"]
    return Answer(int(problem["status"]), "application/problem+json", json.dumps(problem).encode())


def ws_oversize(frame: str) -> Callable[[Scene], list[Answer]]:
    """A frame beyond 4 × ``max_body_bytes``: an ``error`` message, then the close (1009)."""

    def send(scene: Scene) -> list[Answer]:
        with connect(
            scene.ws_url, additional_headers=scene.headers, max_size=None, open_timeout=10
        ) as ws:
            assert json.loads(ws.recv(timeout=10))["type"] == "ack"
            ws.send(frame)
            answer = ws_error(ws)
            with pytest.raises(ConnectionClosed) as closed:
                ws.recv(timeout=10)
        assert closed.value.rcvd is not None and closed.value.rcvd.code == 1009
        return [answer]

    return send


def ws_flood(count: int) -> Callable[[Scene], list[Answer]]:
    """``count`` invalid messages at once: beyond the rate each is refused with a 429 error."""

    def send(scene: Scene) -> list[Answer]:
        with connect(scene.ws_url, additional_headers=scene.headers, open_timeout=10) as ws:
            assert json.loads(ws.recv(timeout=10))["type"] == "ack"
            for _ in range(count):
                ws.send("{}")
            answers = [ws_error(ws) for _ in range(count)]
        assert any(answer.status == 429 for answer in answers)
        return answers

    return send


def ws_upgrade(headers: dict[str, str]) -> Callable[[Scene], list[Answer]]:
    def send(scene: Scene) -> list[Answer]:
        from websockets.exceptions import InvalidStatus

        with pytest.raises(InvalidStatus) as refused:
            connect(scene.ws_url, additional_headers=headers, open_timeout=10).close()
        response = refused.value.response
        content_type = response.headers.get("content-type", "")
        return [Answer(response.status_code, content_type, bytes(response.body or b""))]

    return send


def nested(depth: int, opening: str = "[", closing: str = "]") -> str:
    return opening * depth + closing * depth


def many_tracks(count: int) -> str:
    return json.dumps({"sensor": "radar-1", "time": 13.0, "tracks": [{}] * count})


def focal_sets(count: int) -> str:
    masses = [{"set": [CLASSES[0]], "mass": 1.0 / count}] * count
    return later(lambda body: first_track(body).update(classification={"mass": masses}))


# ------------------------------------------------------------------ the cases
CASES: dict[str, Callable[[Scene], list[Answer]]] = {
    # --- size
    "body over max_body_bytes": tracks(later(lambda b: first_track(b).update(pad="x" * MAX_BODY))),
    "declared Content-Length of 1 GB": raw_http(
        b"POST /v1/sessions HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
        b"Content-Length: 1000000000\r\n\r\n{"
    ),
    "chunked body over the limit": lambda scene: [
        post(scene, scene.tracks_path, iter([b"[" * 8192] * 16))  # type: ignore[arg-type]
    ],
    "one track too many": tracks(many_tracks(MAX_TRACKS + 1)),
    "10 000 empty tracks": tracks(many_tracks(10_000)),
    "20 000 empty tracks to /v1/associate": lambda scene: [
        post(scene, "/v1/associate", json.dumps({"known": [{}] * 20_000, "incoming": []}))
    ],
    "10 000 sensors in a config": lambda scene: [
        post(scene, "/v1/sessions", json.dumps(dict(CONFIG, sensors=[{}] * 10_000)))
    ],
    "focal sets over max_focal_sets": tracks(focal_sets(MAX_FOCAL_SETS + 1)),
    "21 classes": lambda scene: [
        post(scene, "/v1/sessions", json.dumps(dict(CONFIG, classes=[f"c{i}" for i in range(21)])))
    ],
    "track id of 65 characters": tracks(later(lambda b: first_track(b).update(id="i" * 65))),
    "sensor id of 10 000 characters": tracks(later(lambda b: b.update(sensor="s" * 10_000))),
    "state of 65 components": tracks(later(lambda b: first_track(b).update(state=[1.0] * 65))),
    "3 000 unknown keys": tracks(later(lambda b: b.update({f"k{i}": i for i in range(3000)}))),
    "20 invalid tracks (errors capped)": tracks(
        json.dumps({"sensor": "radar-1", "time": 13.0, "tracks": [{"id": 1}] * MAX_TRACKS})
    ),
    # --- depth
    "arrays nested 100 deep in a state": tracks(
        later(lambda b: first_track(b).update(state=json.loads(nested(100))))
    ),
    "arrays nested 20 000 deep": tracks(nested(20_000)),
    "objects nested 10 000 deep": tracks('{"a":' * 10_000 + "1" + "}" * 10_000),
    "nesting 5 000 deep inside a track": tracks(
        raw_later('"state": [', '"classification": ' + nested(5000) + ', "state": [')
    ),
    # --- numbers at the edges of float64
    "NaN token": tracks(raw_later('"time": 13.0', '"time": NaN')),
    "Infinity token": tracks(raw_later('"time": 13.0', '"time": Infinity')),
    "-Infinity in a covariance": tracks(
        raw_later('"covariance": [[', '"covariance": [[-Infinity, ')
    ),
    "1e309 overflows to infinity": tracks(raw_later('"time": 13.0', '"time": 1e309')),
    "-1e309 in a state": tracks(raw_later('"state": [', '"state": [-1e309, ')),
    "1e-400 underflows: zero covariance": tracks(
        later(
            lambda b: first_track(b).update(
                covariance=[[1e-400 * (i == j) for j in range(4)] for i in range(4)]
            )
        )
    ),
    "subnormal 5e-324 covariance": tracks(
        later(
            lambda b: first_track(b).update(
                covariance=[[5e-324 * (i == j) for j in range(4)] for i in range(4)]
            )
        )
    ),
    "covariance 1.7e308 on the diagonal with a negative twin": tracks(
        later(
            lambda b: first_track(b).update(
                covariance=[
                    [1.7e308, -1.7e308, 0, 0],
                    [-1.7e308, 1.7e308, 0, 0],
                    [0, 0, 1, 0],
                    [0, 0, 0, 1],
                ]
            )
        )
    ),
    "asymmetry 1e-11 at scale 1e-3": tracks(
        later(
            lambda b: first_track(b).update(
                covariance=[[1e-3, 1e-11, 0, 0], [0, 1e-3, 0, 0], [0, 0, 1e-3, 0], [0, 0, 0, 1e-3]]
            )
        )
    ),
    "near-singular covariance (eigenvalue 1e-13)": tracks(
        later(
            lambda b: first_track(b).update(
                covariance=[[1, 0, 0, 0], [0, 1e-13, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
            )
        )
    ),
    "negative zero on the diagonal": tracks(
        later(
            lambda b: first_track(b).update(
                covariance=[[-0.0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
            )
        )
    ),
    "integer of 5 000 digits": tracks(raw_later('"time": 13.0', '"time": ' + "9" * 5000)),
    "time 1e308 (cannot be predicted to)": tracks(later(lambda b: b.update(time=1e308))),
    "time -1e308 (stale)": tracks(later(lambda b: b.update(time=-1e308))),
    "time as a string": tracks(later(lambda b: b.update(time="13.0"))),
    "time as true": tracks(later(lambda b: b.update(time=True))),
    "masses summing to 0.9": tracks(
        later(
            lambda b: first_track(b).update(
                classification={"mass": [{"set": ["bomber"], "mass": 0.9}]}
            )
        )
    ),
    # --- encodings
    "invalid UTF-8": tracks(json.dumps(LATER).encode().replace(b'"radar-1"', b'"radar-\xff"')),
    "UTF-16 with a BOM": tracks(json.dumps(LATER).encode("utf-16")),
    "UTF-8 BOM": tracks(b"\xef\xbb\xbf" + json.dumps(LATER).encode()),
    "latin-1 declared and sent": tracks(
        json.dumps(LATER, ensure_ascii=False).replace("radar-1", "radaré").encode("latin-1"),
        **{"Content-Type": "application/json; charset=latin-1"},
    ),
    "lone surrogate in the sensor id": tracks(raw_later('"radar-1"', '"\\ud800"')),
    "NUL in the sensor id": tracks(raw_later('"radar-1"', '"radar\\u0000-1"')),
    "raw control character in a string": tracks(raw_later('"radar-1"', '"radar\x01-1"')),
    "a gzip body (Content-Encoding)": naming(
        "",
        tracks(gzip.compress(json.dumps(LATER).encode()), **{"Content-Encoding": "gzip"}),
    ),
    "plain JSON labelled gzip": naming(
        "", tracks(json.dumps(LATER), **{"Content-Encoding": "gzip"})
    ),
    "text/plain content type": tracks(json.dumps(LATER), **{"Content-Type": "text/plain"}),
    "empty body": tracks(b""),
    "body null": tracks("null"),
    "body an array": tracks("[]"),
    "body a string": tracks('"tracks"'),
    "truncated JSON": tracks(json.dumps(LATER)[:-10]),
    "trailing garbage": tracks(json.dumps(LATER) + " {}"),
    "duplicate key at the top": tracks(raw_later('"time": 13.0', '"time": 13.0, "time": 14.0')),
    "duplicate key in a track": tracks(raw_later('"state": [', '"id": "again", "state": [')),
    "unknown key with a near miss": tracks(later(lambda b: b.update(trackz=[]))),
    # --- queries and paths
    "events after 2**64": get("/v1/sessions/{sid}/events", after=str(2**64)),
    "events after -1": get("/v1/sessions/{sid}/events", after="-1"),
    "events limit 10**9": get("/v1/sessions/{sid}/events", limit=str(10**9)),
    "picture at time NaN": get("/v1/sessions/{sid}/tracks", time="nan"),
    "picture at time 1e308": get("/v1/sessions/{sid}/tracks", time="1e308"),
    "picture at time -1e308": get("/v1/sessions/{sid}/tracks", time="-1e308"),
    "session id of 65 characters": get("/v1/sessions/" + "s" * 65),
    "unknown fused track of 1 000 characters": get("/v1/sessions/{sid}/tracks/" + "t" * 1000),
    "20 tracks over max_input_work (20 × (3 fused + 1))": naming(
        "max_input_work", tracks(json.dumps(track_report("radar-1", 13.0, seed=3, targets=20)))
    ),
    "explain over max_explain_cells ((3 + 8) × 8)": naming(
        "max_explain_cells",
        lambda scene: [
            post(
                scene,
                scene.tracks_path + "?explain=true",
                json.dumps(track_report("radar-1", 13.0, seed=4, targets=8)),
            )
        ],
    ),
    "picture at time 1e102 (beyond the inputs' 1e12)": get(
        "/v1/sessions/{sid}/tracks", time="1e102"
    ),
    "motion.q 1e300 (later predictions overflow)": lambda scene: [
        post(scene, "/v1/sessions", json.dumps(dict(CONFIG, motion={"q": 1e300})))
    ],
    # --- framing and headers
    "body slower than body_read_timeout": raw_http(
        b"POST /v1/sessions/{sid}/tracks HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
        b"Content-Length: 100\r\n\r\n{",
        wait=1.5,
    ),
    "Content-Length not a number": raw_http(
        b"POST /v1/sessions HTTP/1.1\r\nHost: x\r\nContent-Length: abc\r\n\r\n{}"
    ),
    "header line without a colon": raw_http(b"GET /healthz HTTP/1.1\r\nHost: x\r\nbroken\r\n\r\n"),
    "request line garbage": raw_http(b"\x16\x03\x01\x02\x00\x01\x00\x01\xfc\x03\x03\r\n\r\n"),
    "Authorization without a token": tracks(json.dumps(LATER), Authorization="Bearer"),
    "Basic authorization": tracks(json.dumps(LATER), Authorization="Basic dXNlcjpwYXNz"),
    "token of 8 000 characters": tracks(json.dumps(LATER), Authorization="Bearer " + "t" * 8000),
    "PUT on an input route": lambda scene: [
        Answer(
            (response := scene.http.put(scene.tracks_path, content=b"{}")).status_code,
            response.headers.get("content-type", ""),
            response.content,
        )
    ],
    "a 4 MB header (max_header_bytes)": naming(
        "max_header_bytes",
        raw_head(b"GET /healthz HTTP/1.1\r\nHost: x\r\nX-Pad: " + b"a" * (4 << 20) + b"\r\n\r\n"),
    ),
    "a 4 MB request line (max_header_bytes)": naming(
        "max_header_bytes",
        raw_head(b"GET /healthz?" + b"a" * (4 << 20) + b" HTTP/1.1\r\nHost: x\r\n\r\n"),
    ),
    "101 header lines (max_header_count)": naming(
        "max_header_count",
        raw_head(
            b"GET /healthz HTTP/1.1\r\nHost: x\r\n"
            + b"".join(b"X-%d: 1\r\n" % index for index in range(100))
            + b"\r\n"
        ),
    ),
    "head slower than request_head_timeout": naming(
        "request_head_timeout",
        raw_http(b"GET /v1/sessions/{sid} HTTP/1.1\r\nHost: x\r\n", wait=1.5),
    ),
    # --- WebSocket abuse
    "ws: not JSON": ws_messages("hello"),
    "ws: nested 30 000 deep": ws_messages(nested(30_000)),
    "ws: message over max_body_bytes": ws_messages(
        json.dumps({"type": "tracks", "pad": "x" * MAX_BODY})
    ),
    "ws: message over 4 × max_body_bytes": ws_oversize(
        json.dumps({"type": "tracks", "pad": "x" * (4 * MAX_BODY)})
    ),
    "ws: 3-byte characters over max_body_bytes in bytes": naming(
        "max_body_bytes",
        ws_messages(
            json.dumps({"type": "tracks", "pad": "\u20ac" * (MAX_BODY // 2)}, ensure_ascii=False)
        ),
    ),
    "ws: binary frame of invalid UTF-8": ws_messages(b"\xff\xfe\x00"),
    "ws: duplicate keys": ws_messages('{"type": "tracks", "type": "detections"}'),
    "ws: unknown type": ws_messages('{"type": "hello"}'),
    "ws: an array": ws_messages("[1, 2]"),
    "ws: NaN in a message": ws_messages(
        json.dumps({"type": "tracks", **LATER}).replace('"time": 13.0', '"time": NaN')
    ),
    "ws: too many tracks": ws_messages(
        json.dumps({"type": "tracks", "sensor": "radar-1", "time": 13.0, "tracks": [{}] * 5000})
    ),
    "ws: flood beyond the message rate": ws_flood(3 * WS_RATE),
    "ws: upgrade without a token": ws_upgrade({}),
    "ws: upgrade with a forged token": ws_upgrade({"Authorization": "Bearer forged"}),
}


def test_there_are_at_least_60_cases() -> None:
    assert len(CASES) >= 60


def check_refusal(answer: Answer) -> None:
    assert answer.status < 500, answer
    if answer.status == 499 or answer.status < 400:
        return
    assert len(answer.body) <= MAX_REFUSAL_BYTES, (answer.status, len(answer.body))
    if not answer.content_type.startswith("application/problem+json"):
        # refused by the HTTP server before the application (framing): a bare 400 is allowed
        assert answer.status == 400, answer
        return
    problem = json.loads(answer.body)
    assert problem["status"] == answer.status and problem["type"].startswith("urn:credal-fusion:")
    if answer.status == 422:
        assert problem["errors"], problem
        for error in problem["errors"]:
            assert error["pointer"].startswith("#"), error
            assert error["detail"] and not error["detail"].startswith(("Value error", "Assertion"))


@pytest.mark.parametrize("name", list(CASES))
def test_hostile_input_is_refused_and_changes_nothing(scene: Scene, name: str) -> None:
    before = scene.state()
    answers = CASES[name](scene)
    assert answers
    for answer in answers:
        check_refusal(answer)
    refused = all(answer.status >= 400 for answer in answers)
    assert refused, [answer.status for answer in answers]
    assert scene.state() == before
    assert scene.http.get("/healthz").status_code == 200


def test_unknown_keys_name_the_allowed_ones(scene: Scene) -> None:
    (answer,) = tracks(later(lambda b: b.update(trackz=[])))(scene)
    (error,) = json.loads(answer.body)["errors"]
    assert error["pointer"] == "#/trackz"
    assert "allowed: frame, sensor, time, tracks" in error["detail"]
    assert "did you mean 'tracks'?" in error["detail"]


def test_a_long_error_list_is_capped_and_counted(scene: Scene) -> None:
    (answer,) = CASES["20 invalid tracks (errors capped)"](scene)
    problem = json.loads(answer.body)
    listed = scene.server.settings.max_listed_errors
    assert len(problem["errors"]) == listed < problem["error_count"]


def test_after_every_case_the_server_is_healthy_and_counted_no_internal_error(
    scene: Scene,
) -> None:
    for name in ("10 000 empty tracks", "ws: nested 30 000 deep", "Content-Length not a number"):
        CASES[name](scene)
    metrics = scene.http.get("/metrics").text
    internal = [
        line for line in metrics.splitlines() if line.startswith("credal_internal_errors_t")
    ]
    assert internal == ["credal_internal_errors_total 0.0"], internal
    assert 'status="5' not in metrics
    seq = scene.state()[0]
    accepted = scene.http.post(scene.tracks_path, json=LATER, headers=scene.headers)
    assert accepted.status_code == 200, accepted.text
    assert scene.state()[0] == seq + 1  # type: ignore[operator]


def test_keep_alive_survives_refusals(scene: Scene) -> None:
    """Refusals keep the connection: one TCP connection answers all of them, then a read."""
    port = int(scene.server.url.rsplit(":", 1)[1])
    connection = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    try:
        for body in ("{", "null", json.dumps({"sensor": 1}), '{"a": 1, "a": 2}'):
            connection.request(
                "POST",
                scene.tracks_path,
                body=body,
                headers={"Content-Type": "application/json", **scene.headers},
            )
            response = connection.getresponse()
            response.read()
            assert response.status == 422
            assert response.getheader("connection") != "close"
        connection.request("GET", f"/v1/sessions/{scene.sid}", headers=scene.headers)
        assert connection.getresponse().status == 200
    finally:
        connection.close()


def read_frames(peer: socket.socket) -> tuple[list[tuple[int, bytes]], bytes]:
    """The server's frames (opcode, payload) up to its end of stream, and any bytes left over.

    A connection reset while reading fails the test (``ConnectionResetError``)."""
    received = b""
    while chunk := peer.recv(65536):
        received += chunk
    frames = []
    while len(received) >= 2:
        length, start = received[1] & 0x7F, 2
        if length == 126:
            length, start = int.from_bytes(received[2:4], "big"), 4
        elif length == 127:
            length, start = int.from_bytes(received[2:10], "big"), 10
        if len(received) < start + length:
            break
        frames.append((received[0] & 0x0F, received[start : start + length]))
        received = received[start + length :]
    return frames, received


def masked_frame_head(opcode: int, length: int, mask: bytes) -> bytes:
    """A client frame's head (FIN set) for a payload of ``length`` bytes, ``mask`` last."""
    assert length >= 65536
    return bytes([0x80 | opcode, 0x80 | 127]) + length.to_bytes(8, "big") + mask


def masking(data: bytes, mask: bytes) -> bytes:
    """``data`` masked as a client sends it (RFC 6455 § 5.3)."""
    return bytes(byte ^ mask[index % 4] for index, byte in enumerate(data))


def test_the_oversize_error_survives_a_slow_sender(scene: Scene) -> None:
    """The ``error`` and the 1009 close reach a client that sends the rest of its oversize frame
    after the server has refused it (and after the application has ended on that refusal),
    then answers the close: its stream ends cleanly, never with a reset.

    Before the fix, uvicorn closed the socket as soon as the application ended, with the rest of
    the frame unread: the kernel reset the connection, and a client that had not yet processed
    the two frames lost them (the flaky ``ws: message over 4 × max_body_bytes`` case)."""
    port = int(scene.server.url.rsplit(":", 1)[1])
    payload = json.dumps({"type": "tracks", "pad": "x" * (4 * MAX_BODY)}).encode()
    mask = b"\x01\x02\x03\x04"
    masked = masking(payload, mask)
    key = "dGhlIHNhbXBsZSBub25jZQ=="
    with socket.create_connection(("127.0.0.1", port), timeout=30) as peer:
        peer.sendall(
            (
                f"GET /v1/sessions/{scene.sid}/stream HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                "Upgrade: websocket\r\nConnection: Upgrade\r\n"
                f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n"
                f"Authorization: {scene.headers['Authorization']}\r\n\r\n"
            ).encode()
        )
        head = b""
        while b"\r\n\r\n" not in head:
            head += peer.recv(1)
        assert head.startswith(b"HTTP/1.1 101"), head
        peer.sendall(masked_frame_head(0x1, len(payload), mask) + masked[:1000])
        time.sleep(0.5)  # the server refuses at the frame's head; its application ends
        peer.sendall(masked[1000:])
        peer.sendall(bytes([0x88, 0x82]) + mask + masking((1009).to_bytes(2, "big"), mask))
        frames, rest = read_frames(peer)
    assert rest == b""
    opcodes = [opcode for opcode, _ in frames]
    assert opcodes == [0x1, 0x1, 0x8], opcodes  # ack, error, close
    assert json.loads(frames[0][1])["type"] == "ack"
    error = json.loads(frames[1][1])
    assert error["type"] == "error" and "max_body_bytes" in json.dumps(error["problem"])
    assert int.from_bytes(frames[2][1][:2], "big") == 1009


def test_settings_refuse_a_short_admin_token() -> None:
    with pytest.raises(ValueError, match="at least 32 characters"):
        make_settings(admin_token="short")
