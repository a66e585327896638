"""A direction and its size from the fit's two cosine terms, with their uncertainties.

For x = H cos A, y = H sin A with covariance C: A = atan2(y, x), H = hypot(x, y),
σ_A = √(y²σx² + x²σy² − 2xy·σxy)/H² (rad), σ_H = √(x²σx² + y²σy² + 2xy·σxy)/H
(lab-reference §3, the general form of its formula); the exact 68 % half-width where H is
known beforehand (:mod:`app.core.angle_posterior`); and the refusal of an H too small to
give a direction.
"""

from __future__ import annotations

import math

import numpy as np

from app.core.angle_posterior import angle_half_width
from app.core.exceptions import UserError
from app.core.sinusoid import SIGNIFICANCE, SinusoidFit


def polar(
    x: float, y: float, cov_xy: np.ndarray | None
) -> tuple[float, float, float | None, float | None]:
    """Angle (deg) and amplitude of (x, y) with 1σ uncertainties from their 2×2 covariance.

    σ²_angle = (y²σ²x + x²σ²y − 2xy·σxy)/(H²·H_c²), the linearised propagation with one
    factor H² replaced by the noise-bias-corrected H_c² = H² − σ²x − σ²y (E[Ĥ²] = H² + σ²x +
    σ²y, the Rice bias), floored at H²/4.  At high signal-to-noise H_c = H; near the
    significance limit the measured H is inflated by the noise and the plain formula is
    over-confident (a consumer MEMS at 300 s: 64 % coverage instead of 68 %).  Where the
    amplitude is known beforehand (Ω cos φ at a known station, or Ω) the solvers replace
    the angle's σ by the exact 68 % half-width of its posterior (:func:`exact_angle_sigma`).

    Parameters
    ----------
    x, y : float
        The fit's cosine and sine terms (°/h): x = H cos A, y = H sin A.
    cov_xy : numpy.ndarray or None
        Their 2×2 covariance ((°/h)²), or None where the data give none.

    Returns
    -------
    angle : float
        A = atan2(y, x) (°).
    amplitude : float
        H = hypot(x, y) (°/h).
    sigma_angle, sigma_amplitude : float or None
        Their 1σ (°, °/h); None without a covariance or where H = 0.

    References
    ----------
    lab-reference §3; Rice, Bell Syst. Tech. J. 24 (1945) 46 (the amplitude's noise bias).
    """
    amplitude = math.hypot(x, y)
    angle = math.degrees(math.atan2(y, x))
    if cov_xy is None or amplitude == 0.0:
        return angle, amplitude, None, None
    vx, vy, vxy = cov_xy[0, 0], cov_xy[1, 1], cov_xy[0, 1]
    corrected = max(amplitude**2 - vx - vy, 0.25 * amplitude**2)
    var_angle = (y * y * vx + x * x * vy - 2 * x * y * vxy) / (amplitude**2 * corrected)
    var_amp = (x * x * vx + y * y * vy + 2 * x * y * vxy) / amplitude**2
    sigma_angle = math.degrees(math.sqrt(max(var_angle, 0.0)))
    sigma_amp = math.sqrt(max(var_amp, 0.0))
    return angle, amplitude, sigma_angle, sigma_amp


def exact_angle_sigma(
    x: float,
    y: float,
    cov_xy: np.ndarray | None,
    known_amplitude: float | None,
    sigma_amp: float | None,
) -> float | None:
    """The angle's exact 68 % half-width given the known amplitude, or None.

    Parameters
    ----------
    x, y : float
        The fit's cosine and sine terms (°/h).
    cov_xy : numpy.ndarray or None
        Their 2×2 covariance ((°/h)²).
    known_amplitude : float or None
        The amplitude known beforehand (°/h): Ω cos φ at a known station, or Ω.
    sigma_amp : float or None
        The measured amplitude's 1σ (°/h).

    Returns
    -------
    float or None
        The half-width (°) of the posterior's central 68 %
        (:func:`app.core.angle_posterior.angle_half_width`); None where any input is
        missing.
    """
    if known_amplitude is None or cov_xy is None or sigma_amp is None:
        return None
    return angle_half_width(x, y, cov_xy, known_amplitude, sigma_amp)


def check_significant(amplitude: float, sigma: float | None, what: str, scale: float) -> None:
    """Refuse an amplitude that is zero (to rounding) or below 3σ: its direction would be
    noise.

    Parameters
    ----------
    amplitude : float
        H or Ω from the fit (°/h).
    sigma : float or None
        Its 1σ (°/h).
    what : str
        Which amplitude ("horizontal", "Earth-rate"), for the reader of the code.
    scale : float
        The readings' size (:func:`fit_scale`): zero to rounding is 10⁻⁹ of it.

    Returns
    -------
    None

    Raises
    ------
    UserError
        ``readings.amplitude_too_small`` with the amplitude and its σ.
    """
    if amplitude <= 1e-9 * max(scale, 1e-300) or (
        sigma is not None and amplitude < SIGNIFICANCE * sigma
    ):
        raise UserError(
            "readings.amplitude_too_small",
            amplitude=round(amplitude, 4),
            sigma=round(sigma, 4) if sigma is not None and math.isfinite(sigma) else None,
        )


def fit_scale(fit: SinusoidFit) -> float:
    """The largest |position mean| (°/h): what "zero to rounding" is relative to.

    Parameters
    ----------
    fit : SinusoidFit
        The N-position fit.

    Returns
    -------
    float
        max |ω̄_i| (°/h), 0 without positions.
    """
    return float(np.max(np.abs(fit.means))) if fit.means.size else 0.0
