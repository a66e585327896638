"""The gyro noise model against independent numbers: closed forms of the Allan variance,
the simulator's own samples (Monte Carlo of window means), and the coverage of the
reported 1σ under every FOG preset's correlated noise."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from app.core.noise_model import GyroNoise, Window, back_to_back
from app.core.presets import PRESETS
from app.core.simulate import GyroStream

pytestmark = pytest.mark.slow


def test_allan_variance_of_each_term_in_closed_form():
    white = GyroNoise(arw_deg_rt_h=0.05)
    # σ_A(τ) = N/√τ with N in °/√h and τ in hours
    assert math.sqrt(white.allan_variance(3600.0)) == pytest.approx(0.05)
    rrw = GyroNoise(rrw_deg_h_rt_h=0.3)
    # σ_A(τ) = K·√(τ/3), τ in hours
    assert math.sqrt(rrw.allan_variance(3 * 3600.0)) == pytest.approx(0.3)
    quant = GyroNoise(angle_lsb_deg=1e-4)
    # σ_A(τ) = √3·Q/τ with Q = q/√12 (the angle's rounding noise), in °/h
    q = 1e-4 / math.sqrt(12) * 3600
    assert math.sqrt(quant.allan_variance(10.0)) == pytest.approx(math.sqrt(3) * q / 10)
    gm = GyroNoise(bias_instability_deg_h=0.05, bias_corr_time_s=100.0)
    taus = np.geomspace(10, 2000, 400)
    adev = np.sqrt([gm.allan_variance(t) for t in taus])
    # the simulator's calibration: a Gauss–Markov peak of 0.664·B near τ = 1.89·T
    assert adev.max() == pytest.approx(0.664 * 0.05, rel=2e-3)
    assert taus[adev.argmax()] == pytest.approx(189.0, rel=0.03)


def test_single_window_variance_equals_the_allan_variance_for_white_noise():
    noise = GyroNoise(arw_deg_rt_h=0.012)
    [[variance]] = noise.mean_covariance([Window(0.0, 60.0)])
    assert variance == pytest.approx(noise.allan_variance(60.0))


@pytest.mark.parametrize("name", ["teaching-fog", "tactical-fog", "navigation-fog"])
def test_window_covariance_matches_the_simulator(name):
    """Four back-to-back 60 s windows of a static gyro, 3000 seeded runs of the simulator:
    the empirical covariance of the window means against the model's."""
    preset = replace(PRESETS[name], turn_on_bias_sigma_deg_h=0.0, scale_factor_ppm=0.0)
    rate, per_window, runs = preset.sample_rate_hz, 60, 3000
    count = int(per_window * rate)
    means = np.empty((runs, 4))
    for run in range(runs):
        samples = GyroStream(preset, seed=run).read(np.full(4 * count, 7.0))
        means[run] = samples.reshape(4, count).mean(axis=1)
    empirical = np.cov(means, rowvar=False)
    model = GyroNoise.from_preset(preset).mean_covariance(back_to_back([count] * 4, rate))
    # variances within the Monte Carlo's own scatter (√(2/3000) ≈ 2.6 %, so 4σ ≈ 10 %)
    assert np.diag(empirical) == pytest.approx(np.diag(model), rel=0.10)
    # differences of means (what the heading uses): the same, correlations included
    contrast = np.array([1.0, 0.0, -1.0, 0.0])
    assert contrast @ empirical @ contrast == pytest.approx(contrast @ model @ contrast, rel=0.10)


@pytest.mark.parametrize(
    ("name", "dwell"),
    [("teaching-fog", 300.0), ("tactical-fog", 60.0), ("navigation-fog", 1800.0)],
)
def test_the_noise_model_sigma_covers_68_percent(name, dwell):
    """Seeded Monte Carlo of the simulator (600 runs; bench/bench_coverage.py runs 1000 for
    every preset and dwell): the white-noise σ under-covers, the noise model's does not."""
    from bench.bench_coverage import coverage

    result = coverage(name, dwell, runs=600)
    assert result.solved == 600
    assert 0.64 <= result.model <= 0.72, result
    assert result.white < result.model


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_allan_fit_recovers_n_and_b_with_quantisation_on(name):
    """Twenty 6 h static records of the full preset (quantisation and all, after warm-up):
    the joint fit of Q, N, B, K, weighted by each τ's degrees of freedom and reweighted by
    the model, recovers N within 5 % and B within 10 % on average (N from the −½ slope
    alone read the old teaching gyro's N 10.7 % high and its B 22 % low; weights from the
    measured σ² read B 14 % low when its hump dominates).  One record scatters by its own
    statistics: see the bootstrap intervals' test."""
    from app.core.allan import allan_deviation

    # a characterisation record is taken after warm-up: the warm-up transient is not noise
    preset = replace(PRESETS[name], turn_on_bias_sigma_deg_h=0.0).without("warmup")
    count = int(6 * 3600 * preset.sample_rate_hz)
    ratios_n, ratios_b = [], []
    for seed in range(20):
        record = GyroStream(preset, seed).read(np.full(count, 10.0))
        result = allan_deviation(record, preset.sample_rate_hz)
        ratios_n.append(result.arw_deg_rt_h / preset.arw_deg_rt_h)
        ratios_b.append((result.bias_instability_deg_h or 0.0) / preset.bias_instability_deg_h)
    assert np.mean(ratios_n) == pytest.approx(1.0, abs=0.05)
    assert np.mean(ratios_b) == pytest.approx(1.0, abs=0.10)


def test_bootstrap_intervals_cover_n_and_b_about_as_often_as_they_say():
    """30 records of the teaching gyro, 20 bootstrap replicates each: the 68 % intervals
    cover the true N and B in 45–90 % of records (30 records: ±8.5 % per σ).  The full
    table, 60 records per preset, is in bench/README.md (bench_allan_fit.py)."""
    from app.core.allan import allan_deviation
    from app.core.allan_intervals import fit_intervals

    preset = replace(PRESETS["teaching-fog"], turn_on_bias_sigma_deg_h=0.0).without("warmup")
    count = int(6 * 3600 * preset.sample_rate_hz)
    hits_n = hits_b = 0
    for seed in range(30):
        record = GyroStream(preset, 500 + seed).read(np.full(count, 10.0))
        result = allan_deviation(record, preset.sample_rate_hz)
        ranges = fit_intervals(result, preset.sample_rate_hz, count, replicates=20, seed=seed)
        low, high = ranges.arw_deg_rt_h
        hits_n += low <= preset.arw_deg_rt_h <= high
        low, high = ranges.bias_instability_deg_h or (0.0, 0.0)
        hits_b += low <= preset.bias_instability_deg_h <= high
        assert ranges.arw_deg_rt_h[0] < result.arw_deg_rt_h < ranges.arw_deg_rt_h[1]
    assert 0.45 <= hits_n / 30 <= 0.90
    assert 0.45 <= hits_b / 30 <= 0.90
