"""Batched Interacting Multiple Model filter ([MTT] §3, Bar-Shalom et al. 2001 §11.6).

Every array holds all tracks × all models at once: states ``(T, r, n)``,
covariances ``(T, r, n, n)``, mode probabilities ``(T, r)``; there is no Python
loop over tracks or models. One cycle is :meth:`IMMPredictor.predict` (mixing,
then ``x = F x + B u``, ``P = F P Fᵀ + Q`` per model) followed by
:meth:`IMMUpdater.update` (Kalman update of every model with the shared H, R,
mode likelihoods, mode probabilities).

A prediction spans any time step Δt ≥ 0 in constant time: the bank's models
at Δt in closed form, ``F(Δt)``, ``B(Δt) u``, ``Q(Δt)``, and the mode
transitions ``Π(Δt) = Π^{Δt/ΔT}`` (:meth:`ModelBank.at`,
:meth:`ModelBank.mode_transition_at`, :mod:`core.tracking.models`); the
default step is the bank's nominal ΔT.

Mode probabilities live in the **log domain**: the likelihood of model j is
kept as ``log Λ_j = −d_j²/2 − ½ log |2π S_j|`` ([MTT] eq 18) and the update
``μ_j ∝ c̄_j Λ_j`` is normalised with log-sum-exp. filterpy's
``IMMEstimator`` exponentiates first and floors every likelihood at
``sys.float_info.min``; on an outlier all likelihoods hit the floor and its
mode probabilities freeze at the predicted ones. Here the best-fitting model
still wins, whatever the size of the outlier, and nothing becomes NaN.

The covariance update is Joseph's form ``(I − K H) P (I − K H)ᵀ + K R Kᵀ``, as
in filterpy, so the two agree to rounding.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from core.arrays import BoolArray, FloatArray, IntArray
from core.errors import TrackingError
from core.numerics import logsumexp, safe_log
from core.tracking.models import ModelBank

_LOG_2PI = float(np.log(2.0 * np.pi))


def _combine(
    weights: FloatArray, means: FloatArray, covariances: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Moment-matched mixture: ``x̄ = Σ w x``, ``P̄ = Σ w (P + (x − x̄)(x − x̄)ᵀ)``."""
    mean = np.einsum("tr,trn->tn", weights, means)
    spread = means - mean[:, None, :]
    covariance = np.einsum("tr,trkl->tkl", weights, covariances) + np.einsum(
        "trk,trl->tkl", weights[:, :, None] * spread, spread
    )
    return mean, covariance


@dataclass(frozen=True)
class IMMState:
    """Model-conditioned posteriors of T tracks.

    Attributes
    ----------
    means : ndarray, shape (T, r, n)
    covariances : ndarray, shape (T, r, n, n)
    log_mode_probabilities : ndarray, shape (T, r)
        log μ_j, normalised (log-sum-exp over models is 0).
    """

    means: FloatArray
    covariances: FloatArray
    log_mode_probabilities: FloatArray

    @classmethod
    def from_gaussian(
        cls, mean: FloatArray, covariance: FloatArray, mode_probabilities: FloatArray
    ) -> IMMState:
        """Every model starts from the same Gaussian ``(mean (T, n), covariance (T, n, n))``.

        ``mode_probabilities`` has shape (r,) (shared) or (T, r); each row is normalised.
        """
        mean = np.asarray(mean, dtype=np.float64)
        covariance = np.asarray(covariance, dtype=np.float64)
        mu = np.asarray(mode_probabilities, dtype=np.float64)
        if mean.ndim != 2 or covariance.shape != (*mean.shape, mean.shape[1]):
            raise TrackingError(
                f"need means (T, n) and covariances (T, n, n), got {mean.shape} and {covariance.shape}"
            )
        tracks = mean.shape[0]
        if mu.ndim == 1:
            mu = np.broadcast_to(mu, (tracks, mu.shape[0]))
        if mu.ndim != 2 or mu.shape[0] != tracks or np.any(mu < 0.0) or np.any(mu.sum(axis=1) <= 0):
            raise TrackingError("mode probabilities must be non-negative with a positive sum")
        mu = mu / mu.sum(axis=1, keepdims=True)
        models = mu.shape[1]
        return cls(
            means=np.repeat(mean[:, None, :], models, axis=1),
            covariances=np.repeat(covariance[:, None, :, :], models, axis=1),
            log_mode_probabilities=safe_log(mu),
        )

    @property
    def n_tracks(self) -> int:
        """T."""
        return int(self.means.shape[0])

    @property
    def mode_probabilities(self) -> FloatArray:
        """μ, shape (T, r)."""
        return np.asarray(np.exp(self.log_mode_probabilities), dtype=np.float64)

    def combined(self) -> tuple[FloatArray, FloatArray]:
        """The IMM output estimate ``(x̄ (T, n), P̄ (T, n, n))`` weighted by μ."""
        return _combine(self.mode_probabilities, self.means, self.covariances)

    def select(self, tracks: IntArray | BoolArray | list[int]) -> IMMState:
        """The state of some tracks (index array or boolean mask)."""
        index = np.asarray(tracks)
        return IMMState(
            self.means[index], self.covariances[index], self.log_mode_probabilities[index]
        )


