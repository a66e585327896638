"""The simulator: geometry, each error term, reproducibility and chunking."""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from app.core.gyro_stream import GyroStream, turn_on_bias_deg_h
from app.core.presets import PRESETS
from app.core.simulate import (
    Setup,
    axis_vectors,
    indexing_errors,
    simulate_run,
    simulate_static,
    true_rate,
)
from app.core.sinusoid import heading_angles

OMEGA = 15.041


DATA = Path(__file__).resolve().parent / "data"  # the handout's tables


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


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_a_copy_reads_on_as_the_stream_would_and_apart_from_it(name):
    """A copy (kept gyro histories, app.lab.gyro_history) is the same state, not a shared
    one: it and the original each read what an untouched stream reads next, whichever
    reads first -- every noise source, the random walk and the quantiser's angle."""
    preset = replace(PRESETS[name], drift_deg_h_per_h=0.3, rrw_deg_h_rt_h=0.05)
    rates = np.linspace(-10, 10, 700)
    reference = GyroStream(preset, 4)
    reference.read(rates[:300], 0.5)
    expected = reference.read(rates[300:], 0.5)
    stream = GyroStream(preset, 4)
    stream.read(rates[:300], 0.5)
    twin = stream.copy()
    assert twin.samples_read == 300 and twin.preset is stream.preset
    assert np.array_equal(twin.read(rates[300:], 0.5), expected)  # the copy first
    assert np.array_equal(stream.read(rates[300:], 0.5), expected)  # the original unmoved
    assert np.array_equal(stream.copy().read(rates[:50]), twin.copy().read(rates[:50]))


def test_white_noise_level_matches_arw():
    preset = PRESETS["tactical-fog"].ideal()
    preset = replace(preset, arw_deg_rt_h=0.012)
    values = simulate_static(preset, Setup(40.0), 2000.0, seed=1)
    assert values.std(ddof=1) == pytest.approx(60 * 0.012 / math.sqrt(0.1), rel=0.03)


def test_teaching_preset_reads_like_the_handouts_tables():
    """lab-reference §5: after warm-up, ten readings (10 s apart) scatter by 0.06–0.12 °/h
    and step by 0.1 °/h, as the handout's tables do (their std per position: 0.06–0.12)."""
    handout = np.loadtxt(DATA / "handout_horizontal.csv", delimiter=",", skiprows=1)[:, 1:]
    assert handout.std(axis=0, ddof=1).min() > 0.05 and handout.std(axis=0, ddof=1).max() < 0.13
    preset = PRESETS["teaching-fog"]
    stream = GyroStream(preset, 2)
    stream.read(np.zeros(int(1800 * preset.sample_rate_hz)))  # half an hour of warm-up
    stds = []
    for _ in range(40):
        values = stream.read(np.full(10, 10.71))
        steps = np.unique(np.round(np.abs(np.diff(values)), 6))
        assert np.allclose(steps / 0.1, np.round(steps / 0.1), atol=1e-6)
        stds.append(values.std(ddof=1))
    assert 0.07 < np.median(stds) < 0.12


def test_warm_up_bias_decays_while_the_case_warms():
    """b_0·e^(−t/τ_w) after switch-on; the case temperature rises as ΔT(1 − e^(−t/τ_w))."""
    preset = replace(PRESETS["tactical-fog"].ideal(), warmup_bias_deg_h=1.0)
    preset = replace(preset, warmup_time_constant_s=300.0, warmup_temperature_rise_c=8.0)
    stream = GyroStream(preset, 0)
    temperatures = stream.temperatures_c(int(3600 * preset.sample_rate_hz))
    values = stream.read(np.zeros(int(3600 * preset.sample_rate_hz)))
    seconds = np.arange(values.size) / preset.sample_rate_hz
    assert np.allclose(values, np.exp(-seconds / 300.0), atol=1e-9)
    assert temperatures[0] == pytest.approx(20.0)
    assert temperatures[-1] == pytest.approx(28.0, abs=0.01)
    assert temperatures[3000] == pytest.approx(20.0 + 8.0 * (1 - math.exp(-1.0)))
    assert np.all(PRESETS["teaching-fog"].without("warmup").warmup_bias_deg_h == 0.0)


# Classes of gyro, best first; presets within a class may differ, across classes never.
TIERS = [["navigation-fog"], ["tactical-fog", "teaching-fog"], ["mems"]]
QUALITY_TERMS = (  # larger is worse
    "arw_deg_rt_h", "bias_instability_deg_h", "rrw_deg_h_rt_h", "angle_lsb_deg",
    "scale_factor_ppm", "turn_on_bias_sigma_deg_h", "g_sensitivity_deg_h_per_g",
    "indexing_sigma_arcsec", "dial_resolution_deg", "table_tilt_sigma_deg",
    "misalignment_sigma_deg", "warmup_bias_deg_h",
)  # fmt: skip


def test_no_preset_is_better_than_a_better_class_in_any_term():
    assert sorted(name for tier in TIERS for name in tier) == sorted(PRESETS)
    for better_index, better in enumerate(TIERS):
        for worse in (name for tier in TIERS[better_index + 1 :] for name in tier):
            for good in better:
                for term in QUALITY_TERMS:
                    assert getattr(PRESETS[good], term) <= getattr(PRESETS[worse], term), (
                        f"{worse} beats {good} in {term}"
                    )


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
        markov_sigma_deg_h=1.0,
        markov_corr_time_s=5.0,
        sample_rate_hz=10.0,
    )
    values = GyroStream(preset, 3).read(np.zeros(200_000))
    assert values.std() == pytest.approx(1.0, rel=0.05)
    lag = int(5.0 * 10)
    correlation = np.corrcoef(values[:-lag], values[lag:])[0, 1]
    assert correlation == pytest.approx(math.exp(-1), abs=0.05)


def test_linear_drift():
    preset = replace(PRESETS["navigation-fog"].ideal(), drift_deg_h_per_h=2.0, sample_rate_hz=1.0)
    values = GyroStream(preset, 0).read(np.zeros(3601))
    assert values[-1] - values[0] == pytest.approx(2.0)


def test_mems_cannot_find_north_in_a_lab_period():
    """Consumer MEMS, warmed up (10 min before each stop): a 4 × 60 s heading is mostly
    refused or wrong by more than 10°."""
    from app.core.exceptions import UserError
    from app.core.solve import solve_heading

    bad = 0
    for seed in range(20):
        run = simulate_run(
            PRESETS["mems"],
            Setup(40.0, 30.0),
            "heading",
            heading_angles(4),
            60.0,
            seed=seed,
            settle_s=600.0,
        )
        try:
            result = solve_heading(run.positions, heading_angles(4), true_azimuth_deg=30.0)
        except UserError:
            bad += 1
            continue
        bad += abs(result.azimuth_error_deg) > 10
    assert bad >= 12


@pytest.mark.parametrize("name", sorted(PRESETS))
def test_the_turn_on_bias_is_the_streams_without_building_it(name):
    """The lab page asks for the session's turn-on bias on every view: drawn from the
    stream's own seed, it is the stream's value exactly, and it varies with the seed."""
    preset = PRESETS[name]
    draws = [turn_on_bias_deg_h(preset, seed) for seed in range(40)]
    assert draws == [GyroStream(preset, seed).turn_on_bias_deg_h for seed in range(40)]
    if preset.turn_on_bias_sigma_deg_h:
        assert np.std(draws) == pytest.approx(preset.turn_on_bias_sigma_deg_h, rel=0.4)
