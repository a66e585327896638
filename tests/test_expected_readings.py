"""The draw of the station's gyro shown beside a group's readings: checked against closed
forms of white noise and of an exponentially correlated bias averaged over each reading,
and against the scatter check's own expectation (a different computation)."""

from __future__ import annotations

import math

import numpy as np

from app.core.expected_readings import MAX_READINGS, expected_readings
from app.core.noise_model import GyroNoise
from app.core.presets import PRESETS
from app.core.reading_moments import expected_variance


def draws(noise: GyroNoise, rate_hz: float, count: int, runs: int) -> np.ndarray:
    return np.array(
        [expected_readings(noise, rate_hz, [count], None, seed)[0] for seed in range(runs)]
    )


def test_white_noise_readings_have_the_closed_form_sigma():
    # N = 0.01 °/√h at 10 Hz: σ = 60·N·√f = 1.897 °/h, uncorrelated
    records = draws(GyroNoise(arw_deg_rt_h=0.01), 10.0, 25, 800)
    sigma = 60 * 0.01 * math.sqrt(10.0)
    assert abs(records.std() / sigma - 1) < 0.03
    lag = np.mean(records[:, 1:] * records[:, :-1]) / records.var()
    assert abs(lag) < 0.03


def test_a_correlated_bias_averaged_over_each_reading_has_its_closed_form():
    # Cov(t) = s²·e^(−|t|/τ) averaged over windows of T = 1/f:
    # Var = 2s²τ²/T²·(T/τ − 1 + e^(−T/τ)),  Cov(adjacent) = s²τ²/T²·(1 − e^(−T/τ))²
    s, tau, rate = 0.5, 0.3, 10.0
    noise = GyroNoise(markov_sigma_deg_h=s, markov_corr_time_s=tau)
    records = draws(noise, rate, 12, 3000)
    big_t = 1 / rate
    variance = 2 * s * s * tau * tau / big_t**2 * (big_t / tau - 1 + math.exp(-big_t / tau))
    adjacent = s * s * tau * tau / big_t**2 * (1 - math.exp(-big_t / tau)) ** 2
    assert abs(np.mean(records[:, 0] ** 2) / variance - 1) < 0.06
    assert abs(np.mean(records[:, 0] * records[:, 1]) / adjacent - 1) < 0.08


def test_the_draws_scatter_is_what_the_scatter_check_expects():
    preset = PRESETS["teaching-fog"]
    noise, rate = GyroNoise.from_preset(preset), preset.sample_rate_hz
    records = draws(noise, rate, 30, 600)
    s2 = records.var(axis=1, ddof=1).mean()
    assert abs(s2 / expected_variance(noise, rate, 30, None) - 1) < 0.06


def test_draws_are_rounded_capped_and_repeatable():
    noise = GyroNoise(arw_deg_rt_h=0.01)
    first = expected_readings(noise, 10.0, [12, 500, 0], 0.1, seed=7)
    again = expected_readings(noise, 10.0, [12, 500, 0], 0.1, seed=7)
    assert [a.size for a in first] == [12, MAX_READINGS, 0]
    assert all(np.array_equal(a, b) for a, b in zip(first, again, strict=True))
    levels = first[0] / 0.1
    assert np.allclose(levels, np.round(levels))
