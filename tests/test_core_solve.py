"""The solver against independent numbers: the handout, closed forms and properties."""

from __future__ import annotations

import csv
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.stats import t as student_t

from app.core.exceptions import UserError
from app.core.handout_terms import percent_error
from app.core.sinusoid import elevation_angles, fit_sinusoid, heading_angles, wrap180
from app.core.solve import solve_heading, solve_latitude
from app.core.two_position import solve_two_position
from tests.factories import DATA, english

# The handout's raw tables (copied from shared/data so the suite runs anywhere).
PRINTED_HEADING = [10.71, 2.79, -8.95, -0.94]
PRINTED_VERTICAL = [11.14, 9.82, -11.82, -9.92]


def handout_table(name: str) -> list[list[float]]:
    with open(DATA / name) as handle:
        rows = list(csv.DictReader(handle))
    return [[float(row[f"position_{i}"]) for row in rows] for i in range(1, 5)]


def test_handout_heading_from_raw_tables():
    result = solve_heading(handout_table("handout_horizontal.csv"), heading_angles(4, "ccw"))
    assert result.theta_deg == pytest.approx(-10.753, abs=5e-4)
    assert result.azimuth_deg == pytest.approx(10.753, abs=5e-4)
    assert result.rotate_direction == "counterclockwise"
    assert result.then_axis_points == "north"
    # the handout's printed result agrees within ±0.05°
    assert abs(result.theta_deg - (-10.75)) <= 0.05


def test_handout_heading_from_printed_averages():
    result = solve_heading([[w] for w in PRINTED_HEADING], heading_angles(4, "ccw"))
    assert result.theta_deg == pytest.approx(-10.743, abs=5e-4)
    assert math.tan(math.radians(result.theta_deg)) == pytest.approx(
        (-0.94 - 2.79) / (10.71 + 8.95), rel=1e-12
    )
    # One value per position: the closure residual d is a one-degree-of-freedom estimate
    # of a position's noise; Student's t with 1 dof is Cauchy, whose 68.27 % half-width
    # is tan(π·0.34134) = 1.837, and four positions give σ_A = σ/(√2·H_c), with the
    # Rice-corrected amplitude H_c² = H² − σ²x − σ²y = H² − σ².
    w1, w2, w3, w4 = PRINTED_HEADING
    d = (w1 + w3 - w2 - w4) / 2
    sigma = math.tan(math.pi * 0.6826894921 / 2) * abs(d)
    amplitude = math.hypot((w1 - w3) / 2, (w2 - w4) / 2)
    corrected = math.sqrt(amplitude**2 - sigma**2)
    assert result.fit.uncertainty_model == "closure"
    assert result.azimuth_sigma_deg == pytest.approx(
        math.degrees(sigma / (math.sqrt(2) * corrected)), rel=1e-6
    )


def test_handout_latitude_from_raw_tables():
    result = solve_latitude(
        handout_table("handout_vertical.csv"),
        elevation_angles(4),
        true_latitude_deg=39.93,
        true_earth_rate_deg_h=15.04,
    )
    assert result.latitude_deg == pytest.approx(40.727, abs=5e-4)
    assert result.earth_rate_deg_h == pytest.approx(15.133, abs=5e-4)
    assert result.latitude_error_percent == pytest.approx(2.00, abs=5e-3)
    assert result.earth_rate_error_percent == pytest.approx(0.62, abs=5e-3)
    assert abs(result.latitude_deg - 40.71) <= 0.05
    assert abs(result.earth_rate_deg_h - 15.14) <= 0.05
    assert abs(result.latitude_error_percent - 1.95) <= 0.1
    assert abs(result.earth_rate_error_percent - 0.65) <= 0.1


def test_handout_latitude_from_printed_averages():
    result = solve_latitude(
        [[w] for w in PRINTED_VERTICAL],
        elevation_angles(4),
        true_latitude_deg=39.93,
        true_earth_rate_deg_h=15.04,
    )
    assert result.latitude_deg == pytest.approx(40.688, abs=1e-3)
    assert result.earth_rate_deg_h == pytest.approx(15.140, abs=5e-4)
    assert result.latitude_error_percent == pytest.approx(1.90, abs=5e-3)
    assert result.earth_rate_error_percent == pytest.approx(0.66, abs=5e-3)
    # the handout's other forms of Ω agree for exact four-position data
    phi = math.radians(result.latitude_deg)
    assert (11.14 + 11.82) / (2 * math.cos(phi)) == pytest.approx(15.140, abs=0.01)


