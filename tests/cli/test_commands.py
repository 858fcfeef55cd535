"""The CLI beyond `serve`: simulate, reproduce, export and replay (against a live server too)."""

from __future__ import annotations

import dataclasses
import io
import json
from pathlib import Path

import httpx
import pytest

from api_schemas.reports import TrackReport
from app.cli import main
from app.commands import simulate
from app.commands.export import export_events
from app.commands.replay import read_events
from app.commands.runner import run_locally, run_on_server
from app.commands.scenarios import build
from tests.api.conftest import LiveServer, live_server, make_settings, serving
from tests.api.examples import SESSION_CONFIG, TRACK_REPORT

__all__ = ["live_server"]


def test_simulate_t2t_four_in_process_prints_a_clean_summary(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["simulate", "t2t-four", "--seed", "1", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "scenario t2t-four, seed 1: 40 inputs" in out
    assert (
        "identity switches: 0; fused ids per target: 0: ['F1'], 1: ['F2'], 2: ['F3'], 3: ['F4']"
        in out
    )


def test_simulate_overtaking_keeps_the_identity_through_the_blind_zone(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert main(["simulate", "overtaking", "--quiet"]) == 0
    assert "identity switches: 0" in capsys.readouterr().out


@pytest.mark.parametrize("local", [False, True])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_overtaking_keeps_the_fused_id_through_the_blind_zone_on_either_path(
    local: bool, seed: int
) -> None:
    """Rear sensor, blind zone, front sensor ([HZ] §6 Fig 6): the central tracker (the
    session's region makes the gap a blind zone, where its track is a phantom that the
    front sensor's new track hands over to) and the per-sensor trackers with track-to-track
    fusion both keep vehicle 1's fused id (docs/algorithms.md §8.9)."""
    run = build("overtaking", seed=seed)
    config = {
        **run.config,
        "sensors": [{**sensor, "local_tracker": local} for sensor in run.config["sensors"]],
    }
    results = list(run_locally(config, run.inputs))
    summary = simulate.summarise(dataclasses.replace(run, config=config), results)
    assert "identity switches: 0" in summary
    assert "1: ['F1']" in summary


def test_a_scenario_gives_the_same_results_through_a_server(live_server: LiveServer) -> None:
    run = build("aircraft", seed=2)
    inputs = run.inputs[:40]
    assert list(run_on_server(live_server.url, run.config, inputs)) == list(
        run_locally(run.config, inputs)
    )


def test_export_then_replay_gives_exactly_the_recorded_results(
    live_server: LiveServer, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = build("crossing-traffic", seed=3)
    inputs = run.inputs[:30]
    sessions: list[tuple[str, str]] = []
    recorded = list(
        run_on_server(
            live_server.url, run.config, inputs, on_session=lambda i, t: sessions.append((i, t))
        )
    )
    events = tmp_path / "events.jsonl"
    session_id, token = sessions[0]
    events.write_text("\n".join(export_events(live_server.url, session_id, token)) + "\n")
    config, logged = read_events(io.StringIO(events.read_text()))
    assert [TrackReport.model_validate(body) for _, body in logged] == [
        TrackReport.model_validate(body) for _, body in inputs
    ]
    # Through a live server (a new session) and in process: the same results, line by line.
    assert main(["replay", str(events), "--server", live_server.url, "--quiet"]) == 0
    through_server = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert main(["replay", str(events), "--quiet"]) == 0
    in_process = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert through_server == recorded
    assert in_process == recorded
    assert config["sensors"][0]["id"] == "s1"


def test_reproduce_writes_the_png(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["reproduce", "aircraft", "--reduced", "--out", str(tmp_path)]) == 0
    written = Path(capsys.readouterr().out.strip().splitlines()[-1])
    assert written == tmp_path / "aircraft.png"
    assert written.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_bench_refuses_an_unknown_benchmark(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "no-such-bench"]) == 2
    assert "unknown benchmark(s) ['no-such-bench']" in capsys.readouterr().err


def test_read_events_refuses_a_file_without_its_session_line() -> None:
    line = json.dumps({"type": "tracks", "seq": 1, "report": TRACK_REPORT})
    with pytest.raises(ValueError, match="no session line"):
        read_events(io.StringIO(line + "\n"))


def test_read_events_names_the_invalid_field_of_a_line() -> None:
    report = dict(TRACK_REPORT, time="soon")
    lines = [
        json.dumps({"type": "session", "config": SESSION_CONFIG}),
        json.dumps({"type": "tracks", "seq": 1, "report": report}),
    ]
    with pytest.raises(
        ValueError, match=r"^line 2: invalid report: time: .*'soon' is not an RFC 3339 timestamp"
    ):
        read_events(io.StringIO("\n".join(lines)))


def test_speed_releases_the_inputs_on_the_scenario_clock(monkeypatch: pytest.MonkeyPatch) -> None:
    clock = [100.0]  # a fake monotonic clock: sleeping advances it, nothing else does
    slept: list[float] = []

    def sleep(seconds: float) -> None:
        slept.append(seconds)
        clock[0] += seconds

    monkeypatch.setattr(simulate.time, "monotonic", lambda: clock[0])
    monkeypatch.setattr(simulate.time, "sleep", sleep)
    inputs = [("tracks", {"time": t}) for t in (10.0, 10.0, 12.0, 13.0)]
    released = []
    for _kind, body in simulate.paced(inputs, speed=2.0):
        released.append((clock[0], body["time"]))
    # At twice the scenario's speed: 0, 0, 1 and 1.5 s after the start.
    assert released == [(100.0, 10.0), (100.0, 10.0), (101.0, 12.0), (101.5, 13.0)]
    assert slept == [1.0, 0.5]


def test_a_compacted_session_exports_replays_and_restores_to_identical_results(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    run = build("crossing-traffic", seed=3)
    inputs, later = run.inputs[:30], run.inputs[30:40]
    uninterrupted = list(run_locally(run.config, [*inputs, *later]))
    # snapshots at 7, 14, 21, 28; each compacts the log to 3 inputs behind it: 26..30 remain
    settings = make_settings(
        store=f"sqlite:{tmp_path / 'store.db'}",
        snapshot_every=7,
        log_retention=3,
        max_body_bytes=1 << 20,
    )
    sessions: list[tuple[str, str]] = []
    with serving(settings) as server:
        recorded = list(
            run_on_server(
                server.url,
                run.config,
                inputs,
                on_session=lambda i, t: sessions.append((i, t)),
                keep=True,
            )
        )
        session_id, token = sessions[0]
        headers = {"Authorization": f"Bearer {token}"}
        page = httpx.get(
            f"{server.url}/v1/sessions/{session_id}/events", params={"after": 0}, headers=headers
        ).json()
        assert page["snapshot"]["seq"] == 28 and page["last_seq"] == 30
        assert [event["seq"] for event in page["events"]] == [29, 30]
        retained = httpx.get(
            f"{server.url}/v1/sessions/{session_id}/events", params={"after": 25}, headers=headers
        ).json()
        assert "snapshot" not in retained
        assert [event["seq"] for event in retained["events"]] == [26, 27, 28, 29, 30]
        events = tmp_path / "events.jsonl"
        events.write_text("\n".join(export_events(server.url, session_id, token)) + "\n")
    assert recorded == uninterrupted[:30]
    lines = [json.loads(line) for line in events.read_text().splitlines()]
    assert [line["type"] for line in lines] == ["session", "snapshot", "tracks", "tracks"]
    assert main(["replay", str(events), "--quiet"]) == 0
    replayed = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert replayed == uninterrupted[28:30]  # the snapshot's state, then inputs 29 and 30
    assert main(["replay", str(events), "--server", "http://127.0.0.1:9", "--quiet"]) == 2
    assert "replay it locally" in capsys.readouterr().err
    with serving(settings) as server:  # restored from the compacted file: snapshot + 29, 30
        path = f"{server.url}/v1/sessions/{session_id}/tracks"
        continued = [httpx.post(path, json=body, headers=headers).json() for _, body in later]
    assert continued == uninterrupted[30:40]