@dataclass(frozen=True)
class IMMPrediction:
    """Model-conditioned predictions of T tracks, before any measurement.

    Attributes
    ----------
    means : ndarray, shape (T, r, n)
        ``F_j x⁰_j + B u_j`` from the mixed initial conditions x⁰.
    covariances : ndarray, shape (T, r, n, n)
        ``F_j P⁰_j F_jᵀ + Q_j``.
    log_mode_probabilities : ndarray, shape (T, r)
        Predicted mode probabilities log c̄_j = log Σ_i Π_ij μ_i.
    measurement_means : ndarray, shape (T, r, q)
        ẑ_j = H x_j.
    innovation_covariances : ndarray, shape (T, r, q, q)
        S_j = H P_j Hᵀ + R.
    log_held_probabilities : ndarray, shape (T, r), or None
        log h_j, the probability that model j held over the whole step, the path its
        prediction x̄_j assumes (:meth:`IMMPredictor.held`); None: c̄ (a step of at most
        one nominal scan, where the two agree).
    """

    means: FloatArray
    covariances: FloatArray
    log_mode_probabilities: FloatArray
    measurement_means: FloatArray
    innovation_covariances: FloatArray
    log_held_probabilities: FloatArray | None = None

    @property
    def mode_probabilities(self) -> FloatArray:
        """c̄, shape (T, r)."""
        return np.asarray(np.exp(self.log_mode_probabilities), dtype=np.float64)

    @property
    def log_held(self) -> FloatArray:
        """log h_j, shape (T, r) (``log_held_probabilities``, or log c̄ without it)."""
        held = self.log_held_probabilities
        return self.log_mode_probabilities if held is None else held

    def combined(self) -> tuple[FloatArray, FloatArray]:
        """Predicted IMM estimate ``(x̄ (T, n), P̄ (T, n, n))`` weighted by c̄."""
        return _combine(self.mode_probabilities, self.means, self.covariances)

    def combined_measurement(self) -> tuple[FloatArray, FloatArray]:
        """Model-combined ``(ẑ (T, q), S (T, q, q))`` ([MTT] §4, Blackman & Popoli pp. 225–226)."""
        return _combine(
            self.mode_probabilities, self.measurement_means, self.innovation_covariances
        )

    def as_state(self) -> IMMState:
        """The prediction taken as posterior (a track with no measurement: coasting)."""
        return IMMState(self.means, self.covariances, self.log_mode_probabilities)


