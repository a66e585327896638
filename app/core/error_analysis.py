"""How error sources move the heading: first-order formulas and Monte Carlo with the simulator.

γ (= A) is the true azimuth of position 1.  Two-position method (lab-reference §4, from
``two_position_fog_error_analysis.zh.txt``): positions γ and γ+180°,
γ̂ = arccos((U1 − U2)/(2KΩcos φ)), the east/west half-plane taken from the truth.

| source | definition | two-position Δγ | four-position ΔA |
|---|---|---|---|
| drift | ε = bias(1) − bias(2) | −ε/(2KΩ cos φ sin γ) | — |
| linear drift | ḃ °/h per h, T between stops | ḃT/(2KΩ cos φ sin γ) | ḃT(sin A ∓ cos A)/H ccw/cw |
| scale factor | ΔK/K of the K used | (ΔK/K)/tan γ | 0 |
| latitude | Δφ = φ true − φ used | tan φ·Δφ/tan γ | 0 |
| indexing | stop k lands δ past its dial | δ/2 (level)* | k=2,4: (δ/2)cos²A; k=3: (δ/2)sin²A |
| level | elevation α at 1, −α at 2 | arccos(cos α cos γ + tan φ sin α) − γ | 0 (H shrinks) |
| east tilt | east side low by t_E | tan φ·t_E | tan φ·t_E |

* On a table with known (compensated) pitch p and roll r, as in
``two_position_tilt_indexing_error.zh.txt``:
Δγ = (δ/2)·[cos r sin γ − sin r sin p cos γ + tan φ sin r cos p]/(cos p sin γ) — constant
δ/2 when level, a ripple over azimuth for small tilts, large near γ = 0°/180° for big ones.

The four-position rows follow from A = atan2(y, x) with δA = (x·δy − y·δx)/H²; the
Monte Carlo functions reproduce all of them with :func:`app.core.simulate.simulate_run`.

The formula above is for the handout's single-axis FOG solved with arccos.  The tilt
paper's own instrument is a two-axis gyro solved with atan (method ``"seeker"``,
:mod:`app.core.two_axis_seeker`): on a tilted table its indexing error stays between
0.07 and 1.70 × δ/2 at 20° tilt instead of diverging near 0°/180°.  Its curves include the
indexing error, the known tilt and the gyro's noise; the other sources do not apply to it.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, replace

import numpy as np

from app.core.exceptions import UserError
from app.core.presets import GyroPreset
from app.core.simulate import GyroStream, Setup, simulate_run
from app.core.sinusoid import heading_angles, wrap180, wrap360
from app.core.solve import solve_heading, solve_two_position
from app.core.two_axis_seeker import (
    body_rates,
    indexing_error_first_order,
    solve_seeker,
    turned_reading,
)
from app.core.units import EARTH_RATE_DEG_H

METHODS = ("two", "four", "seeker")


@dataclass(frozen=True)
class ErrorSources:
    """Sizes of the deliberate error sources (zero = off)."""

    drift_deg_h: float = 0.0  # two-position drift difference ε
    drift_rate_deg_h_per_h: float = 0.0  # linear drift ḃ
    scale_factor_ppm: float = 0.0  # ΔK/K of the K the method uses
    latitude_error_deg: float = 0.0  # Δφ
    indexing_deg: float = 0.0  # δ on ``indexing_stop``
    indexing_stop: int = 2
    level_deg: float = 0.0  # two-position α
    east_tilt_deg: float = 0.0  # four-position t_E
    pitch_deg: float = 0.0  # known table tilt relative to position 1, compensated (papers)
    roll_deg: float = 0.0


def _rad(deg):
    return np.radians(deg)


def two_position_first_order(
    sources: ErrorSources,
    azimuths_deg,
    latitude_deg: float,
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
    stop_spacing_s: float = 0.0,
) -> np.ndarray:
    """Sum of the first-order heading errors of the two-position method (0° and 180°) at
    each true azimuth.

    Parameters
    ----------
    sources : ErrorSources
        The error terms (bias, drift, scale factor, indexing, tilt, misalignment ...).
    azimuths_deg : array_like
        True azimuths of position 1 (°).
    latitude_deg : float
        φ (°).
    earth_rate_deg_h : float
        Ω (°/h).
    stop_spacing_s : float
        Time between successive stops (s), for the drift term.

    Returns
    -------
    numpy.ndarray
        Heading error (°) at each azimuth.

    References
    ----------
    lab-reference §4 (first-order error analysis of the indexing methods).
    """
    g = _rad(np.asarray(azimuths_deg, dtype=float))
    phi = math.radians(latitude_deg)
    horizontal = 2.0 * earth_rate_deg_h * math.cos(phi)
    total = np.zeros_like(g)
    drift = sources.drift_rate_deg_h_per_h * stop_spacing_s / 3600.0 - sources.drift_deg_h
    cot = sources.scale_factor_ppm * 1e-6 + math.tan(phi) * math.radians(sources.latitude_error_deg)
    with np.errstate(divide="ignore", invalid="ignore"):  # terms that are on diverge at 0°/180°
        if drift:
            total = total + drift / (horizontal * np.sin(g))
        if cot:
            total = total + cot / np.tan(g)
    # an east-west tilt t_E puts −t_E·sin A of elevation on the axis: U1 − U2 gains
    # −2Ω sin φ t_E sin γ, so Δγ = tan φ · t_E, as for four positions
    total = total + math.tan(phi) * math.radians(sources.east_tilt_deg)
    if sources.indexing_deg and not (sources.pitch_deg or sources.roll_deg):
        total = total + math.radians(sources.indexing_deg) / 2.0  # level table: exactly δ/2
    elif sources.indexing_deg:
        # stop 2 lands δ past 180° on a table with known pitch p and roll r:
        # Δγ = (δ/2)·[cos r sin γ − sin r sin p cos γ + tan φ sin r cos p] / (cos p sin γ)
        p, r = math.radians(sources.pitch_deg), math.radians(sources.roll_deg)
        delta = math.radians(sources.indexing_deg)
        with np.errstate(divide="ignore", invalid="ignore"):
            bracket = (
                math.cos(r) * np.sin(g)
                - math.sin(r) * math.sin(p) * np.cos(g)
                + math.tan(phi) * math.sin(r) * math.cos(p)
            )
            total = total + delta / 2.0 * bracket / (math.cos(p) * np.sin(g))
    if sources.level_deg:
        alpha = math.radians(sources.level_deg)
        ratio = np.clip(math.cos(alpha) * np.cos(g) + math.tan(phi) * math.sin(alpha), -1, 1)
        exact = np.arccos(ratio)
        exact = np.where(np.sin(g) >= 0, exact, 2 * math.pi - exact)
        total = total + np.angle(np.exp(1j * (exact - g)))
    return np.degrees(total)


def four_position_first_order(
    sources: ErrorSources,
    azimuths_deg,
    latitude_deg: float,
    amplitude_deg_h: float | None = None,
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
    rotation: str = "ccw",
    stop_spacing_s: float = 0.0,
) -> np.ndarray:
    """Sum of the first-order heading errors of the four-position method at each true azimuth.

    Parameters
    ----------
    sources : ErrorSources
        The error terms (bias, drift, scale factor, indexing, tilt, misalignment ...).
    azimuths_deg : array_like
        True azimuths of position 1 (°).
    latitude_deg : float
        φ (°).
    amplitude_deg_h : float, optional
        H = Ω cos φ (°/h); default from the latitude.
    earth_rate_deg_h : float
        Ω (°/h).
    rotation : {"ccw", "cw"}
        The way the table turns.
    stop_spacing_s : float
        Time between successive stops (s), for the drift term.

    Returns
    -------
    numpy.ndarray
        Heading error (°) at each azimuth.

    References
    ----------
    lab-reference §4 (first-order error analysis of the indexing methods).
    """
    a = _rad(np.asarray(azimuths_deg, dtype=float))
    phi = math.radians(latitude_deg)
    h = amplitude_deg_h or earth_rate_deg_h * math.cos(phi)
    drift = sources.drift_rate_deg_h_per_h * stop_spacing_s / 3600.0
    shape = np.sin(a) - np.cos(a) if rotation == "ccw" else np.sin(a) + np.cos(a)
    total = drift * shape / h
    delta = math.radians(sources.indexing_deg)
    if sources.indexing_stop in (2, 4):
        total = total + delta / 2.0 * np.cos(a) ** 2
    elif sources.indexing_stop == 3:
        total = total + delta / 2.0 * np.sin(a) ** 2
    total = total + math.tan(phi) * math.radians(sources.east_tilt_deg)
    return np.degrees(total)


def seeker_first_order(
    sources: ErrorSources,
    azimuths_deg,
    latitude_deg: float,
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> np.ndarray:
    """First-order heading error of the tilt paper's two-axis seeker.

    Its only modelled sources: the indexing error on its 180° turn, with the table's known
    pitch and roll (:func:`app.core.two_axis_seeker.indexing_error_first_order`).

    Parameters
    ----------
    sources : ErrorSources
        The error terms (its indexing σ, pitch and roll are used).
    azimuths_deg : array_like
        True azimuths of the body x axis (°).
    latitude_deg : float
        φ (°).
    earth_rate_deg_h : float
        Ω (°/h).

    Returns
    -------
    numpy.ndarray
        Heading error (°) at each azimuth.

    References
    ----------
    lab-reference §4 (the tilt paper's instrument).
    """
    azimuths = np.asarray(azimuths_deg, dtype=float)
    if not sources.indexing_deg:
        return np.zeros_like(azimuths)
    return indexing_error_first_order(
        sources.indexing_deg,
        azimuths,
        latitude_deg=latitude_deg,
        pitch_deg=sources.pitch_deg,
        roll_deg=sources.roll_deg,
        earth_rate_deg_h=earth_rate_deg_h,
    )


def first_order(
    method: str,
    sources: ErrorSources,
    azimuths_deg,
    latitude_deg: float,
    *,
    stop_spacing_s: float = 0.0,
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> np.ndarray:
    """The first-order heading error of ``method`` at each true azimuth.

    Parameters
    ----------
    method : {"two", "four", "seeker"}
        Two-position, four-position, or the tilt paper's two-axis seeker.
    sources : ErrorSources
        The error terms.
    azimuths_deg : array_like
        True azimuths (°).
    latitude_deg : float
        φ (°).
    stop_spacing_s : float
        Time between stops (s).
    earth_rate_deg_h : float
        Ω (°/h).

    Returns
    -------
    numpy.ndarray
        Heading error (°) at each azimuth.

    References
    ----------
    lab-reference §4.
    """
    if method == "two":
        return two_position_first_order(
            sources, azimuths_deg, latitude_deg, earth_rate_deg_h, stop_spacing_s
        )
    if method == "four":
        return four_position_first_order(
            sources,
            azimuths_deg,
            latitude_deg,
            earth_rate_deg_h=earth_rate_deg_h,
            stop_spacing_s=stop_spacing_s,
        )
    if method == "seeker":
        return seeker_first_order(sources, azimuths_deg, latitude_deg, earth_rate_deg_h)
    raise ValueError(f"method must be one of {', '.join(METHODS)}")


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
