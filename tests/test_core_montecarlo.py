"""Monte Carlo validation with the simulator: uncertainty, Allan read-outs, seed formulas."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from app.core.allan import allan_deviation
from app.core.error_analysis import (
    ErrorSources,
    four_position_first_order,
    two_position_first_order,
)
from app.core.error_monte_carlo import monte_carlo_heading_errors
from app.core.flicker import gauss_markov_avar
from app.core.noise_model import GyroNoise
from app.core.presets import PRESETS
from app.core.simulate import Setup, simulate_run, simulate_static
from app.core.sinusoid import heading_angles
from app.core.solve import solve_heading

pytestmark = pytest.mark.slow
LATITUDE = 39.93
RUNS = 2000


@pytest.fixture(scope="module")
def white_runs():
    """2000 simulated four-position runs of a white-noise gyro at random azimuths."""
    preset = replace(PRESETS["tactical-fog"].ideal(), arw_deg_rt_h=0.05, sample_rate_hz=10.0)
    dwell, samples = 10.0, 100
    rng = np.random.default_rng(2026)
    azimuths = rng.uniform(0, 360, RUNS)
    angles = heading_angles(4, "ccw")
    errors, sigmas = np.empty(RUNS), np.empty(RUNS)
    for run, azimuth in enumerate(azimuths):
        simulated = simulate_run(
            preset, Setup(LATITUDE, float(azimuth)), "heading", angles, dwell, seed=run
        )
        result = solve_heading(simulated.positions, angles, true_azimuth_deg=float(azimuth))
        errors[run], sigmas[run] = result.azimuth_error_deg, result.azimuth_sigma_deg
    sigma_mean = preset.white_sigma_deg_h / math.sqrt(samples)
    amplitude = 15.041 * math.cos(math.radians(LATITUDE))
    return errors, sigmas, math.degrees(sigma_mean / (math.sqrt(2) * amplitude))


def test_heading_scatter_matches_sigma_over_root2_h(white_runs):
    errors, _, expected = white_runs
    assert abs(errors.mean()) < 4 * expected / math.sqrt(RUNS)
    assert errors.std(ddof=1) == pytest.approx(expected, rel=0.05)


def test_reported_one_sigma_covers_68_percent(white_runs):
    errors, sigmas, _ = white_runs
    coverage = np.mean(np.abs(errors) <= sigmas)
    assert 0.65 <= coverage <= 0.71


def test_expected_sigma_table_of_the_reference():
    """lab-reference §3: σ_A = 60·N/√T /(√2·H); tactical (0.05) at 60 s → 1.36°."""
    amplitude = 15.041 * math.cos(math.radians(LATITUDE))
    sigma = 60 * 0.05 / math.sqrt(60) / (math.sqrt(2) * amplitude)
    assert math.degrees(sigma) == pytest.approx(1.36, abs=0.01)


@pytest.mark.parametrize(("name", "hours"), [("teaching-fog", 24.0), ("mems", 2.0)])
def test_allan_returns_the_simulators_own_arw_and_b(name, hours):
    """The simulator's flicker bias instability reads back as B, its white noise as N."""
    preset = PRESETS[name].without("quantization", "rrw", "warmup")
    ratios_n, ratios_b = [], []
    for seed in range(3):
        record = simulate_static(preset, Setup(40.0), hours * 3600.0, seed=seed)
        result = allan_deviation(record, preset.sample_rate_hz)
        ratios_n.append(result.arw_deg_rt_h / preset.arw_deg_rt_h)
        ratios_b.append(result.bias_instability_deg_h / preset.bias_instability_deg_h)
        assert not result.terms["rrw"].resolved
    assert np.mean(ratios_n) == pytest.approx(1.0, abs=0.10)
    assert np.mean(ratios_b) == pytest.approx(1.0, abs=0.15)


def test_allan_white_noise_slope_and_gauss_markov_peak():
    preset = replace(PRESETS["tactical-fog"].ideal(), arw_deg_rt_h=0.1)
    result = allan_deviation(simulate_static(preset, Setup(40.0), 2000.0, seed=4), 10.0)
    slope = np.polyfit(np.log(result.taus_s[:8]), np.log(result.adev_deg_h[:8]), 1)[0]
    assert slope == pytest.approx(-0.5, abs=0.03)
    x = np.geomspace(0.1, 20, 2000)
    peak = np.sqrt(gauss_markov_avar(x, 1.0))
    assert peak.max() == pytest.approx(0.6178, abs=2e-3)
    assert x[np.argmax(peak)] == pytest.approx(1.89, rel=0.02)


def test_recommended_dwell_comes_from_the_fitted_noise_model():
    """The Allan read-out's advice is the noise model's minimum of the four-position heading
    σ, on the same dwell grid, inside the record's τ range."""
    from app.core.dwell_advice import recommended_dwell

    preset = PRESETS["mems"].without("quantization", "warmup")
    record = simulate_static(preset, Setup(40.0), 2 * 3600.0, seed=1)
    result = allan_deviation(record, preset.sample_rate_hz)
    span = (float(result.taus_s[0]), float(result.taus_s[-1]))
    advice = recommended_dwell(result.noise(), preset.sample_rate_hz, span, "record")
    assert result.recommended_dwell_s == advice.recommended_s
    assert span[0] <= result.recommended_dwell_s <= span[1]
    white = recommended_dwell(GyroNoise(arw_deg_rt_h=0.01), 10.0)
    assert white.recommended_s == 1800.0 and white.lower_bound  # white noise: longer is better
    assert np.allclose(white.sigma, white.white_sigma)


