"""Monte Carlo of the heading error: many seeded runs of the simulator per true azimuth,
solved as a student would, to check the first-order formulas (:mod:`app.core.error_analysis`)
and to show what they leave out (noise, large errors)."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace

import numpy as np

from app.core.error_analysis import METHODS, ErrorSources
from app.core.exceptions import UserError
from app.core.gyro_stream import GyroStream
from app.core.presets import GyroPreset
from app.core.simulate import Setup, simulate_run
from app.core.sinusoid import heading_angles, wrap180, wrap360
from app.core.solve import solve_heading
from app.core.two_axis_seeker import (
    body_rates,
    solve_seeker,
    turned_reading,
)
from app.core.two_position import solve_two_position
from app.core.units import EARTH_RATE_DEG_H


@dataclass(frozen=True)
class MonteCarloCurve:
    azimuths_deg: np.ndarray
    mean_error_deg: np.ndarray
    std_error_deg: np.ndarray
    runs: int
    valid_runs: np.ndarray  # runs that produced a heading, per azimuth


def _tilt_for(sources: ErrorSources, azimuth_deg: float) -> tuple[float, float]:
    """Table pitch/roll (relative to position 1) for the requested tilts."""
    pitch, roll = sources.pitch_deg + sources.level_deg, sources.roll_deg
    if sources.east_tilt_deg:
        a = math.radians(azimuth_deg)
        pitch += -sources.east_tilt_deg * math.sin(a)
        roll += sources.east_tilt_deg * math.cos(a)
    return pitch, roll


def _gyro_for(preset: GyroPreset, sources: ErrorSources) -> GyroPreset:
    # The method assumes K = 1; a gyro whose true K is 1/(1+ΔK/K) makes the used K too large.
    true_sf_ppm = (1.0 / (1.0 + sources.scale_factor_ppm * 1e-6) - 1.0) * 1e6
    return replace(
        preset,
        scale_factor_ppm=preset.scale_factor_ppm + true_sf_ppm,
        drift_deg_h_per_h=preset.drift_deg_h_per_h + sources.drift_rate_deg_h_per_h,
    )


def monte_carlo_heading_errors(
    method: str,
    preset: GyroPreset,
    sources: ErrorSources,
    azimuths_deg,
    *,
    latitude_deg: float,
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
    runs: int = 20,
    dwell_s: float = 60.0,
    rotation: str = "ccw",
    seed: int = 0,
) -> MonteCarloCurve:
    """Heading error (estimate − truth, wrapped to ±180°) of simulated runs at each azimuth.

    Parameters
    ----------
    method : {"two", "four", "seeker"}
        The north-finding method.
    preset : GyroPreset
        The simulated gyro.
    sources : ErrorSources
        Extra error terms on top of the preset's noise.
    azimuths_deg : array_like
        True azimuths (°).
    latitude_deg : float
        φ (°).
    earth_rate_deg_h : float
        Ω (°/h).
    runs : int
        Seeded runs per azimuth.
    dwell_s : float
        Recording time per position (s).
    rotation : {"ccw", "cw"}
        The way the table turns.
    seed : int
        Seed of the runs.

    Returns
    -------
    MonteCarloCurve
        Mean and spread of the error at each azimuth.

    References
    ----------
    lab-reference §4 (checked against the first-order curves).
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}")
    if method == "seeker":
        return _seeker_monte_carlo(
            preset, sources, azimuths_deg, latitude_deg, earth_rate_deg_h, runs, dwell_s, seed
        )
    gyro = _gyro_for(preset, sources)
    stops = 2 if method == "two" else 4
    angles = heading_angles(stops, rotation, 0.0, 180.0 if method == "two" else 90.0)
    extra = np.zeros(stops)
    if sources.indexing_deg and sources.indexing_stop <= stops:
        extra[sources.indexing_stop - 1] = sources.indexing_deg
    azimuths = np.asarray(azimuths_deg, dtype=float)
    errors = np.empty((azimuths.size, runs))
    used_latitude = latitude_deg - sources.latitude_error_deg
    for i, azimuth in enumerate(azimuths):
        pitch, roll = _tilt_for(sources, azimuth)
        setup = Setup(latitude_deg, float(azimuth), earth_rate_deg_h, pitch, roll)
        for run in range(runs):
            simulated = simulate_run(
                gyro,
                setup,
                "heading",
                angles,
                dwell_s,
                seed=seed + 7919 * i + run,
                extra_indexing_deg=extra,
            )
            means = [float(p.mean()) for p in simulated.positions]
            try:
                errors[i, run] = wrap180(
                    _estimate(
                        method,
                        simulated,
                        angles,
                        means,
                        sources,
                        azimuth,
                        earth_rate_deg_h,
                        used_latitude,
                    )
                    - azimuth
                )
            except UserError:  # no heading can be found from this run
                errors[i, run] = np.nan
    return _curve(azimuths, errors)


def _curve(azimuths: np.ndarray, errors: np.ndarray) -> MonteCarloCurve:
    """Mean and spread over the runs (rows: azimuths; NaN = no heading found)."""
    runs = errors.shape[1]
    valid = np.isfinite(errors).sum(axis=1)
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        mean = np.nanmean(errors, axis=1)
        std = np.nanstd(errors, axis=1, ddof=1) if runs > 1 else np.zeros(azimuths.size)
    return MonteCarloCurve(azimuths, mean, std, runs, valid)


def _seeker_monte_carlo(
    preset: GyroPreset,
    sources: ErrorSources,
    azimuths_deg,
    latitude_deg: float,
    earth_rate_deg_h: float,
    runs: int,
    dwell_s: float,
    seed: int,
) -> MonteCarloCurve:
    """The two-axis seeker simulated: each gyro axis is its own noisy stream (the preset's
    noise terms), one position after the other; the table's pitch and roll are known."""
    azimuths = np.asarray(azimuths_deg, dtype=float)
    count = max(1, int(round(dwell_s * preset.sample_rate_hz)))
    errors = np.empty((azimuths.size, runs))
    for i, azimuth in enumerate(azimuths):
        first = body_rates(
            azimuth, latitude_deg, sources.pitch_deg, sources.roll_deg, earth_rate_deg_h
        )
        second = turned_reading(first, sources.indexing_deg)
        for run in range(runs):
            means = []
            for axis in range(2):
                stream = GyroStream(preset, (seed + 7919 * i + run) * 2 + axis)
                at_zero = stream.read(np.full(count, first[axis])).mean()
                turned = stream.read(np.full(count, second[axis])).mean()
                means.append((float(at_zero), float(turned)))
            try:
                found = solve_seeker(
                    (means[0][0], means[1][0]),
                    (means[0][1], means[1][1]),
                    pitch_deg=sources.pitch_deg,
                    roll_deg=sources.roll_deg,
                    latitude_deg=latitude_deg,
                    earth_rate_deg_h=earth_rate_deg_h,
                ).azimuth_deg
                errors[i, run] = wrap180(found - azimuth)
            except UserError:
                errors[i, run] = np.nan
    return _curve(azimuths, errors)


def _estimate(
    method, simulated, angles, means, sources, azimuth, earth_rate_deg_h, used_latitude
) -> float:
    if method == "two":
        result = solve_two_position(
            means[0] + sources.drift_deg_h,
            means[1],
            earth_rate_deg_h=earth_rate_deg_h,
            latitude_deg=used_latitude,
            pitch_deg=sources.pitch_deg,
        )
        gamma = result.gamma_deg
        return gamma if math.sin(math.radians(azimuth)) >= 0 else wrap360(-gamma)
    return solve_heading(simulated.positions, angles).azimuth_deg
