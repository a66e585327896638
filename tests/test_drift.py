"""A linear bias drift during the schedule (lab-reference §3): what it does to the orders
1-2-3-4, 1-3-2-4 and 1-2-3-4-4-3-2-1, and the drift fit when the times are known."""

from __future__ import annotations

import io
import json
import math
import sys
from dataclasses import replace

import numpy as np
import pytest

from app.cli.main import main
from app.core.long_readings import readings_to_long_csv
from app.core.presets import PRESETS
from app.core.simulate import Setup, simulate_run
from app.core.solve import solve_heading

DRIFT = 2.0  # °/h per hour
DWELL = 300.0  # s per position
LATITUDE = 40.0
GYRO = replace(PRESETS["tactical-fog"].ideal(), drift_deg_h_per_h=DRIFT, sample_rate_hz=1.0)
H = 15.041 * math.cos(math.radians(LATITUDE))
ORDERS = {
    "1234": [0.0, -90.0, -180.0, -270.0],
    "1324": [0.0, -180.0, -90.0, -270.0],
    "12344321": [0.0, -90.0, -180.0, -270.0, -270.0, -180.0, -90.0, 0.0],
}


def run(order: str, azimuth: float, *, with_times: bool):
    angles = ORDERS[order]
    simulated = simulate_run(GYRO, Setup(LATITUDE, azimuth), "heading", angles, DWELL, seed=1)
    times = simulated.times_s if with_times else None
    return solve_heading(simulated.positions, angles, true_azimuth_deg=azimuth, times_s=times)


@pytest.mark.parametrize("azimuth", [10.0, 100.0, 235.0, 330.0])
def test_order_1234_is_biased_as_the_closed_form_says(azimuth):
    """ω_i = H cos A_i + b + ḃ·t_i with t_i = (i−1)·T: x = H cos A − ḃT, y = H sin A − ḃT,
    so δA ≈ ḃ·T·(sin A − cos A)/H (rad) to first order."""
    result = run("1234", azimuth, with_times=False)
    a = math.radians(azimuth)
    expected = math.degrees(DRIFT * DWELL / 3600.0 * (math.sin(a) - math.cos(a)) / H)
    assert result.azimuth_error_deg == pytest.approx(expected, rel=0.05, abs=2e-4)


def test_order_1324_and_the_symmetric_order():
    """1-3-2-4 takes less of the drift than 1-2-3-4 in the worst case; the symmetric
    order 1-2-3-4-4-3-2-1 cancels a linear drift even without fitting it."""
    azimuths = np.linspace(0.0, 350.0, 36)
    worst = {
        order: max(abs(run(order, float(a), with_times=False).azimuth_error_deg) for a in azimuths)
        for order in ORDERS
    }
    assert worst["1324"] < worst["1234"]
    assert worst["12344321"] < 0.01 * worst["1234"]


def test_the_drift_is_fitted_when_times_are_known():
    result = run("12344321", 60.0, with_times=True)
    assert result.fit.drift == pytest.approx(DRIFT, rel=1e-3)
    assert abs(result.azimuth_error_deg) < 1e-3
    assert result.to_json()["drift_deg_h_per_h"] == pytest.approx(DRIFT, rel=1e-3)
    # four positions cannot separate a drift from the heading: no drift term then
    assert run("1234", 60.0, with_times=True).fit.drift is None


def test_the_command_line_fits_the_drift_of_a_timed_schedule(capsys):
    drifting = replace(PRESETS["tactical-fog"], drift_deg_h_per_h=3.0)
    simulated = simulate_run(
        drifting,
        Setup(LATITUDE, 30.0),
        "heading",
        ORDERS["12344321"],
        120.0,
        seed=2,
        start_s=3600.0,  # warm: the drift is the only slow change
    )
    text = readings_to_long_csv(simulated.positions, ORDERS["12344321"], simulated.times_s)
    sys.stdin = io.StringIO(text)
    try:
        assert main(["solve", "heading", "-", "--json", "--true-azimuth", "30"]) == 0
    finally:
        sys.stdin = sys.__stdin__
    result = json.loads(capsys.readouterr().out)
    assert result["drift_deg_h_per_h"] == pytest.approx(
        3.0, abs=4 * result["drift_sigma_deg_h_per_h"]
    )
    assert abs(result["azimuth_error_deg"]) < 4 * result["azimuth_sigma_deg"]
