"""The handout's calculation written out with the student's numbers substituted.

Each step (:class:`app.core.worked_steps.Step`) has a title, and perhaps a legend and a
conclusion, as message keys with their numbers (``Words``: the catalogues hold the words in
each language), and lines of mathematics (language-neutral), so the command line, the pages
and the reports all show the same worked solution.
"""

from __future__ import annotations

import math

import numpy as np

from app.core.solve import HeadingResult, LatitudeResult
from app.core.step_decimals import (
    fit_decimals,
    handout_ratio,
    heading_decimals,
    latitude_decimals,
    percent_error_line,
    ratio_decimals_or_usual,
    slope_decimals,
)
from app.core.worked_decimals import (
    MEANS_DECIMALS,
    RATIO_DECIMALS,
    hypot_decimals,
    ratio_decimals,
)
from app.core.worked_steps import (
    AMPLITUDE_LEGEND,
    AZIMUTH_LEGEND,
    ELEVATION_LEGEND,
    FIT_LEGEND,
    MODEL_NOTES,
    Step,
    Words,
)
from app.core.worked_steps import fixed as _f
from app.core.worked_steps import in_formula as _p


def _means_step(fit, decimals: int = MEANS_DECIMALS) -> Step:
    """The positions' means, written to ``decimals`` (:mod:`app.core.worked_decimals`)."""
    sigmas = fit.position_sigmas or [None] * len(fit.stats)
    # σi is shown when the model's σ differs from s/√n at any position -- and then at every
    # position, so that one equal to s/√n never reads as a missing number
    shows_sigma = any(
        sigma is not None and (s.sem is None or abs(sigma - s.sem) > 5e-4)
        for s, sigma in zip(fit.stats, sigmas, strict=True)
    )
    lines = []
    for i, (s, sigma) in enumerate(zip(fit.stats, sigmas, strict=True), start=1):
        line = f"ω{i} = {_f(s.mean, decimals)} °/h   (n = {s.n}"
        if s.sem is not None:
            line += f", s = {_f(s.std)}, s/√n = {_f(s.sem)}"
        if shows_sigma and sigma is not None:
            line += f", σ{i} = {_f(sigma)}"
        lines.append(line + ")")
    return Step(
        Words("steps.means"),
        tuple(lines),
        MODEL_NOTES.get(fit.uncertainty_model),
        legend=MEANS_LEGEND if shows_sigma else None,
    )


MEANS_LEGEND = Words("steps.legend_means")


_FIT_TITLE = Words("steps.fit")


def _four_apart(angles: np.ndarray) -> int:
    """+1 for four positions 90° apart clockwise, −1 counter-clockwise, 0 otherwise."""
    if angles.size != 4:
        return 0
    steps = np.diff(angles)
    if np.allclose(steps, 90.0):
        return 1
    if np.allclose(steps, -90.0):
        return -1
    return 0


def _drift_lines(fit) -> list[str]:
    """The fitted linear drift, when the schedule allowed one (five or more timed positions)."""
    if fit.drift is None:
        return []
    sigma = f" ± {_f(fit.drift_sigma, 4)}" if fit.drift_sigma is not None else ""
    return [f"+ ḃ·(t − t̄):  ḃ = {_f(fit.drift, 4)}{sigma} °/h²"]


def _equal_counts(stats) -> bool:
    return len({s.n for s in stats}) == 1


WEIGHTED_TITLE = Words("steps.fit_weighted")
UNWEIGHTED_TITLE = Words("steps.unweighted")


