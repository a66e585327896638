"""The worked solution shows the numbers the result uses (issue: unequal numbers of readings),
and small input faults get the right words (out of range, not a number)."""

from __future__ import annotations

import math
import re
from decimal import ROUND_HALF_UP, Decimal, localcontext

import numpy as np
import pytest

from app.core.exceptions import UserError
from app.core.explain import explain_heading, explain_latitude
from app.core.readings import parse_readings_csv
from app.core.sinusoid import heading_angles
from app.core.solve import solve_heading, solve_latitude
from app.core.units import to_deg_per_hour
from app.core.worked_steps import Words, render_text
from app.web.i18n import translator
from tests.factories import english, handout

HEADING = handout("handout_horizontal.csv")
VERTICAL = handout("handout_vertical.csv")
ANGLES = heading_angles(4, "ccw")
ELEVATIONS = [0.0, 90.0, 180.0, 270.0]


def said(words: Words, language: str = "en") -> str:
    """A step's words as the reader sees them."""
    return translator(language)(words.key, **words.params)


def unequal(table: dict[int, list[float]]) -> list[list[float]]:
    """The handout's readings with some of positions 1 and 3 missing (the web lab's usual
    case: a position re-recorded with another dwell)."""
    return [table[1][:4], table[2], table[3][:7], table[4]]


def noisy_unequal() -> list[np.ndarray]:
    """A teaching gyro's readings (H = 10 °/h, A1 = 10°, 1 °/h noise) with 3, 40, 5 and
    40 readings: the fit and the handout's closed form differ by tenths of a degree."""
    rng = np.random.default_rng(7)
    counts = (3, 40, 5, 40)
    return [
        10 * np.cos(np.radians(10 + alpha)) + 0.9 + rng.normal(0, 1.0, n)
        for alpha, n in zip(ANGLES, counts, strict=True)
    ]


def weighted_fit(positions, angles_deg) -> np.ndarray:
    """Independent least squares over every sample: ω = a cos α + c sin α + b."""
    rows, values = [], []
    for samples, angle in zip(positions, angles_deg, strict=True):
        alpha = math.radians(angle)
        for value in samples:
            rows.append([math.cos(alpha), math.sin(alpha), 1.0])
            values.append(value)
    solution, *_ = np.linalg.lstsq(np.array(rows), np.array(values), rcond=None)
    return solution


def numbers_after(text: str, label: str) -> list[float]:
    """Every number on the lines that contain ``label``."""
    found = []
    for line in text.splitlines():
        if label in line:
            found += [float(x) for x in re.findall(r"-?\d+\.\d+", line)]
    return found


def test_unequal_counts_show_the_fit_that_is_used():
    positions = noisy_unequal()
    result = solve_heading(positions, ANGLES)
    a, c, _ = weighted_fit(positions, ANGLES)
    assert result.azimuth_deg == pytest.approx(math.degrees(math.atan2(-c, a)) % 360, abs=1e-9)
    means = [np.mean(p) for p in positions]
    closed = math.degrees(math.atan((means[3] - means[1]) / (means[0] - means[2])))
    assert abs(closed - result.theta_deg) > 0.05  # they differ at the precision shown
    steps = explain_heading(result)
    text = render_text(steps, translator("en"))
    fit_step = next(s for s in steps if "each reading counts once" in said(s.title))
    fit_text = "\n".join(fit_step.lines)
    x, y = numbers_after(fit_text, "x = H·cos A1")
    assert math.degrees(math.atan2(y, x)) % 360 == pytest.approx(result.azimuth_deg, abs=0.01)
    ratio, _, theta = numbers_after(fit_text, "tan θ = −y/x")
    assert ratio == pytest.approx(-y / x, abs=2e-4)
    assert theta == pytest.approx(result.theta_deg, abs=0.005)
    assert math.degrees(math.atan(ratio)) == pytest.approx(theta, abs=0.01)
    # the handout's closed form is there, clearly labelled, with its own (different) θ
    comparison = next(s for s in steps if said(s.title).startswith("For comparison, not used"))
    assert f"{closed:.2f}°" in comparison.lines[-1]
    assert "未采用" in said(comparison.title, "zh-CN")
    # H shown is the H reported
    assert f"H = √(x² + y²) = {result.amplitude_deg_h:.3f}" in text
    assert math.hypot(x, y) == pytest.approx(result.amplitude_deg_h, abs=1e-3)


