"""Class evidence on detections reaches the local track's classification (and so the fused one).

One aircraft flies straight past a radar tracked with the aircraft preset;
the same scans are posted twice, without and with class evidence on every
detection. The local tracker's kinematic classification does not depend on
the evidence, and Dempster's rule is associative and commutative: the
class mass with evidence must be the one without, combined by hand (a
brute-force conjunctive rule on frozensets, normalised) with the evidence of
every detection the track took (a single-point start, the default since
issue 22: from the first scan on).
Likelihood evidence is the mass [MTT] eq 10 gives, worked by hand too. A
session without a preset has no local classification: evidence there is
refused, naming the field.
"""

from __future__ import annotations

from itertools import product
from typing import Any

from fastapi.testclient import TestClient

CLASSES = ["liner", "bomber", "fighter"]
SCANS = 10
EVIDENCE = [{"set": ["bomber", "fighter"], "mass": 0.3}, {"set": CLASSES, "mass": 0.7}]
LIKELIHOODS = {"liner": 0.9, "bomber": 0.6, "fighter": 0.2}

Mass = dict[frozenset[str], float]


def _config(preset: str | None = "aircraft") -> dict[str, Any]:
    return {
        "state": {"dim": 4, "position": [0, 2], "velocity": [1, 3]},
        "classes": CLASSES,
        "sensors": [{"id": "radar", "p_detect": 0.95, "measurement": {"r": [[100, 0], [0, 100]]}}],
        "tracking": {"preset": preset, "time_interval": 1.0},
    }


def _scans(evidence: dict[str, Any] | None) -> list[dict[str, Any]]:
    scans = []
    for k in range(SCANS):
        detection: dict[str, Any] = {"z": [1000.0 + 200.0 * k, 5000.0 - 3.0 * k]}
        if evidence is not None:
            detection["classification"] = evidence
        scans.append({"sensor": "radar", "time": float(k), "detections": [detection]})
    return scans


def _run(client: TestClient, evidence: dict[str, Any] | None) -> Mass:
    created = client.post("/v1/sessions", json=_config()).json()
    headers = {"Authorization": f"Bearer {created['token']}"}
    for body in _scans(evidence):
        answer = client.post(f"/v1/sessions/{created['id']}/detections", json=body, headers=headers)
        assert answer.status_code == 200, answer.text
    (track,) = answer.json()["tracks"]
    assert track["status"] == "confirmed"
    return {frozenset(f["set"]): f["mass"] for f in track["classification"]["mass"]}


def _dempster(first: Mass, second: Mass) -> Mass:
    """The normalised conjunctive rule, by brute force over focal-set pairs."""
    combined: Mass = {}
    for (a, x), (b, y) in product(first.items(), second.items()):
        combined[a & b] = combined.get(a & b, 0.0) + x * y
    conflict = combined.pop(frozenset(), 0.0)
    return {focal: value / (1.0 - conflict) for focal, value in combined.items()}


def _close(found: Mass, expected: Mass) -> None:
    kept = {focal: value for focal, value in expected.items() if value > 1e-12}
    assert set(found) == set(kept), (found, kept)
    for focal, value in kept.items():
        assert abs(found[focal] - value) < 1e-9, (focal, found[focal], value)


def test_mass_evidence_on_detections_joins_the_track_classification(client: TestClient) -> None:
    without = _run(client, None)
    evidence: Mass = {frozenset(f["set"]): f["mass"] for f in EVIDENCE}
    expected = without
    for _ in range(SCANS):  # every detection of the track: a single-point start has all
        expected = _dempster(expected, evidence)
    _close(_run(client, {"mass": EVIDENCE}), expected)
    assert _run(client, {"mass": EVIDENCE}) != without


def test_likelihood_evidence_is_the_gbt_mass(client: TestClient) -> None:
    """[MTT] eq 10 (GBT): m(A) = Π_{c∈A} Pl(c) Π_{c∉A} (1 − Pl(c)), the reported likelihoods
    as the plausibilities; normalised (the empty set gets Π (1 − Pl(c)))."""
    plausibility = LIKELIHOODS
    gbt: Mass = {}
    for bits in product([False, True], repeat=len(CLASSES)):
        focal = frozenset(c for c, inside in zip(CLASSES, bits, strict=True) if inside)
        value = 1.0
        for label, inside in zip(CLASSES, bits, strict=True):
            value *= plausibility[label] if inside else 1.0 - plausibility[label]
        gbt[focal] = value
    empty = gbt.pop(frozenset())
    gbt = {focal: value / (1.0 - empty) for focal, value in gbt.items()}
    expected = _run(client, None)
    for _ in range(SCANS):
        expected = _dempster(expected, gbt)
    _close(_run(client, {"likelihoods": LIKELIHOODS}), expected)


def test_evidence_without_a_local_classification_is_refused(client: TestClient) -> None:
    created = client.post("/v1/sessions", json=_config(preset=None)).json()
    headers = {"Authorization": f"Bearer {created['token']}"}
    body = _scans({"mass": EVIDENCE})[0]
    answer = client.post(f"/v1/sessions/{created['id']}/detections", json=body, headers=headers)
    assert answer.status_code == 422
    assert answer.json()["errors"][0]["loc"] == ["body", "detections", 0, "classification"]