def explain_heading(result: HeadingResult) -> list[Step]:
    """The heading worked out step by step with the numbers the result uses.

    With four positions 90° apart and equal numbers of readings the handout's closed form
    *is* the least-squares fit, so it is shown.  With unequal numbers the fit weights each
    position by its count and differs from the closed form: the steps then show the fit's
    x = H·cos A1 and y = H·sin A1 (which give θ, A1 and H exactly as reported) and add the
    closed form of the plain means as a line labelled "for comparison, not used".

    Parameters
    ----------
    result : HeadingResult
        A solved part A.

    Returns
    -------
    list of Step
        Message keys with the numbers to fill in (rendered in either language).

    References
    ----------
    The handout, part A; lab-reference §3.
    """
    fit = result.fit
    w = fit.means
    turn = _four_apart(fit.angles_deg)
    # What the result uses: x and y of position 1 from the fit (lab-reference §3).
    x_used = result.amplitude_deg_h * math.cos(math.radians(result.azimuth_deg))
    y_used = result.amplitude_deg_h * math.sin(math.radians(result.azimuth_deg))
    closed_form = bool(turn) and _equal_counts(fit.stats)
    # the means and the ratio to as many decimals as make the lines work out by hand
    ratio = handout_ratio(w, turn)[2] if turn and w[0] != w[2] else math.inf
    theta = result.theta_deg if closed_form else math.degrees(math.atan(ratio))
    ratio_at = ratio_decimals_or_usual(ratio, theta)
    closed = (
        (x_used, y_used, fit.b, result.closure_residual_deg_h, result.azimuth_deg)
        if closed_form
        else None
    )
    decimals, (xy_at, b_at, d_at) = (
        heading_decimals(w, turn, ratio, ratio_at, closed) if turn else (MEANS_DECIMALS, (4, 3, 3))
    )
    steps = [_means_step(fit, decimals)]
    if closed_form:
        formula, _, ratio = handout_ratio(w, turn, decimals)
        steps.append(
            Step(
                Words("steps.handout_theta"),
                (
                    f"{formula} = {_f(ratio, ratio_at)}",
                    f"θ = arctan({_f(ratio, ratio_at)}) = {_f(result.theta_deg, 2)}°",
                ),
            )
        )
        y_text = "(ω2 − ω4)/2" if turn < 0 else "(ω4 − ω2)/2"
        steps.append(
            Step(
                Words("steps.full_circle_azimuth"),
                (
                    f"x = (ω1 − ω3)/2 = {_f(x_used, xy_at)} °/h,   "
                    f"y = {y_text} = {_f(y_used, xy_at)} °/h",
                    f"A1 = atan2(y, x) = {_f(result.azimuth_deg, 2)}°",
                ),
                legend=AZIMUTH_LEGEND,
            )
        )
    else:
        slope = -y_used / x_used if abs(x_used) > 1e-12 else math.inf
        slope_at = ratio_decimals_or_usual(slope, result.theta_deg)
        xy_at = slope_decimals(x_used, y_used, slope, slope_at, result.azimuth_deg)
        lines = [
            "ω = a·cos α + c·sin α + b",
            f"a = {_f(fit.a, 4)}, c = {_f(fit.c, 4)}, b = {_f(fit.b, 4)} °/h",
            *_drift_lines(fit),
            f"x = H·cos A1 = {_f(x_used, xy_at)} °/h,   y = H·sin A1 = {_f(y_used, xy_at)} °/h",
            f"A1 = atan2(y, x) = {_f(result.azimuth_deg, 2)}°",
        ]
        if math.isfinite(slope):
            lines.append(
                f"tan θ = −y/x = {_f(slope, slope_at)},   θ = arctan({_f(slope, slope_at)}) = "
                f"{_f(result.theta_deg, 2)}°"
            )
        else:
            lines.append(f"θ = {_f(result.theta_deg, 2)}°")
        steps.append(Step(WEIGHTED_TITLE if turn else _FIT_TITLE, tuple(lines), legend=FIT_LEGEND))
        if turn and w[0] != w[2]:
            formula, _, ratio = handout_ratio(w, turn, decimals)
            closed = math.degrees(math.atan(ratio))
            steps.append(
                Step(
                    UNWEIGHTED_TITLE,
                    (
                        f"{formula} = {_f(ratio, ratio_at)}",
                        f"θ = arctan({_f(ratio, ratio_at)}) = {_f(closed, 2)}°",
                    ),
                    Words(
                        "steps.handout_weights",
                        {"closed": _f(closed, 2), "theta": _f(result.theta_deg, 2)},
                    ),
                )
            )
    turn_words = {"clockwise": "cw", "counterclockwise": "ccw"}[result.rotate_direction]
    rotate = _f(result.rotate_deg, 2)
    steps.append(
        Step(
            Words("steps.find_north"),
            (f"θ {'≥' if result.theta_deg >= 0 else '<'} 0,  |θ| = {rotate}°",),
            Words(f"steps.turn_{turn_words}_{result.then_axis_points}", {"rotate": rotate}),
        )
    )
    h_at = hypot_decimals(_f(x_used, xy_at), _f(y_used, xy_at), result.amplitude_deg_h)
    lines = [
        f"H = √(x² + y²) = {_f(result.amplitude_deg_h, h_at)} °/h,   b = {_f(fit.b, b_at)} °/h"
    ]
    if result.closure_residual_deg_h is not None:
        closure = f"d = (ω1 + ω3 − ω2 − ω4)/2 = {_f(result.closure_residual_deg_h, d_at)} °/h"
        if fit.closure_sigma is not None and fit.uncertainty_model != "closure":
            closure += f"  (σ_d = {_f(fit.closure_sigma)} °/h)"
        lines.append(closure)
    if result.azimuth_sigma_deg is not None and fit.cov is not None:
        h = result.amplitude_deg_h
        corrected = math.sqrt(max(h * h - fit.cov[0, 0] - fit.cov[1, 1], 0.25 * h * h))
        lines.append(
            f"σx = {_f(math.sqrt(fit.cov[0, 0]), 4)},  σy = {_f(math.sqrt(fit.cov[1, 1]), 4)} °/h,"
            f"  H_c = √(H² − σx² − σy²) = {_f(corrected)} °/h"
        )
        linear = (
            result.linear_sigma_deg
            if result.linear_sigma_deg is not None
            else (result.azimuth_sigma_deg)
        )
        lines.append(f"σ_A = √(y²σx² + x²σy² − 2xy·σxy)/(H·H_c) = {_f(linear, 3)}°")
        lines.extend(_exact_lines(result.exact_sigma_deg, linear, result.expected_amplitude_deg_h,
                                  "A1", "Ω cos φ"))  # fmt: skip
        lines.extend(_warm_up_lines(result.drift_check, result.noise_sigma_deg,
                                    result.azimuth_sigma_deg, "A1", "azimuth_deg"))  # fmt: skip
    if result.azimuth_error_deg is not None:
        lines.append(f"ΔA1 = A1 − A1,true = {_f(result.azimuth_error_deg, 2)}°")
    steps.append(
        Step(
            Words("steps.amplitude"),
            tuple(lines),
            legend=AMPLITUDE_LEGEND,
        )
    )
    return steps


