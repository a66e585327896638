"""N-position solver: heading (part A), latitude and Earth rate (part B), two-position method.

Model (lab-reference §3) and the least-squares fit: :mod:`app.core.sinusoid`.

Heading: ω_i = H·cos(A_1 + α_i) + b  ⇒  a = H cos A_1, c = −H sin A_1, so
A_1 = atan2(−c, a) mod 360° (no quadrant ambiguity), H = hypot(a, c).  For four positions
turned counter-clockwise this is A_1 = atan2((ω2−ω4)/2, (ω1−ω3)/2); the handout's
θ = arctan((ω4−ω2)/(ω1−ω3)) is −A_1 folded into (−90°, 90°].

Latitude: ω_i = Ω·cos(e_i − φ) + b  ⇒  a = Ω cos φ, c = Ω sin φ, φ = atan2(c, a),
Ω = hypot(a, c); for e = 0°, 90°, 180°, 270°: φ = atan2(ω2−ω4, ω1−ω3),
Ω = hypot(ω1−ω3, ω2−ω4)/2.  Percent errors as the handout defines them:
η_φ = |φ−φ0|/φ0·100 %, η_Ω = |Ω−Ω0|/Ω0·100 %.

Angle uncertainty (:mod:`app.core.polar`): for x = H cos A, y = H sin A,
σ_A = √(y²σx² + x²σy² − 2xy·cov)/H² (rad), σ_H = √(x²σx² + y²σy² + 2xy·cov)/H — the
general form of the reference's formula.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from app.core.drift_check import DriftCheck, drift_and_its_effect
from app.core.exceptions import UserError
from app.core.handout_terms import handout_theta, percent_error
from app.core.polar import check_significant, exact_angle_sigma, fit_scale, polar
from app.core.sinusoid import SinusoidFit, fit_sinusoid, wrap180, wrap360
from app.core.units import EARTH_RATE_DEG_H


@dataclass(frozen=True)
class HeadingResult:
    """Part A.  ``to_json()`` gives exactly the keys of ``gyrolab solve heading --json``."""

    fit: SinusoidFit
    azimuth_deg: float
    azimuth_sigma_deg: float | None
    amplitude_deg_h: float
    amplitude_sigma_deg_h: float | None
    theta_deg: float
    rotate_direction: str
    rotate_deg: float
    then_axis_points: str
    closure_residual_deg_h: float | None
    azimuth_error_deg: float | None = None
    notes: tuple[str, ...] = field(default=())
    drift_check: DriftCheck | None = None
    noise_sigma_deg: float | None = None  # the σ before a flagged drift widened it
    linear_sigma_deg: float | None = None  # the propagated (linearised) σ
    exact_sigma_deg: float | None = None  # the exact half-width, H known
    expected_amplitude_deg_h: float | None = None  # that H

    @property
    def bias_deg_h(self) -> float:
        return self.fit.b

    @property
    def bias_sigma_deg_h(self) -> float | None:
        return self.fit.bias_sigma

    def to_json(self) -> dict:
        return {
            "part": "heading",
            "n_positions": len(self.fit.stats),
            "samples_per_position": [s.n for s in self.fit.stats],
            "position_means_deg_h": [s.mean for s in self.fit.stats],
            "position_sems_deg_h": [s.sem for s in self.fit.stats],
            "position_sigmas_deg_h": self.fit.position_sigmas,
            "azimuth_deg": self.azimuth_deg,
            "azimuth_sigma_deg": self.azimuth_sigma_deg,
            "theta_deg": self.theta_deg,
            "rotate_direction": self.rotate_direction,
            "rotate_deg": self.rotate_deg,
            "then_axis_points": self.then_axis_points,
            "bias_deg_h": self.fit.b,
            "bias_sigma_deg_h": self.bias_sigma_deg_h,
            "amplitude_deg_h": self.amplitude_deg_h,
            "amplitude_sigma_deg_h": self.amplitude_sigma_deg_h,
            "closure_residual_deg_h": self.closure_residual_deg_h,
            "closure_sigma_deg_h": self.fit.closure_sigma,
            "uncertainty_model": self.fit.uncertainty_model,
            "drift_deg_h_per_h": self.fit.drift,
            "drift_sigma_deg_h_per_h": self.fit.drift_sigma,
            "azimuth_error_deg": self.azimuth_error_deg,
            "azimuth_noise_sigma_deg": self.noise_sigma_deg,
            "warm_up": None if self.drift_check is None else self.drift_check.to_json(),
        }


def solve_heading(
    positions: Sequence[Sequence[float]],
    angles_deg: Sequence[float],
    *,
    true_azimuth_deg: float | None = None,
    position_cov: np.ndarray | None = None,
    indexing_sigma_deg: float = 0.0,
    times_s: Sequence[Sequence[float]] | None = None,
    temperatures_c: Sequence[Sequence[float]] | None = None,
    expected_amplitude_deg_h: float | None = None,
    warm_up_cov: np.ndarray | None = None,
) -> HeadingResult:
    """Azimuth of position 1 (clockwise from true north, [0°, 360°)) with its 1σ.

    Fits ω_i = H·cos(A_1 + α_i) + b (:func:`app.core.sinusoid.fit_sinusoid`):
    A_1 = atan2(−c, a) mod 360°, H = hypot(a, c), and
    σ_A = √(y²σx² + x²σy² − 2xy·cov)/H_c² with the Rice-corrected amplitude
    H_c² = H² − σx² − σy² (floored at H²/4).

    Parameters
    ----------
    positions : sequence of sequences of float
        Each position's readings (°/h), in the order recorded.
    angles_deg : sequence of float
        Each position's axis azimuth relative to position 1 (°, clockwise positive).
    true_azimuth_deg : float, optional
        The known azimuth of position 1 (°), for the error.
    position_cov : numpy.ndarray, optional
        The position means' covariance from a known noise model ((°/h)²); default: from the
        readings (white noise with Student-t, or the closure residual).
    indexing_sigma_deg : float
        The turntable's indexing error, 1σ (°), added for every stop after the first.
    times_s : sequence of sequences of float, optional
        Each reading's time (s, one clock): with 5+ positions a linear drift is fitted.
    temperatures_c : sequence of sequences of float, optional
        Each reading's case temperature (°C), for the warm-up check.
    expected_amplitude_deg_h : float, optional
        H = Ω cos φ at the known station (°/h): the azimuth's σ is then the exact 68 %
        half-width of its posterior (:mod:`app.core.angle_posterior`).
    warm_up_cov : numpy.ndarray, optional
        The warm-up's part of ``position_cov`` (a known noise model on a timeline from
        switch-on), for the warm-up check.

    Returns
    -------
    HeadingResult
        Azimuth, θ and turn, bias, amplitude H, 1σ of each, closure and drift.

    Raises
    ------
    UserError
        Too few readings or positions, non-finite values, or an amplitude below 3σ.

    References
    ----------
    lab-reference §3; the handout's four-position method (part A).
    """
    fit = fit_sinusoid(
        positions,
        angles_deg,
        position_cov=position_cov,
        indexing_sigma_deg=indexing_sigma_deg,
        times_s=times_s,
    )
    cov_xy = None
    if fit.cov is not None:
        # (x, y) = (a, −c): flip the sign of c's covariance terms.
        flip = np.diag([1.0, -1.0])
        cov_xy = flip @ fit.cov[:2, :2] @ flip
    angle_ref, amplitude, linear_az, sigma_amp = polar(fit.a, -fit.c, cov_xy)
    check_significant(amplitude, sigma_amp, "horizontal", fit_scale(fit))
    exact = exact_angle_sigma(fit.a, -fit.c, cov_xy, expected_amplitude_deg_h, sigma_amp)
    sigma_az = exact if exact is not None else linear_az
    azimuth = wrap360(angle_ref + float(fit.angles_deg[0]))
    theta, direction, rotate, points = handout_theta(azimuth)
    check, shift = drift_and_its_effect(
        positions, fit, times_s, temperatures_c, "heading", angles_deg, warm_up_cov
    )
    noise_sigma = sigma_az
    if check is not None and check.flagged and shift is not None and sigma_az is not None:
        moved = wrap180(azimuth - shift[0])
        check = replace(check, shift={"azimuth_deg": moved})
        sigma_az = math.hypot(sigma_az, moved)
    error = None if true_azimuth_deg is None else wrap180(azimuth - true_azimuth_deg)
    return HeadingResult(
        fit=fit,
        azimuth_deg=azimuth,
        azimuth_sigma_deg=sigma_az,
        amplitude_deg_h=amplitude,
        amplitude_sigma_deg_h=sigma_amp,
        theta_deg=theta,
        rotate_direction=direction,
        rotate_deg=rotate,
        then_axis_points=points,
        closure_residual_deg_h=fit.closure_residual,
        azimuth_error_deg=error,
        drift_check=check,
        noise_sigma_deg=noise_sigma,
        linear_sigma_deg=linear_az,
        exact_sigma_deg=exact,
        expected_amplitude_deg_h=expected_amplitude_deg_h if exact is not None else None,
    )


@dataclass(frozen=True)
class LatitudeResult:
    """Part B.  ``to_json()`` gives exactly the keys of ``gyrolab solve latitude --json``."""

    fit: SinusoidFit
    latitude_deg: float
    latitude_sigma_deg: float | None
    earth_rate_deg_h: float
    earth_rate_sigma_deg_h: float | None
    true_latitude_deg: float | None
    true_earth_rate_deg_h: float
    latitude_error_percent: float | None
    earth_rate_error_percent: float
    drift_check: DriftCheck | None = None
    noise_sigmas: tuple[float | None, float | None] = (None, None)  # before a drift widened
    linear_sigma_deg: float | None = None  # the propagated (linearised) σ of φ
    exact_sigma_deg: float | None = None  # its exact half-width, Ω known

    @property
    def bias_deg_h(self) -> float:
        return self.fit.b

    @property
    def bias_sigma_deg_h(self) -> float | None:
        return self.fit.bias_sigma

    @property
    def latitude_error_deg(self) -> float | None:
        """φ − φ0 in degrees: meaningful near the equator, where the percent explodes."""
        if self.true_latitude_deg is None:
            return None
        return self.latitude_deg - self.true_latitude_deg

    def to_json(self) -> dict:
        return {
            "part": "latitude",
            "n_positions": len(self.fit.stats),
            "samples_per_position": [s.n for s in self.fit.stats],
            "position_means_deg_h": [s.mean for s in self.fit.stats],
            "position_sems_deg_h": [s.sem for s in self.fit.stats],
            "position_sigmas_deg_h": self.fit.position_sigmas,
            "latitude_deg": self.latitude_deg,
            "latitude_sigma_deg": self.latitude_sigma_deg,
            "earth_rate_deg_h": self.earth_rate_deg_h,
            "earth_rate_sigma_deg_h": self.earth_rate_sigma_deg_h,
            "bias_deg_h": self.fit.b,
            "bias_sigma_deg_h": self.bias_sigma_deg_h,
            "latitude_error_percent": self.latitude_error_percent,
            "latitude_error_deg": self.latitude_error_deg,
            "earth_rate_error_percent": self.earth_rate_error_percent,
            "closure_residual_deg_h": self.fit.closure_residual,
            "closure_sigma_deg_h": self.fit.closure_sigma,
            "uncertainty_model": self.fit.uncertainty_model,
            "drift_deg_h_per_h": self.fit.drift,
            "drift_sigma_deg_h_per_h": self.fit.drift_sigma,
            "latitude_noise_sigma_deg": self.noise_sigmas[0],
            "earth_rate_noise_sigma_deg_h": self.noise_sigmas[1],
            "warm_up": None if self.drift_check is None else self.drift_check.to_json(),
        }


def solve_latitude(
    positions: Sequence[Sequence[float]],
    elevations_deg: Sequence[float],
    *,
    true_latitude_deg: float | None = None,
    true_earth_rate_deg_h: float = EARTH_RATE_DEG_H,
    position_cov: np.ndarray | None = None,
    indexing_sigma_deg: float = 0.0,
    times_s: Sequence[Sequence[float]] | None = None,
    temperatures_c: Sequence[Sequence[float]] | None = None,
    warm_up_cov: np.ndarray | None = None,
) -> LatitudeResult:
    """Latitude φ and Earth rate Ω from readings in the meridian plane, with 1σ.

    Fits ω_i = Ω·cos(e_i − φ) + b: φ = atan2(c, a), Ω = hypot(a, c); for elevations
    0°, 90°, 180°, 270°: φ = atan2(ω2 − ω4, ω1 − ω3), Ω = hypot(ω1 − ω3, ω2 − ω4)/2.

    Parameters
    ----------
    positions : sequence of sequences of float
        Each position's readings (°/h).
    elevations_deg : sequence of float
        Each position's axis elevation in the meridian plane (°; 0° north horizon, 90° up).
    true_latitude_deg : float, optional
        The station's latitude φ0 (°), for η_φ.
    true_earth_rate_deg_h : float
        Ω0 (°/h), for η_Ω; default the sidereal rate 15.041 °/h.
    position_cov, indexing_sigma_deg, times_s, temperatures_c, warm_up_cov
        As for :func:`solve_heading`.

    Returns
    -------
    LatitudeResult
        φ, Ω, bias, their 1σ, percent errors η_φ and η_Ω, closure and drift.

    Raises
    ------
    UserError
        Too few readings or positions, non-finite values, or Ω below 3σ.

    References
    ----------
    lab-reference §3; the handout, part B.
    """
    if true_earth_rate_deg_h <= 0 or not math.isfinite(true_earth_rate_deg_h):
        raise UserError("station.bad_earth_rate")
    fit = fit_sinusoid(
        positions,
        elevations_deg,
        position_cov=position_cov,
        indexing_sigma_deg=indexing_sigma_deg,
        times_s=times_s,
    )
    cov_xy = None if fit.cov is None else fit.cov[:2, :2]
    latitude, omega, linear_lat, sigma_omega = polar(fit.a, fit.c, cov_xy)
    check_significant(omega, sigma_omega, "Earth-rate", fit_scale(fit))
    exact = exact_angle_sigma(fit.a, fit.c, cov_xy, true_earth_rate_deg_h, sigma_omega)
    sigma_lat = exact if exact is not None else linear_lat
    if abs(latitude) > 90.0:
        raise UserError(
            "readings.latitude_out_of_range",
            latitude=round(latitude, 2),
        )
    check, shift = drift_and_its_effect(
        positions, fit, times_s, temperatures_c, "latitude", elevations_deg, warm_up_cov
    )
    noise_sigmas = (sigma_lat, sigma_omega)
    if check is not None and check.flagged and shift is not None and sigma_lat is not None:
        moved_lat, moved_omega = latitude - shift[0], omega - shift[1]
        check = replace(check, shift={"latitude_deg": moved_lat, "earth_rate_deg_h": moved_omega})
        sigma_lat = math.hypot(sigma_lat, moved_lat)
        sigma_omega = math.hypot(sigma_omega, moved_omega)
    return LatitudeResult(
        drift_check=check,
        noise_sigmas=noise_sigmas,
        linear_sigma_deg=linear_lat,
        exact_sigma_deg=exact,
        fit=fit,
        latitude_deg=latitude,
        latitude_sigma_deg=sigma_lat,
        earth_rate_deg_h=omega,
        earth_rate_sigma_deg_h=sigma_omega,
        true_latitude_deg=true_latitude_deg,
        true_earth_rate_deg_h=true_earth_rate_deg_h,
        latitude_error_percent=percent_error(latitude, true_latitude_deg),
        earth_rate_error_percent=percent_error(omega, true_earth_rate_deg_h),
    )
