"""The handout's calculation written out with the student's numbers substituted.

Each :class:`Step` has a bilingual title and lines of mathematics (language-neutral), so
the command line, the pages and exports all show the same worked solution.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from app.core.solve import HeadingResult, LatitudeResult


@dataclass(frozen=True)
class Step:
    title: dict[str, str]
    lines: tuple[str, ...]
    sentence: dict[str, str] | None = None  # a conclusion in words, per language


def _f(value: float, digits: int = 3) -> str:
    return f"{value:.{digits}f}"


def _p(value: float, digits: int = 3) -> str:
    """A number in a formula: negatives in parentheses."""
    text = _f(value, digits)
    return f"({text})" if value < 0 else text


def _means_step(stats) -> Step:
    lines = [
        f"ω{i} = {_f(s.mean)} °/h   (n = {s.n}"
        + (f", s = {_f(s.std)}, s/√n = {_f(s.sem)})" if s.sem is not None else ")")
        for i, s in enumerate(stats, start=1)
    ]
    return Step(
        {"en": "Average the readings at each position", "zh-CN": "求各位置读数的平均值"},
        tuple(lines),
    )


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


def explain_heading(result: HeadingResult) -> list[Step]:
    fit = result.fit
    steps = [_means_step(fit.stats)]
    w = fit.means
    turn = _four_apart(fit.angles_deg)
    if turn:
        w1, w2, w3, w4 = w
        numerator = (w4 - w2) if turn < 0 else (w2 - w4)
        top = "ω4 − ω2" if turn < 0 else "ω2 − ω4"
        sub_top = f"{_p(w4)} − {_p(w2)}" if turn < 0 else f"{_p(w2)} − {_p(w4)}"
        ratio = numerator / (w1 - w3) if w1 != w3 else math.inf
        steps.append(
            Step(
                {"en": "The handout's angle θ", "zh-CN": "讲义中的角度 θ"},
                (
                    f"tan θ = ({top}) / (ω1 − ω3) = ({sub_top}) / ({_p(w1)} − {_p(w3)}) = "
                    f"{_f(ratio, 4)}",
                    f"θ = arctan({_f(ratio, 4)}) = {_f(result.theta_deg, 2)}°",
                ),
            )
        )
        x, y = (w1 - w3) / 2, ((w2 - w4) if turn < 0 else (w4 - w2)) / 2
        y_text = "(ω2 − ω4)/2" if turn < 0 else "(ω4 − ω2)/2"
        steps.append(
            Step(
                {
                    "en": "Full-circle azimuth of position 1 (no quadrant ambiguity)",
                    "zh-CN": "位置 1 的全圆周方位角（无象限模糊）",
                },
                (
                    f"x = (ω1 − ω3)/2 = {_f(x, 4)} °/h,   y = {y_text} = {_f(y, 4)} °/h",
                    f"A1 = atan2(y, x) = {_f(result.azimuth_deg, 2)}°  (clockwise from true north)",
                ),
            )
        )
    else:
        steps.append(
            Step(
                {"en": "Least-squares fit over all readings", "zh-CN": "对全部读数做最小二乘拟合"},
                (
                    "ω = a·cos α + c·sin α + b   (α = position angle, clockwise)",
                    f"a = {_f(fit.a, 4)}, c = {_f(fit.c, 4)}, b = {_f(fit.b, 4)} °/h",
                    f"A1 = atan2(−c, a) + α1 = {_f(result.azimuth_deg, 2)}°",
                    f"θ = {_f(result.theta_deg, 2)}°",
                ),
            )
        )
    direction = {
        "clockwise": ("clockwise", "顺时针"),
        "counterclockwise": ("counter-clockwise", "逆时针"),
    }[result.rotate_direction]
    points = {"north": ("north", "北"), "south": ("south", "南")}[result.then_axis_points]
    rotate = _f(result.rotate_deg, 2)
    steps.append(
        Step(
            {"en": "Find north on the table", "zh-CN": "在转台上找到北向"},
            (f"θ {'≥' if result.theta_deg >= 0 else '<'} 0,  |θ| = {rotate}°",),
            {
                "en": f"Turn the table {direction[0]} by {rotate}°: "
                f"the axis then points {points[0]}.",
                "zh-CN": f"将转台{direction[1]}转动 {rotate}°，此时陀螺轴指向{points[1]}。",
            },
        )
    )
    lines = [f"H = √(x² + y²) = {_f(result.amplitude_deg_h)} °/h,   b = {_f(fit.b)} °/h"]
    if result.closure_residual_deg_h is not None:
        lines.append(f"closure d = (ω1 + ω3 − ω2 − ω4)/2 = {_f(result.closure_residual_deg_h)} °/h")
    if result.azimuth_sigma_deg is not None:
        lines.append(f"σ_A = √(y²σx² + x²σy²)/H² = {_f(result.azimuth_sigma_deg, 3)}°")
    if result.azimuth_error_deg is not None:
        lines.append(f"error against the true azimuth = {_f(result.azimuth_error_deg, 2)}°")
    steps.append(
        Step(
            {"en": "Amplitude, bias and uncertainty", "zh-CN": "幅值、零偏与不确定度"}, tuple(lines)
        )
    )
    return steps


def explain_latitude(result: LatitudeResult) -> list[Step]:
    fit = result.fit
    steps = [_means_step(fit.stats)]
    phi = result.latitude_deg
    standard = fit.angles_deg.size == 4 and np.allclose(
        np.mod(fit.angles_deg, 360), [0, 90, 180, 270]
    )
    if standard:
        w1, w2, w3, w4 = fit.means
        steps.append(
            Step(
                {"en": "Latitude from the four positions", "zh-CN": "由四个位置求纬度"},
                (
                    f"tan φ = (ω2 − ω4)/(ω1 − ω3) = ({_p(w2)} − {_p(w4)}) / "
                    f"({_p(w1)} − {_p(w3)}) = "
                    f"{_f((w2 - w4) / (w1 - w3), 4) if w1 != w3 else '∞'}",
                    f"φ = {_f(phi, 2)}°",
                ),
            )
        )
        lines = [
            f"Ω = (ω1 − ω3)/(2 cos φ) = {_f((w1 - w3) / (2 * math.cos(math.radians(phi))))} °/h"
        ]
        if abs(math.sin(math.radians(phi))) > 1e-9:
            lines.append(
                f"Ω = (ω2 − ω4)/(2 sin φ) = {_f((w2 - w4) / (2 * math.sin(math.radians(phi))))} °/h"
            )
        lines.append(f"Ω = √((ω1 − ω3)² + (ω2 − ω4)²)/2 = {_f(result.earth_rate_deg_h)} °/h")
        steps.append(Step({"en": "Earth's rotation rate", "zh-CN": "地球自转角速度"}, tuple(lines)))
    else:
        steps.append(
            Step(
                {"en": "Least-squares fit over all readings", "zh-CN": "对全部读数做最小二乘拟合"},
                (
                    "ω = a·cos e + c·sin e + b   (e = elevation from the north horizon)",
                    f"a = {_f(fit.a, 4)}, c = {_f(fit.c, 4)}, b = {_f(fit.b, 4)} °/h",
                    f"φ = atan2(c, a) = {_f(phi, 2)}°,   Ω = √(a² + c²) = "
                    f"{_f(result.earth_rate_deg_h)} °/h",
                ),
            )
        )
    lines = []
    if result.latitude_error_percent is not None:
        lines.append(
            f"η_φ = |φ − φ0|/φ0 × 100% = |{_f(phi, 2)} − {_f(result.true_latitude_deg, 2)}|"
            f" / {_f(result.true_latitude_deg, 2)} × 100% = "
            f"{_f(result.latitude_error_percent, 2)}%"
        )
    lines.append(
        f"η_Ω = |Ω − Ω0|/Ω0 × 100% = |{_f(result.earth_rate_deg_h)} − "
        f"{_f(result.true_earth_rate_deg_h)}| / {_f(result.true_earth_rate_deg_h)} × "
        f"100% = {_f(result.earth_rate_error_percent, 2)}%"
    )
    if result.latitude_sigma_deg is not None:
        lines.append(
            f"1σ: φ ± {_f(result.latitude_sigma_deg, 3)}°,  Ω ± "
            f"{_f(result.earth_rate_sigma_deg_h, 3)} °/h"
        )
    steps.append(
        Step(
            {"en": "Percent errors and uncertainties", "zh-CN": "百分误差与不确定度"}, tuple(lines)
        )
    )
    return steps


def render_text(steps: list[Step], language: str = "en") -> str:
    out = []
    for number, step in enumerate(steps, start=1):
        out.append(f"{number}. {step.title.get(language, step.title['en'])}")
        out.extend(f"   {line}" for line in step.lines)
        if step.sentence:
            out.append(f"   {step.sentence.get(language, step.sentence['en'])}")
    return "\n".join(out)
