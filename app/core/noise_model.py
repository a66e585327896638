"""A gyro's noise model (IEEE Std 952 terms) and what it means for position means.

When the noise model is known -- the simulator's preset, or a gyro characterised by its
Allan deviation -- the uncertainty of each position mean no longer has to be guessed from
the readings' scatter (which assumes white noise and is over-confident for correlated
noise: bias instability, rate random walk).  Here the covariance of the position means is
computed from the model, windows of the recording schedule given (lab-reference §3, §5).

Terms, with continuous-time covariances of the rate (°/h):

* angle random walk N (°/√h): white, spectral density (60·N)² (°/h)²·s;
* bias instability: first-order Gauss–Markov, variance σ² = (1.075·B)², correlation time
  T, autocovariance σ²·e^(−|Δ|/T);
* rate random walk K (°/h/√h): Brownian, Cov(r(s), r(t)) = (K²/3600)·min(s, t) with s, t
  in seconds from switch-on;
* angle quantisation q (°): the rate is the difference of an angle rounded to q, so a
  window mean is off by (e_end − e_start)·3600/L with e uniform: variance 2·(q²/12)·3600²/L²,
  and adjacent windows share an end.

Allan variance of the same model (used by the dwell advice and printed by the CLI):

    σ²_A(τ) = (60N)²/τ + (3600·q)²/(4τ²) + (2σ²T/τ)·[1 − (T/2τ)(3 − 4e^(−τ/T) + e^(−2τ/T))]
              + (K²/3600)·τ/3                                   (IEEE 952, annex C)
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from app.core.presets import GyroPreset
from app.core.simulate import GM_SIGMA_PER_B

SECONDS_PER_HOUR = 3600.0


@dataclass(frozen=True)
class Window:
    """One position's recording: start and length in seconds from switch-on."""

    start_s: float
    length_s: float

    @property
    def end_s(self) -> float:
        return self.start_s + self.length_s


def back_to_back(
    counts: Sequence[int], rate_hz: float, gap_s: float = 0.0, start_s: float = 0.0
) -> list[Window]:
    """Windows of ``counts`` samples recorded one after another.

    Parameters
    ----------
    counts : sequence of int
        Samples in each window.
    rate_hz : float
        Sample rate (Hz).
    gap_s : float
        Time between windows (s).
    start_s : float
        When the first window starts, after switch-on (s).

    Returns
    -------
    list of Window
        Each window's start and end (s).
    """
    windows, clock = [], float(start_s)
    for count in counts:
        length = count / rate_hz
        windows.append(Window(clock, length))
        clock += length + gap_s
    return windows


