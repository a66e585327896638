"""The simulator: geometry, each error term, reproducibility and chunking."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from app.core.simulate import (
    PRESETS,
    GyroStream,
    Setup,
    axis_vectors,
    indexing_errors,
    simulate_run,
    simulate_static,
    true_rate,
)
from app.core.solve import heading_angles

OMEGA = 15.041


def test_earth_rate_projection_closed_forms():
    phi = 39.93
    north = axis_vectors(0.0, 0.0, 0.0)
    up = axis_vectors(0.0, 0.0, 90.0)
    east = axis_vectors(0.0, 90.0, 0.0)
    assert true_rate(phi, north) == pytest.approx(OMEGA * math.cos(math.radians(phi)))
    assert true_rate(phi, up) == pytest.approx(OMEGA * math.sin(math.radians(phi)))
    assert true_rate(phi, east) == pytest.approx(0.0, abs=1e-12)
    # axis elevated 30° at azimuth A: Ω cosφ cos30 cosA + Ω sinφ sin30
    vector = axis_vectors(25.0, 0.0, 30.0)
    expected = OMEGA * (
        math.cos(math.radians(phi)) * math.cos(math.radians(30)) * math.cos(math.radians(25))
        + math.sin(math.radians(phi)) * 0.5
    )
    assert true_rate(phi, vector) == pytest.approx(expected)


def test_tilt_geometry():
    # pitching the table up by p raises the reference direction by p
    vector = axis_vectors(0.0, 0.0, 0.0, pitch_deg=5.0)
    assert math.degrees(math.asin(vector[2])) == pytest.approx(5.0)
    # rolling right side down lowers the direction 90° clockwise of the reference
    vector = axis_vectors(0.0, 90.0, 0.0, roll_deg=5.0)
    assert math.degrees(math.asin(vector[2])) == pytest.approx(-5.0)
    assert np.linalg.norm(axis_vectors(33.0, 71.0, 12.0, 3.0, -4.0)) == pytest.approx(1.0)


def test_ideal_gyro_reads_the_true_rate():
    preset = PRESETS["teaching-fog"].ideal()
    run = simulate_run(preset, Setup(40.0, 30.0), "heading", heading_angles(4), 5.0)
    expected = [
        OMEGA * math.cos(math.radians(40)) * math.cos(math.radians(30 - 90 * i)) for i in range(4)
    ]
    assert [p.mean() for p in run.positions] == pytest.approx(expected, abs=1e-9)


def test_same_seed_same_run_and_different_seed_different_run():
    preset = PRESETS["tactical-fog"]
    a = simulate_run(preset, Setup(40, 10), "heading", heading_angles(4), 3.0, seed=5)
    b = simulate_run(preset, Setup(40, 10), "heading", heading_angles(4), 3.0, seed=5)
    c = simulate_run(preset, Setup(40, 10), "heading", heading_angles(4), 3.0, seed=6)
    assert all(np.array_equal(x, y) for x, y in zip(a.positions, b.positions, strict=True))
    assert not np.array_equal(a.positions[0], c.positions[0])


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_any_chunking_gives_identical_samples(name):
    preset = replace(PRESETS[name], drift_deg_h_per_h=0.3)
    rates = np.linspace(-10, 10, 2000)
    whole = GyroStream(preset, 11).read(rates, 0.5)
    stream = GyroStream(preset, 11)
    cuts = [0, 1, 2, 57, 1000, 1001, 2000]
    pieces = [stream.read(rates[lo:hi], 0.5) for lo, hi in zip(cuts, cuts[1:], strict=False)]
    assert np.array_equal(whole, np.concatenate(pieces))


def test_white_noise_level_matches_arw():
    preset = PRESETS["tactical-fog"].ideal()
    preset = replace(preset, arw_deg_rt_h=0.012)
    values = simulate_static(preset, Setup(40.0), 2000.0, seed=1)
    assert values.std(ddof=1) == pytest.approx(60 * 0.012 / math.sqrt(0.1), rel=0.03)


def test_quantisation_gives_handout_like_steps():
    preset = PRESETS["teaching-fog"]
    values = simulate_static(preset, Setup(39.93), 300.0, seed=2)
    steps = np.unique(np.round(np.abs(np.diff(values)), 6))
    assert np.allclose(steps / 0.1, np.round(steps / 0.1), atol=1e-6)
    assert 0.05 < values.std(ddof=1) < 0.2  # ≈0.1 °/h scatter as in the handout


def test_scale_factor_and_constant_bias():
    preset = replace(
        PRESETS["navigation-fog"].ideal(), scale_factor_ppm=1000.0, constant_bias_deg_h=2.5
    )
    values = simulate_static(preset, Setup(0.0), 10.0)
    assert values.mean() == pytest.approx(OMEGA * 1.001 + 2.5)


def test_turn_on_bias_is_random_per_run_and_recorded():
    preset = PRESETS["teaching-fog"].ideal()
    preset = replace(preset, turn_on_bias_sigma_deg_h=1.0)
    biases = [GyroStream(preset, seed).turn_on_bias_deg_h for seed in range(400)]
    assert abs(np.mean(biases)) < 0.15 and np.std(biases) == pytest.approx(1.0, rel=0.12)
    run = simulate_run(preset, Setup(0.0, 90.0), "heading", [0.0, 180.0, 90.0], 2.0, seed=3)
    assert run.positions[0].mean() == pytest.approx(run.turn_on_bias_deg_h, abs=1e-9)


def test_g_sensitivity_up_versus_down():
    preset = replace(PRESETS["navigation-fog"].ideal(), g_sensitivity_deg_h_per_g=0.5)
    run = simulate_run(preset, Setup(0.0), "latitude", [90.0, 270.0], 1.0)
    assert run.positions[0].mean() - run.positions[1].mean() == pytest.approx(1.0)


def test_indexing_errors_are_per_stop_and_reproducible():
    preset = replace(PRESETS["teaching-fog"], indexing_sigma_arcsec=36.0)
    errors = np.concatenate([indexing_errors(preset, seed, 4)[1:] for seed in range(300)])
    assert indexing_errors(preset, 4, 4)[0] == 0.0
    assert errors.std() * 3600 == pytest.approx(36.0, rel=0.1)
    assert np.array_equal(indexing_errors(preset, 9, 4), indexing_errors(preset, 9, 4))


def test_dial_reads_to_its_resolution():
    preset = replace(
        PRESETS["teaching-fog"].ideal(), indexing_sigma_arcsec=600.0, dial_resolution_deg=0.5
    )
    run = simulate_run(preset, Setup(40.0), "heading", heading_angles(4), 1.0, seed=2)
    assert all(abs(d / 0.5 - round(d / 0.5)) < 1e-9 for d in run.dial_angles_deg)
    assert run.true_angles_deg != run.dial_angles_deg


def test_rate_random_walk_grows_like_sqrt_time():
    preset = replace(PRESETS["navigation-fog"].ideal(), rrw_deg_h_rt_h=1.0, sample_rate_hz=1.0)
    ends = np.array([GyroStream(preset, seed).read(np.zeros(3600))[-1] for seed in range(300)])
    assert ends.std() == pytest.approx(1.0, rel=0.12)  # K·√(1 h)


def test_gauss_markov_is_stationary_with_its_sigma():
    preset = replace(
        PRESETS["navigation-fog"].ideal(),
        bias_instability_deg_h=1.0,
        bias_corr_time_s=5.0,
        sample_rate_hz=10.0,
    )
    values = GyroStream(preset, 3).read(np.zeros(200_000))
    assert values.std() == pytest.approx(0.664 / 0.6178, rel=0.05)
    lag = int(5.0 * 10)
    correlation = np.corrcoef(values[:-lag], values[lag:])[0, 1]
    assert correlation == pytest.approx(math.exp(-1), abs=0.05)


def test_linear_drift():
    preset = replace(PRESETS["navigation-fog"].ideal(), drift_deg_h_per_h=2.0, sample_rate_hz=1.0)
    values = GyroStream(preset, 0).read(np.zeros(3601))
    assert values[-1] - values[0] == pytest.approx(2.0)


def test_mems_cannot_find_north_in_a_lab_period():
    """Consumer MEMS: a 4 × 60 s heading is either refused or wrong by tens of degrees."""
    from app.core.exceptions import GyroInputError
    from app.core.solve import solve_heading

    bad = 0
    for seed in range(20):
        run = simulate_run(
            PRESETS["mems"], Setup(40.0, 30.0), "heading", heading_angles(4), 60.0, seed=seed
        )
        try:
            result = solve_heading(run.positions, heading_angles(4), true_azimuth_deg=30.0)
        except GyroInputError:
            bad += 1
            continue
        bad += abs(result.azimuth_error_deg) > 10
    assert bad >= 12
