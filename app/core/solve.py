"""N-position solver: heading (part A), latitude and Earth rate (part B), two-position method.

Model (lab-reference §3).  Position i has a known angle α_i (heading part: axis azimuth
relative to position 1, clockwise positive seen from above; latitude part: axis elevation
e_i in the meridian plane, 0° = north horizon, 90° = up).  Every reading is

    ω = a·cos α + c·sin α + b + noise

and (a, c, b) come from least squares over all samples.  With n_i samples and mean m_i at
position i this is the weighted fit of the means, β = (XᵀNX)⁻¹XᵀN·m, N = diag(n_i), so
the 1σ covariance propagated from the positions' standard errors s_i/√n_i is
Cov β = L·diag(s_i²/n_i)·Lᵀ with L = (XᵀNX)⁻¹XᵀN.

Heading: ω_i = H·cos(A_1 + α_i) + b  ⇒  a = H cos A_1, c = −H sin A_1, so
A_1 = atan2(−c, a) mod 360° (no quadrant ambiguity), H = hypot(a, c).  For four positions
turned counter-clockwise this is A_1 = atan2((ω2−ω4)/2, (ω1−ω3)/2); the handout's
θ = arctan((ω4−ω2)/(ω1−ω3)) is −A_1 folded into (−90°, 90°].

Latitude: ω_i = Ω·cos(e_i − φ) + b  ⇒  a = Ω cos φ, c = Ω sin φ, φ = atan2(c, a),
Ω = hypot(a, c); for e = 0°, 90°, 180°, 270°: φ = atan2(ω2−ω4, ω1−ω3),
Ω = hypot(ω1−ω3, ω2−ω4)/2.  Percent errors as the handout defines them:
η_φ = |φ−φ0|/φ0·100 %, η_Ω = |Ω−Ω0|/Ω0·100 %.

Angle uncertainty: for x = H cos A, y = H sin A, σ_A = √(y²σx² + x²σy² − 2xy·cov)/H²
(rad), σ_H = √(x²σx² + y²σy² + 2xy·cov)/H — the general form of the reference's formula.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from app.core.exceptions import UserError
from app.core.uncertainty import PositionNoise, closure_residual, position_noise
from app.core.units import EARTH_RATE_DEG_H

SIGNIFICANCE = 3.0  # an amplitude below 3σ is not a measurement of anything
MAX_RATE_DEG_H = 1e12  # far beyond any gyro; past it sums and squares would overflow
MAX_ANGLE_DEG = 3600.0  # ten turns of a dial: anything beyond is a typing mistake
ROTATIONS = ("ccw", "cw")


@dataclass(frozen=True)
class PositionStats:
    """Per-position summary: count, mean, sample std (ddof=1) and standard error."""

    n: int
    mean: float
    std: float | None
    sem: float | None


@dataclass(frozen=True)
class SinusoidFit:
    a: float
    c: float
    b: float
    cov: np.ndarray | None  # 3×3 covariance of (a, c, b), None when nothing estimates it
    angles_deg: np.ndarray
    stats: tuple[PositionStats, ...]
    noise: PositionNoise | None = None  # the position means' 1σ and its model
    drift: float | None = None  # ḃ (°/h per hour) when the schedule lets it be fitted

    @property
    def means(self) -> np.ndarray:
        return np.array([s.mean for s in self.stats])

    @property
    def drift_sigma(self) -> float | None:
        if self.drift is None or self.cov is None or self.cov.shape[0] < 4:
            return None
        return float(math.sqrt(max(self.cov[3, 3], 0.0)))

    @property
    def position_sigmas(self) -> list[float] | None:
        """The 1σ(-equivalent) of each position mean that the fit propagates."""
        return None if self.noise is None else [float(x) for x in self.noise.sigmas]

    @property
    def uncertainty_model(self) -> str | None:
        return None if self.noise is None else self.noise.model

    @property
    def closure_residual(self) -> float | None:
        return closure_residual(self.angles_deg, self.means)

    @property
    def closure_sigma(self) -> float | None:
        """σ_d = √(σ1² + σ2² + σ3² + σ4²)/2 (None without four positions 90° apart)."""
        if self.noise is None or self.closure_residual is None:
            return None
        return float(math.sqrt(float(np.sum(self.noise.variances))) / 2)

    @property
    def closure_consistent(self) -> bool | None:
        """|d| ≤ 3σ_d: the noise is what the σ assumes (None when d itself gave σ)."""
        sigma = self.closure_sigma
        if sigma is None or self.uncertainty_model == "closure" or sigma == 0:
            return None
        return abs(self.closure_residual) <= SIGNIFICANCE * sigma


def position_stats(samples: np.ndarray) -> PositionStats:
    n = int(samples.size)
    mean = float(samples.mean())
    if n < 2:
        return PositionStats(n, mean, None, None)
    std = float(samples.std(ddof=1))
    return PositionStats(n, mean, std, std / math.sqrt(n))


def wrap180(angle_deg: float) -> float:
    """Wrap an angle to (−180°, 180°]."""
    wrapped = math.fmod(angle_deg, 360.0)
    if wrapped <= -180.0:
        wrapped += 360.0
    elif wrapped > 180.0:
        wrapped -= 360.0
    return wrapped


def wrap360(angle_deg: float) -> float:
    """Wrap an angle to [0°, 360°) (a tiny negative rounds to 0, never to 360)."""
    wrapped = angle_deg % 360.0
    return 0.0 if wrapped >= 360.0 else wrapped


def heading_angles(
    n_positions: int, rotation: str = "ccw", start_deg: float = 0.0, step_deg: float = 90.0
) -> np.ndarray:
    """Axis azimuths relative to the reference, clockwise positive: counter-clockwise turns
    give start, start−step, ...; clockwise turns give start, start+step, ..."""
    if rotation not in ROTATIONS:
        raise UserError(
            "rotation.unknown",
            f"Rotation must be 'ccw' or 'cw', not {rotation!r}.",
            rotation=rotation,
        )
    _check_schedule(start_deg, step_deg)
    sign = -1.0 if rotation == "ccw" else 1.0
    return start_deg + sign * step_deg * np.arange(n_positions)


def _check_schedule(start_deg: float, step_deg: float) -> None:
    """A start angle within ±3600° and a step within ±360° (finite), else a range message."""
    if not (math.isfinite(start_deg) and abs(start_deg) <= MAX_ANGLE_DEG):
        raise UserError(
            "angles.start_out_of_range",
            f"The start angle must be a number of degrees within ±{MAX_ANGLE_DEG:g}.",
            limit=MAX_ANGLE_DEG,
        )
    if not (math.isfinite(step_deg) and abs(step_deg) <= 360.0):
        raise UserError(
            "angles.step_out_of_range", "The step between positions must be within ±360°."
        )


def elevation_angles(
    n_positions: int, start_deg: float = 0.0, step_deg: float = 90.0
) -> np.ndarray:
    """Axis elevations in the meridian plane: start, start+step, ... (0° north, 90° up)."""
    _check_schedule(start_deg, step_deg)
    return start_deg + step_deg * np.arange(n_positions)


def _clean_positions(positions: Sequence[Sequence[float]]) -> list[np.ndarray]:
    arrays = []
    for index, samples in enumerate(positions, start=1):
        try:
            array = np.asarray(samples, dtype=float).ravel()
        except (TypeError, ValueError) as error:
            raise UserError(
                "readings.not_numbers",
                f"Position {index} has readings that are not numbers.",
                position=index,
            ) from error
        if array.size == 0:
            raise UserError(
                "readings.empty_position", f"Position {index} has no readings.", position=index
            )
        if not np.all(np.isfinite(array)):
            raise UserError(
                "readings.not_finite",
                f"Position {index} has a reading that is not a finite number (NaN or infinity).",
                position=index,
            )
        if np.any(np.abs(array) > MAX_RATE_DEG_H):
            raise UserError(
                "readings.out_of_range",
                "A reading is out of range for an angular rate: check the unit.",
                position=index,
            )
        arrays.append(array)
    return arrays


def fit_sinusoid(
    positions: Sequence[Sequence[float]],
    angles_deg: Sequence[float],
    *,
    position_cov: np.ndarray | None = None,
    indexing_sigma_deg: float = 0.0,
    times_s: Sequence[Sequence[float]] | None = None,
) -> SinusoidFit:
    """Least-squares fit of ω = a·cos α + c·sin α + b over every sample, with covariance
    Cov β = L·Σ·Lᵀ propagated from the position means' covariance Σ
    (:func:`app.core.uncertainty.position_noise`: white noise with Student-t, the closure
    residual, or a known noise model's ``position_cov``).

    ``indexing_sigma_deg``: each stop after the first lands off by N(0, σ_idx), which moves
    its reading by ∂ω/∂α·δ = (−a·sin α + c·cos α)·δ; that variance joins Σ's diagonal.

    ``times_s`` (each sample's time on one clock): with five or more positions (e.g. the
    symmetric order 1-2-3-4-4-3-2-1) a linear bias drift is fitted too,
    ω = a·cos α + c·sin α + b + ḃ·(t − t̄); a position's mean is then the model at its
    mean time, so the fit of the means stays exact (lab-reference §3, drift)."""
    arrays = _clean_positions(positions)
    angles = np.asarray(angles_deg, dtype=float)
    if angles.shape != (len(arrays),):
        raise UserError(
            "readings.angle_count",
            f"There are {len(arrays)} positions but {angles.size} angles.",
            positions=len(arrays),
            angles=int(angles.size),
        )
    if not np.all(np.isfinite(angles)):
        raise UserError("readings.angle_not_finite", "A position angle is not a finite number.")
    distinct = np.unique(np.round(np.mod(angles, 360.0), 6) % 360.0)
    if distinct.size < 3:
        raise UserError(
            "readings.too_few_angles",
            f"At least 3 different angles are needed; got {distinct.size}.",
            distinct=int(distinct.size),
        )
    stats = tuple(position_stats(a) for a in arrays)
    counts = np.array([s.n for s in stats], dtype=float)
    means = np.array([s.mean for s in stats])
    radians = np.radians(angles)
    design = np.column_stack([np.cos(radians), np.sin(radians), np.ones_like(radians)])
    clock = _mean_times_h(times_s, arrays)
    if clock is not None:
        with_drift = np.column_stack([design, clock])
        drift_normal = with_drift.T @ (counts[:, None] * with_drift)
        if np.linalg.cond(drift_normal) < 1e10:
            design = with_drift
    normal = design.T @ (counts[:, None] * design)
    if np.linalg.cond(normal) > 1e12:
        raise UserError(
            "readings.too_few_angles",
            "The angles do not determine a sinusoid; use 3 or more different "
            "angles spread around the circle.",
            distinct=int(distinct.size),
        )
    mapping = np.linalg.solve(normal, design.T * counts)  # L = (XᵀNX)⁻¹XᵀN
    a, c, b, *rest = mapping @ means
    noise = position_noise(arrays, angles, position_cov=position_cov)
    if noise is not None and indexing_sigma_deg > 0:
        slope = -a * np.sin(radians) + c * np.cos(radians)  # ∂ω/∂α at each stop, per rad
        extra = (slope * math.radians(indexing_sigma_deg)) ** 2
        extra[0] = 0.0  # the first stop is the reference
        noise = PositionNoise(noise.cov + np.diag(extra), noise.model)
    cov = None if noise is None else mapping @ noise.cov @ mapping.T
    drift = float(rest[0]) if rest else None
    return SinusoidFit(float(a), float(c), float(b), cov, angles, stats, noise, drift)


MIN_POSITIONS_FOR_DRIFT = 5


def _mean_times_h(
    times_s: Sequence[Sequence[float]] | None, arrays: list[np.ndarray]
) -> np.ndarray | None:
    """Each position's mean time in hours from the schedule's mean (None when the times
    are missing, do not match the readings, or the schedule is too short for a drift)."""
    if times_s is None or len(arrays) < MIN_POSITIONS_FOR_DRIFT or len(times_s) != len(arrays):
        return None
    means = []
    for times, values in zip(times_s, arrays, strict=True):
        stamps = np.asarray(times, dtype=float).ravel()
        if stamps.size != values.size or not np.all(np.isfinite(stamps)):
            return None
        means.append(float(stamps.mean()))
    hours = np.asarray(means) / 3600.0
    return hours - hours.mean()


def _polar(
    x: float, y: float, cov_xy: np.ndarray | None
) -> tuple[float, float, float | None, float | None]:
    """Angle (deg) and amplitude of (x, y) with 1σ uncertainties from their 2×2 covariance.

    σ²_angle = (y²σ²x + x²σ²y − 2xy·σxy)/(H²·H_c²), the linearised propagation with one
    factor H² replaced by the noise-bias-corrected H_c² = H² − σ²x − σ²y (E[Ĥ²] = H² + σ²x +
    σ²y, the Rice bias), floored at H²/4.  At high signal-to-noise H_c = H; near the
    significance limit the measured H is inflated by the noise and the plain formula is
    over-confident (a consumer MEMS at 300 s: 64 % coverage instead of 68 %)."""
    amplitude = math.hypot(x, y)
    angle = math.degrees(math.atan2(y, x))
    if cov_xy is None or amplitude == 0.0:
        return angle, amplitude, None, None
    vx, vy, vxy = cov_xy[0, 0], cov_xy[1, 1], cov_xy[0, 1]
    corrected = max(amplitude**2 - vx - vy, 0.25 * amplitude**2)
    var_angle = (y * y * vx + x * x * vy - 2 * x * y * vxy) / (amplitude**2 * corrected)
    var_amp = (x * x * vx + y * y * vy + 2 * x * y * vxy) / amplitude**2
    return (
        angle,
        amplitude,
        math.degrees(math.sqrt(max(var_angle, 0.0))),
        math.sqrt(max(var_amp, 0.0)),
    )


def _check_significant(amplitude: float, sigma: float | None, what: str, scale: float) -> None:
    """Refuse an amplitude that is zero (to rounding) or below 3σ."""
    if amplitude <= 1e-9 * max(scale, 1e-300) or (
        sigma is not None and amplitude < SIGNIFICANCE * sigma
    ):
        sigma_text = f" ± {sigma:.3g}" if sigma is not None and math.isfinite(sigma) else ""
        raise UserError(
            "readings.amplitude_too_small",
            f"The {what} amplitude ({amplitude:.3g}{sigma_text} °/h) is not clearly larger than "
            "its uncertainty, so the direction cannot be determined. Take more readings per "
            "position or use a less noisy gyro.",
            amplitude=round(amplitude, 4),
            sigma=None if sigma is None else round(sigma, 4),
        )


def _scale(fit: SinusoidFit) -> float:
    return float(np.max(np.abs(fit.means))) if fit.means.size else 0.0


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

    @property
    def bias_deg_h(self) -> float:
        return self.fit.b

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
            "amplitude_deg_h": self.amplitude_deg_h,
            "amplitude_sigma_deg_h": self.amplitude_sigma_deg_h,
            "closure_residual_deg_h": self.closure_residual_deg_h,
            "closure_sigma_deg_h": self.fit.closure_sigma,
            "uncertainty_model": self.fit.uncertainty_model,
            "drift_deg_h_per_h": self.fit.drift,
            "drift_sigma_deg_h_per_h": self.fit.drift_sigma,
            "azimuth_error_deg": self.azimuth_error_deg,
        }


def handout_theta(azimuth_deg: float) -> tuple[float, str, float, str]:
    """The handout's θ, turn direction, |θ| and where the axis then points.

    θ = arctan(−y/x) with x = H cos A_1, y = H sin A_1 (for four counter-clockwise
    positions: arctan((ω4−ω2)/(ω1−ω3))).  Turning the table by θ (clockwise positive)
    brings the axis to A_1 + θ ∈ {0°, 180°}: north when x > 0, south when x < 0.
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


def solve_heading(
    positions: Sequence[Sequence[float]],
    angles_deg: Sequence[float],
    *,
    true_azimuth_deg: float | None = None,
    position_cov: np.ndarray | None = None,
    indexing_sigma_deg: float = 0.0,
    times_s: Sequence[Sequence[float]] | None = None,
) -> HeadingResult:
    """Azimuth of position 1 (clockwise from true north, [0°, 360°)) with its 1σ.

    ``position_cov`` and ``indexing_sigma_deg``: a known noise model (see
    :func:`fit_sinusoid` and :mod:`app.core.noise_model`)."""
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
    angle_ref, amplitude, sigma_az, sigma_amp = _polar(fit.a, -fit.c, cov_xy)
    _check_significant(amplitude, sigma_amp, "horizontal", _scale(fit))
    azimuth = wrap360(angle_ref + float(fit.angles_deg[0]))
    theta, direction, rotate, points = handout_theta(azimuth)
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

    @property
    def bias_deg_h(self) -> float:
        return self.fit.b

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
            "latitude_error_percent": self.latitude_error_percent,
            "latitude_error_deg": self.latitude_error_deg,
            "earth_rate_error_percent": self.earth_rate_error_percent,
            "closure_residual_deg_h": self.fit.closure_residual,
            "closure_sigma_deg_h": self.fit.closure_sigma,
            "uncertainty_model": self.fit.uncertainty_model,
            "drift_deg_h_per_h": self.fit.drift,
            "drift_sigma_deg_h_per_h": self.fit.drift_sigma,
        }


