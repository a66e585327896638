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
from dataclasses import dataclass

import numpy as np

from app.core.two_axis_seeker import (
    indexing_error_first_order,
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
