"""Allan deviation of a static rate record and its IEEE Std 952 read-outs.

σ²(τ) = 3Q²/τ² + N²/τ + (2 ln2/π)·B² + K²·τ/3 + R²·τ²/2   (IEEE Std 952-1997, Annex C).

Computed with ``allantools.oadev`` (overlapping, octave-spaced τ).  Read-outs (rates in
°/h, τ in hours): one weighted non-negative least-squares fit of σ²(τ) over every τ with
all terms at once -- quantisation Q, angle random walk N (°/√h), rate random walk K
(°/h/√h) and the bias instability as a first-order Gauss–Markov term (correlation time
scanned), reported as B = peak/0.664, the value whose flicker floor 0.664·B equals the
Gauss–Markov peak.  Fitting Q with N keeps quantisation from reading as extra angle random
walk at short τ (the teaching preset's N read +10.7 % when N came from the −½ slope alone).

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
# A Gauss–Markov term whose correlation time is within a few of the shortest τ looks like
# white noise over the whole record and would take angle random walk from N.
MIN_CORR_TAUS = 8.0


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


def white_noise_dof(taus_s: np.ndarray, rate_hz: float, count: int) -> np.ndarray:
    """Equivalent degrees of freedom of each overlapping Allan variance for white rate
    noise (NIST SP 1065, table 5, via ``allantools.edf_simple``): about 3N/2m, so a τ
    averaged over few stretches of the record weighs little.  allantools' own δσ = σ/√N
    ignores that and lets the noisy long-τ end steer a fit."""
    edf = [allantools.edf_simple(count + 1, max(1, int(round(tau * rate_hz))), 0) for tau in taus_s]
    return np.maximum(np.asarray(edf, dtype=float), 1.0)


def fit_noise_model(
    taus_s: np.ndarray, adev: np.ndarray, error: np.ndarray, dof: np.ndarray | None = None
) -> NoiseFit:
    """All IEEE 952 terms at once: weighted non-negative least squares of

        σ²(τ) = 3Q²/τ² + N²/τ + σ_GM²·g(τ/T) + K²τ/3      (τ in hours)

    over every τ, the Gauss–Markov correlation time T scanned on a log grid (T ≥ the
    shortest τ, so it cannot pose as white noise).  Fitting Q and N together keeps
    quantisation from passing for angle random walk at short τ.  B = 0.6178·σ_GM/0.664.
    Weights: 1/(2σ·δσ), the standard error of σ² from allantools' δσ."""
    tau_h = taus_s / 3600.0
    if dof is not None:  # Var(σ̂²) ≈ 2σ⁴/edf
        weight = np.sqrt(dof / 2.0) / np.maximum(adev**2, 1e-300)
    else:
        weight = 1.0 / np.maximum(2.0 * adev * np.maximum(error, 1e-12 * adev), 1e-300)
    basis = [3.0 / tau_h**2, 1.0 / tau_h, tau_h / 3.0]
    target = adev**2 * weight
    best = None
    grid = np.geomspace(tau_h[0] * MIN_CORR_TAUS, tau_h[-1] * 4.0, 64) if tau_h.size > 3 else [None]
    for corr in grid:
        columns = [*basis, gauss_markov_avar(tau_h, corr)] if corr is not None else basis
        matrix = np.column_stack(columns) * weight[:, None]
        scale = np.linalg.norm(matrix, axis=0)
        scale[scale == 0] = 1.0
        coefficients, residual = nnls(matrix / scale, target)
        coefficients = coefficients / scale
        if best is None or residual < best[0]:
            best = (residual, coefficients, corr)
    _, c, corr = best
    gm_sigma = math.sqrt(c[3]) if len(c) > 3 and c[3] > 0 else 0.0
    arw = math.sqrt(c[1]) if c[1] > 0 else white_noise_arw(taus_s, adev)
    return NoiseFit(
        quantization_deg=math.sqrt(c[0]),
        arw_deg_rt_h=arw,
        bias_instability_deg_h=GM_PEAK * gm_sigma / FLOOR_FACTOR if gm_sigma else None,
        bias_corr_time_s=corr * 3600.0 if gm_sigma else None,
        rrw_deg_h_rt_h=math.sqrt(c[2]) if c[2] > 0 else None,
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
    fit = fit_noise_model(taus, adev, error, white_noise_dof(taus, rate_hz, data.size))
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