def percent_error(value: float, true_value: float | None) -> float | None:
    """The handout's η = |value − true| / |true| × 100 % (None when true is 0 or unknown)."""
    if true_value is None or true_value == 0:
        return None
    return abs(value - true_value) / abs(true_value) * 100.0


def solve_latitude(
    positions: Sequence[Sequence[float]],
    elevations_deg: Sequence[float],
    *,
    true_latitude_deg: float | None = None,
    true_earth_rate_deg_h: float = EARTH_RATE_DEG_H,
    position_cov: np.ndarray | None = None,
    indexing_sigma_deg: float = 0.0,
    times_s: Sequence[Sequence[float]] | None = None,
) -> LatitudeResult:
    """Latitude φ and Earth rate Ω from readings in the meridian plane, with 1σ."""
    if true_earth_rate_deg_h <= 0 or not math.isfinite(true_earth_rate_deg_h):
        raise UserError("station.bad_earth_rate", "The true Earth rate must be positive.")
    fit = fit_sinusoid(
        positions,
        elevations_deg,
        position_cov=position_cov,
        indexing_sigma_deg=indexing_sigma_deg,
        times_s=times_s,
    )
    cov_xy = None if fit.cov is None else fit.cov[:2, :2]
    latitude, omega, sigma_lat, sigma_omega = _polar(fit.a, fit.c, cov_xy)
    _check_significant(omega, sigma_omega, "Earth-rate", _scale(fit))
    if abs(latitude) > 90.0:
        raise UserError(
            "readings.latitude_out_of_range",
            f"The fitted latitude {latitude:.1f}° lies outside ±90°: check that position 1 is "
            "the axis pointing north (0°) and that the angles increase towards the zenith.",
            latitude=round(latitude, 2),
        )
    return LatitudeResult(
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
    """γ = arccos((U1 − U2) / (2 K Ω cos φ)) (lab-reference §4).

    With a measured table pitch p (the reference direction raised by p, as a north seeker's
    accelerometers report it) the vertical rate is compensated:
    cos γ = ((U1 − U2)/2K − Ω sin φ sin p) / (Ω cos φ cos p); roll cancels in U1 − U2.
    Needs K, Ω and φ; cannot tell east from west (γ and 360° − γ fit equally); the
    derivative 1/sin γ makes it ill-conditioned near 0° and 180°.
    """
    phi, pitch = math.radians(latitude_deg), math.radians(pitch_deg)
    horizontal = 2.0 * scale_factor * earth_rate_deg_h * math.cos(phi) * math.cos(pitch)
    if horizontal <= 0:
        raise UserError(
            "two_position.no_horizontal", "K·Ω·cos φ must be positive for the two-position method."
        )
    vertical = 2.0 * scale_factor * earth_rate_deg_h * math.sin(phi) * math.sin(pitch)
    ratio = (u1 - u2 - vertical) / horizontal
    clipped = False
    if abs(ratio) > 1.0:
        if abs(ratio) > 1.05:
            raise UserError(
                "two_position.ratio",
                f"(U1 − U2)/(2KΩcos φ) = {ratio:.3f} is outside [−1, 1]: the readings do not fit "
                "the given scale factor, Earth rate and latitude.",
                ratio=round(ratio, 4),
            )
        ratio, clipped = math.copysign(1.0, ratio), True
    gamma = math.degrees(math.acos(ratio))
    return TwoPositionResult(gamma, (gamma, wrap360(360.0 - gamma)), ratio, clipped)
