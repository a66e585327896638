"""The tilt paper's instrument: a strapdown two-position north seeker with a two-axis gyro.

Source: ``two_position_tilt_indexing_error.zh.txt`` (Xue, Guo, Zhou, "Transposition error
analysis under north seeker incline state"); lab-reference §4.  Unlike the handout's
single-axis FOG, this seeker has a TWO-axis (dynamically tuned) gyro measuring both body
rates ω_x, ω_y in the plane of the turntable, and two accelerometers giving pitch θ and
roll γ from a_x = g·sin θ, a_y = g·cos θ·sin γ.

Frames (our conventions, right-handed): the level frame has x forward (azimuth α,
clockwise from true north), y to the left, z up, so Earth's rate in it is

    L = (Ω cos φ cos α,  Ω cos φ sin α,  Ω sin φ),      α = atan2(L_y, L_x).

The body (table) frame is pitched by θ about y, then rolled by γ about x:
``ω_b = C·L`` with C = R_x(γ)·R_y(θ), whose rows are

    (cos θ, 0, sin θ),  (−sin γ sin θ, cos γ, sin γ cos θ),  (−cos γ sin θ, −sin γ, cos γ cos θ),

which is what makes gravity read a_x = g sin θ and a_y = g cos θ sin γ.

Two positions: the gyro reads ω_b + ε at 0° and, turned about the body z axis by 180° + δ
(δ > 0: the table overshoots clockwise seen from above), R_z(180° + δ)·ω_b + ε.  Halving
the differences cancels the constant drift ε:

    ω̂_x = ω_x (1 + cos δ)/2 − ω_y sin δ / 2,   ω̂_y = ω_y (1 + cos δ)/2 + ω_x sin δ / 2,

i.e. the measured horizontal body rate is the true one turned by δ/2.  The solver undoes
pitch and roll with the known L_z = Ω sin φ:

    L_x = (ω̂_x − sin θ · L_z) / cos θ,
    L_y = (ω̂_y + sin γ sin θ · L_x − sin γ cos θ · L_z) / cos γ,   α̂ = atan2(L_y, L_x).

First order in δ: the error is Δα = (L_x δL_y − L_y δL_x)/(L_x² + L_y²) with
(δL_x, δL_y) the solver applied (without L_z) to (δ/2)·(−ω_y, ω_x).  Level: exactly δ/2 at
every azimuth; tilted: δ/2 times a factor that ripples over azimuth — at φ = 60° between
0.78 and 1.21 for (θ, γ) = (5°, −5°), 0.55 … 1.39 for (−10°, 10°) and 0.07 … 1.70 for
(20°, 20°), the paper's figures.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from app.core.exceptions import UserError
from app.core.units import EARTH_RATE_DEG_H


def body_matrix(pitch_deg: float, roll_deg: float) -> np.ndarray:
    """C = R_x(γ)·R_y(θ): level-frame vectors to body-frame coordinates.

    Parameters
    ----------
    pitch_deg : float
        θ (°).
    roll_deg : float
        γ (°).

    Returns
    -------
    numpy.ndarray
        The 3×3 matrix C.

    References
    ----------
    lab-reference §4 (the tilt paper's two-axis strapdown seeker).
    """
    t, g = math.radians(pitch_deg), math.radians(roll_deg)
    pitch = np.array(
        [[math.cos(t), 0.0, math.sin(t)], [0.0, 1.0, 0.0], [-math.sin(t), 0.0, math.cos(t)]]
    )
    roll = np.array(
        [[1.0, 0.0, 0.0], [0.0, math.cos(g), math.sin(g)], [0.0, -math.sin(g), math.cos(g)]]
    )
    return roll @ pitch


def level_earth_rate(
    azimuth_deg, latitude_deg: float, earth_rate_deg_h: float = EARTH_RATE_DEG_H
) -> np.ndarray:
    """Earth's rate in the level frame of a body x axis at ``azimuth_deg``.

    L = (Ω cos φ cos α, Ω cos φ sin α, Ω sin φ).

    Parameters
    ----------
    azimuth_deg : array_like
        α, azimuth of the body x axis (°).
    latitude_deg : float
        φ (°).
    earth_rate_deg_h : float
        Ω (°/h).

    Returns
    -------
    numpy.ndarray
        L (°/h), shape (…, 3).

    References
    ----------
    lab-reference §4.
    """
    a = np.radians(np.asarray(azimuth_deg, dtype=float))
    phi = math.radians(latitude_deg)
    horizontal = earth_rate_deg_h * math.cos(phi)
    vertical = np.full(a.shape, earth_rate_deg_h * math.sin(phi))
    return np.stack([horizontal * np.cos(a), horizontal * np.sin(a), vertical], axis=-1)


def body_rates(
    azimuth_deg,
    latitude_deg: float,
    pitch_deg: float,
    roll_deg: float,
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> np.ndarray:
    """Earth's rate in the body frame: ω_b = C·L.

    Parameters
    ----------
    azimuth_deg : array_like
        α (°).
    latitude_deg : float
        φ (°).
    pitch_deg, roll_deg : float
        The table's pitch and roll (°).
    earth_rate_deg_h : float
        Ω (°/h).

    Returns
    -------
    numpy.ndarray
        ω_b (°/h), shape (…, 3).

    References
    ----------
    lab-reference §4.
    """
    return (
        level_earth_rate(azimuth_deg, latitude_deg, earth_rate_deg_h)
        @ body_matrix(pitch_deg, roll_deg).T
    )


def turned_reading(body: np.ndarray, indexing_deg: float) -> np.ndarray:
    """What the gyro's x and y axes read after turning 180° + δ about the body z axis.

    Parameters
    ----------
    body : numpy.ndarray
        ω_b before the turn (°/h), shape (…, 3).
    indexing_deg : float
        δ, the turn's error (°).

    Returns
    -------
    numpy.ndarray
        (ω_x, ω_y) after the turn (°/h), shape (…, 2).
    """
    d = math.radians(indexing_deg)
    wx, wy = body[..., 0], body[..., 1]
    # the gyro axes turned clockwise by 180° + δ: x' = −cos δ·x + sin δ·y … in body terms
    return np.stack(
        [-math.cos(d) * wx + math.sin(d) * wy, -math.sin(d) * wx - math.cos(d) * wy], axis=-1
    )


@dataclass(frozen=True)
class SeekerResult:
    azimuth_deg: float
    level_rate_deg_h: tuple[float, float]  # (L_x, L_y), the horizontal Earth rate found


def solve_seeker(
    first: tuple[float, float],
    second: tuple[float, float],
    *,
    pitch_deg: float,
    roll_deg: float,
    latitude_deg: float,
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> SeekerResult:
    """Azimuth of the body x axis from the mean (ω_x, ω_y) at 0° and at 180°.

    The differences are halved (the biases cancel), then pitch and roll are undone with the
    known vertical rate L_z = Ω sin φ (see the module's docstring): α̂ = atan2(L_y, L_x).

    Parameters
    ----------
    first, second : tuple of float
        Mean (ω_x, ω_y) at 0° and after the 180° turn (°/h).
    pitch_deg, roll_deg : float
        The table's pitch and roll, as its accelerometers give them (°).
    latitude_deg : float
        φ (°).
    earth_rate_deg_h : float
        Ω (°/h).

    Returns
    -------
    SeekerResult
        α̂ (°) and the level-frame components.

    References
    ----------
    lab-reference §4 (the tilt paper's instrument).
    """
    values = (*first, *second, pitch_deg, roll_deg, latitude_deg, earth_rate_deg_h)
    if not all(math.isfinite(v) for v in values):
        raise UserError("seeker.not_finite")
    t, g = math.radians(pitch_deg), math.radians(roll_deg)
    if math.cos(t) < 1e-6 or math.cos(g) < 1e-6:
        raise UserError("seeker.tilt_too_large")
    wx = (first[0] - second[0]) / 2.0
    wy = (first[1] - second[1]) / 2.0
    lz = earth_rate_deg_h * math.sin(math.radians(latitude_deg))
    lx, ly = _undo_tilt(wx, wy, lz, t, g)
    if math.hypot(lx, ly) == 0.0:
        raise UserError("seeker.no_horizontal")
    return SeekerResult(math.degrees(math.atan2(ly, lx)) % 360.0, (lx, ly))


def _undo_tilt(wx, wy, lz, t: float, g: float):
    lx = (wx - math.sin(t) * lz) / math.cos(t)
    ly = (wy + math.sin(g) * math.sin(t) * lx - math.sin(g) * math.cos(t) * lz) / math.cos(g)
    return lx, ly


def indexing_error_first_order(
    indexing_deg: float,
    azimuths_deg,
    *,
    latitude_deg: float,
    pitch_deg: float,
    roll_deg: float,
    earth_rate_deg_h: float = EARTH_RATE_DEG_H,
) -> np.ndarray:
    """First-order heading error of the seeker from an indexing error δ on the 180° turn.

    Δα = (L_x·δL_y − L_y·δL_x)/(L_x² + L_y²), (δL_x, δL_y) the tilt solver applied without
    L_z to the body-rate error (δ/2)·(−ω_y, ω_x); exactly δ/2 on a level table.

    Parameters
    ----------
    indexing_deg : float
        δ (°).
    azimuths_deg : array_like
        True azimuths (°).
    latitude_deg : float
        φ (°).
    pitch_deg, roll_deg : float
        The table's pitch and roll (°).
    earth_rate_deg_h : float
        Ω (°/h).

    Returns
    -------
    numpy.ndarray
        Δα (°) at each azimuth (0.07 … 1.70 × δ/2 over the paper's tilts).

    References
    ----------
    lab-reference §4.
    """
    body = body_rates(azimuths_deg, latitude_deg, pitch_deg, roll_deg, earth_rate_deg_h)
    level = level_earth_rate(azimuths_deg, latitude_deg, earth_rate_deg_h)
    half = math.radians(indexing_deg) / 2.0
    t, g = math.radians(pitch_deg), math.radians(roll_deg)
    dlx, dly = _undo_tilt(-half * body[..., 1], half * body[..., 0], 0.0, t, g)
    lx, ly = level[..., 0], level[..., 1]
    return np.degrees((lx * dly - ly * dlx) / (lx * lx + ly * ly))