def _latitude_closed_form(
    means: np.ndarray, phi_used: float | None, omega_used: float | None
) -> tuple[list[Step], int]:
    """The handout's latitude and Earth rate from four means at e = 0°, 90°, 180°, 270°.

    ``phi_used``/``omega_used`` are the reported values (equal to the closed form when
    every position has the same number of readings); None computes them from the means.
    The means, the ratio and φ in the lines of Ω are written to as many decimals as make
    each line work out by hand (:mod:`app.core.worked_decimals`): the steps, and the
    decimals of the means."""
    w1, w2, w3, w4 = means
    phi = phi_used if phi_used is not None else math.degrees(math.atan2(w2 - w4, w1 - w3))
    omega = omega_used if omega_used is not None else math.hypot(w1 - w3, w2 - w4) / 2
    cos_phi, sin_phi = math.cos(math.radians(phi)), math.sin(math.radians(phi))
    by_cos = (w1 - w3) / (2 * cos_phi) if abs(cos_phi) > 1e-9 else None
    by_sin = (w2 - w4) / (2 * sin_phi) if abs(sin_phi) > 1e-9 else None
    ratio = (w2 - w4) / (w1 - w3) if w1 != w3 else math.inf
    ratio_at = ratio_decimals(ratio, phi) if math.isfinite(ratio) and w1 > w3 else RATIO_DECIMALS
    decimals, phi_at = latitude_decimals(means, ratio, ratio_at, omega, phi, by_cos, by_sin)
    d = decimals
    differences = {
        "cos": f"({_p(w1, d)} − {_p(w3, d)}) / (2 cos {_f(phi, phi_at)}°)",
        "sin": f"({_p(w2, d)} − {_p(w4, d)}) / (2 sin {_f(phi, phi_at)}°)",
    }
    lines = []
    if by_cos is not None:
        lines.append(f"Ω = (ω1 − ω3)/(2 cos φ) = {differences['cos']} = {_f(by_cos)} °/h")
    if by_sin is not None:
        lines.append(f"Ω = (ω2 − ω4)/(2 sin φ) = {differences['sin']} = {_f(by_sin)} °/h")
    lines.append(f"Ω = √((ω1 − ω3)² + (ω2 − ω4)²)/2 = {_f(omega)} °/h")
    return [
        Step(
            Words("steps.latitude"),
            (
                f"tan φ = (ω2 − ω4)/(ω1 − ω3) = ({_p(w2, d)} − {_p(w4, d)}) / "
                f"({_p(w1, d)} − {_p(w3, d)}) = "
                + (_f(ratio, ratio_at) if math.isfinite(ratio) else "∞"),
                f"φ = {_f(phi, 2)}°",
            ),
        ),
        Step(Words("steps.earth_rate"), tuple(lines)),
    ], decimals