def test_equal_counts_keep_the_handout_form():
    result = solve_heading([HEADING[k] for k in range(1, 5)], ANGLES)
    text = render_text(explain_heading(result), translator("en"))
    assert "tan θ = (ω4 − ω2) / (ω1 − ω3)" in text and "θ = arctan(-0.1899) = -10.75°" in text
    assert "For comparison" not in text
    assert "From position 1, turn the table counter-clockwise by 10.75°" in text
    assert "从位置 1 起" in render_text(explain_heading(result), translator("zh-CN"))


def test_latitude_with_unequal_counts_shows_the_fit():
    positions = unequal(VERTICAL)
    result = solve_latitude(positions, ELEVATIONS, true_latitude_deg=39.93)
    a, c, _ = weighted_fit(positions, ELEVATIONS)
    assert result.latitude_deg == pytest.approx(math.degrees(math.atan2(c, a)), abs=1e-9)
    steps = explain_latitude(result)
    fit_step = next(s for s in steps if "each reading counts once" in said(s.title))
    fit_text = "\n".join(fit_step.lines)
    assert f"φ = atan2(c, a) = {result.latitude_deg:.2f}°" in fit_text
    assert f"Ω = √(a² + c²) = {result.earth_rate_deg_h:.3f}" in fit_text
    means = [np.mean(p) for p in positions]
    closed = math.degrees(math.atan2(means[1] - means[3], means[0] - means[2]))
    comparison = next(s for s in steps if said(s.title).startswith("For comparison, not used"))
    assert f"φ = {closed:.2f}°" in comparison.lines
    assert abs(closed - result.latitude_deg) > 0.05


def test_latitude_error_in_degrees():
    result = solve_latitude([VERTICAL[k] for k in range(1, 5)], ELEVATIONS, true_latitude_deg=39.93)
    assert result.latitude_error_deg == pytest.approx(result.latitude_deg - 39.93)
    assert result.to_json()["latitude_error_deg"] == pytest.approx(0.797, abs=1e-3)
    assert "Δφ = φ − φ0 = 0.80°" in render_text(explain_latitude(result), translator("en"))
    near_equator = solve_latitude(
        [VERTICAL[k] for k in range(1, 5)], ELEVATIONS, true_latitude_deg=0.01
    )
    assert near_equator.latitude_error_percent > 1e5  # why degrees are shown too
    assert near_equator.latitude_error_deg == pytest.approx(near_equator.latitude_deg - 0.01)


PERCENT_LINE = re.compile(
    r"η_(?:φ|Ω) = .*? = \|\(?(-?[\d.]+)\)? − \(?(-?[\d.]+)\)?\| / \|?(-?[\d.]+)\|?"
    r" × 100% = ([\d.]+)%"
)


def test_each_percent_error_line_worked_by_hand_gives_its_own_result():
    """η written into the steps from the numbers beside it: φ = 31.24695° written 31.25 and
    φ0 = 39.93 give 21.74 %, where the result is 21.75 %; a student checking the line by
    hand found the steps wrong.  Random stations, both hemispheres, many gyro runs: each
    line's numbers give its η to the last digit written."""
    rng = np.random.default_rng(5)
    checked = 0
    for _ in range(300):
        truth = float(rng.uniform(-70.0, 70.0))
        true_rate = float(rng.choice([15.04, 15.041, 15.0411]))
        phi = math.radians(truth + rng.normal(0.0, 2.0))
        rate = true_rate * (1 + rng.normal(0.0, 0.02))
        positions = [
            rate * math.cos(math.radians(e) - phi) + 1.5 + rng.normal(0.0, 0.3, 10)
            for e in ELEVATIONS
        ]
        result = solve_latitude(
            positions,
            ELEVATIONS,
            true_latitude_deg=round(truth, 2),
            true_earth_rate_deg_h=true_rate,
        )
        text = render_text(explain_latitude(result), translator("en"))
        for measured, true, over, written in PERCENT_LINE.findall(text):
            worked = abs(float(measured) - float(true)) / abs(float(over)) * 100
            assert f"{worked:.2f}" == written, text
            checked += 1
    assert checked == 600


