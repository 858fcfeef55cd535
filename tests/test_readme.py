"""The README runs: its ```sh blocks, pasted in order into one bash, against a live server.

Every ```sh block is run (``set -euo pipefail``, in a temporary directory
holding a link to this ``.venv``) with ``BASE`` set to the test's server,
and what each prints is checked against what the README says it shows. The
set-up block (`make run`, `make test`) is fenced ```shell: it starts things
and is not run here. The README's lists of scenarios and of the system
packages that ``make test`` installs are checked against their sources.
"""

from __future__ import annotations

import calendar
import json
import re
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from app.commands.scenarios import names as scenario_names
from tests.api.conftest import LiveServer, live_server

__all__ = ["live_server"]

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text(encoding="utf-8")
FENCE = re.compile(r"^```(\w*)\n(.*?)^```$", re.MULTILINE | re.DOTALL)
BASE_LINE = "BASE=http://127.0.0.1:8000\n"
MARK = "@@readme-block"
TIMEOUT_S = 300.0


def fenced(language: str) -> list[str]:
    return [body for lang, body in FENCE.findall(README) if lang == language]


def one_json_per_line(output: str) -> list[dict[str, object]]:
    return [json.loads(line) for line in output.splitlines() if line.strip()]


def created(output: str) -> None:
    assert re.fullmatch(
        r"session [0-9a-f]{32}; watch it live at http://127\.0\.0\.1:\d+/"
        r"#session=[0-9a-f]{32}&token=[\w-]+\n",
        output,
    ), output


def tied(output: str) -> None:
    [result] = one_json_per_line(output)
    classification = result["tracks"][0]["classification"]  # type: ignore[index]
    # By hand: radar-1 discounted (λ = 0.9): {bomber, fighter} 0.54, Ω 0.46.
    betp = {"liner": 0.46 / 3, "bomber": 0.27 + 0.46 / 3, "fighter": 0.27 + 0.46 / 3}
    assert classification["pignistic"] == pytest.approx(betp, abs=1e-12)
    assert classification["decision"] is None and classification["decision_state"] == "tied"


def decided(output: str) -> None:
    [result] = one_json_per_line(output)
    [track] = result["tracks"]  # type: ignore[index]
    assert (track["status"], track["reason"]) == ("confirmed", "second_sensor")
    assert track["classification"]["decision"] == "fighter"
    assert track["classification"]["decision_state"] == "decided"


def detections(output: str) -> None:
    results = one_json_per_line(output)
    assert [result["seq"] for result in results] == [3, 4, 5, 6]
    final = results[-1]["tracks"][0]  # type: ignore[index]
    assert final["id"] == "F1" and final["status"] == "confirmed"
    assert {source["sensor"] for source in final["sources"]} == {"radar-1", "radar-2", "radar-3"}


def picture(output: str) -> None:
    heading, track = output.splitlines()
    assert heading == "seq 6 predicted to t = 20.0"
    assert re.match(r"F1 confirmed x, y = \[1\d\d\.\d, 2\d\d\.\d\] from ", track), track
    assert "class: fighter" in track


def streamed(output: str) -> None:
    ack, answer = output.splitlines()
    assert json.loads(ack) == {"type": "ack", "ref": None, "seq": 6}
    assert answer == "result r1 seq 7 [('F1', 'confirmed')]"


def simulated(output: str) -> None:
    lines = output.splitlines()
    assert lines[0].startswith("session ") and lines[1].startswith("viewer: http://127.0.0.1:")
    assert "identity switches: 0" in output
    assert lines[-1].startswith(lines[0].split(" (")[0] + " left open")


def replayed(output: str) -> None:
    last, status = output.splitlines()
    assert last.startswith('{"seq":7,')  # the replay's last result is the session's input 7
    assert status == "204"


def stalls(output: str) -> None:
    """The loop's lag is sampled every 5 ms: a server that has answered the blocks above
    has many samples, and the collector's pauses are there by generation."""
    samples = dict(line.rsplit(" ", 1) for line in output.splitlines())
    assert float(samples["credal_event_loop_lag_seconds_count"]) > 10
    assert 'credal_event_loop_lag_seconds_bucket{le="0.05"}' in samples
    generations = {key for key in samples if key.startswith("credal_gc_pause_seconds_count")}
    assert generations == {
        f'credal_gc_pause_seconds_count{{generation="{n}"}}' for n in range(3)
    }, generations


