"""The gyro noise model against independent numbers: closed forms of the Allan variance,
the simulator's own samples (Monte Carlo of window means), and the coverage of the
reported 1σ under every FOG preset's correlated noise."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from app.core.gyro_stream import GyroStream
from app.core.noise_model import GyroNoise, Window, back_to_back
from app.core.presets import PRESETS

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
    gm = GyroNoise(markov_sigma_deg_h=0.05, markov_corr_time_s=100.0)
    taus = np.geomspace(10, 2000, 400)
    adev = np.sqrt([gm.allan_variance(t) for t in taus])
    # a Gauss–Markov bias: its Allan deviation peaks at 0.6178·σ near τ = 1.89·T
    assert adev.max() == pytest.approx(0.6178 * 0.05, rel=2e-3)
    assert taus[adev.argmax()] == pytest.approx(189.0, rel=0.03)
    # bias instability as flicker noise: the flat floor 0.664·B over decades of τ
    flicker = GyroNoise(bias_instability_deg_h=0.05)
    floor = np.sqrt(flicker.allan_variance(np.geomspace(10.0, 1e4, 30)))
    assert floor == pytest.approx(np.full(30, 0.664 * 0.05), rel=0.05)


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
    model = GyroNoise.from_preset(preset).mean_covariance(
        back_to_back([count] * 4, rate),
        warm_up=False,  # the deterministic warm-up is no scatter
    )
    # variances within the Monte Carlo's own scatter (√(2/3000) ≈ 2.6 %, so 4σ ≈ 10 %)
    assert np.diag(empirical) == pytest.approx(np.diag(model), rel=0.10)
    # differences of means (what the heading uses): the same, correlations included
    contrast = np.array([1.0, 0.0, -1.0, 0.0])
    assert contrast @ empirical @ contrast == pytest.approx(contrast @ model @ contrast, rel=0.10)


@pytest.mark.parametrize(("name", "dwell"), [("teaching-fog", 300.0), ("tactical-fog", 60.0)])
def test_the_noise_model_sigma_covers_68_percent(name, dwell):
    """Seeded Monte Carlo of the simulator (600 runs): the white-noise σ under-covers, the
    noise model's does not -- for the handout's gyro and the lab's live preset here;
    bench/bench_coverage.py runs 1000 for every preset and dwell (the navigation FOG's
    ≈ 10 s here went to keep the suite under five minutes)."""
    from bench.bench_coverage import coverage

    # warm after ten warm-up time constants (e^-10 of the warm-up bias left), not the
    # bench's hour: each run simulates its history since switch-on, and the tactical FOG's
    # hour of it (19 flicker components at 10 Hz) was 60 % of this test's 17 s
    warm_s = 10.0 * PRESETS[name].warmup_time_constant_s
    result = coverage(name, dwell, runs=600, cold=False, warm_s=warm_s)
    assert result.solved == 600
    assert 0.64 <= result.model <= 0.72, result
    assert result.white < result.model


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_allan_fit_recovers_each_presets_terms_with_quantisation_on(name):
    """Five 24 h static records of the full preset (quantisation and all, after warm-up):
    N within 5 % on average; B, where the record resolves it, within 25 %; no rate random
    walk where the preset has none.  The full table, 100 records per preset:
    bench/README.md (bench/bench_allan_fit.py)."""
    from app.core.allan import allan_deviation

    # a characterisation record is taken after warm-up: the warm-up transient is not noise
    preset = replace(PRESETS[name], turn_on_bias_sigma_deg_h=0.0).without("warmup")
    count = int(24 * 3600 * preset.sample_rate_hz)
    ratios_n, ratios_b = [], []
    for seed in range(5):
        record = GyroStream(preset, seed).read(np.full(count, 10.0))
        result = allan_deviation(record, preset.sample_rate_hz)
        ratios_n.append(result.arw_deg_rt_h / preset.arw_deg_rt_h)
        if result.bias_instability_deg_h is not None:
            ratios_b.append(result.bias_instability_deg_h / preset.bias_instability_deg_h)
        if not preset.rrw_deg_h_rt_h:
            assert not result.terms["rrw"].resolved
    assert np.mean(ratios_n) == pytest.approx(1.0, abs=0.05)
    assert all(abs(r - 1.0) <= 0.25 for r in ratios_b), ratios_b


@pytest.mark.parametrize("corr_time_s", [0.5, 10.0, 1.0e3, 1.0e5, 3.0e7])
def test_exponential_covariance_of_two_windows_to_double_precision(corr_time_s):
    """∫∫ e^(−|s−u|/T) ds du over two windows against the closed form in 60-digit decimal
    arithmetic: the four-exponential sum cancelled to 0.3 % at T = 3e7 s; the product form
    is exact to rounding at every T (the flicker band reaches 1e5 s)."""
    from decimal import Decimal, localcontext

    from app.core.noise_model import _exponential_mean_products

    def reference(first: Window, second: Window, t: float) -> float:
        with localcontext() as context:
            context.prec = 60
            a1, b1, a2, b2, big_t = (
                Decimal(first.start_s),
                Decimal(first.end_s),
                Decimal(second.start_s),
                Decimal(second.end_s),
                Decimal(t),
            )

            def e(x):
                return (-x / big_t).exp()

            return float(big_t * big_t * (e(a2 - b1) - e(a2 - a1) - e(b2 - b1) + e(b2 - a1)))

    for first, second in [
        (Window(100.0, 60.0), Window(170.0, 60.0)),
        (Window(0.0, 5.0), Window(5.0, 5.0)),  # touching
        (Window(10.0, 7.0), Window(17.0, 1000.0)),
        (Window(3.0, 0.5), Window(10.0, 2.0)),
    ]:
        expected = reference(first, second, corr_time_s)
        for pair in ((first, second), (second, first)):
            got = float(_exponential_mean_products(*pair, np.array([corr_time_s]))[0])
            assert got == pytest.approx(expected, rel=1e-13)
