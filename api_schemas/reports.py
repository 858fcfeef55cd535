"""Sensor inputs: a track list (``POST …/tracks``) and detections (``POST …/detections``).

Checks that need only the body live here (square symmetric positive-definite
covariances of the right size, distinct track ids, valid class evidence).

Each track or detection checks that its matrix is square and of its vector's
size; whether the matrices are symmetric positive definite is checked once per
input, for all of them together (:func:`~api_schemas.linalg.covariance_problems`),
by the model that holds the list.

Checks against the session configuration (state dimension, known sensor,
class labels in the frame) are in :mod:`api_schemas.consistency`.
"""

from __future__ import annotations

from typing import Annotated, Literal, Self

from pydantic import Discriminator, Field, Tag, model_validator

from api_schemas.base import FiniteFloat, Identifier, Matrix, Vector, WireModel
from api_schemas.classification import ClassEvidence
from api_schemas.issues import FieldIssue, raise_issues
from api_schemas.limits import MAX_ITEMS, bounded
from api_schemas.linalg import R_DESCRIPTION, check_square, covariance_problems, noise_problems
from api_schemas.timing import SessionTime

StateVector = Annotated[Vector, Field(min_length=1, max_length=64)]
MAX_RANGE = 1e8
"""A polar detection's range is in (0, 1e8] m (beyond the Moon: a unit error, not a target)."""


class SensorTrack(WireModel):
    """One track of a sensor's track list: local id, state, covariance, optional class evidence."""

    id: Identifier
    state: StateVector
    covariance: Matrix
    classification: ClassEvidence | None = None
    coasted: bool = Field(
        default=False,
        description=(
            "true: the source did not update this track in its latest scan (its local "
            "track is coasting, the state is its prediction): its miss of the track, not "
            "a new estimate (docs/algorithms.md §8.10)"
        ),
    )

    @model_validator(mode="after")
    def _covariance_matches_state(self) -> Self:
        """Square and of the state's size; symmetric positive definite is checked by the list.

        Every model holding tracks (:class:`TrackReport`, ``AssociateRequest``) checks
        all their covariances at once with :func:`~api_schemas.linalg.covariance_problems`.
        """
        try:
            check_square(self.covariance, len(self.state), name="covariance", vector="state")
        except ValueError as error:
            raise_issues("SensorTrack", [FieldIssue(("covariance",), str(error), self.covariance)])
        return self


TrackFrame = Literal["session", "sensor", "geodetic"]


class TrackReport(WireModel):
    """A sensor's track list at one time (``time``: seconds on the session clock, or an RFC 3339
    timestamp: :mod:`api_schemas.timing`).

    ``frame``: ``"session"`` (default) the session frame; ``"sensor"`` the
    sending sensor's own frame (origin at its site, y along its heading);
    ``"geodetic"``: positions are lat°, lon° (, alt m), velocities east/north/up
    m/s and the covariance in metres of the local ENU at the point. The
    service turns states and covariances into the session frame before
    association.
    """

    sensor: Identifier
    time: SessionTime
    frame: TrackFrame = "session"
    tracks: Annotated[
        list[SensorTrack],
        Field(max_length=MAX_ITEMS),
        bounded("max_tracks_per_input", "tracks"),
    ]

    @model_validator(mode="after")
    def _covariances_and_distinct_ids(self) -> Self:
        """Every covariance symmetric positive definite (one batch), every track id once.

        Runs once every track is otherwise valid (a model validator): a body
        with type errors lists those first, its covariance problems after they
        are fixed. The field paths are those of a per-track check.
        """
        bad_covariances = covariance_problems([track.covariance for track in self.tracks])
        seen: set[str] = set()
        issues: list[FieldIssue] = []
        for index, track in enumerate(self.tracks):
            if index in bad_covariances:
                issues.append(
                    FieldIssue(
                        ("tracks", index, "covariance"), bad_covariances[index], track.covariance
                    )
                )
            if track.id in seen:
                issues.append(
                    FieldIssue(
                        ("tracks", index, "id"), f"track id {track.id!r} appears twice", track.id
                    )
                )
            seen.add(track.id)
        if issues:
            raise_issues("TrackReport", issues)
        return self


class CartesianDetection(WireModel):
    """A detection of a sensor that measures positions: ``z``, optionally its own noise
    ``r`` (default: its sensor's ``measurement.r``) and class evidence."""

    z: Annotated[Vector, Field(min_length=1, max_length=3)]
    r: Matrix | None = Field(
        default=None, description=f"{R_DESCRIPTION} (default: its sensor's measurement.r)"
    )
    classification: ClassEvidence | None = None

    @model_validator(mode="after")
    def _r_matches_z(self) -> Self:
        """Square and of ``z``'s size; a noise (:func:`~api_schemas.linalg.noise_problems`) is
        checked by the report."""
        if self.r is not None:
            try:
                check_square(self.r, len(self.z), name="r", vector="z")
            except ValueError as error:
                raise_issues("CartesianDetection", [FieldIssue(("r",), str(error), self.r)])
        return self


class PolarDetection(WireModel):
    """A polar sensor's detection: ``range`` (m) and ``azimuth_deg`` (clockwise from north at
    the site), ``elevation_deg`` in 3-D, optionally ``range_rate`` (m/s, positive away from
    the site; used when the sensor gives ``sigma_range_rate``) and class evidence. Its noise
    is its sensor's (``measurement`` σs)."""

    range: Annotated[float, Field(allow_inf_nan=False, gt=0.0, le=MAX_RANGE)]
    azimuth_deg: Annotated[float, Field(allow_inf_nan=False, ge=-360.0, le=360.0)]
    elevation_deg: Annotated[float, Field(allow_inf_nan=False, ge=-90.0, le=90.0)] | None = None
    range_rate: FiniteFloat | None = None
    classification: ClassEvidence | None = None


def _detection_kind(value: object) -> str:
    """A detection's tag: ``cartesian`` when it gives ``z``, else ``polar``."""
    if isinstance(value, dict):
        return "cartesian" if "z" in value else "polar"
    return "polar" if isinstance(value, PolarDetection) else "cartesian"


Detection = Annotated[
    Annotated[CartesianDetection, Tag("cartesian")] | Annotated[PolarDetection, Tag("polar")],
    Discriminator(_detection_kind),
]
"""One detection: cartesian (``z``) or polar (``range``, ``azimuth_deg``), told apart by
``z`` (the detections carry no tag of their own on the wire)."""


class DetectionReport(WireModel):
    """A sensor's detections at one time (``time`` as a track list's)."""

    sensor: Identifier
    time: SessionTime
    detections: Annotated[
        list[Detection],
        Field(max_length=MAX_ITEMS),
        bounded("max_tracks_per_input", "detections"),
    ]

    @model_validator(mode="after")
    def _noise_is_covariance(self) -> Self:
        """Every detection's own ``r`` symmetric positive definite, of bounded variances (one
        batch: :func:`~api_schemas.linalg.noise_problems`)."""
        noisy = [
            (index, detection.r)
            for index, detection in enumerate(self.detections)
            if isinstance(detection, CartesianDetection) and detection.r is not None
        ]
        bad_noise = noise_problems([r for _, r in noisy])
        if bad_noise:
            raise_issues(
                "DetectionReport",
                [
                    FieldIssue(("detections", noisy[position][0], "r"), problem, noisy[position][1])
                    for position, problem in bad_noise.items()
                ],
            )
        return self
