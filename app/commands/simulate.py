"""``credal-fusion simulate SCENARIO``: a paper scenario through the engine or a server."""

from __future__ import annotations

import argparse
import time
from collections.abc import Iterator, Sequence
from typing import Any
from urllib.parse import urlencode

import numpy as np

from app.commands.progress import shown as progress
from app.commands.runner import Input, run_locally, run_on_server
from app.commands.scenarios import ScenarioRun, build
from core.metrics import identity_switches, ospa

Body = dict[str, Any]


def covering_tracks(
    result: Body, positions: np.ndarray, target_ids: tuple[int, ...]
) -> dict[int, str | None]:
    """Which confirmed fused track covers each true target (nearest within its 99.9 % gate)."""
    gate = 13.8155  # chi2.ppf(0.999, 2)
    covering: dict[int, str | None] = {}
    tracks = [t for t in result["tracks"] if t["status"] in ("confirmed", "coasting")]
    for target, position in zip(target_ids, positions, strict=True):
        best: tuple[float, str] | None = None
        for track in tracks:
            state = np.asarray(track["state"])
            covariance = np.asarray(track["covariance"])[np.ix_([0, 2], [0, 2])]
            difference = state[[0, 2]] - position
            distance = float(difference @ np.linalg.solve(covariance, difference))
            if distance <= gate and (best is None or distance < best[0]):
                best = (distance, track["id"])
        covering[target] = None if best is None else best[1]
    return covering


def summarise(run: ScenarioRun, results: list[Body]) -> str:
    """A few lines: inputs, fused tracks, identity, OSPA, class decisions."""
    covering = [
        covering_tracks(result, truth.positions, truth.target_ids)
        for result, truth in zip(results, run.truth, strict=True)
    ]
    ospas = []
    for result, truth in zip(results, run.truth, strict=True):
        estimates = np.array(
            [np.asarray(t["state"])[[0, 2]] for t in result["tracks"] if t["status"] == "confirmed"]
        ).reshape(-1, 2)
        ospas.append(ospa(estimates, truth.positions, cutoff=run.cutoff, order=2.0))
    ids: dict[int, set[str]] = {}
    for step in covering:
        for target, fused in step.items():
            if fused is not None:
                ids.setdefault(target, set()).add(fused)
    final = results[-1]
    decisions = {  # the class, or why there is none ("tied", "undefined")
        t["id"]: t["classification"]["decision"] or t["classification"]["decision_state"]
        for t in final["tracks"]
        if t.get("classification")
    }
    lines = [
        f"scenario {run.name}, seed {run.seed}: {len(results)} inputs, fusion time {final['time']:.6g}",
        f"fused tracks at the end: {len(final['tracks'])} "
        f"({sum(t['status'] == 'confirmed' for t in final['tracks'])} confirmed)",
        f"identity switches: {identity_switches(covering)}; fused ids per target: "
        + ", ".join(f"{target}: {sorted(fused)}" for target, fused in sorted(ids.items())),
        f"OSPA (p = 2, c = {run.cutoff:.3g}): time-mean {np.mean(ospas):.4g}, last {ospas[-1]:.4g}",
    ]
    if decisions:
        lines.append("class decisions: " + ", ".join(f"{k}: {v}" for k, v in decisions.items()))
    return "\n".join(lines)


def command(args: argparse.Namespace) -> int:
    """Run the scenario and print its summary (progress on stderr).

    With ``--server`` the session's id, token and viewer URL are printed
    first, so the run can be watched; the session is deleted at the end
    unless ``--keep``.
    """
    run = build(args.scenario, args.seed, args.preset)
    timed = run.inputs if args.speed is None else paced(run.inputs, args.speed)
    inputs = progress(timed, run.name, args.quiet, total=len(run.inputs))
    if not args.server:
        print(summarise(run, list(run_locally(run.config, inputs))))
        return 0
    server = args.server.rstrip("/")
    sessions: list[str] = []

    def tell(session: str, token: str) -> None:
        sessions.append(session)
        print(
            f"session {session} (token {token})\nviewer: {viewer_url(server, session, token)}",
            flush=True,
        )

    results = list(run_on_server(server, run.config, inputs, on_session=tell, keep=args.keep))
    print(summarise(run, results))
    if args.keep:
        print(
            f"session {sessions[0]} left open: it ends after the server's idle timeout "
            f"(CREDAL_SESSION_IDLE_SECONDS) or with DELETE {server}/v1/sessions/{sessions[0]}"
        )
    else:
        print(f"session {sessions[0]} deleted at the end of the run (--keep leaves it open)")
    return 0


def viewer_url(server: str, session: str, token: str) -> str:
    """The live viewer of ``session``: id and token in the fragment, never sent to the server."""
    return f"{server}/#{urlencode({'session': session, 'token': token})}"


def paced(inputs: Sequence[Input], speed: float) -> Iterator[Input]:
    """``inputs`` released at ``speed`` times the scenario's own clock (their ``time``)."""
    if not inputs:
        return
    start, first = time.monotonic(), float(inputs[0][1]["time"])
    for kind, body in inputs:
        wait = (float(body["time"]) - first) / speed - (time.monotonic() - start)
        if wait > 0:
            time.sleep(wait)
        yield kind, body
