"""The two-position method (lab-reference §4): the heading from two readings 180° apart,
γ = arccos((U1 − U2)/(2KΩ cos φ)), with the tilt paper's pitch compensation."""

from __future__ import annotations

import math
from dataclasses import dataclass

from app.core.exceptions import UserError
from app.core.sinusoid import wrap360
from app.core.units import EARTH_RATE_DEG_H


@dataclass(frozen=True)
class TwoPositionResult:
    """γ from the two-position method and the east/west ambiguity it cannot resolve."""

    gamma_deg: float  # in [0°, 180°]
    candidates_deg: tuple[float, float]  # γ and 360° − γ
    ratio: float  # (U1 − U2) / (2 K Ω cos φ), clipped into [−1, 1] when within noise
    clipped: bool


def solve_two_position(
    u1: float,
    u2: float,
    *,
    scale_factor: float = 1.0,
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
    latitude_deg: float,
    pitch_deg: float = 0.0,
) -> TwoPositionResult:
    """The two-position method: γ = arccos((U1 − U2) / (2 K Ω cos φ)).

    With a measured table pitch p (the reference direction raised by p, as a north seeker's
    accelerometers report it) the vertical rate is compensated:
    cos γ = ((U1 − U2)/2K − Ω sin φ sin p) / (Ω cos φ cos p); roll cancels in U1 − U2.
    It needs K, Ω and φ; it cannot tell east from west (γ and 360° − γ fit equally); the
    derivative 1/sin γ makes it ill-conditioned near 0° and 180°.

    Parameters
    ----------
    u1, u2 : float
        The gyro's outputs at 0° and 180° (its own unit; ``scale_factor`` per °/h).
    scale_factor : float
        K, output per °/h.
    earth_rate_deg_h : float
        Ω (°/h).
    latitude_deg : float
        φ (°).
    pitch_deg : float
        The table's pitch p (°).

    Returns
    -------
    TwoPositionResult
        γ, both candidates (γ, 360° − γ), the cosine and whether it was clipped to ±1.

    References
    ----------
    lab-reference §4 (the tilt paper's two-position comparison).
    """
    phi, pitch = math.radians(latitude_deg), math.radians(pitch_deg)
    horizontal = 2.0 * scale_factor * earth_rate_deg_h * math.cos(phi) * math.cos(pitch)
    if horizontal <= 0:
        raise UserError("two_position.no_horizontal")
    vertical = 2.0 * scale_factor * earth_rate_deg_h * math.sin(phi) * math.sin(pitch)
    ratio = (u1 - u2 - vertical) / horizontal
    clipped = False
    if abs(ratio) > 1.0:
        if abs(ratio) > 1.05:
            raise UserError(
                "two_position.ratio",
                ratio=round(ratio, 4),
            )
        ratio, clipped = math.copysign(1.0, ratio), True
    gamma = math.degrees(math.acos(ratio))
    return TwoPositionResult(gamma, (gamma, wrap360(360.0 - gamma)), ratio, clipped)
