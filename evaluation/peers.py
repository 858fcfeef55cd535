"""The Stone Soup side-by-side of ``bench/peers.py`` (issue 13), over several seeds.

``bench/peers.py`` is the one definition of the scenes (Stone Soup 1.9.1's
own simulators), the trackers (Stone Soup's tutorial GNN, its kd-tree form,
JPDA with LBP; our :class:`~core.tracking.tracker.LocalTracker`; the service
over REST, one session on a live uvicorn server) and the metrics (Stone
Soup's GOSPA with its parts, SIAP, identity switches, per-scan time). The
bench runs each scene once, at one seed; here every scene is drawn at
:data:`SEEDS` seeds and every tracker runs on the same draws, so that each
number has a 95 % t interval over the seeds and each comparison with Stone
Soup's GNN is paired (the GOSPA ratio and the per-scan speed-up of each
seed). As in the bench, above ``GNN_FULL_MAX_TARGETS`` targets the tutorial
GNN runs its first scans for its time only and its kd-tree form (the same
tracks) is the GOSPA reference; below it the kd-tree form, which would repeat
the tutorial GNN's tracks, is not run.

The scenes' sizes are those of the bench's ``SCENES``
(:data:`SCENE_SIZES`; a test checks that the first seed of each rebuilds the
bench's own scene). The bench is loaded from the repository's ``bench/``
(it is not part of the installed package): ``make figures`` runs from a
checkout.
"""

from __future__ import annotations

import importlib.util
import sys
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from core.arrays import FloatArray
from core.errors import InvalidInput

BENCH = Path(__file__).resolve().parents[1] / "bench" / "peers.py"
"""The peers bench, the one source of the scenes, trackers and metrics."""

SCENE_SIZES: Mapping[str, tuple[int, int, int]] = {
    "~10": (10, 60, 31),
    "~50": (50, 40, 32),
    "~200": (200, 15, 33),
}
"""Simulated scenes of the bench: name → (targets at start, scans, the bench's seed)."""
CROSSING_SEED = 37
"""The bench's seed of the ``crossing`` scene."""
SCENES = (*SCENE_SIZES, "crossing")
SEEDS: Mapping[str, int] = {"~10": 5, "~50": 3, "~200": 1, "crossing": 10}
"""Seeds per scene: the bench's own seed and the next ones. A draw of ``~200`` takes
about 4 minutes on a loaded 2-core machine (Stone Soup's trackers in Python), so it
has one draw — its numbers carry no interval and support no claim — and ``~50``
three; ``~10`` and ``crossing`` carry the claims."""
TRACKERS = ("ss-gnn", "ss-kdgnn", "ss-jpda", "ours", "ours-rest")
FIELDS = ("gospa", "localisation", "missed", "false", "switches", "late", "scan_ms")
SIAP_FIELDS = ("completeness", "spuriousness", "position")


@cache
def load_bench() -> ModuleType:
    """``bench/peers.py`` as a module (it sets one BLAS thread only if imported first)."""
    if not BENCH.is_file():
        raise InvalidInput(f"the peers figure needs a checkout with {BENCH}")
    sys.path.insert(0, str(BENCH.parent))
    spec = importlib.util.spec_from_file_location("evaluation_peers_bench", BENCH)
    if spec is None or spec.loader is None:
        raise InvalidInput(f"cannot load {BENCH}")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # its dataclasses look their module up
    spec.loader.exec_module(module)
    return module


def scene(name: str, seed: int, scans: int | None = None) -> Any:
    """The bench's scene ``name`` drawn at ``seed`` (its first ``scans`` scans if given)."""
    bench = load_bench()
    if name == "crossing":
        built = bench.crossing_scene(seed=seed)
    elif name in SCENE_SIZES:
        targets, steps, _ = SCENE_SIZES[name]
        built = bench.simulated_scene(name, targets, steps if scans is None else scans, seed=seed)
    else:
        raise InvalidInput(f"unknown peers scene {name!r}; choose one of {list(SCENES)}")
    return built if scans is None else built.head(scans)


def first_seed(name: str) -> int:
    """The bench's own seed of scene ``name``."""
    return CROSSING_SEED if name == "crossing" else SCENE_SIZES[name][2]