def test_default_earth_rate_is_sidereal():
    result = solve_latitude([[w] for w in PRINTED_VERTICAL], elevation_angles(4))
    assert result.true_earth_rate_deg_h == 15.041
    assert result.latitude_error_percent is None


@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_least_squares_equals_closed_form(rotation):
    rng = np.random.default_rng(1)
    positions = [rng.normal(mean, 0.1, 20) for mean in rng.uniform(-12, 12, 4)]
    result = solve_heading(positions, heading_angles(4, rotation))
    w1, w2, w3, w4 = (p.mean() for p in positions)
    y = (w2 - w4) / 2 if rotation == "ccw" else (w4 - w2) / 2
    x = (w1 - w3) / 2
    assert result.azimuth_deg == pytest.approx(math.degrees(math.atan2(y, x)) % 360, abs=1e-9)
    assert result.amplitude_deg_h == pytest.approx(math.hypot(x, y), rel=1e-12)
    assert result.bias_deg_h == pytest.approx((w1 + w2 + w3 + w4) / 4, abs=1e-12)
    assert result.closure_residual_deg_h == pytest.approx((w1 + w3 - w2 - w4) / 2, abs=1e-12)
    # 20 readings: each standard error widened by Student's t with 19 dof (1σ-equivalent)
    k19 = student_t.ppf(0.5 + 0.6826894921 / 2, 19)
    assert k19 == pytest.approx(1.0270, abs=1e-4)
    sems = [k19 * p.std(ddof=1) / math.sqrt(p.size) for p in positions]
    sx2 = (sems[0] ** 2 + sems[2] ** 2) / 4
    sy2 = (sems[1] ** 2 + sems[3] ** 2) / 4
    corrected = math.sqrt(x * x + y * y - sx2 - sy2)  # the Rice-corrected amplitude
    expected = math.sqrt(y * y * sx2 + x * x * sy2) / (math.hypot(x, y) * corrected)
    assert result.azimuth_sigma_deg == pytest.approx(math.degrees(expected), rel=1e-9)


@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_the_bias_sigma_is_that_of_the_mean_of_four_means(rotation):
    """b = (m1 + m2 + m3 + m4)/4, so σ_b = √(σ1² + σ2² + σ3² + σ4²)/4 with each σi the
    Student-t-widened s_i/√n_i; the latitude part fits the same sinusoid."""
    rng = np.random.default_rng(3)
    positions = [
        rng.normal(mean, sd, n)
        for mean, sd, n in zip(
            [11.0, -0.3, -11.6, 0.2], [0.05, 0.2, 0.1, 0.4], [12, 20, 30, 15], strict=True
        )
    ]
    k = [student_t.ppf(0.5 + 0.6826894921 / 2, p.size - 1) for p in positions]
    sigmas = [ki * p.std(ddof=1) / math.sqrt(p.size) for ki, p in zip(k, positions, strict=True)]
    expected = math.sqrt(sum(s * s for s in sigmas)) / 4
    heading = solve_heading(positions, heading_angles(4, rotation))
    latitude = solve_latitude(positions, elevation_angles(4))
    assert heading.bias_sigma_deg_h == pytest.approx(expected, rel=1e-9)
    assert latitude.bias_sigma_deg_h == pytest.approx(expected, rel=1e-9)
    assert heading.to_json()["bias_sigma_deg_h"] == heading.bias_sigma_deg_h