@pytest.mark.parametrize("text", ["1_000", "nan", "inf", "Infinity", " 1 2", "0x10", "1e5e5"])
def test_only_plain_decimals_are_numbers(text):
    with pytest.raises(UserError) as caught:
        parse_readings_csv(f"position_1,position_2,position_3\n1,2,{text}\n")
    assert caught.value.key == "csv.not_a_number"


def test_overflowing_numbers_are_out_of_range():
    with pytest.raises(UserError) as caught:
        parse_readings_csv("position_1,position_2,position_3\n1,2,1e400\n")
    assert caught.value.key == "csv.out_of_range" and "out of range" in english(caught.value)
    with pytest.raises(UserError) as converted:
        to_deg_per_hour([1e306, 1.0], "deg/s")
    assert converted.value.key == "readings.out_of_range"
    assert "finite" not in str(converted.value)


@pytest.mark.parametrize("start", [1e20, -1e20, 3601.0, math.inf, math.nan])
def test_start_angle_gets_a_range_message(start):
    with pytest.raises(UserError) as caught:
        heading_angles(4, "ccw", start)
    assert caught.value.key == "angles.start_out_of_range"
    assert "inf" not in english(caught.value) and "nan" not in english(caught.value)


def test_huge_readings_never_print_inf_or_nan():
    positions = [[1e300] * 3, [2.0] * 3, [3.0] * 3, [4.0] * 3]
    with pytest.raises(UserError) as caught:
        solve_heading(positions, ANGLES)
    assert caught.value.key == "readings.out_of_range"
    message = english(caught.value).lower()
    assert "inf" not in message and "nan" not in message


# --- honest 1σ (lab-reference §3) ------------------------------------------------------------


def test_identical_readings_get_the_quantisation_floor():
    """All readings of position 2 are the same: its mean is uncertain by LSB/√12, the LSB
    being the data's own step (0.09 °/h in the other positions), not zero."""
    positions = [
        [10.74, 10.65, 10.84, 10.65],
        [2.79] * 4,
        [-8.95, -9.04, -8.86, -8.95],
        [-0.94, -0.85, -1.03, -0.94],
    ]
    result = solve_heading(positions, ANGLES)
    step = 0.09  # 10.74 − 10.65, the smallest gap within a position
    assert result.fit.position_sigmas[1] == pytest.approx(step / math.sqrt(12), rel=1e-6)
    assert result.fit.uncertainty_model == "white"
    every_identical = solve_heading([[v] * 5 for v in (10.71, 2.79, -8.95, -0.94)], ANGLES)
    # no step in the data: the resolution the numbers were written with (0.01 °/h)
    assert every_identical.fit.position_sigmas == pytest.approx([0.01 / math.sqrt(12)] * 4)
    assert every_identical.azimuth_sigma_deg > 0


def test_small_n_is_widened_by_student_t():
    from scipy.stats import t as student_t

    rng = np.random.default_rng(3)
    positions = [10 * math.cos(math.radians(a + 20)) + rng.normal(0, 0.3, 3) for a in ANGLES]
    result = solve_heading(positions, ANGLES)
    k2 = student_t.ppf(0.5 + 0.6826894921 / 2, 2)  # 1.3210
    for samples, sigma in zip(positions, result.fit.position_sigmas, strict=True):
        assert sigma == pytest.approx(k2 * samples.std(ddof=1) / math.sqrt(3), rel=1e-9)


def test_one_reading_per_position_uses_the_closure_and_refuses_noise():
    """The handout's four typed averages get a σ from d; when H is not clearly larger than
    that σ the heading is refused, never printed."""
    result = solve_heading([[10.71], [2.79], [-8.95], [-0.94]], ANGLES)
    assert result.fit.uncertainty_model == "closure" and result.azimuth_sigma_deg > 0
    assert result.to_json()["uncertainty_model"] == "closure"
    with pytest.raises(UserError) as caught:
        solve_heading([[0.30], [-0.25], [0.10], [0.35]], ANGLES)  # |d| ≈ H: pure noise
    assert caught.value.key == "readings.amplitude_too_small"


