"""A gyro's noise model (IEEE Std 952 terms) and what it means for position means.

When the noise model is known -- the simulator's preset, or a gyro characterised by its
Allan deviation -- the uncertainty of each position mean no longer has to be guessed from
the readings' scatter (which assumes white noise and is over-confident for correlated
noise: bias instability, rate random walk).  Here the covariance of the position means is
computed from the model, windows of the recording schedule given (lab-reference §3, §5).

Terms, with continuous-time covariances of the rate (°/h):

* angle random walk N (°/√h): white, spectral density (60·N)² (°/h)²·s;
* bias instability B (°/h): flicker (1/f) noise, the sum of Gauss–Markov components of
  :mod:`app.core.flicker` (equal variances v, correlation times T_j log-spaced over the
  band), autocovariance Σ_j v·e^(−|Δ|/T_j) -- an Allan floor 0.664·B over the band;
* a correlated bias where one is known (a data sheet's correlation time, or a fit that
  found the Gauss–Markov bump): variance σ_m², correlation time T_m;
* rate random walk K (°/h/√h): Brownian, Cov(r(s), r(t)) = (K²/3600)·min(s, t) with s, t
  in seconds from switch-on;
* angle quantisation q (°): the rate is the difference of an angle rounded to q, so a
  window mean is off by (e_end − e_start)·3600/L with e uniform: variance 2·(q²/12)·3600²/L²,
  and adjacent windows share an end;
* a rate ramp R (°/h²), where an Allan fit resolved one: a bias that drifts as R·t, its
  sign unknown (a slope of variance R²), so window means centred at c_i (h) share
  R²·(c_i − c̄)(c_j − c̄) -- the origin c̄ is the windows' mean centre, and any other adds
  only a common bias, which every difference of means (the heading) cancels.

Allan variance of the same model (used by the dwell advice and printed by the CLI):

    σ²_A(τ) = (60N)²/τ + (3600·q)²/(4τ²) + Σ_j v_j·g(τ/T_j) + (K²/3600)·τ/3 + R²·τ_h²/2
    g(x) = (2/x)·[1 − (3 − 4e^(−x) + e^(−2x))/(2x)]             (IEEE 952, annex C)

the sum running over the flicker components and the Gauss–Markov bias, τ_h = τ/3600
(IEEE Std 952-1997, annex C: C.1–C.6).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from app.core.flicker import (
    DEFAULT_BAND_S,
    flicker_components,
    gauss_markov_avar,
    sinusoid_avar,
)
from app.core.presets import GyroPreset

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
    """The noise terms of one gyro and the indexing σ of its turntable.

    ``bias_instability_deg_h`` is the flicker floor B over ``flicker_band_s``;
    ``markov_sigma_deg_h`` and ``markov_corr_time_s`` a correlated (Gauss–Markov) bias;
    ``sine_amplitude_deg_h`` and ``sine_period_s`` a bias that swings periodically (the
    lab's air conditioning), of unknown phase; ``ramp_deg_h_per_h`` a rate ramp, of unknown
    sign (a long record's slow trend: the Allan fit's R)."""

    arw_deg_rt_h: float = 0.0
    bias_instability_deg_h: float = 0.0
    rrw_deg_h_rt_h: float = 0.0
    angle_lsb_deg: float = 0.0
    indexing_sigma_deg: float = 0.0
    flicker_band_s: tuple[float, float] = DEFAULT_BAND_S
    markov_sigma_deg_h: float = 0.0
    markov_corr_time_s: float = 0.0
    warmup_bias_deg_h: float = 0.0  # the warm-up: b_w·e^(−t/τ_w), b_w of this size
    warmup_time_constant_s: float = 0.0
    sine_amplitude_deg_h: float = 0.0  # a periodic bias: Ω0·sin(2πt/P + φ), φ unknown
    sine_period_s: float = 0.0
    ramp_deg_h_per_h: float = 0.0  # a rate ramp R (°/h²) of unknown sign

    @classmethod
    def from_preset(cls, preset: GyroPreset) -> GyroNoise:
        return cls(
            arw_deg_rt_h=preset.arw_deg_rt_h,
            bias_instability_deg_h=preset.bias_instability_deg_h,
            rrw_deg_h_rt_h=preset.rrw_deg_h_rt_h,
            angle_lsb_deg=preset.angle_lsb_deg,
            indexing_sigma_deg=preset.indexing_sigma_arcsec / 3600.0,
            flicker_band_s=preset.flicker_band_s,
            markov_sigma_deg_h=preset.markov_sigma_deg_h,
            markov_corr_time_s=preset.markov_corr_time_s,
            warmup_bias_deg_h=preset.warmup_bias_deg_h,
            warmup_time_constant_s=preset.warmup_time_constant_s,
        )

    def correlated_terms(self) -> list[tuple[float, float]]:
        """(variance (°/h)², correlation time s) of every exponentially correlated part:
        the flicker components and the Gauss–Markov bias."""
        terms = flicker_components(self.bias_instability_deg_h, self.flicker_band_s)
        if self.markov_sigma_deg_h > 0 and self.markov_corr_time_s > 0:
            terms.append((self.markov_sigma_deg_h**2, self.markov_corr_time_s))
        return terms

    @property
    def white_density(self) -> float:
        """(60·N)²: the white rate noise's two-sided density, (°/h)²·s."""
        return (60.0 * self.arw_deg_rt_h) ** 2

    @property
    def rrw_rate(self) -> float:
        """K²/3600: growth of the random walk's variance, (°/h)² per second."""
        return self.rrw_deg_h_rt_h**2 / SECONDS_PER_HOUR

    def allan_variance(self, tau_s) -> np.ndarray | float:
        """σ²_A(τ) in (°/h)² (see the module docstring); τ a number or an array."""
        tau = np.asarray(tau_s, dtype=float)
        total = self.white_density / tau
        total = total + (SECONDS_PER_HOUR * self.angle_lsb_deg) ** 2 / (4.0 * tau * tau)
        for variance, corr in self.correlated_terms():
            total = total + variance * gauss_markov_avar(tau, corr)
        total = total + self.rrw_rate * tau / 3.0
        if self.has_sinusoid:
            total = total + self.sine_amplitude_deg_h**2 * sinusoid_avar(tau, self.sine_period_s)
        total = total + (self.ramp_deg_h_per_h * tau / SECONDS_PER_HOUR) ** 2 / 2.0
        return float(total) if total.ndim == 0 else total

    @property
    def has_sinusoid(self) -> bool:
        return self.sine_amplitude_deg_h > 0 and self.sine_period_s > 0

    def sinusoid_cov(self, windows: Sequence[Window], continuous: bool = True) -> np.ndarray:
        """The periodic bias's share of :meth:`mean_covariance`.

        Ω0·sin(ωt + φ) with φ uniform has Cov(r(s), r(u)) = (Ω0²/2)·cos(ω(s − u)), so the
        means over windows i, j share (Ω0²/2)·Re(c_i·c̄_j), c = (e^(iωb) − e^(iωa))/(iωL)
        the mean of e^(iωt) over [a, b] of length L; separate recordings (not
        ``continuous``) share nothing, each its own φ."""
        if not self.has_sinusoid:
            return np.zeros((len(windows), len(windows)))
        omega = 2.0 * math.pi / self.sine_period_s
        c = np.array(
            [
                (np.exp(1j * omega * w.end_s) - np.exp(1j * omega * w.start_s))
                / (1j * omega * w.length_s)
                for w in windows
            ]
        )
        cov = 0.5 * self.sine_amplitude_deg_h**2 * np.real(np.outer(c, np.conj(c)))
        return cov if continuous else np.diag(np.diag(cov))

    def ramp_cov(self, windows: Sequence[Window]) -> np.ndarray:
        """The rate ramp's share of :meth:`mean_covariance` on one timeline:
        R²·(c_i − c̄)(c_j − c̄), c the windows' centres in hours and c̄ their mean (a slope
        of unknown sign; the origin adds only a bias common to every window)."""
        if not self.ramp_deg_h_per_h:
            return np.zeros((len(windows), len(windows)))
        centres = np.array([w.start_s + w.length_s / 2.0 for w in windows]) / SECONDS_PER_HOUR
        offsets = centres - centres.mean()
        return self.ramp_deg_h_per_h**2 * np.outer(offsets, offsets)

    def warm_up_profile(self, windows: Sequence[Window]) -> np.ndarray:
        """Each window's mean of e^(−t/τ_w), t from switch-on:
        (τ_w/L)·(e^(−a/τ_w) − e^(−(a+L)/τ_w)) for a window from a of length L."""
        tau = self.warmup_time_constant_s
        if tau <= 0 or not self.warmup_bias_deg_h:
            return np.zeros(len(windows))
        return np.array(
            [
                tau / w.length_s * (math.exp(-w.start_s / tau) - math.exp(-w.end_s / tau))
                for w in windows
            ]
        )

    def mean_covariance(
        self, windows: Sequence[Window], *, continuous: bool = True, warm_up: bool = True
    ) -> np.ndarray:
        """Covariance matrix of the rate's mean over each window, (°/h)².

        ``continuous``: one gyro running through every window (one timeline, times from
        switch-on); otherwise each window is a separate recording started afresh (no
        correlation between windows, random walk from zero, Gauss–Markov stationary).
        ``warm_up`` (on one timeline): the warm-up b_w·e^(−t/τ_w) is a bias of unknown
        size b_w ~ N(0, warmup_bias²) -- its sign and size differ from one switch-on to the
        next -- so the means share the rank-one term b²·g·gᵀ, g the windows'
        :meth:`warm_up_profile`: nothing once the gyro is warm, the honest uncertainty of a
        cold start."""
        count = len(windows)
        cov = np.zeros((count, count))
        quant = (SECONDS_PER_HOUR * self.angle_lsb_deg) ** 2 / 12.0
        terms = [(v, t) for v, t in self.correlated_terms() if t > 0]
        variances = np.array([v for v, _ in terms])
        corr_times = np.array([t for _, t in terms])
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
                if terms:
                    products = _exponential_mean_products(wi, wj, corr_times)
                    value += float(variances @ products) / (li * lj)
                if continuous:
                    value += self.rrw_rate * _brownian_integral(wi, wj) / (li * lj)
                elif i == j:
                    value += self.rrw_rate * li / 3.0  # a walk from zero at the start
                cov[i, j] = value
        cov = cov + self.sinusoid_cov(windows, continuous)
        if continuous:
            cov = cov + self.ramp_cov(windows)
        if continuous and warm_up:
            cov = cov + self.warm_up_cov(windows)
        return cov

    def warm_up_cov(self, windows: Sequence[Window]) -> np.ndarray:
        """The warm-up's share of :meth:`mean_covariance`: b²·g·gᵀ (zero once warm)."""
        profile = self.warm_up_profile(windows)
        return self.warmup_bias_deg_h**2 * np.outer(profile, profile)


def _exponential_mean_products(wi: Window, wj: Window, t: np.ndarray) -> np.ndarray:
    """∫∫ e^(−|s−u|/T) ds du over the two windows, for each correlation time T > 0 in ``t``.

    One window of length L: 2TL + 2T²·(e^(−L/T) − 1).  Windows [a1, b1] before [a2, b2]:
    T²·(e^(−(a2−b1)/T) − e^(−(a2−a1)/T) − e^(−(b2−b1)/T) + e^(−(b2−a1)/T)), computed as
    the equal T²·e^(−(a2−b1)/T)·(e^(−L1/T) − 1)·(e^(−L2/T) − 1): the four-term sum cancels
    for T ≫ L (1e-6 relative error for 0.5 s windows at T = 1e5 s), the product does not."""
    if wi is wj or (wi.start_s == wj.start_s and wi.length_s == wj.length_s):
        length = wi.length_s
        return 2.0 * t * length + 2.0 * t * t * np.expm1(-length / t)
    first, second = (wi, wj) if wi.start_s <= wj.start_s else (wj, wi)
    if first.end_s > second.start_s + 1e-9:
        raise ValueError("windows overlap")
    gap = max(second.start_s - first.end_s, 0.0)
    return (
        (t * t) * np.exp(-gap / t) * np.expm1(-first.length_s / t) * np.expm1(-second.length_s / t)
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
    cov = noise.mean_covariance(back_to_back([count] * 4, rate_hz), warm_up=False)  # warm
    variance = (FOUR_X @ cov @ FOUR_X + FOUR_Y @ cov @ FOUR_Y) / 2.0
    return math.degrees(math.sqrt(max(variance, 0.0)) / amplitude)