def explain_latitude(result: LatitudeResult) -> list[Step]:
    """Latitude and Earth rate worked out step by step with the numbers the result uses.

    Parameters
    ----------
    result : LatitudeResult
        A solved part B.

    Returns
    -------
    list of Step
        Message keys with the numbers to fill in, ending with η_φ and η_Ω.

    References
    ----------
    The handout, part B; lab-reference §3.
    """
    fit = result.fit
    steps: list[Step] = []
    decimals = MEANS_DECIMALS
    phi = result.latitude_deg
    standard = fit.angles_deg.size == 4 and np.allclose(
        np.mod(fit.angles_deg, 360), [0, 90, 180, 270]
    )
    if standard and _equal_counts(fit.stats):
        closed, decimals = _latitude_closed_form(fit.means, phi, result.earth_rate_deg_h)
        steps.extend(closed)
    else:
        ac_at = fit_decimals(fit.a, fit.c, phi, result.earth_rate_deg_h)
        steps.append(
            Step(
                WEIGHTED_TITLE if standard else _FIT_TITLE,
                (
                    "ω = a·cos e + c·sin e + b",
                    f"a = {_f(fit.a, ac_at)}, c = {_f(fit.c, ac_at)}, b = {_f(fit.b, 4)} °/h",
                    *_drift_lines(fit),
                    f"φ = atan2(c, a) = {_f(phi, 2)}°,   Ω = √(a² + c²) = "
                    f"{_f(result.earth_rate_deg_h)} °/h",
                ),
                legend=ELEVATION_LEGEND,
            )
        )
        if standard:
            closed, decimals = _latitude_closed_form(fit.means, None, None)
            steps.append(Step(UNWEIGHTED_TITLE, closed[0].lines + closed[1].lines))
    steps.insert(0, _means_step(fit, decimals))
    lines = []
    if result.latitude_error_percent is not None:
        lines.append(percent_error_line("φ", phi, result.true_latitude_deg, 2,
                                         result.latitude_error_percent))  # fmt: skip
    if result.latitude_error_deg is not None:
        lines.append(f"Δφ = φ − φ0 = {_f(result.latitude_error_deg, 2)}°")
    lines.append(percent_error_line("Ω", result.earth_rate_deg_h, result.true_earth_rate_deg_h,
                                     3, result.earth_rate_error_percent))  # fmt: skip
    if result.latitude_sigma_deg is not None:
        linear = result.linear_sigma_deg
        if linear is not None and result.exact_sigma_deg is not None:
            lines.append(Words("steps.sigma_propagated", {"name": "φ", "sigma": _f(linear, 3)}))
            lines.extend(_exact_lines(result.exact_sigma_deg, linear,
                                      result.true_earth_rate_deg_h, "φ", "Ω0"))  # fmt: skip
        lines.extend(_warm_up_lines(result.drift_check, result.noise_sigmas[0],
                                    result.latitude_sigma_deg, "φ", "latitude_deg"))  # fmt: skip
        lines.append(
            f"1σ: φ ± {_f(result.latitude_sigma_deg, 3)}°,  Ω ± "
            f"{_f(result.earth_rate_sigma_deg_h, 3)} °/h"
        )
    steps.append(Step(Words("steps.percent_errors"), tuple(lines)))
    return steps


def _exact_lines(exact, linear, amplitude, name: str, amplitude_name: str) -> list[Words]:
    """The exact σ of the angle when it differs from the propagated one as shown."""
    if exact is None or linear is None or _f(exact, 3) == _f(linear, 3):
        return []
    params = {"known": amplitude_name, "amplitude": _f(amplitude), "name": name}
    return [Words("steps.sigma_exact", {**params, "sigma": _f(exact, 3)})]


def _warm_up_lines(check, noise_sigma, final_sigma, name: str, key: str) -> list[str | Words]:
    """A drift flagged as warm-up: its rate, how far it moved the result, and the widened σ."""
    if check is None or not check.flagged or not check.shift or noise_sigma is None:
        return []
    rate = _f(check.rate, 4) if check.rate is not None else "—"
    spread = f" ± {_f(check.sigma, 4)}" if check.sigma is not None else ""
    moved = check.shift.get(key, 0.0)
    drift = f"{rate}{spread}"
    shift = f"ω̄_i − ḃ·(t̄_i − t̄)  →  Δ{name} = {_f(moved, 3)}°"
    return [
        f"ḃ = {drift} °/h²:  {shift}"
        if check.timed  # a clock: per hour; else per reading, said in words
        else Words("steps.drift_per_reading", {"drift": drift, "shift": shift}),
        f"σ = √({_f(noise_sigma, 3)}² + {_f(moved, 3)}²) = {_f(final_sigma, 3)}°",
    ]