@dataclass(frozen=True)
class GyroNoise:
    """The noise terms of one gyro and the indexing σ of its turntable."""

    arw_deg_rt_h: float = 0.0
    bias_instability_deg_h: float = 0.0
    bias_corr_time_s: float = 0.0
    rrw_deg_h_rt_h: float = 0.0
    angle_lsb_deg: float = 0.0
    indexing_sigma_deg: float = 0.0

    @classmethod
    def from_preset(cls, preset: GyroPreset) -> GyroNoise:
        return cls(
            arw_deg_rt_h=preset.arw_deg_rt_h,
            bias_instability_deg_h=preset.bias_instability_deg_h,
            bias_corr_time_s=preset.bias_corr_time_s,
            rrw_deg_h_rt_h=preset.rrw_deg_h_rt_h,
            angle_lsb_deg=preset.angle_lsb_deg,
            indexing_sigma_deg=preset.indexing_sigma_arcsec / 3600.0,
        )

    @property
    def gm_variance(self) -> float:
        return (GM_SIGMA_PER_B * self.bias_instability_deg_h) ** 2

    @property
    def white_density(self) -> float:
        """(60·N)²: the white rate noise's two-sided density, (°/h)²·s."""
        return (60.0 * self.arw_deg_rt_h) ** 2

    @property
    def rrw_rate(self) -> float:
        """K²/3600: growth of the random walk's variance, (°/h)² per second."""
        return self.rrw_deg_h_rt_h**2 / SECONDS_PER_HOUR

    def allan_variance(self, tau_s: float) -> float:
        """σ²_A(τ) in (°/h)² (see the module docstring)."""
        tau = float(tau_s)
        total = self.white_density / tau
        total += (SECONDS_PER_HOUR * self.angle_lsb_deg) ** 2 / (4.0 * tau * tau)
        if self.gm_variance and self.bias_corr_time_s:
            t = self.bias_corr_time_s
            x = tau / t
            total += (2.0 * self.gm_variance * t / tau) * (
                1.0 - (3.0 - 4.0 * math.exp(-x) + math.exp(-2.0 * x)) / (2.0 * x)
            )
        total += self.rrw_rate * tau / 3.0
        return total

    def mean_covariance(self, windows: Sequence[Window], *, continuous: bool = True) -> np.ndarray:
        """Covariance matrix of the rate's mean over each window, (°/h)².

        ``continuous``: one gyro running through every window (one timeline);
        otherwise each window is a separate recording started afresh (no correlation
        between windows, random walk from zero, Gauss–Markov stationary)."""
        count = len(windows)
        cov = np.zeros((count, count))
        quant = (SECONDS_PER_HOUR * self.angle_lsb_deg) ** 2 / 12.0
        for i, wi in enumerate(windows):
            for j, wj in enumerate(windows):
                if i != j and not continuous:
                    continue
                li, lj = wi.length_s, wj.length_s
                value = 0.0
                if i == j:
                    value += self.white_density / li + 2.0 * quant / (li * li)
                elif abs(wi.end_s - wj.start_s) < 1e-9 or abs(wj.end_s - wi.start_s) < 1e-9:
                    value -= quant / (li * lj)  # a shared end of the rounded angle
                value += (
                    self.gm_variance
                    * _exponential_mean_product(wi, wj, self.bias_corr_time_s)
                    / (li * lj)
                )
                if continuous:
                    value += self.rrw_rate * _brownian_integral(wi, wj) / (li * lj)
                elif i == j:
                    value += self.rrw_rate * li / 3.0  # a walk from zero at the start
                cov[i, j] = value
        return cov


def _exponential_mean_product(wi: Window, wj: Window, t: float) -> float:
    """∫∫ e^(−|s−u|/T) ds du over the two windows (0 without a correlation time)."""
    if t <= 0:
        return 0.0
    if wi is wj or (wi.start_s == wj.start_s and wi.length_s == wj.length_s):
        length = wi.length_s
        return 2.0 * t * length - 2.0 * t * t * (1.0 - math.exp(-length / t))
    first, second = (wi, wj) if wi.start_s <= wj.start_s else (wj, wi)
    if first.end_s > second.start_s + 1e-9:
        raise ValueError("windows overlap")
    a1, b1, a2, b2 = first.start_s, first.end_s, second.start_s, second.end_s
    return (t * t) * (
        math.exp(-(a2 - b1) / t)
        - math.exp(-(a2 - a1) / t)
        - math.exp(-(b2 - b1) / t)
        + math.exp(-(b2 - a1) / t)
    )


def _brownian_integral(wi: Window, wj: Window) -> float:
    """∫∫ min(s, u) ds du over the two windows (s, u ≥ 0, windows not overlapping)."""
    if wi.start_s == wj.start_s and wi.length_s == wj.length_s:
        a, length = wi.start_s, wi.length_s
        return a * length * length + length**3 / 3.0
    first, second = (wi, wj) if wi.start_s <= wj.start_s else (wj, wi)
    # every s in the first window is below every u in the second: min = s
    return (first.end_s**2 - first.start_s**2) / 2.0 * second.length_s


