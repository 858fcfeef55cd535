"""3-D polar detections of a radar at a distant geodetic site, converted into the session frame.

The radar measures range, azimuth and elevation in the ENU plane at its own
site (tilted 0.36° from the session's 40 km away). The measurements are made
by PROJ (target → WGS84 → the site's topocentric frame); the converted
positions must be the targets again, and the converted covariance must have
σ_range² along the line of sight (an eigenvector, by hand) and the
cross-range variances (ρ σ_az cos e)² and (ρ σ_el)².
"""

from __future__ import annotations

import math

import numpy as np

from api_schemas.config import SessionConfig
from api_schemas.reports import DetectionReport
from app.inputs.detections import core_detection_report
from app.sessions.translate import fusion_config

from .proj_oracle import proj_enu

ORIGIN = (48.85, 2.35, 100.0)
SITE = (48.85, 2.90, 60.0)  # ~40 km east of the origin
SIGMA_RANGE, SIGMA_AZ, SIGMA_EL = 20.0, 0.2, 0.3


def test_3d_polar_detections_at_a_geodetic_site_land_on_the_targets() -> None:
    config = SessionConfig.model_validate(
        {
            "state": {"dim": 6, "position": [0, 2, 4], "velocity": [1, 3, 5]},
            "origin": {"lat": ORIGIN[0], "lon": ORIGIN[1], "alt": ORIGIN[2]},
            "sensors": [
                {
                    "id": "radar",
                    "site": {"lat": SITE[0], "lon": SITE[1], "alt": SITE[2]},
                    "measurement": {
                        "kind": "polar",
                        "sigma_range": SIGMA_RANGE,
                        "sigma_azimuth_deg": SIGMA_AZ,
                        "sigma_elevation_deg": SIGMA_EL,
                    },
                }
            ],
        }
    )
    oracle, at_site = proj_enu(ORIGIN), proj_enu(SITE)
    targets = np.array(
        [[30_000.0, 15_000.0, 9000.0], [80_000.0, -20_000.0, 11_000.0], [41_000.0, 500.0, 300.0]]
    )
    detections, local = [], []
    for target in targets:
        east, north, up = at_site.transform(*oracle.transform(*target, direction="INVERSE"))
        local.append((east, north, up))
        detections.append(
            {
                "range": math.sqrt(east**2 + north**2 + up**2),
                "azimuth_deg": math.degrees(math.atan2(east, north)),
                "elevation_deg": math.degrees(math.atan2(up, math.hypot(east, north))),
            }
        )
    report = DetectionReport.model_validate(
        {"sensor": "radar", "time": 0.0, "detections": detections}
    )
    converted = core_detection_report(report, config, fusion_config(config))
    np.testing.assert_allclose(converted.measurements, targets, atol=1e-3)
    assert converted.covariances is not None
    site = np.asarray(oracle.transform(*SITE))
    for target, covariance, detection in zip(
        targets, converted.covariances, detections, strict=True
    ):
        sight = (target - site) / np.linalg.norm(target - site)
        np.testing.assert_allclose(covariance @ sight, SIGMA_RANGE**2 * sight, atol=1e-6 * 1e4)
        rho, elevation = detection["range"], math.radians(detection["elevation_deg"])
        expected = sorted(
            [
                SIGMA_RANGE**2,
                (rho * math.cos(elevation) * math.radians(SIGMA_AZ)) ** 2,
                (rho * math.radians(SIGMA_EL)) ** 2,
            ]
        )
        np.testing.assert_allclose(np.linalg.eigvalsh(covariance), expected, rtol=1e-9)
