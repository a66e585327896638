"""What a warm gyro's readings look like under its noise model: one reading's variance,
the lag-1 correlation of consecutive readings, the variance of their mean, and the expected
sample variance of n readings typed to a step (:mod:`app.core.data_evidence` holds readings
to these).

E[s²] = n/(n − 1)·(σ₁² − σ²_mean) (+ u²/12 for a typed step u coarser than the gyro's own),
σ₁² and σ²_mean from :meth:`app.core.noise_model.GyroNoise.mean_covariance`.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np

from app.core.noise_model import GyroNoise, Window


@lru_cache(maxsize=1024)
def reading_moments(noise: GyroNoise, rate_hz: float, count: int) -> tuple[float, float, float]:
    """The model's moments of ``count`` consecutive readings from a warm gyro.

    Parameters
    ----------
    noise : GyroNoise
        The gyro's noise terms.
    rate_hz : float
        Readings per second.
    count : int
        How many readings.

    Returns
    -------
    tuple of float
        σ₁² (one reading's variance, (°/h)²), ρ₁ = Cov(x_i, x_i+1)/σ₁², and σ²_mean (the
        variance of their mean), from :meth:`GyroNoise.mean_covariance` of one-sample
        windows and of the whole record.
    """
    dt = 1.0 / rate_hz
    pair = noise.mean_covariance([Window(0.0, dt), Window(dt, dt)], warm_up=False)
    whole = noise.mean_covariance([Window(0.0, count * dt)], warm_up=False)
    one = float(pair[0, 0])
    rho = float(pair[0, 1]) / one if one > 0 else 0.0
    return one, rho, float(whole[0, 0])


def expected_variance(noise: GyroNoise, rate_hz: float, count: int, step: float | None) -> float:
    """The expected sample variance of ``count`` readings.

    Parameters
    ----------
    noise : GyroNoise
        The gyro's noise terms.
    rate_hz : float
        Readings per second.
    count : int
        How many readings (≥ 2).
    step : float or None
        The step they were typed to.

    Returns
    -------
    float
        E[s²] = n/(n − 1)·(σ₁² − σ²_mean), plus u²/12 when the typed step u is coarser
        than the gyro's own output step (module docstring).
    """
    one, _rho, mean = reading_moments(noise, rate_hz, count)
    variance = count / (count - 1) * max(one - mean, 0.0)
    own_step = 3600.0 * noise.angle_lsb_deg * rate_hz
    if step is not None and step > 1.5 * own_step:
        variance += step * step / 12.0
    return variance


def readings_rate_hz(times: Sequence[np.ndarray | None] | None, rate_hz: float) -> float:
    """The rate at which a part's readings were averaged: their times' typical step where
    every position has times and that step is shorter than the gyro's (a device sampling
    faster than the characterisation's record: each reading's noise is that of its own
    short average, √(f/f₀) times the gyro's per-reading noise for white noise), else the
    gyro's rate -- as a position's σ takes its span (:func:`app.lab.results.recorded_seconds`).

    Parameters
    ----------
    times : sequence of numpy.ndarray or None, optional
        Each position's reading times (s), None where the readings came without.
    rate_hz : float
        The station's gyro's readings per second.

    Returns
    -------
    float
        Readings per second: ``max(rate_hz, 1/step)`` for timed readings, else ``rate_hz``.
    """
    if not times or any(t is None for t in times):
        return rate_hz
    steps = [np.diff(np.asarray(t, float)) for t in times if np.asarray(t).size >= 2]
    steps = [step for step in steps if step.size]
    if not steps:
        return rate_hz
    typical = float(np.median(np.concatenate(steps)))
    return max(rate_hz, 1.0 / typical) if typical > 0 else rate_hz