@dataclass(frozen=True)
class PeerScene:
    """Every tracker's scores on one scene, per seed.

    Attributes
    ----------
    name : str
    seeds : tuple of int
    targets : ndarray, shape (seeds,)
        Mean number of simultaneous targets of each draw.
    scores : dict
        ``tracker → field → (seeds,)``: :data:`FIELDS` and, where the bench
        computes SIAP, :data:`SIAP_FIELDS` (NaN where it does not).
    reference : str
        The GOSPA reference: Stone Soup's tutorial GNN, or its kd-tree form
        (the same tracks) where the bench runs the tutorial GNN for its time only.
    timing_only : tuple of str
        Trackers whose accuracy is not scored here (run on a few scans, for the time).
    """

    name: str
    seeds: tuple[int, ...]
    targets: FloatArray
    scores: Mapping[str, Mapping[str, FloatArray]]
    reference: str
    timing_only: tuple[str, ...]

    @property
    def trackers(self) -> tuple[str, ...]:
        return tuple(self.scores)

    def ratio(self, tracker: str, field: str = "gospa") -> FloatArray:
        """Per seed: ``field`` of ``tracker`` over the reference's (GOSPA/ss of the bench)."""
        return np.asarray(
            self.scores[tracker][field] / self.scores[self.reference][field], dtype=np.float64
        )

    def speed_up(self, tracker: str) -> FloatArray:
        """Per seed: Stone Soup GNN's per-scan time over ``tracker``'s (the bench's "vs ss-gnn")."""
        return np.asarray(
            self.scores["ss-gnn"]["scan_ms"] / self.scores[tracker]["scan_ms"], dtype=np.float64
        )


def _runs(bench: ModuleType, built: Any, url: str) -> dict[str, tuple[Any, Any]]:
    """Tracker → (its run, the scene it ran on), as the bench's ``main`` chooses them."""
    targets = built.mean_targets()
    gnn_scene = (
        built if targets <= bench.GNN_FULL_MAX_TARGETS else built.head(bench.GNN_TIMING_SCANS)
    )
    runs = {"ss-gnn": (bench.stone_soup_run(gnn_scene, "ss-gnn"), gnn_scene)}
    if gnn_scene is not built:
        runs["ss-kdgnn"] = (bench.stone_soup_run(built, "ss-kdgnn"), built)
    if targets <= bench.JPDA_MAX_TARGETS:
        runs["ss-jpda"] = (bench.stone_soup_run(built, "ss-jpda"), built)
    runs["ours"] = (bench.local_run(built), built)
    runs["ours-rest"] = (bench.rest_run(built, url), built)
    return runs


def peer_scene(
    name: str, seeds: Sequence[int], scans: int | None = None, url: str | None = None
) -> PeerScene:
    """Run every tracker of the bench on scene ``name`` at each seed (module docstring)."""
    bench = load_bench()
    if url is None:
        with bench.live_service() as served:
            return peer_scene(name, seeds, scans, served)
    rows: dict[str, dict[str, list[float]]] = {}
    targets = []
    timing_only: set[str] = set()
    for seed in seeds:
        built = scene(name, seed, scans)
        targets.append(built.mean_targets())
        with_siap = built.mean_targets() <= bench.SIAP_MAX_TARGETS
        for tracker, (run, ran_on) in _runs(bench, built, url).items():
            if ran_on is not built:
                timing_only.add(tracker)
            result = bench.score(ran_on, run, with_siap)
            row = rows.setdefault(tracker, {})
            for field in FIELDS:
                row.setdefault(field, []).append(float(getattr(result, field)))
            for field in SIAP_FIELDS:
                siap = result.siap or {}
                row.setdefault(field, []).append(float(siap.get(field, np.nan)))
    complete = {t: v for t, v in rows.items() if len(v["gospa"]) == len(seeds)}
    return PeerScene(
        name=name,
        seeds=tuple(seeds),
        targets=np.array(targets),
        scores={
            tracker: {field: np.array(values) for field, values in fields.items()}
            for tracker, fields in complete.items()
        },
        reference="ss-kdgnn" if "ss-gnn" in timing_only else "ss-gnn",
        timing_only=tuple(sorted(timing_only)),
    )


def peer_study(
    names: Sequence[str] = SCENES,
    seeds: Mapping[str, int] = SEEDS,
    scans: int | None = None,
    progress: Callable[[str], None] | None = None,
) -> tuple[PeerScene, ...]:
    """Every scene of ``names`` at ``seeds[name]`` seeds from the bench's own, one live service."""
    bench = load_bench()
    studies = []
    with bench.live_service() as url:
        for name in names:
            chosen = tuple(range(first_seed(name), first_seed(name) + seeds[name]))
            if progress is not None:
                progress(f"peers: scene {name}, seeds {chosen[0]}..{chosen[-1]}")
            studies.append(peer_scene(name, chosen, scans, url))
    return tuple(studies)


def machine() -> str:
    """The bench's one-line description of this machine."""
    return str(load_bench().describe_machine())