FOUR_X = np.array([0.5, 0.0, -0.5, 0.0])  # x = (m1 − m3)/2
FOUR_Y = np.array([0.0, 0.5, 0.0, -0.5])  # y = (m2 − m4)/2


def four_position_sigma(
    noise: GyroNoise, rate_hz: float, dwell_s: float, amplitude: float
) -> float:
    """Heading σ of four back-to-back positions of ``dwell_s`` each, averaged over the azimuth.

    σ_A = √((v_x + v_y)/2)/H rad, v_x and v_y the variances of x = (ω1 − ω3)/2 and
    y = (ω2 − ω4)/2 from the noise model's covariance of the four windows' means.

    Parameters
    ----------
    noise : GyroNoise
        The gyro's noise terms (IEEE 952).
    rate_hz : float
        Sample rate (Hz).
    dwell_s : float
        Recording time per position (s).
    amplitude : float
        H = Ω cos φ (°/h).

    Returns
    -------
    float
        σ_A (°).

    References
    ----------
    lab-reference §3 and §6; IEEE Std 952-1997.
    """
    count = max(1, int(round(dwell_s * rate_hz)))
    cov = noise.mean_covariance(back_to_back([count] * 4, rate_hz))
    variance = (FOUR_X @ cov @ FOUR_X + FOUR_Y @ cov @ FOUR_Y) / 2.0
    return math.degrees(math.sqrt(max(variance, 0.0)) / amplitude)


DWELL_RANGE_S = (5.0, 1800.0)  # the lab's shortest sensible and longest allowed dwell
CORRELATED_SHARE = 1.5  # σ² = 1.5·σ²_white: correlated noise adds half the white variance


@dataclass(frozen=True)
class DwellAdvice:
    """Four-position heading σ against dwell (for an amplitude H of 1 °/h: divide by H)."""

    dwell_s: np.ndarray
    sigma: np.ndarray  # the full noise model
    white_sigma: np.ndarray  # angle random walk alone
    recommended_s: float


def recommended_dwell(noise: GyroNoise, rate_hz: float) -> DwellAdvice:
    """The dwell per position to recommend for four-position north finding.

    From the same noise model the simulator generates: where the correlated noise (bias
    instability, rate random walk, quantisation) has grown to half the white noise's variance
    in the heading, σ_full² = 1.5·σ_white²; beyond it a longer dwell pays off more slowly
    than 1/√T.  Within 5 s … 30 min (the longest dwell the lab allows when white noise
    always wins).  The threshold sits where σ_full²/σ_white² still rises steeply for every
    preset, so the crossing does not flip with small changes of a fitted B.  The heading σ
    scales as 1/H, so the choice does not depend on the latitude.  ("Where the ARW line
    meets 0.664·B" jumped with every estimate of B, and a Gauss–Markov bias has no such
    floor; this crossing of two smooth curves moves smoothly with the noise terms.)

    Parameters
    ----------
    noise : GyroNoise
        The gyro's noise terms.
    rate_hz : float
        Sample rate (Hz).

    Returns
    -------
    DwellAdvice
        The heading σ against dwell (s), with the full noise model and with white noise
    alone, and the recommended dwell (s).

    References
    ----------
    lab-reference §6; IEEE Std 952-1997, annex C.
    """
    dwell = np.geomspace(*DWELL_RANGE_S, 72)
    white_noise = GyroNoise(arw_deg_rt_h=noise.arw_deg_rt_h)
    sigma = np.array([four_position_sigma(noise, rate_hz, t, 1.0) for t in dwell])
    white = np.array([four_position_sigma(white_noise, rate_hz, t, 1.0) for t in dwell])
    crossing = np.flatnonzero(sigma**2 >= CORRELATED_SHARE * white**2)
    recommended = float(dwell[crossing[0]]) if crossing.size else DWELL_RANGE_S[1]
    return DwellAdvice(dwell, sigma, white, recommended)
