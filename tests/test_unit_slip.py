"""Readings saved in the wrong unit: the factor between what a fit measures and what Earth's
rotation gives names the unit they were recorded in (closed forms: 1 °/s = 3600 °/h,
1 rad/s = 3600·180/π °/h)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.core.solve import solve_heading
from app.core.units import unit_slip

EARTH = 15.041
RAD_S = 3600 * 180 / math.pi  # °/h in 1 rad/s


@pytest.mark.parametrize(
    ("measured", "chosen", "likely"),
    [
        (EARTH / 3600, "deg/h", "deg/s"),  # °/s typed, saved as °/h
        (EARTH / RAD_S, "deg/h", "rad/s"),  # rad/s typed, saved as °/h
        (EARTH * 3600 / RAD_S, "deg/s", "rad/s"),  # rad/s typed, saved as °/s (57.3× small)
        (EARTH * RAD_S / 3600, "rad/s", "deg/s"),  # °/s typed, saved as rad/s (57.3× large)
        (EARTH * 1.3 / 3600, "deg/h", "deg/s"),  # and with a 30 % error on top
    ],
)
def test_a_unit_slip_is_named(measured, chosen, likely):
    assert unit_slip(measured, EARTH, chosen) == likely


@pytest.mark.parametrize(
    "measured",
    [EARTH, EARTH * 0.5, EARTH * 3, EARTH / 30, EARTH / 10_000, 0.0, -1.0, math.nan, math.inf],
)
def test_no_slip_is_named_where_no_unit_explains_the_ratio(measured):
    assert unit_slip(measured, EARTH, "deg/h") is None


def test_an_independent_fit_of_degrees_per_second_saved_as_degrees_per_hour():
    """Four positions drawn here (not by the app's simulator): ω = Ω·cos φ·cos(ψ − θ) + b
    with white noise, written in °/s and saved as °/h; the fit's amplitude names °/s."""
    rng = np.random.default_rng(7)
    horizontal = EARTH * math.cos(math.radians(30.0))
    angles = [0.0, -90.0, -180.0, -270.0]
    positions = [
        (horizontal * math.cos(math.radians(a + 40.0)) + 2.0 + rng.normal(0, 0.05, 50)) / 3600
        for a in angles
    ]
    fit = solve_heading(positions, angles)
    assert unit_slip(fit.amplitude_deg_h, horizontal, "deg/h") == "deg/s"
    assert unit_slip(fit.amplitude_deg_h * 3600, horizontal, "deg/s") is None
