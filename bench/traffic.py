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
from pathlib import Path

import httpx

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from machine import describe_machine

from evaluation.service import live_service
from evaluation.traffic import (
    ADSB,
    DURATION,
    KINDS,
    TrafficScore,
    assess,
    measurement_rmse,
    paired_rmse,
    run_service,
    simulate,
)


def _row(label: str, score: TrafficScore, seconds: float, rmse_radar_only: float) -> str:
    return (
        f"{label:>10} {100 * score.min_coverage:7.1f} {100 * score.mean_coverage:7.1f} "
        f"{score.total_extra_ids:6d} {score.false_tracks:6d} {score.rmse():8.1f} "
        f"{rmse_radar_only:8.1f} {score.status_changes:8.1f} {score.flickering_tracks:6d} "
        + " ".join(f"{100 * score.military_share(kind):6.1f}" for kind in KINDS)
        + f" {seconds:6.1f}"
    )


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--duration", type=float, default=DURATION)
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
        f"{'run':>10} {'mincov%':>7} {'meancov%':>7} {'extra':>6} {'false':>6} {'RMSE':>8} "
        f"{'RMSE-nc':>8} {'chg/h':>8} {'flick':>6} "
        + " ".join(f"{kind[:6]:>6}" for kind in KINDS)
        + f" {'wall s':>6}"
    )
    scores = {}
    with live_service() as url, httpx.Client(base_url=url, timeout=120) as client:
        for sensors in [None, *([radar.id] for radar in scene.radars)]:
            label = "fused" if sensors is None else sensors[0]
            run = run_service(client, scene, sensors)
            scores[label] = score = assess(scene, run)
            print(_row(label, score, run.seconds, score.rmse(radar_only)), flush=True)
    print(
        "columns: coverage (min, mean over aircraft), extra fused ids, false tracks, 3-D RMSE (m) "
        "of all matched / of the radar-only aircraft, confirmed↔coasting changes per track-hour, "
        "tracks changing more than once a minute, % of decided pictures decided fighter or "
        "bomber per kind, wall time"
    )
    fused = scores["fused"]
    best = min((r.id for r in scene.radars), key=lambda r: scores[r].rmse(radar_only))
    both, alone = paired_rmse(fused, scores[best], radar_only)
    goals = {
        "coverage ≥ 95 % for every aircraft": fused.min_coverage >= 0.95,
        "extra ids ≤ 5 % of the aircraft": fused.total_extra_ids <= 0.05 * len(scene.flights),
        f"fused RMSE below {best}'s alone (radar-only aircraft, same pictures: "
        f"{both:.0f} vs {alone:.0f} m)": both < alone,
        "airliners decided fighter/bomber ≤ 2 %": fused.military_share("airliner") <= 0.02,
        "status stable (no track changing > once a minute)": fused.flickering_tracks == 0,
    }
    for goal, met in goals.items():
        print(f"goal {'met    ' if met else 'NOT met'}: {goal}")
    print(f"({ADSB} configured with its id only; defaults otherwise)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
