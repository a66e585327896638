"""Gyro noise that GyroLab did not generate, for testing its estimators.

Written independently of ``app.core.simulate`` and ``app.core.flicker``: the flicker noise
here is Kasdin & Walter's fractional integration (Proc. IEEE Freq. Control Symp. 1992;
Kasdin, Proc. IEEE 83 (1995) 802), not a sum of Gauss–Markov processes, and each term has
its closed-form Allan variance (IEEE Std 952-1997, annex C), τ in seconds, rates in °/h:

* white rate noise, N (°/√h): per-sample σ = 60·N/√Δt, σ²_A = (60N)²/τ;
* flicker rate noise, B (°/h): white noise of σ = B put through (1 − z⁻¹)^(−1/2), whose
  one-sided spectrum is S(f) ≈ B²/(πf) at low f, so σ²_A = 2 ln2·B²/π = (0.664·B)²;
* rate random walk, K (°/h/√h): a cumulative sum of steps of σ = K·√(Δt/3600),
  σ²_A = K²·τ/(3·3600);
* quantisation of the angle to ``lsb`` (°): σ²_A = (3600·lsb)²/(4τ²) for τ ≫ Δt.
"""

from __future__ import annotations

import math

import numpy as np


def kasdin_flicker(count: int, sigma: float, rng: np.random.Generator) -> np.ndarray:
    """Flicker (1/f) noise by fractional integration of white noise of std ``sigma``."""
    coefficients = np.empty(count)
    coefficients[0] = 1.0
    for k in range(1, count):  # h_k = h_(k−1)·(α/2 + k − 1)/k with α = 1
        coefficients[k] = coefficients[k - 1] * (0.5 + k - 1) / k
    white = rng.standard_normal(count) * sigma
    size = 1 << (2 * count - 1).bit_length()
    spectrum = np.fft.rfft(coefficients, size) * np.fft.rfft(white, size)
    return np.fft.irfft(spectrum, size)[:count]


def static_record(
    hours: float,
    rate_hz: float,
    *,
    arw: float = 0.0,
    flicker: float = 0.0,
    rrw: float = 0.0,
    lsb_deg: float = 0.0,
    seed: int = 0,
    bias: float = 10.0,
) -> np.ndarray:
    """A static gyro record (°/h) with the chosen terms, independent of GyroLab's simulator."""
    rng = np.random.default_rng(seed)
    count = int(round(hours * 3600.0 * rate_hz))
    dt = 1.0 / rate_hz
    rate = np.full(count, bias)
    if arw:
        rate = rate + rng.standard_normal(count) * 60.0 * arw / math.sqrt(dt)
    if flicker:
        rate = rate + kasdin_flicker(count, flicker, rng)
    if rrw:
        rate = rate + np.cumsum(rng.standard_normal(count)) * rrw * math.sqrt(dt / 3600.0)
    if lsb_deg:
        angle = np.concatenate([[0.0], np.cumsum(rate * dt / 3600.0)])
        counts = np.diff(np.floor(angle / lsb_deg))
        rate = counts * lsb_deg * 3600.0 / dt
    return rate


def closed_form_adev(
    taus_s: np.ndarray, *, arw: float = 0.0, flicker: float = 0.0, rrw: float = 0.0
) -> np.ndarray:
    """σ_A(τ) (°/h) of :func:`static_record`'s terms (quantisation left out)."""
    taus = np.asarray(taus_s, dtype=float)
    variance = (60.0 * arw) ** 2 / taus
    variance = variance + 2.0 * math.log(2.0) / math.pi * flicker**2
    variance = variance + rrw**2 * taus / (3.0 * 3600.0)
    return np.sqrt(variance)