def test_the_bias_sigma_matches_the_spread_of_b_over_repeated_runs():
    """Monte Carlo of the whole solve (white noise, 30 readings a position): the standard
    deviation of b over 2,000 runs against the mean of the σ_b each run reports."""
    rng = np.random.default_rng(11)
    means = np.array([11.5, 0.4, -11.5, -0.4]) + 0.8
    biases, sigmas = [], []
    for _ in range(2000):
        positions = [rng.normal(m, 0.3, 30) for m in means]
        result = solve_heading(positions, heading_angles(4, "ccw"))
        biases.append(result.bias_deg_h)
        sigmas.append(result.bias_sigma_deg_h)
    spread = float(np.std(biases, ddof=1))
    assert spread == pytest.approx(0.3 / math.sqrt(30) / 2, rel=0.05)  # σ/√n over 2
    # Student-t widening (29 dof) makes each reported σ_b a little larger than the spread
    assert float(np.mean(sigmas)) == pytest.approx(spread, rel=0.06)


def test_latitude_closed_form():
    w = [11.14, 9.82, -11.82, -9.92]
    result = solve_latitude([[v, v] for v in w], elevation_angles(4))
    assert result.latitude_deg == pytest.approx(
        math.degrees(math.atan2(w[1] - w[3], w[0] - w[2])), abs=1e-12
    )
    assert result.earth_rate_deg_h == pytest.approx(math.hypot(w[0] - w[2], w[1] - w[3]) / 2)


def test_n_position_fit_with_uneven_angles_and_counts():
    angles = np.array([0.0, 47.0, 133.0, 201.0, 290.0])
    a_true, c_true, b_true = 3.0, -7.0, 0.5
    positions = [
        np.full(n, a_true * math.cos(math.radians(t)) + c_true * math.sin(math.radians(t)) + b_true)
        for t, n in zip(angles, [5, 9, 12, 7, 30], strict=True)
    ]
    fit = fit_sinusoid(positions, angles)
    assert (fit.a, fit.c, fit.b) == pytest.approx((a_true, c_true, b_true), abs=1e-10)


def heading_data(azimuth, amplitude, bias, rotation="ccw", start=0.0, noise_sigma=0.01):
    angles = heading_angles(4, rotation, start)
    rng = np.random.default_rng(7)
    noise = rng.normal(0, noise_sigma, (4, 5))
    return [
        amplitude * np.cos(np.radians(azimuth + angle - start)) + bias + noise[i]
        for i, angle in enumerate(angles)
    ], angles


@settings(max_examples=60, deadline=None)
@given(
    azimuth=st.floats(0, 359.99),
    bias=st.floats(-1000, 1000),
    scale=st.floats(0.01, 100),
    rotation=st.sampled_from(["ccw", "cw"]),
)
def test_bias_and_scale_do_not_move_the_azimuth(azimuth, bias, scale, rotation):
    positions, angles = heading_data(azimuth, 10.0, 0.0, rotation)
    base = solve_heading(positions, angles).azimuth_deg
    moved = solve_heading([scale * (p + bias) for p in positions], angles).azimuth_deg
    assert abs(wrap180(moved - base)) < 1e-6


@settings(max_examples=60, deadline=None)
@given(
    azimuth=st.floats(0, 359.99),
    shift=st.floats(-720, 720),
    rotation=st.sampled_from(["ccw", "cw"]),
)
def test_rotating_the_start_shifts_the_azimuth(azimuth, shift, rotation):
    positions, angles = heading_data(azimuth, 10.0, 2.0, rotation, noise_sigma=0.0)
    shifted, _ = heading_data(azimuth + shift, 10.0, 2.0, rotation, noise_sigma=0.0)
    first = solve_heading(positions, angles).azimuth_deg
    second = solve_heading(shifted, angles).azimuth_deg
    assert abs(wrap180(second - first - shift)) < 1e-6
    assert 0.0 <= second < 360.0


@settings(max_examples=40, deadline=None)
@given(azimuth=st.floats(0, 359.99), start=st.floats(-180, 180))
def test_measured_dial_angles_are_relative_to_position_one(azimuth, start):
    """A start offset on the dial does not change where position 1 points."""
    positions, angles = heading_data(azimuth, 10.0, 0.0, "ccw")
    with_offset = solve_heading(positions, angles + start).azimuth_deg
    assert abs(wrap180(with_offset - azimuth)) < 0.5


