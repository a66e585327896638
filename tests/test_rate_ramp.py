"""A rate ramp (IEEE 952's R, °/h²) in the noise model: a long record's slow trend makes the
four-position heading worse the longer each position is read, so the dwell advice has a
best dwell inside the record, not "at least the record's longest τ".  Checked against
closed forms, records of the independent generator of ``tests.noise_sources`` with a ramp
added, and a Monte Carlo of the simulated gyro drifting by R through its runs."""

from __future__ import annotations

import io
import math
from dataclasses import replace

import allantools
import numpy as np
import pytest

from app.core.accuracy_plan import plan_point
from app.core.allan import allan_deviation
from app.core.noise_model import GyroNoise, Window, back_to_back, four_position_sigma
from tests.noise_sources import static_record

OMEGA, LATITUDE = 15.041, 39.93
RAMP = 0.2  # °/h per hour: a room warming through an afternoon
AMPLITUDE = OMEGA * math.cos(math.radians(LATITUDE))


def ramped_record(seed: int, ramp: float = RAMP) -> np.ndarray:
    """8 h at 5 Hz of white noise (0.005 °/√h) and a ramp of ``ramp`` °/h²."""
    rates = static_record(8.0, 5.0, arw=0.005, seed=seed)
    return rates + ramp * np.arange(rates.size) / 5.0 / 3600.0


def test_a_ramps_allan_variance_and_window_means_against_closed_forms():
    """σ²_A(τ) = R²τ_h²/2 (IEEE 952 C.6), as allantools computes it on a pure ramp; two
    adjacent means differ by R·τ_h; x = (ω1 − ω3)/2 and y = (ω2 − ω4)/2 move by R·T each,
    so σ_A = R·T_h/H (lab-reference §3: a linear drift biases the heading)."""
    ramp = GyroNoise(ramp_deg_h_per_h=RAMP)
    taus = np.array([10.0, 100.0, 1000.0])
    _, adev, _, _ = allantools.oadev(
        RAMP * np.arange(0.0, 10_000.0, 0.5) / 3600.0, rate=2.0, data_type="freq", taus=taus
    )
    assert ramp.allan_variance(taus) == pytest.approx(adev**2, rel=1e-6)
    [[v11, v12], [_, v22]] = ramp.mean_covariance([Window(0.0, 600.0), Window(600.0, 600.0)])
    assert v11 + v22 - 2 * v12 == pytest.approx((RAMP * 600.0 / 3600.0) ** 2)
    for dwell in (60.0, 600.0, 1800.0):
        expected = math.degrees(RAMP * dwell / 3600.0 / AMPLITUDE)
        assert four_position_sigma(ramp, 5.0, dwell, AMPLITUDE) == pytest.approx(expected)
    # separate recordings share no trend; the symmetric eight fits the drift and cancels it
    separate = ramp.mean_covariance(back_to_back([100] * 4, 1.0), continuous=False)
    assert not separate.any()
    four = plan_point(ramp, 5.0, 600.0, "1234", LATITUDE, OMEGA)
    eight = plan_point(ramp, 5.0, 600.0, "12344321", LATITUDE, OMEGA)
    assert eight.heading_sigma_deg < 1e-6 * four.heading_sigma_deg


@pytest.mark.parametrize("seed", [0, 2])
def test_a_resolved_ramp_gives_a_best_dwell_inside_the_record(seed):
    """Before, the advice left the ramp out: σ fell for ever, and an 8-hour record was told
    its best dwell was at least 13107 s -- where the ramp alone moves the heading by 3.6°."""
    from app.core.allan_summary import dwell_lines
    from app.web.i18n import translator

    result = allan_deviation(ramped_record(seed), 5.0)
    assert result.terms["rate_ramp"].resolved
    assert result.value("rate_ramp") == pytest.approx(RAMP, rel=0.1)
    advice = result.dwell
    assert not advice.lower_bound and not advice.levels_off
    # σ² ≈ (60N)²/(2T) + (R·T_h)² over H²: least at T = (60N·3600/R)^(2/3)/2^(1/3) ≈ 190 s
    closed_form = (60 * 0.005 * 3600 / RAMP) ** (2 / 3) / 2 ** (1 / 3)
    assert advice.recommended_s == pytest.approx(closed_form, rel=0.25)
    for language in ("en", "zh-CN"):
        said = " ".join(dwell_lines(advice.to_json(), translator(language)))
        assert f"{advice.recommended_s:.0f}" in said and "13107" not in said


def test_the_ramps_sigma_is_what_the_simulator_drifting_by_r_does():
    """200 four-position runs of a gyro drifting by R (the simulator's drift term, random
    azimuths, no indexing error) at a 10-minute dwell: the RMS heading error against the
    model with the ramp (within 15 %; 200 runs scatter by 5 %) -- without it the model
    says about half."""
    from app.core.presets import PRESETS
    from app.core.simulate import Setup, simulate_run
    from app.core.sinusoid import heading_angles
    from app.core.solve import solve_heading

    gyro = replace(
        PRESETS["tactical-fog"].without(
            "indexing", "dial", "warmup", "bias_instability", "quantization", "turn_on_bias"
        ),
        drift_deg_h_per_h=RAMP,
    )
    dwell, angles = 600.0, heading_angles(4, "ccw")
    rng = np.random.default_rng(5)
    errors = []
    for run, azimuth in enumerate(rng.uniform(0, 360, 200)):
        simulated = simulate_run(
            gyro, Setup(LATITUDE, float(azimuth)), "heading", angles, dwell, seed=run
        )
        result = solve_heading(simulated.positions, angles, true_azimuth_deg=float(azimuth))
        errors.append(result.azimuth_error_deg)
    rms = math.sqrt(np.mean(np.square(errors)))
    noise = GyroNoise(arw_deg_rt_h=gyro.arw_deg_rt_h, ramp_deg_h_per_h=RAMP)
    expected = four_position_sigma(noise, gyro.sample_rate_hz, dwell, AMPLITUDE)
    assert rms == pytest.approx(expected, rel=0.15)
    white = four_position_sigma(
        GyroNoise(arw_deg_rt_h=gyro.arw_deg_rt_h), gyro.sample_rate_hz, dwell, AMPLITUDE
    )
    assert white < 0.65 * rms


def test_a_characterised_gyro_keeps_its_ramp_and_the_planner_prefers_the_symmetric_eight():
    from app.core.accuracy_plan import accuracy_plan
    from app.courses.characterisation import characterise, station_noise, store
    from app.models import Assignment

    rates = ramped_record(0)
    text = "time_s,value\n" + "".join(f"{k / 5.0:.1f},{v:.5f}\n" for k, v in enumerate(rates))
    summary = characterise(io.BytesIO(text.encode()), None, None, None)
    assert summary["ramp_deg_h_per_h"] == pytest.approx(RAMP, rel=0.1)
    assignment = Assignment()
    store(assignment, summary)
    station = station_noise(assignment)
    assert station.noise.ramp_deg_h_per_h == summary["ramp_deg_h_per_h"]
    plan = accuracy_plan(station.noise, station.rate_hz, LATITUDE, OMEGA)
    four, eight = plan.at("1234", 1800.0), plan.at("12344321", 1800.0)
    assert eight.heading_sigma_deg < 0.2 * four.heading_sigma_deg
    # a characterisation stored before the ramp was kept reads as none
    del summary["ramp_deg_h_per_h"]
    store(assignment, summary)
    assert station_noise(assignment).noise.ramp_deg_h_per_h == 0.0
