"""The accuracy planner against numbers it did not make: the white-noise closed form, and
the spread of four-position fits over records from the tests' own noise generator (white
and Kasdin flicker noise, tests/noise_sources.py), cut into back-to-back positions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.core.accuracy_plan import accuracy_plan, plan_point
from app.core.noise_model import GyroNoise, four_position_sigma
from app.core.presets import PRESETS
from tests.noise_sources import static_record

OMEGA = 15.041


@pytest.mark.parametrize("latitude", [0.0, 39.9, 60.0])
def test_white_noise_closed_form(latitude):
    """σ_m = 60N/√T per position mean; a = (m1 − m3)/2 and c = (m2 − m4)/2 have variance
    σ_m²/2, so σ_A = σ_m/(√2·H), σ_φ = σ_m/(√2·Ω) and σ_Ω = σ_m/√2."""
    arw, dwell = 0.05, 60.0
    point = plan_point(GyroNoise(arw_deg_rt_h=arw), 10.0, dwell, "1234", latitude, OMEGA)
    sigma_m = 60.0 * arw / math.sqrt(dwell)
    amplitude = OMEGA * math.cos(math.radians(latitude))
    assert point.heading_sigma_deg == pytest.approx(
        math.degrees(sigma_m / math.sqrt(2) / amplitude), rel=1e-9
    )
    assert point.latitude_sigma_deg == pytest.approx(
        math.degrees(sigma_m / math.sqrt(2) / OMEGA), rel=1e-9
    )
    assert point.earth_rate_sigma_deg_h == pytest.approx(sigma_m / math.sqrt(2), rel=1e-9)
    assert point.total_s == 4 * dwell
    # the symmetric eight: each stop averaged twice, and its drift column (t − t̄) is
    # orthogonal to cos α and sin α, so it costs nothing: σ/√2 for twice the time
    eight = plan_point(GyroNoise(arw_deg_rt_h=arw), 10.0, dwell, "12344321", latitude, OMEGA)
    assert eight.heading_sigma_deg == pytest.approx(point.heading_sigma_deg / math.sqrt(2))
    assert eight.total_s == 8 * dwell


@pytest.mark.parametrize("name", ["teaching-fog", "tactical-fog", "navigation-fog"])
def test_the_four_position_heading_sigma_is_the_dwell_advices(name):
    preset = PRESETS[name]
    noise = GyroNoise.from_preset(preset)
    amplitude = OMEGA * math.cos(math.radians(30.0))
    for dwell in (20.0, 300.0):
        point = plan_point(noise, preset.sample_rate_hz, dwell, "1234", 30.0, OMEGA)
        expected = four_position_sigma(noise, preset.sample_rate_hz, dwell, amplitude)
        assert point.heading_sigma_deg == pytest.approx(expected, rel=1e-9)


def test_the_plan_matches_the_spread_of_fits_to_independent_white_and_flicker_noise():
    """600 four-position runs cut from records of the tests' generator (N = 0.02 °/√h,
    B = 0.2 °/h, 10 Hz, 120 s a position, so flicker noise is most of the scatter): the
    standard deviations of the fitted a and c against the plan's, within 12 % -- white
    noise alone would predict about half."""
    rate_hz, dwell, runs = 10.0, 120.0, 600
    count = int(dwell * rate_hz)
    fits = []
    for seed in range(3):
        record = static_record(
            runs / 3 * 4 * dwell / 3600.0, rate_hz, arw=0.02, flicker=0.2, seed=seed
        )
        means = record[: (record.size // count) * count].reshape(-1, count).mean(axis=1)
        for m1, m2, m3, m4 in means[: (means.size // 4) * 4].reshape(-1, 4):
            fits.append(((m1 - m3) / 2.0, (m2 - m4) / 2.0))
    a, c = np.array(fits).T
    noise = GyroNoise(arw_deg_rt_h=0.02, bias_instability_deg_h=0.2)
    point = plan_point(noise, rate_hz, dwell, "1234", 0.0, OMEGA)  # at φ = 0: σ_Ω² = v_a
    spread = math.sqrt((np.var(a, ddof=1) + np.var(c, ddof=1)) / 2.0)
    assert spread == pytest.approx(point.earth_rate_sigma_deg_h, rel=0.12)
    assert math.degrees(spread / OMEGA) == pytest.approx(point.heading_sigma_deg, rel=0.12)
    white = plan_point(GyroNoise(arw_deg_rt_h=0.02), rate_hz, dwell, "1234", 0.0, OMEGA)
    assert white.earth_rate_sigma_deg_h < 0.7 * spread


def test_the_plan_has_an_optimum_where_slow_noise_takes_over():
    """With rate random walk the heading σ falls, then rises: the best dwell lies inside."""
    noise = GyroNoise(arw_deg_rt_h=0.02, bias_instability_deg_h=0.01, rrw_deg_h_rt_h=0.5)
    plan = accuracy_plan(noise, 10.0, 39.9, OMEGA)
    best = plan.best["1234"]
    dwells = [p.dwell_s for p in plan.points if p.order == "1234"]
    assert dwells[0] < best.dwell_s < dwells[-1]
    assert plan.at("1234", 65.0).dwell_s == 60.0
    assert plan.to_json()["best"]["1234"]["dwell_s"] == best.dwell_s


def test_the_class_agreement_is_a_chi_square_range():
    """k = 30 standard normal errors agree; the same errors doubled are "larger", halved
    "smaller"; the range is √(χ²_k(2.5 %)/k) … √(χ²_k(97.5 %)/k) (k = 30: 0.685 … 1.279,
    from the tables of χ²_30: 16.791 and 46.979)."""
    from app.core.accuracy_plan import scatter_agreement

    rng = np.random.default_rng(5)
    sigmas = rng.uniform(0.1, 0.5, 30)
    errors = rng.standard_normal(30) * sigmas
    fair = scatter_agreement(errors, sigmas)
    assert fair.groups == 30 and fair.verdict == "agrees"
    assert fair.low == pytest.approx(math.sqrt(16.791 / 30), abs=1e-3)
    assert fair.high == pytest.approx(math.sqrt(46.979 / 30), abs=1e-3)
    assert scatter_agreement(2 * errors, sigmas).verdict == "larger"
    assert scatter_agreement(errors / 3, sigmas).verdict == "smaller"
    assert scatter_agreement(errors[:2], sigmas[:2]).verdict == "too_few"
    assert scatter_agreement(np.array([np.nan]), np.array([0.1])).groups == 0