@pytest.mark.parametrize("azimuth", [5.0, 95.0, 185.0, 275.0, 359.0, 0.0, 90.0, 180.0, 270.0])
@pytest.mark.parametrize("rotation", ["ccw", "cw"])
def test_every_quadrant_and_the_turn_instruction(azimuth, rotation):
    positions, angles = heading_data(azimuth, 10.0, 1.0, rotation)
    result = solve_heading(positions, angles, true_azimuth_deg=azimuth)
    assert abs(result.azimuth_error_deg) < 0.2
    final = wrap180(azimuth + result.theta_deg)  # turning by θ, clockwise positive
    target = 0.0 if result.then_axis_points == "north" else 180.0
    assert abs(wrap180(final - target)) < 0.2
    assert -90.0 <= result.theta_deg <= 90.0
    assert result.rotate_deg == pytest.approx(abs(result.theta_deg))


def test_azimuth_error_wraps_around_north():
    positions, angles = heading_data(359.5, 10.0, 0.0)
    result = solve_heading(positions, angles, true_azimuth_deg=0.5)
    assert result.azimuth_error_deg == pytest.approx(-1.0, abs=0.05)


@pytest.mark.parametrize(
    ("positions", "angles", "key"),
    [
        ([[1.0], [2.0]], [0, 90], "readings.too_few_angles"),
        ([[1.0], [2.0], [3.0], [4.0]], [0, 360, 720, 90], "readings.too_few_angles"),
        ([[1.0], [], [3.0], [4.0]], [0, -90, -180, -270], "readings.empty_position"),
        ([[1.0], [float("nan")], [3.0], [4.0]], [0, -90, -180, -270], "readings.not_finite"),
        ([[1.0], [float("inf")], [3.0], [4.0]], [0, -90, -180, -270], "readings.not_finite"),
        ([[1.0], [2.0], [3.0]], [0, -90, -180, -270], "readings.angle_count"),
        (
            [[1.0, 1.0], [1.0, 1.0], [1.0, 1.0], [1.0, 1.0]],
            [0, -90, -180, -270],
            "readings.amplitude_too_small",
        ),
        ([["a"], [2.0], [3.0]], [0, 120, 240], "readings.not_numbers"),
    ],
)
def test_bad_input_raises_a_clear_error(positions, angles, key):
    with pytest.raises(UserError) as info:
        solve_heading(positions, angles)
    assert info.value.key == key
    assert english(info.value)[0].isupper() and english(info.value).endswith(".")


def test_amplitude_buried_in_noise_is_refused():
    rng = np.random.default_rng(3)
    positions = [
        rng.normal(0, 5.0, 10) + 0.5 * math.cos(math.radians(a)) for a in heading_angles(4)
    ]
    with pytest.raises(UserError) as caught:
        solve_heading(positions, heading_angles(4))
    assert "not clearly larger" in english(caught.value)


def test_latitude_outside_range_is_explained():
    w = [-11.14, -9.82, 11.82, 9.92]  # started pointing south
    with pytest.raises(UserError) as info:
        solve_latitude([[v] for v in w], elevation_angles(4))
    assert info.value.key == "readings.latitude_out_of_range"


def test_percent_error_definition():
    assert percent_error(40.71, 39.93) == pytest.approx(1.9534, abs=1e-4)
    assert percent_error(1.0, 0.0) is None and percent_error(1.0, None) is None


def test_two_position_method():
    omega, phi, k = 15.041, 40.0, 1.0
    for gamma in (30.0, 100.0, 150.0):
        h = k * omega * math.cos(math.radians(phi)) * math.cos(math.radians(gamma))
        result = solve_two_position(h + 3.0, -h + 3.0, latitude_deg=phi)
        assert result.gamma_deg == pytest.approx(gamma, abs=1e-9)
        assert result.candidates_deg == pytest.approx((gamma, 360 - gamma))
    with pytest.raises(UserError):
        solve_two_position(30.0, -30.0, latitude_deg=phi)
    clipped = solve_two_position(11.6, -11.6, latitude_deg=phi)
    assert clipped.clipped and clipped.gamma_deg == 0.0