def test_closure_consistency_is_checked_and_flagged():
    """White-noise σ of 0.01 °/h per mean, but a bump of 1 °/h at position 3: |d| ≫ 3σ_d."""
    rng = np.random.default_rng(5)
    true = [10 * math.cos(math.radians(a + 20)) + 1.0 for a in ANGLES]
    positions = [t + rng.normal(0, 0.03, 9) for t in true]
    consistent = solve_heading(positions, ANGLES)
    assert consistent.fit.closure_consistent is True
    positions[2] = positions[2] + 1.0
    bumped = solve_heading(positions, ANGLES)
    assert bumped.fit.closure_consistent is False
    sigma_d = math.sqrt(sum(s**2 for s in bumped.fit.position_sigmas)) / 2
    assert bumped.to_json()["closure_sigma_deg_h"] == pytest.approx(sigma_d)
    assert f"(σ_d = {sigma_d:.3f} °/h)" in render_text(explain_heading(bumped), translator("en"))


def test_a_refusal_never_prints_a_non_finite_sigma():
    from app.core.polar import check_significant as _check_significant

    for sigma in (math.nan, math.inf):
        with pytest.raises(UserError) as caught:
            _check_significant(0.0, sigma, "horizontal", 1.0)
        message = english(caught.value).lower()
        assert "nan" not in message and "inf" not in message


def test_when_one_sigma_differs_from_s_over_root_n_every_sigma_is_shown():
    """Positions 1, 2 and 4 have 4 readings (σ widened by Student's t), position 3 has
    2000 (σ3 = s/√n to the digits shown): σ3 is shown too, never left blank."""
    rng = np.random.default_rng(5)
    counts = (4, 4, 2000, 4)
    positions = [
        10 * np.cos(np.radians(30 + alpha)) + rng.normal(0, 0.3, n)
        for alpha, n in zip(ANGLES, counts, strict=True)
    ]
    result = solve_heading(positions, ANGLES)
    sem3 = positions[2].std(ddof=1) / math.sqrt(2000)
    assert round(result.fit.position_sigmas[2], 3) == round(sem3, 3)
    text = render_text(explain_heading(result), translator("en"))
    means = [line for line in text.splitlines() if re.match(r"\s*ω\d = ", line)]
    assert len(means) == 4
    for i, (line, sigma) in enumerate(zip(means, result.fit.position_sigmas, strict=True), 1):
        assert f"σ{i} = {sigma:.3f}" in line, line


def _as_written(worked: Decimal, written: str) -> str:
    """A number worked by hand, rounded as a student rounds (a half away from zero) to the
    decimals ``written`` has."""
    decimals = len(written.split(".")[1]) if "." in written else 0
    return str(worked.quantize(Decimal(1).scaleb(-decimals), rounding=ROUND_HALF_UP))


def _fog_readings(rng, angles, amplitude, phase_deg, bias) -> list[np.ndarray]:
    """Ten readings per position written to three decimals, as a FOG's logger writes them:
    their means have four, which the steps write to three where that is enough."""
    return [
        np.round(bias + amplitude * np.cos(np.radians(a - phase_deg)) + rng.normal(0, 0.1, 10), 3)
        for a in angles
    ]


NUMBER = r"\(?(-?[\d.]+)\)?"


