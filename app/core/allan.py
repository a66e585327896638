"""Allan deviation of a static rate record and its IEEE Std 952 read-outs.

σ²(τ) = 3Q²/τ² + N²/τ + (2 ln2/π)·B² + K²·τ/3 + R²·τ²/2   (IEEE Std 952-1997, Annex C).

Computed with ``allantools.oadev`` (overlapping, octave-spaced τ).  Read-outs (rates in
°/h, τ in hours): one weighted non-negative least-squares fit of σ²(τ) over every τ with
all terms at once -- quantisation Q, angle random walk N (°/√h), rate random walk K
(°/h/√h) and the bias instability as a first-order Gauss–Markov term (correlation time
scanned), reported as B = peak/0.664, the value whose flicker floor 0.664·B equals the
Gauss–Markov peak.  Fitting Q with N keeps quantisation from reading as extra angle random
walk at short τ (the teaching preset's N read +10.7 % when N came from the −½ slope alone).

Recommended dwell per position (lab-reference §6): from the fitted model itself, where
correlated noise starts to outweigh white noise in the four-position heading σ
(:func:`app.core.noise_model.recommended_dwell`) -- the same noise model the simulator
generates, so the advice does not jump with each estimate of B.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from app.core.exceptions import UserError
from app.core.noise_model import GyroNoise, recommended_dwell

FLOOR_FACTOR = 0.664  # √(2 ln2 / π)
GM_PEAK = 0.6178  # peak Allan deviation of a unit-variance Gauss–Markov process
MIN_SAMPLES = 16
# A Gauss–Markov term whose correlation time is within a few of the shortest τ looks like
# white noise over the whole record and would take angle random walk from N.
MIN_CORR_TAUS = 8.0
REWEIGHT_PASSES = 3


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
    arw_sigma_deg_rt_h: float | None = None
    bias_instability_sigma_deg_h: float | None = None
    quantization_deg: float = 0.0
    bias_corr_time_s: float | None = None

    def to_json(self) -> dict:
        return {
            "taus_s": self.taus_s.tolist(),
            "adev_deg_h": self.adev_deg_h.tolist(),
            "adev_error_deg_h": self.adev_error_deg_h.tolist(),
            "arw_deg_rt_h": self.arw_deg_rt_h,
            "arw_sigma_deg_rt_h": self.arw_sigma_deg_rt_h,
            "bias_instability_deg_h": self.bias_instability_deg_h,
            "bias_instability_sigma_deg_h": self.bias_instability_sigma_deg_h,
            "bias_corr_time_s": self.bias_corr_time_s,
            "quantization_deg": self.quantization_deg,
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
    arw_sigma_deg_rt_h: float | None = None  # 1σ of N from the fit's covariance
    bias_instability_sigma_deg_h: float | None = None  # 1σ of B


def _coefficient_sigmas(matrix: np.ndarray, coefficients: np.ndarray, residual: float):
    """1σ of each fitted coefficient (NaN where the constraint holds it at zero):
    Cov = s²·(AᵀA)⁻¹ over the free columns of the weighted design A, with
    s² = max(1, χ²/(n − p)) so a misfit widens the intervals rather than hiding."""
    free = np.flatnonzero(coefficients > 0)
    sigmas = np.full(coefficients.size, np.nan)
    if free.size == 0 or matrix.shape[0] <= free.size:
        return sigmas
    design = matrix[:, free]
    scale2 = max(1.0, residual**2 / (matrix.shape[0] - free.size))
    try:
        cov = np.linalg.inv(design.T @ design) * scale2
    except np.linalg.LinAlgError:
        return sigmas
    sigmas[free] = np.sqrt(np.maximum(np.diag(cov), 0.0))
    return sigmas


def gauss_markov_avar(tau_h: np.ndarray, corr_time_h: float) -> np.ndarray:
    """Allan variance of a unit-variance first-order Gauss–Markov process.

    σ²(τ) = (2T/τ)·[1 − (T/2τ)(3 − 4e^(−τ/T) + e^(−2τ/T))]; its deviation peaks at 0.6178
    near τ = 1.89·T.

    Parameters
    ----------
    tau_h : numpy.ndarray
        Averaging times τ (h).
    corr_time_h : float
        The correlation time T (h).

    Returns
    -------
    numpy.ndarray
        σ²(τ) for unit process variance.

    References
    ----------
    IEEE Std 952-1997, annex C (exponentially correlated noise).
    """
    x = tau_h / corr_time_h
    return (2.0 / x) * (1.0 - (3.0 - 4.0 * np.exp(-x) + np.exp(-2.0 * x)) / (2.0 * x))


def white_noise_arw(taus_s: np.ndarray, adev: np.ndarray) -> float:
    """Angle random walk N = σ(τ)·√τ (τ in hours), read where the curve has slope −½.

    Parameters
    ----------
    taus_s : numpy.ndarray
        Averaging times τ (s).
    adev : numpy.ndarray
        Allan deviation σ(τ) (°/h).

    Returns
    -------
    float
        N (°/√h) at the shortest τ on the −½ slope (else at the shortest τ).

    References
    ----------
    IEEE Std 952-1997, annex C (angle random walk: σ(τ) = N/√τ).
    """
    if taus_s.size < 2:
        return float(adev[0] * math.sqrt(taus_s[0] / 3600.0))
    slopes = np.gradient(np.log(adev), np.log(taus_s))
    white = np.flatnonzero(np.abs(slopes + 0.5) < 0.15)
    first = int(white[0]) if white.size else 0
    return float(adev[first] * math.sqrt(taus_s[first] / 3600.0))


def white_noise_dof(taus_s: np.ndarray, rate_hz: float, count: int) -> np.ndarray:
    """Equivalent degrees of freedom of each overlapping Allan variance for white rate noise.

    About 3N/2m (N samples, m = τ·rate), so a τ averaged over few stretches of the record
    weighs little; allantools' own δσ = σ/√N ignores that and lets the noisy long-τ end
    steer a fit.

    Parameters
    ----------
    taus_s : numpy.ndarray
        Averaging times τ (s).
    rate_hz : float
        Sample rate (Hz).
    count : int
        Samples in the record.

    Returns
    -------
    numpy.ndarray
        edf for each τ.

    References
    ----------
    NIST SP 1065 (2008), table 5, via ``allantools.edf_simple``.
    """
    import allantools  # with scipy and matplotlib: imported when first needed

    edf = [allantools.edf_simple(count + 1, max(1, int(round(tau * rate_hz))), 0) for tau in taus_s]
    return np.maximum(np.asarray(edf, dtype=float), 1.0)


def fit_noise_model(
    taus_s: np.ndarray, adev: np.ndarray, error: np.ndarray, dof: np.ndarray | None = None
) -> NoiseFit:
    """All IEEE 952 terms at once, by weighted non-negative least squares of

        σ²(τ) = 3Q²/τ² + N²/τ + σ_GM²·g(τ/T) + K²τ/3      (τ in hours)

    over every τ, the Gauss–Markov correlation time T scanned on a log grid (T ≥ the
    shortest τ, so it cannot pose as white noise).  Fitting Q and N together keeps
    quantisation from passing for angle random walk at short τ.  B = 0.6178·σ_GM/0.664.
    Weights: the standard error of each σ², √(2/edf)·σ², first with the measured σ², then
    (iteratively reweighted) with the model's: weighing by the measured value favours the
    τ's that happened to come out low and read B 14 % low when its hump dominates.
    Without degrees of freedom, allantools' δσ gives 1/(2σ·δσ).

    Parameters
    ----------
    taus_s : numpy.ndarray
        Averaging times τ (s).
    adev : numpy.ndarray
        Allan deviation σ(τ) (°/h).
    error : numpy.ndarray
        allantools' δσ(τ) (°/h), used without ``dof``.
    dof : numpy.ndarray, optional
        Equivalent degrees of freedom of each σ²(τ) (:func:`white_noise_dof`).

    Returns
    -------
    NoiseFit
        Q (°), N (°/√h), B (°/h) with its correlation time T (s), K (°/h/√h), and the 1σ
    of N and B from the fit's covariance.

    References
    ----------
    IEEE Std 952-1997, annex C; lab-reference §6 (the Allan fit).
    """
    tau_h = taus_s / 3600.0
    basis = [3.0 / tau_h**2, 1.0 / tau_h, tau_h / 3.0]
    grid = np.geomspace(tau_h[0] * MIN_CORR_TAUS, tau_h[-1] * 4.0, 64) if tau_h.size > 3 else [None]
    expected = adev**2  # the first pass weighs by the measured σ², later ones by the model's
    for _ in range(REWEIGHT_PASSES):
        if dof is not None:  # Var(σ̂²) ≈ 2σ⁴/edf
            weight = np.sqrt(dof / 2.0) / np.maximum(expected, 1e-300)
        else:
            weight = 1.0 / np.maximum(2.0 * adev * np.maximum(error, 1e-12 * adev), 1e-300)
        target = adev**2 * weight
        best = None
        for corr in grid:
            columns = [*basis, gauss_markov_avar(tau_h, corr)] if corr is not None else basis
            matrix = np.column_stack(columns) * weight[:, None]
            scale = np.linalg.norm(matrix, axis=0)
            scale[scale == 0] = 1.0
            from scipy.optimize import nnls

            scaled, residual = nnls(matrix / scale, target)
            if best is None or residual < best[0]:
                sigmas = _coefficient_sigmas(matrix / scale, scaled, residual) / scale
                best = (residual, scaled / scale, corr, sigmas, matrix / weight[:, None])
        model = best[4] @ best[1]
        if dof is None or not np.all(model > 0):
            break
        expected = model
    _, c, corr, c_sigma, _ = best
    gm_sigma = math.sqrt(c[3]) if len(c) > 3 and c[3] > 0 else 0.0
    arw = math.sqrt(c[1]) if c[1] > 0 else white_noise_arw(taus_s, adev)
    # δ√c = δc/(2√c): N from the N² coefficient, B ∝ σ_GM from the σ_GM² coefficient
    arw_sigma = c_sigma[1] / (2.0 * arw) if c[1] > 0 else None
    bias = GM_PEAK * gm_sigma / FLOOR_FACTOR if gm_sigma else None
    bias_sigma = GM_PEAK / FLOOR_FACTOR * c_sigma[3] / (2.0 * gm_sigma) if gm_sigma else None
    return NoiseFit(
        quantization_deg=math.sqrt(c[0]),
        arw_deg_rt_h=arw,
        bias_instability_deg_h=bias,
        bias_corr_time_s=corr * 3600.0 if gm_sigma else None,
        rrw_deg_h_rt_h=math.sqrt(c[2]) if c[2] > 0 else None,
        arw_sigma_deg_rt_h=_finite_or_none(arw_sigma),
        bias_instability_sigma_deg_h=_finite_or_none(bias_sigma),
    )


def _finite_or_none(value: float | None) -> float | None:
    return float(value) if value is not None and math.isfinite(value) else None


def fitted_noise(fit: NoiseFit) -> GyroNoise:
    """The fit as a noise model for :mod:`app.core.noise_model`.

    Parameters
    ----------
    fit : NoiseFit
        A fit from :func:`fit_noise_model`.

    Returns
    -------
    GyroNoise
        The same terms: Q → an angle LSB of √12·Q; B → the Gauss–Markov σ and T.

    References
    ----------
    IEEE Std 952-1997, annex C.
    """
    return GyroNoise(
        arw_deg_rt_h=fit.arw_deg_rt_h,
        bias_instability_deg_h=fit.bias_instability_deg_h or 0.0,
        bias_corr_time_s=fit.bias_corr_time_s or 0.0,
        rrw_deg_h_rt_h=fit.rrw_deg_h_rt_h or 0.0,
        angle_lsb_deg=fit.quantization_deg * math.sqrt(12.0),
    )


def allan_deviation(rates_deg_h, rate_hz: float) -> AllanResult:
    """Overlapping Allan deviation (octave-spaced τ) of a rate record, with read-outs.

    Parameters
    ----------
    rates_deg_h : array_like
        The rate record (°/h), equally spaced.
    rate_hz : float
        The sample rate (Hz).

    Returns
    -------
    AllanResult
        τ (s), σ(τ) (°/h) with its error, and the fitted IEEE 952 terms: angle random walk N
        (°/√h), bias instability B (°/h), rate random walk K (°/h/√h), quantisation Q (°)
    and the dwell to recommend (s).

    Raises
    ------
    UserError
        Too short a record, a non-positive rate, or non-finite readings.

    References
    ----------
    IEEE Std 952-1997, annex C; allantools ``oadev``; NIST SP 1065 (edf).
    """
    data = np.asarray(rates_deg_h, dtype=float).ravel()
    if data.size < MIN_SAMPLES:
        raise UserError(
            "allan.too_short",
            f"The Allan deviation needs at least {MIN_SAMPLES} readings.",
            minimum=MIN_SAMPLES,
        )
    if not np.all(np.isfinite(data)):
        raise UserError("readings.not_finite", "A reading is not a finite number.")
    if not (rate_hz > 0 and math.isfinite(rate_hz)):
        raise UserError("allan.bad_rate", "The sample rate must be a positive number.")
    import allantools

    taus, adev, error, _ = allantools.oadev(data, rate=rate_hz, data_type="freq", taus="octave")
    keep = adev > 0
    taus, adev, error = taus[keep], adev[keep], error[keep]
    if taus.size == 0:
        raise UserError(
            "allan.constant",
            "The readings never change; there is no noise "
            "to analyse (is the record quantised too coarsely?).",
        )
    fit = fit_noise_model(taus, adev, error, white_noise_dof(taus, rate_hz, data.size))
    arw, bias, rrw = fit.arw_deg_rt_h, fit.bias_instability_deg_h, fit.rrw_deg_h_rt_h
    smallest = int(np.argmin(adev))
    dwell = recommended_dwell(fitted_noise(fit), rate_hz).recommended_s
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
        fit.arw_sigma_deg_rt_h,
        fit.bias_instability_sigma_deg_h,
        fit.quantization_deg,
        fit.bias_corr_time_s,
    )
