"""Bias instability as flicker (1/f) rate noise: a sum of Gauss–Markov processes.

Real gyros' bias instability is flicker noise -- a flat Allan floor σ = 0.664·B over
decades of τ (IEEE Std 952-1997, annex C; lab-reference §6) -- not one first-order
Gauss–Markov process, which rises to a peak near τ ≈ 1.89·T and falls again.  Here flicker
noise is built from M first-order Gauss–Markov processes with correlation times T_j spread
evenly in log over the band [T_lo, T_hi] (``PER_DECADE`` per decade) and equal variances
v: each contributes a Lorentzian 2vT_j/(1 + (2πfT_j)²) to the spectrum, and equal v over a
log-uniform grid sums to S(f) ∝ 1/f between 1/(2πT_hi) and 1/(2πT_lo) (Keshner 1982;
Van der Ziel 1950).  The same sum serves the simulator (:class:`app.core.gyro_stream.GyroStream`,
one exact first-order recursion per component) and the σ model
(:mod:`app.core.noise_model`, one closed-form exponential covariance per component), so the
uncertainty the lab reports and the noise it generates are the same model.

Calibration: v is chosen so that the Allan deviation at the band's centre is exactly
0.664·B, v = (0.664·B)² / Σ_j g(τ_c/T_j), g the unit-variance Gauss–Markov Allan variance
and τ_c = 1.89·√(T_lo·T_hi).  With 3 components per decade the floor ripples by < 1 % and
stays within 10 % of 0.664·B from ≈ 3·T_lo to ≈ T_hi/3.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

FLOOR_FACTOR = 0.664  # √(2 ln2 / π): the flicker floor σ = 0.664·B
PER_DECADE = 3
DEFAULT_BAND_S = (1.0, 1.0e5)  # five decades: a flat floor from seconds to a day
GM_PEAK_TAU_PER_T = 1.89


def gauss_markov_avar(tau, corr_time):
    """Allan variance of a unit-variance first-order Gauss–Markov process.

    σ²(τ) = (2T/τ)·[1 − (T/2τ)(3 − 4e^(−τ/T) + e^(−2τ/T))], peaking at 0.6178² near
    τ = 1.89·T.  τ and T in the same unit.

    Parameters
    ----------
    tau : float or numpy.ndarray
        Averaging times τ.
    corr_time : float
        The correlation time T.

    Returns
    -------
    float or numpy.ndarray
        σ²(τ) for unit process variance.

    References
    ----------
    IEEE Std 952-1997, annex C (exponentially correlated noise).
    """
    x = np.asarray(tau, dtype=float) / corr_time
    small = x < 1e-4  # the series 2x/3 − x²/6… avoids cancellation at τ ≪ T
    safe = np.where(small, 1.0, x)
    exact = (2.0 / safe) * (1.0 - (3.0 - 4.0 * np.exp(-safe) + np.exp(-2.0 * safe)) / (2.0 * safe))
    return np.where(small, 2.0 * x / 3.0 - x * x / 6.0, exact)


SINE_PEAK_TAU_PER_PERIOD = 0.371  # the Allan deviation of a sinusoid peaks near τ = 0.371·P


def sinusoid_avar(tau, period):
    """Allan variance of a sinusoid of unit amplitude: σ²(τ) = sin⁴(πτ/P)/(πτ/P)².

    IEEE 952's sinusoidal noise term, Ω0²·(sin²(πf0τ)/(πf0τ))² with f0 = 1/P: it rises as
    τ² to its peak (≈ 0.725² near τ = 0.371·P), then falls as 1/τ², to zero at every whole
    period -- a bias that swings with the lab's air conditioning or heating cycle.

    Parameters
    ----------
    tau : float or numpy.ndarray
        Averaging times τ.
    period : float
        The period P, in τ's unit.

    Returns
    -------
    float or numpy.ndarray
        σ²(τ) for amplitude 1.

    References
    ----------
    IEEE Std 952-1997, annex C (C.9, sinusoidal noise).
    """
    x = np.pi * np.asarray(tau, dtype=float) / period
    return np.sin(x) ** 4 / (x * x)


@lru_cache(maxsize=64)
def _unit_components(low_s: float, high_s: float) -> tuple[tuple[float, ...], float]:
    decades = max(math.log10(high_s / low_s), 0.0)
    count = max(2, int(round(decades * PER_DECADE)) + 1)
    times = np.geomspace(low_s, high_s, count)
    centre = GM_PEAK_TAU_PER_T * math.sqrt(low_s * high_s)
    level = float(np.sum(gauss_markov_avar(centre, times)))
    return tuple(float(t) for t in times), level


def flicker_components(
    bias_instability_deg_h: float, band_s: tuple[float, float] = DEFAULT_BAND_S
) -> list[tuple[float, float]]:
    """The Gauss–Markov components whose sum is flicker noise with floor 0.664·B.

    Parameters
    ----------
    bias_instability_deg_h : float
        B (°/h): the Allan floor is 0.664·B.
    band_s : (float, float)
        The correlation times T_lo … T_hi (s) that the floor spans.

    Returns
    -------
    list of (float, float)
        (variance v in (°/h)², correlation time T_j in s) for each component; empty when
        B is 0.

    References
    ----------
    Keshner, "1/f noise", Proc. IEEE 70 (1982) 212; IEEE Std 952-1997, annex C;
    lab-reference §6.
    """
    if bias_instability_deg_h <= 0:
        return []
    low, high = sorted(float(b) for b in band_s)
    if not (low > 0 and math.isfinite(high)):
        raise ValueError("the flicker band must be two positive correlation times")
    times, level = _unit_components(low, high)
    variance = (FLOOR_FACTOR * bias_instability_deg_h) ** 2 / level
    return [(variance, t) for t in times]


def flicker_avar(tau_s, bias_instability_deg_h: float, band_s=DEFAULT_BAND_S):
    """Allan variance (°/h)² of the band-limited flicker noise of :func:`flicker_components`.

    Parameters
    ----------
    tau_s : float or numpy.ndarray
        Averaging times τ (s).
    bias_instability_deg_h : float
        B (°/h).
    band_s : (float, float)
        The band of correlation times (s).

    Returns
    -------
    float or numpy.ndarray
        Σ_j v·g(τ/T_j): ≈ (0.664·B)² inside the band.

    References
    ----------
    IEEE Std 952-1997, annex C.
    """
    tau = np.asarray(tau_s, dtype=float)
    total = np.zeros_like(tau)
    for variance, corr in flicker_components(bias_instability_deg_h, band_s):
        total = total + variance * gauss_markov_avar(tau, corr)
    return total
