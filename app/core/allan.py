"""Allan deviation of a static rate record and its IEEE Std 952 read-outs.

σ²(τ) = 3Q²/τ² + N²/τ + (2 ln2/π)·B² + K²·τ/3 + R²·τ²/2   (IEEE Std 952-1997, Annex C).

Computed with ``allantools.oadev`` (overlapping, octave-spaced τ).  Read-outs (rates in
°/h, τ in hours): ARW N (°/√h) = σ(τ)·√τ on the −½ slope; then a weighted non-negative
least-squares fit of the rest of σ²(τ), which uses every τ rather than one point on each
slope: quantisation Q, rate random walk K (°/h/√h), and the bias instability as a
first-order Gauss–Markov term (correlation time scanned), reported as B = peak/0.664 —
the value whose flicker floor 0.664·B equals the Gauss–Markov peak.

Recommended dwell per position: where the ARW line meets the bias-instability floor,
τ* = (N / 0.664·B)² — averaging longer gains little (lab-reference §6); without a floor,
the τ of the smallest σ computed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import allantools
import numpy as np
from scipy.optimize import nnls

from app.core.exceptions import GyroInputError

FLOOR_FACTOR = 0.664  # √(2 ln2 / π)
GM_PEAK = 0.6178  # peak Allan deviation of a unit-variance Gauss–Markov process
MIN_SAMPLES = 16


@dataclass(frozen=True)
class AllanResult:
    taus_s: np.ndarray
    adev_deg_h: np.ndarray
    adev_error_deg_h: np.ndarray
    arw_deg_rt_h: float
    bias_instability_deg_h: float | None
    rrw_deg_h_rt_h: float | None
    tau_min_s: float
    adev_min_deg_h: float
    recommended_dwell_s: float

    def to_json(self) -> dict:
        return {
            "taus_s": self.taus_s.tolist(),
            "adev_deg_h": self.adev_deg_h.tolist(),
            "adev_error_deg_h": self.adev_error_deg_h.tolist(),
            "arw_deg_rt_h": self.arw_deg_rt_h,
            "bias_instability_deg_h": self.bias_instability_deg_h,
            "rrw_deg_h_rt_h": self.rrw_deg_h_rt_h,
            "tau_min_s": self.tau_min_s,
            "adev_min_deg_h": self.adev_min_deg_h,
            "recommended_dwell_s": self.recommended_dwell_s,
        }


@dataclass(frozen=True)
class NoiseFit:
    quantization_deg: float
    arw_deg_rt_h: float
    bias_instability_deg_h: float | None
    bias_corr_time_s: float | None
    rrw_deg_h_rt_h: float | None


def gauss_markov_avar(tau_h: np.ndarray, corr_time_h: float) -> np.ndarray:
    """Allan variance of a unit-variance first-order Gauss–Markov process:
    (2T/τ)·[1 − (T/2τ)(3 − 4e^(−τ/T) + e^(−2τ/T))]; its deviation peaks at 0.6178 near τ=1.89T.
    """
    x = tau_h / corr_time_h
    return (2.0 / x) * (1.0 - (3.0 - 4.0 * np.exp(-x) + np.exp(-2.0 * x)) / (2.0 * x))


def white_noise_arw(taus_s: np.ndarray, adev: np.ndarray) -> float:
    """N = σ(τ)·√τ (τ in hours) at the shortest τ on the −½ slope (else the shortest τ)."""
    if taus_s.size < 2:
        return float(adev[0] * math.sqrt(taus_s[0] / 3600.0))
    slopes = np.gradient(np.log(adev), np.log(taus_s))
    white = np.flatnonzero(np.abs(slopes + 0.5) < 0.15)
    first = int(white[0]) if white.size else 0
    return float(adev[first] * math.sqrt(taus_s[first] / 3600.0))


def fit_noise_model(taus_s: np.ndarray, adev: np.ndarray, error: np.ndarray) -> NoiseFit:
    """N from the −½ slope, then weighted non-negative least squares of what remains,
    σ² − N²/τ = 3Q²/τ² + σ_GM²·g(τ/T) + K²τ/3, with the Gauss–Markov correlation time T
    scanned on a log grid (T ≥ the shortest τ, so it cannot pose as white noise).
    B = 0.6178·σ_GM / 0.664."""
    tau_h = taus_s / 3600.0
    arw = white_noise_arw(taus_s, adev)
    rest = adev**2 - arw**2 / tau_h
    weight = 1.0 / np.maximum(2.0 * adev * np.maximum(error, 1e-12 * adev), 1e-300)
    basis = [3.0 / tau_h**2, tau_h / 3.0]
    best = None
    grid = np.geomspace(tau_h[0], tau_h[-1] * 4.0, 48) if tau_h.size > 2 else [None]
    for corr in grid:
        columns = [*basis, gauss_markov_avar(tau_h, corr)] if corr is not None else basis
        matrix = np.column_stack(columns) * weight[:, None]
        scale = np.linalg.norm(matrix, axis=0)
        scale[scale == 0] = 1.0
        coefficients, residual = nnls(matrix / scale, rest * weight)
        coefficients = coefficients / scale
        if best is None or residual < best[0]:
            best = (residual, coefficients, corr)
    _, c, corr = best
    gm_sigma = math.sqrt(c[2]) if len(c) > 2 and c[2] > 0 else 0.0
    return NoiseFit(
        quantization_deg=math.sqrt(c[0]),
        arw_deg_rt_h=arw,
        bias_instability_deg_h=GM_PEAK * gm_sigma / FLOOR_FACTOR if gm_sigma else None,
        bias_corr_time_s=corr * 3600.0 if gm_sigma else None,
        rrw_deg_h_rt_h=math.sqrt(c[1]) if c[1] > 0 else None,
    )


def allan_deviation(rates_deg_h, rate_hz: float) -> AllanResult:
    """Overlapping Allan deviation (octave τ) of a rate record in °/h sampled at ``rate_hz``."""
    data = np.asarray(rates_deg_h, dtype=float).ravel()
    if data.size < MIN_SAMPLES:
        raise GyroInputError(
            "allan.too_short",
            f"The Allan deviation needs at least {MIN_SAMPLES} readings.",
            minimum=MIN_SAMPLES,
        )
    if not np.all(np.isfinite(data)):
        raise GyroInputError("readings.not_finite", "A reading is not a finite number.")
    if not (rate_hz > 0 and math.isfinite(rate_hz)):
        raise GyroInputError("allan.bad_rate", "The sample rate must be a positive number.")
    taus, adev, error, _ = allantools.oadev(data, rate=rate_hz, data_type="freq", taus="octave")
    keep = adev > 0
    taus, adev, error = taus[keep], adev[keep], error[keep]
    if taus.size == 0:
        raise GyroInputError(
            "allan.constant",
            "The readings never change; there is no noise "
            "to analyse (is the record quantised too coarsely?).",
        )
    fit = fit_noise_model(taus, adev, error)
    arw, bias, rrw = fit.arw_deg_rt_h, fit.bias_instability_deg_h, fit.rrw_deg_h_rt_h
    smallest = int(np.argmin(adev))
    dwell = (arw / (FLOOR_FACTOR * bias)) ** 2 * 3600.0 if bias else float(taus[smallest])
    return AllanResult(
        taus,
        adev,
        error,
        arw,
        bias,
        rrw,
        float(taus[smallest]),
        float(adev[smallest]),
        float(dwell),
    )
