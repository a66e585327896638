"""The error-analysis explorer: formulas, Monte Carlo agreement, the papers' findings, HTTP."""

from __future__ import annotations

import csv
import io
import math

import numpy as np
import pytest

from app.explore.scenarios import ExplorerInput, dwell_curve, heading_error_curves, scenario_input


def curve_of(curves, method):
    return next(c for c in curves if c.method == method)


def at(curve, azimuth):
    return curve.formula_deg[curve.azimuths_deg.index(azimuth)]


def test_formula_curves_equal_hand_computed_values():
    params = ExplorerInput(
        method="both", latitude_deg=40.0, scale_factor_ppm=2000.0, noise=False, runs=1
    )
    curves, _ = heading_error_curves(params)
    two, four = curve_of(curves, "two"), curve_of(curves, "four")
    for azimuth in (30.0, 60.0, 120.0, 300.0):
        hand = math.degrees(2000e-6 / math.tan(math.radians(azimuth)))
        assert at(two, azimuth) == pytest.approx(hand, rel=1e-9)
        assert at(four, azimuth) == 0.0
    tilt, _ = heading_error_curves(
        ExplorerInput(method="four", latitude_deg=40.0, east_tilt_deg=1.0, noise=False)
    )
    assert at(tilt[0], 90.0) == pytest.approx(math.tan(math.radians(40.0)), rel=1e-9)  # 0.839°
    drift, _ = heading_error_curves(
        ExplorerInput(method="two", latitude_deg=40.0, drift_deg_h=0.05, noise=False)
    )
    hand = math.degrees(
        -0.05 / (2 * 15.041 * math.cos(math.radians(40.0)) * math.sin(math.radians(60.0)))
    )
    assert at(drift[0], 60.0) == pytest.approx(hand, rel=1e-9)


@pytest.mark.parametrize("name", ["scale-factor", "latitude-error", "four-east-tilt"])
def test_monte_carlo_points_agree_with_the_formulas_for_small_errors(name):
    curves, _ = heading_error_curves(scenario_input(name))
    for curve in curves:
        for azimuth, mean in zip(curve.mc_azimuths_deg, curve.mc_mean_deg, strict=True):
            if abs(math.sin(math.radians(azimuth))) < 0.3:
                continue  # the two-position laws diverge near north and south
            formula = np.interp(
                azimuth, curve.azimuths_deg, np.array(curve.formula_deg, dtype=float)
            )
            assert mean == pytest.approx(formula, abs=0.01 + 0.05 * abs(formula)), (name, azimuth)


def test_monte_carlo_with_noise_reports_its_spread():
    curves, info = heading_error_curves(scenario_input("noise"))
    assert info["runs"] == 10 and info["simulated_runs"] == 10 * 24 * 2
    two, four = curve_of(curves, "two"), curve_of(curves, "four")
    assert np.nanmedian(four.mc_std_deg) < np.nanmedian(two.mc_std_deg)
    assert all(s is not None and s > 0 for s in four.mc_std_deg)


def mc_errors(name):
    curves, _ = heading_error_curves(scenario_input(name))
    return np.array(curves[0].mc_mean_deg, dtype=float)


def test_the_papers_findings_as_numbers():
    delta = 900.0 / 3600 / 2  # δ/2 for δ = 15′
    level = mc_errors("indexing-level")
    assert np.all(np.abs(level - delta) <= 0.02 * delta)
    tilt5, tilt10, tilt20 = (mc_errors(f"indexing-tilt-{t}") for t in (5, 10, 20))
    assert np.mean(tilt10) == pytest.approx(delta, rel=0.05)
    assert np.ptp(tilt10) > np.ptp(tilt5)
    assert np.std(tilt20) > np.std(tilt10)


def test_dwell_curve_white_part_matches_the_reference_table():
    data = dwell_curve("tactical-fog", 39.93)
    sigma = np.array(data["sigma_deg"])
    assert np.all(np.diff(sigma[:40]) < 0)
    amplitude = 15.041 * math.cos(math.radians(39.93))
    # the reference's table: tactical (0.012 °/√h): 0.33° at 60 s (white noise only)
    white60 = 60 * 0.012 / math.sqrt(60) / (math.sqrt(2) * amplitude)
    assert np.interp(60, data["dwell_s"], data["white_only_deg"]) == pytest.approx(
        math.degrees(white60), rel=0.02
    )
    # the dashed line: the least σ within the lab's dwells.  White noise and a flicker floor
    # only: σ still falls at 30 min, so the best dwell is a lower bound, and the advice
    # gives the shortest dwell within 10 % of it (the same rule as the Allan read-out's)
    best = data["dwell_s"].index(data["best_dwell_s"])
    assert data["floor_deg"] == pytest.approx(sigma[best]) == pytest.approx(sigma.min())
    assert data["best_dwell_s"] == 1800.0 and data["lower_bound"]
    near = data["dwell_s"].index(data["near_best_s"])
    assert sigma[near] <= 1.1 * sigma.min() < sigma[near - 1]
    # with a rate random walk σ turns up again: a true optimum inside the range
    mems = dwell_curve("mems", 39.93)
    assert not mems["lower_bound"] and 5.0 < mems["best_dwell_s"] < 1800.0