def test_each_heading_line_worked_by_hand_from_the_means_gives_its_own_result():
    """From the means as step 1 writes them, by hand: tan θ, θ = arctan(tan θ), x, y,
    H = √(x² + y²), the bias b and the closure d.  With readings of three decimals, the
    means written to three gave another x or y in the last digit in 97 % of sessions,
    another tan θ in 56 %, another θ in 8 %, another b or d in 3 %.  The steps now write
    the means (and each line's result) to as many decimals as it takes."""
    rng = np.random.default_rng(11)
    for _ in range(150):
        positions = _fog_readings(
            rng, ANGLES, rng.uniform(4, 12), rng.uniform(0, 360), rng.uniform(-2, 2)
        )
        text = render_text(explain_heading(solve_heading(positions, ANGLES)), translator("en"))
        w = [Decimal(v) for v in re.findall(r"ω\d = (-?[\d.]+) °/h", text)[:4]]
        tan = re.search(rf"tan θ = .*? = \({NUMBER} − {NUMBER}\) / \({NUMBER} − {NUMBER}\) "
                        r"= (-?[\d.]+)", text)  # fmt: skip
        top, bottom = Decimal(tan[1]) - Decimal(tan[2]), Decimal(tan[3]) - Decimal(tan[4])
        assert [Decimal(tan[k]) for k in (3, 4)] == [w[0], w[2]], text  # the means of step 1
        assert _as_written(top / bottom, tan[5]) == tan[5], text
        theta = re.search(r"θ = arctan\((-?[\d.]+)\) = (-?[\d.]+)°", text)
        assert f"{math.degrees(math.atan(float(theta[1]))):.2f}" == theta[2], text
        xy = re.search(r"x = \(ω1 − ω3\)/2 = (-?[\d.]+) °/h,\s+y = \(ω(\d) − ω(\d)\)/2 = "
                       r"(-?[\d.]+)", text)  # fmt: skip
        assert _as_written((w[0] - w[2]) / 2, xy[1]) == xy[1], text
        y = (w[int(xy[2]) - 1] - w[int(xy[3]) - 1]) / 2
        assert _as_written(y, xy[4]) == xy[4], text
        azimuth = re.search(r"A1 = atan2\(y, x\) = (-?[\d.]+)°", text)[1]
        assert f"{math.degrees(math.atan2(float(xy[4]), float(xy[1]))) % 360:.2f}" == azimuth
        bias = re.search(r"b = (-?[\d.]+) °/h", text)[1]
        assert _as_written((w[0] + w[1] + w[2] + w[3]) / 4, bias) == bias, text
        closure = re.search(r"d = \(ω1 \+ ω3 − ω2 − ω4\)/2 = (-?[\d.]+)", text)[1]
        assert _as_written((w[0] + w[2] - w[1] - w[3]) / 2, closure) == closure, text
        size = re.search(r"H = √\(x² \+ y²\) = (-?[\d.]+)", text)[1]
        with localcontext() as context:
            context.prec = 40
            by_hand = (Decimal(xy[1]) ** 2 + Decimal(xy[4]) ** 2).sqrt()
        assert _as_written(by_hand, size) == size, text


def test_the_weighted_fits_tan_theta_worked_by_hand_from_x_and_y_gives_its_own_result():
    """Unequal numbers of readings: tan θ = −y/x from x and y as written, and θ from it.
    Written to four decimals each, a third of the sessions' lines gave another tan θ or θ;
    x and y now take a decimal or two more where that makes it work (not within 5° of
    ±90°, where x is too small for any few decimals to fix tan θ's fourth)."""
    rng = np.random.default_rng(13)
    checked = 0
    for _ in range(150):
        angles, counts = ANGLES, (4, 10, 7, 10)
        amplitude, phase, bias = rng.uniform(4, 12), rng.uniform(0, 360), rng.uniform(-2, 2)
        positions = [
            np.round(bias + amplitude * np.cos(np.radians(a - phase)) + rng.normal(0, 0.1, n), 3)
            for a, n in zip(angles, counts, strict=True)
        ]
        result = solve_heading(positions, angles)
        if abs(result.theta_deg) > 85:
            continue
        text = render_text(explain_heading(result), translator("en"))
        line = re.search(
            r"x = H·cos A1 = (-?[\d.]+) °/h,\s+y = H·sin A1 = (-?[\d.]+).*?"
            r"tan θ = −y/x = (-?[\d.]+),\s+θ = arctan\((-?[\d.]+)\) = (-?[\d.]+)°",
            text,
            re.S,
        )
        assert _as_written(-Decimal(line[2]) / Decimal(line[1]), line[3]) == line[3], text
        assert f"{math.degrees(math.atan(float(line[4]))):.2f}" == line[5], text
        azimuth = re.search(r"A1 = atan2\(y, x\) = (-?[\d.]+)°", text)[1]
        by_hand = math.degrees(math.atan2(float(line[2]), float(line[1]))) % 360
        assert f"{by_hand:.2f}" == azimuth, text
        checked += 1
    assert checked > 120


