"""Real traffic through the service, configured as a new user would (issue 22, EVALUATION.md).

The scene, the session and the metrics are :mod:`evaluation.traffic`'s: twenty
recorded flights around Paris (the ``traffic`` package's sample, MIT), three
simulated 3-D radars at geodetic sites (4, 5 and 12 s scans, P_D 0.9,
clutter) and an ADS-B station reporting half of the fleet, posted over REST
to a live uvicorn server. Every run is one session: all sensors fused, then
each radar alone (the reference of the RMSE goal), in the same run.

Goals, with the defaults plus physics: every aircraft covered in ≥ 95 % of
the pictures where a sensor could see it; extra fused ids ≤ 5 % of the
aircraft; fused RMSE below the best radar's alone (over the aircraft-pictures
both hold, and on the radar-only aircraft); airliners decided fighter or
bomber in ≤ 2 % of their decided pictures; no track whose status changes
more than once a minute. Each goal is printed met or not.

Run: ``.venv/bin/python bench/traffic.py [--seed N] [--duration S]`` (about two
minutes of CPU for the full 30 minutes of scene time).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import httpx

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from machine import describe_machine

from evaluation.service import live_service
from evaluation.traffic import (
    ADSB,
    DURATION,
    KINDS,
    Scene,
    TrafficScore,
    assess,
    decided_shares,
    measurement_rmse,
    paired_rmse,
    run_service,
    session_config,
    simulate,
)


def _row(label: str, score: TrafficScore, seconds: float, rmse_radar_only: float) -> str:
    shares = []
    for kind in KINDS:
        decided, military = decided_shares(score, kind)
        shares.append(f"{100 * decided:5.1f}/{100 * military:4.1f}")
    return (
        f"{label:>16} {100 * score.min_coverage:7.1f} {100 * score.mean_coverage:7.1f} "
        f"{score.total_extra_ids:6d} {score.false_tracks:6d} {score.rmse():8.1f} "
        f"{rmse_radar_only:8.1f} {score.status_changes:8.1f} {score.flickering_tracks:6d} "
        + " ".join(f"{share:>10}" for share in shares)
        + f" {seconds:6.1f}"
    )


def termination_off(scene: Scene, sensors: Iterable[str] | None) -> dict[str, Any]:
    """The labelled tuned row: [HZ]'s gate-emptiness termination off (the calibration that
    issue 22's part A brings to the defaults)."""
    config = session_config(scene, sensors)
    config["tracking"]["thresholds"] = {"termination_probability": 0.0}
    return config


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--duration", type=float, default=DURATION)
    parser.add_argument(
        "--tuned", action="store_true", help="add the labelled row with termination off"
    )
    args = parser.parse_args()
    print(describe_machine())
    scene = simulate(seed=args.seed, duration=args.duration)
    radar_only = [f.callsign for f in scene.flights if f.callsign not in scene.equipped]
    print(
        f"seed {args.seed}: {len(scene.flights)} aircraft ({len(scene.equipped)} with ADS-B), "
        f"{args.duration:.0f} s, {len(scene.inputs)} inputs; radars "
        + ", ".join(
            f"{r.id} σ {r.sigma_range:g} m / {r.sigma_azimuth_deg:g}° / {r.sigma_elevation_deg:g}° "
            f"every {r.period:g} s (measurement RMSE {measurement_rmse(scene, r.id):.0f} m)"
            for r in scene.radars
        )
    )
    print(
        f"{'run':>16} {'mincov%':>7} {'meancov%':>7} {'extra':>6} {'false':>6} {'RMSE':>8} "
        f"{'RMSE-nc':>8} {'chg/h':>8} {'flick':>6} "
        + " ".join(f"{kind[:10]:>10}" for kind in KINDS)
        + f" {'wall s':>6}"
    )
    scores = {}
    with live_service() as url:
        runs: list[tuple[str, list[str] | None, Any]] = [
            ("fused", None, session_config),
            *((radar.id, [radar.id], session_config) for radar in scene.radars),
        ]
        if args.tuned:
            runs.append(("fused, term. off", None, termination_off))
        for label, sensors, config in runs:
            # a client per run: the scoring between runs outlasts the server's keep-alive
            with httpx.Client(base_url=url, timeout=120) as client:
                run = run_service(client, scene, sensors, config=config)
            scores[label] = score = assess(scene, run)
            print(_row(label, score, run.seconds, score.rmse(radar_only)), flush=True)
    print(
        "columns: coverage (min, mean over aircraft), extra fused ids, false tracks, 3-D RMSE (m) "
        "of all matched / of the radar-only aircraft, confirmed↔coasting changes per track-hour, "
        "tracks changing more than once a minute, per kind the % of its held pictures decided "
        "/ decided fighter or bomber, wall time"
    )
    fused = scores["fused"]
    best = min((r.id for r in scene.radars), key=lambda r: scores[r].rmse(radar_only))
    both, alone = paired_rmse(fused, scores[best], radar_only)
    goals = {
        "coverage ≥ 95 % for every aircraft": fused.min_coverage >= 0.95,
        "extra ids ≤ 5 % of the aircraft": fused.total_extra_ids <= 0.05 * len(scene.flights),
        f"fused RMSE below {best}'s alone (radar-only aircraft, same pictures: "
        f"{both:.0f} vs {alone:.0f} m)": both < alone,
        "airliners decided fighter/bomber ≤ 2 % of their decided pictures "
        f"({100 * fused.military_share('airliner'):.0f} %; of their held pictures "
        f"{100 * decided_shares(fused, 'airliner')[1]:.1f} %)": fused.military_share("airliner")
        <= 0.02,
        "status stable (no track changing > once a minute)": fused.flickering_tracks == 0,
    }
    for goal, met in goals.items():
        print(f"goal {'met    ' if met else 'NOT met'}: {goal}")
    print(f"({ADSB} configured with its id only; defaults otherwise)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