@pytest.mark.slow
@pytest.mark.parametrize(("preset", "dwell"), [("tactical-fog", 1800.0), ("teaching-fog", 600.0)])
def test_dwell_curve_is_what_the_simulator_does(preset, dwell):
    """The curve against the simulator itself: the RMS heading error of 200 seeded
    four-position runs (indexing errors off: the curve is about the gyro's noise).  The old
    curve's flat 0.664·B floor was 2.3× too pessimistic at 1800 s."""
    from app.core.presets import PRESETS
    from app.core.simulate import Setup, simulate_run
    from app.core.sinusoid import heading_angles
    from app.core.solve import solve_heading

    gyro = PRESETS[preset].without("indexing", "dial", "warmup")  # a warmed-up gyro
    angles = heading_angles(4, "ccw")
    rng = np.random.default_rng(11)
    errors = []
    for run, azimuth in enumerate(rng.uniform(0, 360, 200)):
        simulated = simulate_run(
            gyro, Setup(39.93, float(azimuth)), "heading", angles, dwell, seed=run
        )
        result = solve_heading(simulated.positions, angles, true_azimuth_deg=float(azimuth))
        errors.append(result.azimuth_error_deg)
    rms = math.sqrt(np.mean(np.square(errors)))
    data = dwell_curve(preset, 39.93)
    expected = float(np.interp(dwell, data["dwell_s"], data["sigma_deg"]))
    assert rms == pytest.approx(expected, rel=0.15)  # 200 runs: the RMS scatters by 5 %


def test_explorer_over_http(student_client):
    page = student_client.get("/explore")
    assert page.status_code == 200 and "Why four positions beat two" in page.text
    data = student_client.get(
        "/explore/data", params={"method": "two", "indexing_arcsec": 900, "noise": "false"}
    ).json()
    assert data["curves"][0]["method"] == "two" and data["info"]["points"] == 24
    assert student_client.get("/explore/data", params={"runs": 1000}).status_code in (400, 422)
    assert student_client.get("/explore/data", params={"latitude_deg": "nan"}).status_code in (
        400,
        422,
    )
    exported = student_client.get(
        "/explore/data.csv", params={"chart": "heading", "indexing_arcsec": 900}
    )
    rows = list(csv.DictReader(io.StringIO(exported.content.decode("utf-8-sig"))))
    assert {r["kind"] for r in rows} == {"first_order", "monte_carlo"}
    assert rows[0]["heading_error_deg"] != ""
    dwell = student_client.get("/explore/data.csv", params={"chart": "dwell"})
    assert dwell.content.decode("utf-8-sig").startswith("dwell_s,heading_sigma_deg")
    zh = student_client.get("/explore", headers={"Accept-Language": "zh-CN"})
    assert "为什么四位置法优于二位置法" in zh.text
    orders = student_client.get(
        "/explore/data.csv", params={"chart": "orders", "bias_drift_deg_h_per_h": 2}
    )
    table = list(csv.DictReader(io.StringIO(orders.content.decode("utf-8-sig"))))
    assert len(table) == 72 and "heading_error_deg_order_12344321" in table[0]


def test_drift_orders_against_the_closed_form():
    """ḃ·T·√2/H is the worst heading error of the order 1-2-3-4 (T the dwell); 1-3-2-4
    halves it; the symmetric order cancels it (lab-reference §3)."""
    from app.explore.scenarios import drift_order_curves

    data = drift_order_curves(40.0, 300.0, 2.0)
    amplitude = 15.041 * math.cos(math.radians(40.0))
    worst = math.degrees(2.0 * 300.0 / 3600.0 * math.sqrt(2.0) / amplitude)
    assert max(np.abs(data["orders"]["1234"])) == pytest.approx(worst, rel=0.01)
    assert max(np.abs(data["orders"]["1324"])) == pytest.approx(worst / 2, rel=0.01)
    assert max(np.abs(data["orders"]["12344321"])) < 1e-9


def test_explorer_needs_a_log_in(client):
    assert client.get("/explore").status_code == 303
    assert client.get("/explore/data", headers={"Accept": "application/json"}).status_code == 401