def test_each_latitude_line_worked_by_hand_from_the_means_gives_its_own_result():
    """From the means of step 1 and φ as the lines write it, by hand: tan φ, φ, and Ω three
    ways.  The lines of Ω took φ to the two decimals "φ = 40.73°" shows and gave another Ω
    in most sessions (the handout's own: 15.131 for 15.133); they now write the φ they use
    (cos 40.7274°) and the means to as many decimals as it takes."""
    rng = np.random.default_rng(12)
    for _ in range(150):
        phi = rng.uniform(15, 65)
        positions = _fog_readings(rng, ELEVATIONS, 15.041, phi, rng.uniform(-2, 2))
        result = solve_latitude(positions, ELEVATIONS, true_latitude_deg=39.93)
        text = render_text(explain_latitude(result), translator("en"))
        w = [Decimal(v) for v in re.findall(r"ω\d = (-?[\d.]+) °/h", text)[:4]]
        ratio = re.search(r"tan φ = .*? = (-?[\d.]+)\n", text)[1]
        assert _as_written((w[1] - w[3]) / (w[0] - w[2]), ratio) == ratio, text
        written_phi = re.search(r"\n\s*φ = (-?[\d.]+)°", text)[1]
        assert f"{math.degrees(math.atan(float(ratio))):.2f}" == written_phi, text
        for difference, trig, function in (
            (w[0] - w[2], "cos", math.cos),
            (w[1] - w[3], "sin", math.sin),
        ):
            line = re.search(rf"/\(2 {trig} φ\) = .*? {trig} (-?[\d.]+)°\) = (-?[\d.]+)", text)
            angle = Decimal(repr(function(math.radians(float(line[1])))))
            assert _as_written(difference / (2 * angle), line[2]) == line[2], text
        omega = re.search(r"Ω = √\(\(ω1 − ω3\)² \+ \(ω2 − ω4\)²\)/2 = (-?[\d.]+)", text)[1]
        with localcontext() as context:
            context.prec = 40
            by_hand = ((w[0] - w[2]) ** 2 + (w[1] - w[3]) ** 2).sqrt() / 2
        assert _as_written(by_hand, omega) == omega, text


def test_the_weighted_fits_latitude_worked_by_hand_from_a_and_c_gives_its_own_result():
    """Unequal numbers of readings in part B: φ = atan2(c, a) and Ω = √(a² + c²) from a and c
    as written (four decimals) gave another Ω in 4 % of sessions and another φ in 1 %; a and
    c now take a decimal or two more where that is needed."""
    rng = np.random.default_rng(14)
    for _ in range(150):
        phi = rng.uniform(15, 65)
        positions = [
            np.round(
                rng.uniform(-2, 2)
                + 15.041 * math.cos(math.radians(e - phi))
                + rng.normal(0, 0.1, n),
                3,
            )
            for e, n in zip(ELEVATIONS, (4, 10, 7, 10), strict=True)
        ]
        result = solve_latitude(positions, ELEVATIONS, true_latitude_deg=39.93)
        text = render_text(explain_latitude(result), translator("en"))
        line = re.search(
            r"a = (-?[\d.]+), c = (-?[\d.]+), b = .*?φ = atan2\(c, a\) = (-?[\d.]+)°,\s+"
            r"Ω = √\(a² \+ c²\) = (-?[\d.]+)",
            text,
            re.S,
        )
        assert f"{math.degrees(math.atan2(float(line[2]), float(line[1]))):.2f}" == line[3]
        with localcontext() as context:
            context.prec = 40
            size = (Decimal(line[1]) ** 2 + Decimal(line[2]) ** 2).sqrt()
        assert _as_written(size, line[4]) == line[4], text


