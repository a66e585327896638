"""The tilt paper's two-axis north seeker against the paper's figures and an independent
geometry (the simulator's rotations, with pitch and roll read from 'accelerometers')."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from app.cli.main import main
from app.core.error_analysis import ErrorSources, first_order
from app.core.error_monte_carlo import monte_carlo_heading_errors
from app.core.presets import PRESETS
from app.core.simulate import axis_vectors, earth_rate_vector
from app.core.two_axis_seeker import (
    body_rates,
    indexing_error_first_order,
    solve_seeker,
    turned_reading,
)
from app.explore.scenarios import SCENARIOS, heading_error_curves, scenario_input

DELTA = 0.25  # 15′
FINE = np.arange(0.25, 360.0, 0.5)

# the paper's figures as quoted in lab-reference §4: error/(δ/2), min and max over azimuth
PAPER = {(0.0, 0.0): (1.0, 1.0), (5.0, -5.0): (0.78, 1.21), (-10.0, 10.0): (0.55, 1.39),
         (20.0, 20.0): (0.07, 1.70)}  # fmt: skip


def _nonlinear_errors(pitch, roll, azimuths=FINE, delta=DELTA, latitude=60.0):
    body = body_rates(azimuths, latitude, pitch, roll)
    turned = turned_reading(body, delta)
    found = [
        solve_seeker(
            tuple(body[i, :2]), tuple(turned[i]), pitch_deg=pitch, roll_deg=roll,
            latitude_deg=latitude,
        ).azimuth_deg
        for i in range(len(azimuths))
    ]  # fmt: skip
    return (np.asarray(found) - azimuths + 180.0) % 360.0 - 180.0


@pytest.mark.parametrize("tilt", list(PAPER))
def test_indexing_error_matches_the_papers_figures(tilt):
    ratio = _nonlinear_errors(*tilt) / (DELTA / 2)
    low, high = PAPER[tilt]
    assert ratio.min() == pytest.approx(low, abs=0.01)
    assert ratio.max() == pytest.approx(high, abs=0.01)
    first = indexing_error_first_order(
        DELTA, FINE, latitude_deg=60.0, pitch_deg=tilt[0], roll_deg=tilt[1]
    ) / (DELTA / 2)
    assert np.max(np.abs(first - ratio)) < 0.01  # first order is the paper's small-δ formula


def test_level_table_gives_exactly_half_the_indexing_error_with_its_sign():
    for delta in (0.25, -0.1):
        errors = _nonlinear_errors(0.0, 0.0, delta=delta)
        assert np.allclose(errors, delta / 2, atol=1e-6)


def test_solver_undoes_tilt_given_by_an_independent_rotation_and_accelerometers():
    """Body axes from the simulator's yaw-pitch-roll (not the seeker's matrices); pitch and
    roll recovered as the paper's accelerometers would: a_x = g sin θ, a_y = g cos θ sin γ."""
    rng = np.random.default_rng(5)
    omega = earth_rate_vector(37.0)
    for _ in range(200):
        yaw, pitch, roll = rng.uniform(0, 360), rng.uniform(-25, 25), rng.uniform(-25, 25)
        forward = axis_vectors(yaw, 0.0, 0.0, pitch, roll)
        left = axis_vectors(yaw, -90.0, 0.0, pitch, roll)
        theta = math.degrees(math.asin(forward[2]))
        gamma = math.degrees(math.asin(left[2] / math.cos(math.radians(theta))))
        rates = (float(forward @ omega), float(left @ omega))
        opposite = (-rates[0] + 0.3, -rates[1] - 0.2)  # same constant drift at both stops
        shifted = (rates[0] + 0.3, rates[1] - 0.2)
        found = solve_seeker(
            shifted, opposite, pitch_deg=theta, roll_deg=gamma, latitude_deg=37.0
        ).azimuth_deg
        assert (found - yaw + 180) % 360 - 180 == pytest.approx(0.0, abs=1e-9)


def test_monte_carlo_with_noise_scatters_around_the_first_order_curve():
    sources = ErrorSources(indexing_deg=DELTA, pitch_deg=-10.0, roll_deg=10.0)
    azimuths = np.array([45.0, 135.0, 225.0, 315.0])
    curve = monte_carlo_heading_errors(
        "seeker", PRESETS["navigation-fog"], sources, azimuths, latitude_deg=60.0,
        runs=30, dwell_s=60.0, seed=3,
    )  # fmt: skip
    expected = first_order("seeker", sources, azimuths, 60.0)
    standard_error = curve.std_error_deg / math.sqrt(30)
    assert np.all(np.abs(curve.mean_error_deg - expected) < 4 * standard_error + 1e-4)
    assert np.all(curve.std_error_deg > 0)


def test_explorer_tilt_presets_use_the_papers_instrument_and_match_its_figures():
    presets = {"indexing-level": (0.0, 0.0), "indexing-tilt-5": (5.0, -5.0),
               "indexing-tilt-10": (-10.0, 10.0), "indexing-tilt-20": (20.0, 20.0)}  # fmt: skip
    for name, tilt in presets.items():
        assert SCENARIOS[name]["method"] == "seeker"
        (curve,), _ = heading_error_curves(scenario_input(name))
        formula = np.array(curve.formula_deg) / (DELTA / 2)
        low, high = PAPER[tilt]
        assert formula.min() == pytest.approx(low, abs=0.02)
        assert formula.max() == pytest.approx(high, abs=0.02)
        simulated = np.array(curve.mc_mean_deg) / (DELTA / 2)
        assert low - 0.02 <= simulated.min() and simulated.max() <= high + 0.02


def test_single_axis_contrast_is_labelled_and_diverges_near_north_and_south():
    params = scenario_input("indexing-tilt-5-single-axis")
    assert params.method == "two"
    (curve,), _ = heading_error_curves(params)
    ratio = np.array([v if v is not None else np.nan for v in curve.formula_deg]) / (DELTA / 2)
    assert np.nanmax(np.abs(ratio)) > 3  # several times δ/2, unlike the seeker
    near_north = np.abs(np.array(curve.azimuths_deg) - 2.0) < 1e-9
    assert abs(ratio[near_north][0]) > 2


def test_errors_command_lists_and_prints_every_scenario(capsys):
    assert main(["errors", "--list"]) == 0
    listed = capsys.readouterr().out.split("\n")
    assert {line.split()[0] for line in listed if line} == set(SCENARIOS)
    assert main(["errors", "--scenario", "indexing-tilt-10", "--json"]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["parameters"]["pitch_deg"] == -10.0
    (seeker,) = report["methods"]
    ratio = np.array(seeker["first_order_error_deg"]) / (DELTA / 2)
    assert ratio.min() > 0.54 and ratio.max() < 1.40
    assert main(["errors", "--scenario", "four-east-tilt", "--method", "four"]) == 0
    text = capsys.readouterr().out
    assert "method four" in text and "+0.83910" in text  # tan 40° · 1° in degrees
    assert main(["errors"]) == 2
    assert "--list" in capsys.readouterr().err