@dataclass(frozen=True)
class IMMUpdate:
    """Result of one IMM update, with everything the tracker and classifier need.

    Attributes
    ----------
    state : IMMState
        Posterior; for undetected tracks, the prediction itself.
    detected : ndarray of bool, shape (T,)
    innovations : ndarray, shape (T, r, q)
        ``z − ẑ_j`` per model (NaN for undetected tracks).
    innovation_covariances : ndarray, shape (T, r, q, q)
        S_j per model.
    log_likelihoods : ndarray, shape (T, r)
        log Λ_j of [MTT] eq 18 (NaN for undetected tracks).
    """

    state: IMMState
    detected: BoolArray
    innovations: FloatArray
    innovation_covariances: FloatArray
    log_likelihoods: FloatArray

    @property
    def log_mode_probabilities(self) -> FloatArray:
        """Updated log μ_j, shape (T, r)."""
        return self.state.log_mode_probabilities

    @property
    def mode_probabilities(self) -> FloatArray:
        """Updated μ_j, shape (T, r)."""
        return self.state.mode_probabilities

    def combined(self) -> tuple[FloatArray, FloatArray]:
        """Updated IMM estimate ``(x̄ (T, n), P̄ (T, n, n))``."""
        return self.state.combined()


class IMMPredictor:
    """Mixing and model-conditioned prediction for a :class:`ModelBank`.

    Parameters
    ----------
    bank : ModelBank
    """

    def __init__(self, bank: ModelBank) -> None:
        self.bank = bank
        h = bank.measurement.matrix
        self._h = h
        self._h_t = np.ascontiguousarray(h.T)
        self._r = bank.measurement.noise_covariance

    def _check(self, state: IMMState) -> None:
        r, n = self.bank.n_models, self.bank.state_dim
        tracks = state.means.shape[0] if state.means.ndim == 3 else -1
        if (
            state.means.shape != (tracks, r, n)
            or state.covariances.shape != (tracks, r, n, n)
            or state.log_mode_probabilities.shape != (tracks, r)
        ):
            raise TrackingError(
                f"IMM state must be (T, {r}, {n}) / (T, {r}, {n}, {n}) / (T, {r}); got "
                f"{state.means.shape} / {state.covariances.shape} / {state.log_mode_probabilities.shape}"
            )

    def mix(
        self, state: IMMState, dt: float | None = None
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Mixed initial conditions, with the mode transitions over Δt (default: ΔT).

        Returns
        -------
        means : (T, r, n)
            ``x⁰_j = Σ_i ω_ij x_i``, ``ω_ij = Π_ij μ_i / c̄_j``.
        covariances : (T, r, n, n)
            ``P⁰_j = Σ_i ω_ij (P_i + (x_i − x⁰_j)(x_i − x⁰_j)ᵀ)``.
        log_predicted : (T, r)
            ``log c̄_j = log Σ_i Π_ij μ_i``.
        """
        self._check(state)
        if self.bank.n_models == 1:  # ω = Π = 1: each track's one model is its own mix
            return state.means, state.covariances, state.log_mode_probabilities
        step = self.bank.time_interval if dt is None else dt
        log_transition = safe_log(self.bank.mode_transition_at(step))
        joint = state.log_mode_probabilities[:, :, None] + log_transition[None, :, :]
        log_predicted = logsumexp(joint, axis=1)  # (T, r_j)
        reachable = np.isfinite(log_predicted)
        log_mixing = joint - np.where(reachable, log_predicted, 0.0)[:, None, :]
        mixing = np.exp(log_mixing)  # ω[t, i, j]
        # An unreachable mode (c̄_j = 0) keeps its own state: its weight is zero anyway.
        identity = np.broadcast_to(np.eye(self.bank.n_models), mixing.shape)
        mixing = np.where(reachable[:, None, :], mixing, identity)
        # Σ_i ω_ij (P_i + (x_i − x⁰_j)(x_i − x⁰_j)ᵀ) = Σ_i ω_ij (P_i + y_i y_iᵀ) − ȳ_j ȳ_jᵀ with
        # y = x − c centred on the track's combined mean c: the spreads are small, so the
        # expansion loses nothing, and every sum over i is one batched matmul.
        tracks, models, n = state.means.shape
        weights_t = np.swapaxes(mixing, 1, 2)  # (T, j, i)
        centre = np.einsum("ti,tin->tn", state.mode_probabilities, state.means)
        centred = state.means - centre[:, None, :]
        mixed_centred = weights_t @ centred  # ȳ_j, (T, j, n)
        second_moment = state.covariances + centred[:, :, :, None] * centred[:, :, None, :]
        covariances = (weights_t @ second_moment.reshape(tracks, models, n * n)).reshape(
            tracks, models, n, n
        ) - mixed_centred[:, :, :, None] * mixed_centred[:, :, None, :]
        means = mixed_centred + centre[:, None, :]
        return means, covariances, log_predicted

    def predict(self, state: IMMState, dt: float | None = None) -> IMMPrediction:
        """Mix, then predict every model over Δt (default: the nominal ΔT):
        ``x = F(Δt) x + B(Δt) u``, ``P = F(Δt) P F(Δt)ᵀ + Q(Δt)``."""
        step = self.bank.time_interval if dt is None else dt
        mixed_means, mixed_covariances, log_predicted = self.mix(state, step)
        models = self.bank.at(step)
        transitions = models.transition
        means = np.einsum("jkl,tjl->tjk", transitions, mixed_means) + models.input_offset
        covariances = (
            np.matmul(np.matmul(transitions, mixed_covariances), np.swapaxes(transitions, -1, -2))
            + models.process_noise
        )
        measurement_means = means @ self._h_t
        innovation_covariances = self._h @ covariances @ self._h_t + self._r
        return IMMPrediction(
            means=means,
            covariances=covariances,
            log_mode_probabilities=log_predicted,
            measurement_means=measurement_means,
            innovation_covariances=innovation_covariances,
            log_held_probabilities=self.held(state, step),
        )

    def held(self, state: IMMState, dt: float) -> FloatArray | None:
        """log h_j: the probability, under the bank's mode chain, that model j held over the
        whole step Δt — the path its prediction ``F_j(Δt) x⁰_j + B_j(Δt) u_j`` assumes
        (docs/algorithms.md §8.1, "A detection after a long gap"). None (h = c̄) for a step
        of at most one nominal scan ΔT, where the chain switches once at most.

        Over k = Δt/ΔT > 1 scans c̄_j = (μ Π^k)_j is the probability of being in mode j at
        the *end* of the gap; the held input's displacement ½ u_j Δt² needs mode j from
        the first scan on and staying: ``h_j = (μ Π)_j Π_jj^(k−1)``.
        """
        interval = self.bank.time_interval
        if self.bank.n_models == 1 or dt <= interval:
            return None
        transition = self.bank.mode_transition
        first = logsumexp(
            state.log_mode_probabilities[:, :, None] + safe_log(transition)[None], axis=1
        )
        stay = safe_log(np.diagonal(transition).copy())
        return np.asarray(first + (dt / interval - 1.0) * stay[None, :], dtype=np.float64)


def posterior_log_modes(prior: FloatArray, joint: FloatArray, hit: BoolArray) -> FloatArray:
    """Updated log mode probabilities ([MTT] eq 18-19, log domain): ``joint`` (prior
    + log-likelihood per track × model) normalised by log-sum-exp where the track
    was hit and the normaliser is finite; the prior elsewhere."""
    log_norm = logsumexp(joint, axis=1)
    usable = hit & np.isfinite(log_norm)
    return np.asarray(
        np.where(usable[:, None], joint - np.where(usable, log_norm, 0.0)[:, None], prior),
        dtype=np.float64,
    )


class IMMUpdater:
    """Kalman update of every model with the shared H, R, then the mode probabilities.

    Parameters
    ----------
    bank : ModelBank
    """

    def __init__(self, bank: ModelBank) -> None:
        self.bank = bank
        self._h = bank.measurement.matrix
        self._h_t = np.ascontiguousarray(self._h.T)
        self._r = bank.measurement.noise_covariance
        self._identity = np.eye(bank.state_dim)

    def update(
        self,
        prediction: IMMPrediction,
        measurements: FloatArray,
        detected: BoolArray | None = None,
        measurement_noises: FloatArray | None = None,
    ) -> IMMUpdate:
        """Update T tracks, each with one measurement (or none).

        Parameters
        ----------
        prediction : IMMPrediction
        measurements : ndarray, shape (T, q)
            Row t is the measurement assigned to track t; ignored where not detected.
        detected : ndarray of bool, shape (T,), optional
            False for tracks with no measurement this scan: their posterior is
            the prediction and their mode probabilities the predicted c̄.
            Default: every track is detected.
        measurement_noises : ndarray, shape (T, q, q), optional
            Per-track measurement noise R_t of the assigned measurement
            (a sensor that reports a covariance with each detection):
            ``S_j = H P_j Hᵀ + R_t`` and the Joseph term uses R_t. Default:
            the bank's shared R.
        """
        z = np.asarray(measurements, dtype=np.float64)
        tracks, q = prediction.measurement_means.shape[0], self.bank.measurement.dim
        if z.shape != (tracks, q):
            raise TrackingError(f"measurements must have shape ({tracks}, {q}), got {z.shape}")
        hit = np.ones(tracks, dtype=bool) if detected is None else np.asarray(detected, dtype=bool)
        if hit.shape != (tracks,):
            raise TrackingError(f"detected must have shape ({tracks},), got {hit.shape}")
        if not np.all(np.isfinite(z[hit])):
            raise TrackingError("measurements of detected tracks must be finite")

        # Undetected rows see their own prediction (zero innovation); they are reset below.
        z_used = np.where(hit[:, None], z, 0.0)
        innovations = z_used[:, None, :] - prediction.measurement_means
        innovations[~hit] = 0.0
        s = prediction.innovation_covariances
        noise: FloatArray = self._r
        if measurement_noises is not None:
            noise = np.asarray(measurement_noises, dtype=np.float64)
            if noise.shape != (tracks, q, q) or not np.all(np.isfinite(noise)):
                raise TrackingError(
                    f"measurement_noises must be finite with shape ({tracks}, {q}, {q})"
                )
            noise = noise[:, None, :, :]
            s = s - self._r + noise
        s_inv = np.linalg.inv(s)
        p_ht = prediction.covariances @ self._h_t  # (T, r, n, q)
        gain = p_ht @ s_inv
        means = prediction.means + (gain @ innovations[..., None])[..., 0]
        i_kh = self._identity - gain @ self._h
        covariances = i_kh @ prediction.covariances @ np.swapaxes(i_kh, -1, -2) + (
            gain @ noise @ np.swapaxes(gain, -1, -2)
        )
        covariances = 0.5 * (covariances + np.swapaxes(covariances, -1, -2))

        # [MTT] eq 18 in the log domain.
        distances = np.sum((s_inv @ innovations[..., None])[..., 0] * innovations, axis=-1)
        _, log_det = np.linalg.slogdet(s)
        log_likelihoods = -0.5 * (distances + log_det + q * _LOG_2PI)

        log_mu = posterior_log_modes(
            prediction.log_mode_probabilities,
            prediction.log_mode_probabilities + log_likelihoods,
            hit,
        )

        means = np.where(hit[:, None, None], means, prediction.means)
        covariances = np.where(hit[:, None, None, None], covariances, prediction.covariances)
        innovations = np.where(hit[:, None, None], innovations, np.nan)
        log_likelihoods = np.where(hit[:, None], log_likelihoods, np.nan)
        return IMMUpdate(
            state=IMMState(means, covariances, log_mu),
            detected=hit,
            innovations=innovations,
            innovation_covariances=s,
            log_likelihoods=log_likelihoods,
        )