QUIET = replace(PRESETS["navigation-fog"].ideal(), arw_deg_rt_h=0.00005)
AZIMUTHS = np.array([30.0, 60.0, 120.0, 150.0, 210.0, 330.0])


def mc(method, sources, latitude=LATITUDE, runs=10):
    return monte_carlo_heading_errors(
        method, QUIET, sources, AZIMUTHS, latitude_deg=latitude, runs=runs, dwell_s=30.0
    )


def test_two_position_indexing_is_half_the_error():
    sources = ErrorSources(indexing_deg=0.2)
    curve = mc("two", sources)
    assert curve.mean_error_deg == pytest.approx(np.full(AZIMUTHS.size, 0.1), rel=0.05)


@pytest.mark.parametrize(
    "sources", [ErrorSources(scale_factor_ppm=2000.0), ErrorSources(latitude_error_deg=0.1)]
)
def test_two_position_cotangent_laws(sources):
    curve = mc("two", sources)
    formula = two_position_first_order(sources, AZIMUTHS, LATITUDE)
    assert curve.mean_error_deg == pytest.approx(formula, rel=0.05)
    # ∝ 1/tan γ, independently of the code: ΔK/K / tan γ in degrees
    if sources.scale_factor_ppm:
        hand = np.degrees(2000e-6 / np.tan(np.radians(AZIMUTHS)))
    else:
        hand = np.degrees(
            math.tan(math.radians(LATITUDE)) * math.radians(0.1) / np.tan(np.radians(AZIMUTHS))
        )
    assert formula == pytest.approx(hand, rel=1e-9)


def test_two_position_drift_law():
    sources = ErrorSources(drift_deg_h=0.05)
    curve = mc("two", sources)
    hand = np.degrees(
        -0.05 / (2 * 15.041 * math.cos(math.radians(LATITUDE)) * np.sin(np.radians(AZIMUTHS)))
    )
    assert curve.mean_error_deg == pytest.approx(hand, rel=0.05)


def test_four_position_east_tilt_gives_tan_phi_times_tilt():
    sources = ErrorSources(east_tilt_deg=0.5)
    curve = mc("four", sources)
    expected = math.tan(math.radians(LATITUDE)) * 0.5
    assert curve.mean_error_deg == pytest.approx(np.full(AZIMUTHS.size, expected), rel=0.05)
    one_degree = ErrorSources(east_tilt_deg=1.0)
    assert four_position_first_order(one_degree, [0.0], 40.0)[0] == pytest.approx(0.8391, abs=1e-3)


def test_four_position_cancels_bias_scale_factor_and_latitude():
    preset_with_bias = replace(QUIET, constant_bias_deg_h=50.0)
    curve = monte_carlo_heading_errors(
        "four",
        preset_with_bias,
        ErrorSources(scale_factor_ppm=5000.0, latitude_error_deg=1.0),
        AZIMUTHS,
        latitude_deg=LATITUDE,
        runs=5,
        dwell_s=30.0,
    )
    assert np.all(np.abs(curve.mean_error_deg) < 0.01)


@pytest.mark.parametrize(("stop", "shape"), [(2, np.cos), (3, np.sin), (4, np.cos)])
def test_four_position_indexing_on_one_stop(stop, shape):
    sources = ErrorSources(indexing_deg=0.4, indexing_stop=stop)
    curve = mc("four", sources, runs=4)
    expected = 0.2 * shape(np.radians(AZIMUTHS)) ** 2
    assert curve.mean_error_deg == pytest.approx(expected, abs=0.004)


def test_two_position_on_a_level_table_with_paper_tilts():
    """Papers (φ = 60°): level → δ/2; tilt 10° → ≈ δ/2 with ripple; 20° → larger spread."""
    delta = 0.5
    azimuths = np.arange(15.0, 360.0, 30.0)

    def errors(pitch, roll):
        sources = ErrorSources(indexing_deg=delta, pitch_deg=pitch, roll_deg=roll)
        # the papers' figures are noise-free first-order analyses: an ideal gyro here
        return monte_carlo_heading_errors(
            "two", QUIET.ideal(), sources, azimuths, latitude_deg=60.0, runs=1, dwell_s=10.0
        ).mean_error_deg

    level = errors(0, 0)
    assert level == pytest.approx(np.full(azimuths.size, delta / 2), rel=0.02)
    tilt5, tilt10, tilt20 = errors(5, -5), errors(-10, 10), errors(20, 20)
    assert np.mean(tilt10) == pytest.approx(delta / 2, rel=0.05)
    assert np.ptp(tilt10) > np.ptp(tilt5) > 0.02
    assert np.std(tilt20) > np.std(tilt10)
    formula = two_position_first_order(
        ErrorSources(indexing_deg=delta, pitch_deg=-10, roll_deg=10), azimuths, 60.0
    )
    assert tilt10 == pytest.approx(formula, abs=0.02)