def geodetic(output: str) -> None:
    """The track is where the WGS84 geodesic from the radar puts it (PROJ's Geod), to 30 m:
    12.5 km at azimuth 45° (the session's north and the radar's differ by 0.03°: 6 m)."""
    from pyproj import Geod

    [line] = output.splitlines()
    match = re.fullmatch(r"F1 confirmed lon, lat = (\S+) (\S+)", line)
    assert match is not None, line
    lon, lat, _ = Geod(ellps="WGS84").fwd(1.40, 43.55, 45.0, 12_500.0)
    _, _, distance = Geod(ellps="WGS84").inv(lon, lat, float(match[1]), float(match[2]))
    assert distance < 30.0, distance


def timestamped(output: str) -> None:
    """The timestamp is worked out here by the C library's ``timegm`` (UTC), not the service's
    parser; the number sent after it is refused (422)."""
    first, second, seconds, epoch = output.split()
    assert (first, second, epoch) == ("200", "422", "unix"), output
    assert float(seconds) == calendar.timegm((2026, 12, 3, 8, 0, 0)) + 0.5


CHECKS: dict[str, Callable[[str], None]] = {
    "SESSION=$(curl": created,
    '"sensor": "radar-1", "time": 12,': tied,
    '"sensor": "radar-2"': decided,
    '"sensor": "radar-3", "time": %d': detections,
    "/tracks?time=20": picture,
    "websockets.sync.client": streamed,
    "simulate t2t-four --server": simulated,
    "credal-fusion export": replayed,
    "/metrics": stalls,
    "format=geojson": geodetic,
    '"2026-12-03T09:00:00.5+01:00"': timestamped,
}
"""Each runnable block, by a piece of its text, and what its output must show."""


def test_the_set_up_comes_first_and_is_not_run() -> None:
    first_language, first = FENCE.findall(README)[0]
    assert first_language == "shell"
    assert [line.split("#")[0].strip() for line in first.splitlines()] == ["make run", "make test"]
    assert fenced("shell") == [first]
    assert not fenced("bash") and not fenced("console")


def test_every_sh_block_of_the_readme_runs_against_a_live_server(
    live_server: LiveServer, tmp_path: Path
) -> None:
    blocks = fenced("sh")
    assert sum(block.count(BASE_LINE) for block in blocks) == 1 and BASE_LINE in blocks[0]
    checks = []
    for block in blocks:
        matching = [check for key, check in CHECKS.items() if key in block]
        assert len(matching) == 1, f"one check per README block:\n{block}"
        checks.append(matching[0])
    script = ["set -euo pipefail"]
    for index, block in enumerate(blocks):
        script += [f"echo {MARK} {index}", block.replace(BASE_LINE, f"BASE={live_server.url}\n")]
    script.append(f"echo {MARK} end")
    (tmp_path / ".venv").symlink_to(sys.prefix)
    done = subprocess.run(
        ["bash", "-c", "\n".join(script)],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=TIMEOUT_S,
        check=False,
    )
    pieces = re.split(rf"^{MARK} (\S+)\n", done.stdout, flags=re.MULTILINE)
    ran = pieces[1::2]
    assert done.returncode == 0 and ran[-1:] == ["end"], (
        f"README block {ran[-1] if ran else 0} failed ({done.returncode}):\n"
        f"{blocks[int(ran[-1])] if ran and ran[-1] != 'end' else ''}\n{done.stderr}"
    )
    # nothing left where the blocks ran (a user's clone): example files go to temporary ones
    assert sorted(path.name for path in tmp_path.iterdir()) == [".venv"]
    outputs = pieces[2::2]
    for index, (check, output) in enumerate(zip(checks, outputs, strict=False)):
        try:
            check(output)
        except AssertionError as error:
            raise AssertionError(f"README block {index} printed:\n{output}") from error


def test_the_readme_lists_every_scenario_of_simulate() -> None:
    row = next(line for line in README.splitlines() if "`credal-fusion simulate" in line)
    listed = re.search(r"\(([^)]*`t2t-four`[^)]*)\)", row)
    assert listed is not None, row
    assert re.findall(r"`([\w-]+)`", listed.group(1)) == scenario_names()


def test_the_readme_names_the_system_packages_of_make_test() -> None:
    script = (ROOT / "tools" / "test-prerequisites").read_text(encoding="utf-8")
    installed = re.findall(r"missing\+=\(([\w-]+)\)", script)
    assert installed == ["chromium", "redis-server"]
    assert "`tools/test-prerequisites`" in README
    for package in installed:
        assert f"`{package}`" in README, f"make test installs {package}: the README must say so"