def test_the_handouts_means_are_written_as_the_handout_writes_them():
    """Readings of two decimals: their means are exact to three, and the steps keep three."""
    heading = render_text(
        explain_heading(solve_heading([HEADING[k] for k in range(1, 5)], ANGLES)),
        translator("en"),
    )
    assert "ω1 = 10.706 °/h" in heading and "x = (ω1 − ω3)/2 = 9.8285 °/h" in heading
    latitude = render_text(
        explain_latitude(solve_latitude([VERTICAL[k] for k in range(1, 5)], ELEVATIONS)),
        translator("en"),
    )
    assert "ω1 = 11.133 °/h" in latitude and "(2 cos 40.7274°) = 15.133 °/h" in latitude


def test_the_chinese_steps_have_no_english_words_in_their_lines():
    """The lines of mathematics are the same in both languages, so the words among them --
    "(propagated)", "known: 68 % of … within", "°/h per reading" -- were English on the
    Chinese page and in its PDF.  They come from the catalogues now."""
    rng = np.random.default_rng(3)
    angles = heading_angles(4, "ccw")
    drifting, index = [], 0
    for angle in angles:  # a bias falling by 0.05 °/h per reading, typed (no clock)
        clean = 12.0 * math.cos(math.radians(40.0 + angle))
        drifting.append(clean + 2.0 - 0.05 * (index + np.arange(12)) + rng.normal(0, 0.03, 12))
        index += 12
    noisy = [np.array(VERTICAL[k]) + rng.normal(0.0, 2.0, len(VERTICAL[k])) for k in range(1, 5)]
    results = {
        "warm-up": explain_heading(solve_heading(drifting, angles, true_azimuth_deg=40.0)),
        "exact": explain_latitude(
            solve_latitude(noisy, ELEVATIONS, true_latitude_deg=39.93, true_earth_rate_deg_h=15.04)
        ),
    }
    allowed = {"atan", "arctan", "true"}  # function names; A1,true is a symbol's subscript
    for name, steps in results.items():
        english_text = render_text(steps, translator("en"))
        chinese = render_text(steps, translator("zh-CN"))
        words = {w for line in chinese.splitlines() for w in re.findall(r"[A-Za-z]{4,}", line)}
        assert words <= allowed, (name, words - allowed)
        assert ("per reading" in english_text) == (name == "warm-up"), english_text
        if name == "exact":
            assert "(propagated)" in english_text and "（线性传播）" in chinese


@pytest.mark.one_backend  # the page's words, not the database's
def test_the_lab_page_says_a_steps_words_in_its_language(student_client):
    """A line with words among its mathematics is a message of the catalogues on the page
    too (the PDF's template is the same loop): the handout's station, whose known Earth
    rate makes the latitude's exact σ differ from the propagated one."""
    from tests.factories import new_session, save_manual

    session_id = new_session(student_client)
    noisy = {k: [v + 1.5 * (-1) ** i for i, v in enumerate(VERTICAL[k])] for k in range(1, 5)}
    assert save_manual(student_client, session_id, "latitude", noisy).status_code == 200
    page = f"/lab/sessions/{session_id}"
    zh = student_client.get(page, headers={"Accept-Language": "zh-CN"}).text
    en = student_client.get(page, headers={"Accept-Language": "en"}).text
    assert "σ_φ（线性传播）" in zh and "propagated" not in zh
    assert "σ_φ (propagated)" in en


def test_a_hand_rounds_a_half_away_from_zero_and_a_ratio_gets_the_decimals_its_angle_needs():
    from app.core.worked_decimals import by_hand, hypot_decimals, ratio_decimals

    assert (
        by_hand(Decimal("0.44645"), 4) == "0.4465" and by_hand(Decimal("-0.44645"), 4) == "-0.4465"
    )
    # tan 40.7275° = 0.861044…: written 0.8610, arctan gives 40.727…° → 40.73° (enough)
    assert ratio_decimals(math.tan(math.radians(40.7275)), 40.7275) == 4
    # θ = 41.84593° (41.85°): tan θ = 0.895547… written 0.8955 gives 41.8444° → 41.84°
    theta = 41.84593
    assert f"{math.degrees(math.atan(0.8955)):.2f}" == "41.84"
    assert ratio_decimals(math.tan(math.radians(theta)), theta) == 5
    assert hypot_decimals("3.0000", "4.0000", 5.0) == 3  # 3-4-5: three decimals are exact
