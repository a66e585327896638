"""The handout's own terms: θ and which way to turn the table to north (part A), and the
percent errors η of the latitude and Earth rate (part B).

θ = arctan((ω4 − ω2)/(ω1 − ω3)) for four counter-clockwise positions, i.e. −A_1 folded into
(−90°, 90°]; η = |x − x0|/x0 × 100 % (the handout, ``../shared/seeds``; lab-reference §3).
"""

from __future__ import annotations

import math


def handout_theta(azimuth_deg: float) -> tuple[float, str, float, str]:
    """The handout's θ, turn direction, |θ| and where the axis then points.

    θ = arctan(−y/x) with x = H cos A_1, y = H sin A_1 (for four counter-clockwise
    positions: arctan((ω4−ω2)/(ω1−ω3))).  Turning the table by θ (clockwise positive)
    brings the axis to A_1 + θ ∈ {0°, 180°}: north when x > 0, south when x < 0.

    Parameters
    ----------
    azimuth_deg : float
        A_1, the azimuth of position 1 (°, clockwise from true north).

    Returns
    -------
    theta_deg : float
        θ in (−90°, 90°].
    direction : {"clockwise", "counterclockwise"}
        Which way to turn the table by |θ|.
    turn_deg : float
        |θ| (°).
    axis : {"north", "south"}
        Where the sensitive axis then points.

    References
    ----------
    The handout, part A (``../shared/seeds``); lab-reference §3.
    """
    x = math.cos(math.radians(azimuth_deg))
    y = math.sin(math.radians(azimuth_deg))
    if abs(x) < 1e-12:  # exactly east or west: a quarter turn reaches north
        theta = -90.0 if y > 0 else 90.0
        points = "north"
    else:
        theta = math.degrees(math.atan(-y / x))
        points = "north" if x > 0 else "south"
    direction = "clockwise" if theta >= 0 else "counterclockwise"
    return theta, direction, abs(theta), points


def percent_error(value: float, true_value: float | None) -> float | None:
    """The handout's η = |value − true| / |true| × 100 %.

    Parameters
    ----------
    value : float
        The measured value (latitude in °, or Earth rate in °/h).
    true_value : float or None
        The true value in the same unit.

    Returns
    -------
    float or None
        η in percent; None when the true value is 0 or unknown.

    References
    ----------
    The handout, part B: η_φ = |φ − φ0|/φ0 × 100 %, η_Ω = |Ω − Ω0|/Ω0 × 100 %.
    """
    if true_value is None or true_value == 0:
        return None
    return abs(value - true_value) / abs(true_value) * 100.0
