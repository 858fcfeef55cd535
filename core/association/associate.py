"""The entry point: :func:`associate` dispatches to one method module.

Defaults (docs/algorithms.md §3.7): track-to-track association uses ``denoeux``
with ``gate_probability`` 0.999, α = 1 and the ``sum`` covariance;
local tracking (measurement-to-track) uses ``gnn`` with ``gate_probability``
0.999 (:func:`associate_measurements`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from numpy.typing import ArrayLike

from core.association.assignment import SOLVERS, Solver
from core.association.classes import check_classes
from core.association.problem import AssociationProblem
from core.association.registry import REGISTRY, method_spec, methods
from core.association.result import AssociationResult
from core.association.spec import MethodSpec, Scope
from core.belief import MassFunction
from core.distance import DistanceModel, Estimates
from core.errors import InvalidInput

Side = Estimates | tuple[ArrayLike, ArrayLike | None]

METHODS: tuple[str, ...] = methods("track_to_track")
"""The track-to-track methods (:mod:`core.association.registry`)."""
LOCAL_METHODS: tuple[str, ...] = methods("local")
"""The measurement-to-track methods of local tracking."""

TRACK_TO_TRACK_DEFAULT = "denoeux"
"""The track-to-track method when the caller names none (§3.7), on its ``sum`` distance."""
LOCAL_TRACKING_DEFAULT = "gnn"
"""The local tracker's method when the configuration names none (§3.7)."""

DEFAULT_DISTANCE: dict[str, str] = {name: REGISTRY[name].distance for name in METHODS}
"""Track-to-track distance of each method when the caller names none (its spec's): the
``mean`` covariance of [T2T] eq 1-2 for the methods compared there, ``sum``
for the session default ``denoeux`` (docs/algorithms.md §3.7)."""


def _side(side: Side, name: str) -> Estimates:
    if isinstance(side, Estimates):
        return side
    if not isinstance(side, tuple) or len(side) != 2:
        raise InvalidInput(f"{name} must be Estimates or a (states, covariances) pair")
    states, covariances = side
    return Estimates.of(states, covariances, name=name)


def resolve_method(
    method: str,
    options: Mapping[str, object] | None,
    distance: str | DistanceModel,
    scope: Scope = "track_to_track",
) -> tuple[MethodSpec[Any], Any, DistanceModel]:
    """A method's spec, its parsed options and the distance model; refuses any of them by name.

    Raises
    ------
    InvalidInput
        Unknown method (of ``scope``) or distance, invalid option
        (:class:`~core.errors.OptionError`).
    """
    spec = method_spec(method, scope)
    return spec, spec.parse(dict(options or {})), DistanceModel.of(distance)


def associate(
    known: Side,
    incoming: Side,
    method: str = TRACK_TO_TRACK_DEFAULT,
    options: Mapping[str, object] | None = None,
    distance: str | DistanceModel = "sum",
    known_classes: Sequence[MassFunction] | None = None,
    incoming_classes: Sequence[MassFunction] | None = None,
    *,
    solver: Solver = "lapjv",
    cluster: bool = True,
    scope: Scope = "track_to_track",
) -> AssociationResult:
    """Associate known items (rows) with incoming items (columns).

    Parameters
    ----------
    known, incoming : Estimates or (states N × q, covariances N × q × q)
        For measurement-to-track use ``distance="innovation"``: known =
        (ẑ, S), incoming = (z, None); or :func:`associate_measurements`.
    method : a method of ``scope`` (:data:`METHODS`)
        Default ``denoeux`` (§3.7).
    options : mapping
        The method's options, by their API names (see each method module).
        ``denoeux`` without options uses ``gate_probability`` 0.999, α = 1.
    distance : {"sum", "mean", "innovation"} or DistanceModel
        Default ``sum`` (§3.7); a :class:`DistanceModel` selects the modified
        distance of [HZ] §4.1 and the position components of the gate.
    known_classes, incoming_classes : sequences of MassFunction, optional
        One class mass function per item on a common frame (§3.6).
    solver : {"lapjv", "scipy"}
        Linear-assignment solver (lapjv is faster; scipy is the reference).
    cluster : bool
        Solve independent clusters separately (default; False for testing).
    scope : {"track_to_track", "local"}
        The methods allowed (:func:`associate_measurements` passes ``local``).

    Raises
    ------
    InvalidInput
        Unknown method, invalid option (:class:`~core.errors.OptionError`),
        bad shapes, non-finite numbers, invalid covariances
        (:class:`~core.errors.CovarianceError`).
    """
    if solver not in SOLVERS:
        raise InvalidInput(f"solver must be one of {list(SOLVERS)}, got {solver!r}")
    spec, parsed, model = resolve_method(method, options, distance, scope)
    known_side = _side(known, "known")
    incoming_side = _side(incoming, "incoming")
    check_classes(known_classes, incoming_classes, len(known_side), len(incoming_side))
    problem = AssociationProblem(
        known=known_side,
        incoming=incoming_side,
        distance=model,
        known_classes=known_classes,
        incoming_classes=incoming_classes,
        solver=solver,
        cluster=cluster,
    )
    return spec.run(problem, parsed)


def associate_measurements(
    predicted_measurements: ArrayLike,
    innovation_covariances: ArrayLike,
    measurements: ArrayLike,
    method: str = LOCAL_TRACKING_DEFAULT,
    options: Mapping[str, object] | None = None,
    *,
    modified: DistanceModel | None = None,
    solver: Solver = "lapjv",
) -> AssociationResult:
    """Measurement-to-track association ([MTT] eq 15): rows are tracks (ẑ, S), columns z.

    ``D = (z − ẑ)ᵀ S⁻¹ (z − ẑ)``. Default ``gnn`` with ``gate_probability``
    0.999 (§3.7). ``modified`` may pass a DistanceModel with covariance
    ``"innovation"`` and a ModifiedScale for the [HZ] §4.1 distance.
    """
    known = Estimates.of(predicted_measurements, innovation_covariances, name="tracks")
    incoming = Estimates.of(
        measurements, None, name="measurements", dimension=known.dimension if len(known) else None
    )
    model = modified if modified is not None else DistanceModel(covariance="innovation")
    if model.covariance != "innovation":
        raise InvalidInput("measurement-to-track association needs the 'innovation' covariance")
    return associate(known, incoming, method, options, model, solver=solver, scope="local")
