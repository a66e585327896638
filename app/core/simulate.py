"""Fibre-optic gyro on a manual two-axis turntable: a seeded, vectorised simulator.

True rate (lab-reference §1, §5).  In the local north-east-up frame Earth's rate is
Ω_vec = (Ω cos φ, 0, Ω sin φ).  The gyro axis in the turntable frame, for horizontal dial
angle h (clockwise) and vertical dial angle v (elevation), is u_t = (cos v cos h,
cos v sin h, sin v); the table is rolled by r (right side down), pitched by p (reference
direction up) and yawed to the true azimuth ψ of its reference direction, so
u = R_yaw(ψ)·R_pitch(p)·R_roll(r)·u_t and the true rate is Ω_vec·u.

The measured rate is the true rate through the sensor's error model
(:class:`app.core.gyro_stream.GyroStream`: scale factor, biases, noise, quantisation).
The turntable: each stop after the first lands at its dial angle plus an indexing error
~ N(0, σ_idx); the dial reads to its resolution; the sensitive axis may be misaligned
from the dial by (δh, δv).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from app.core.gyro_stream import GyroStream
from app.core.presets import GyroPreset
from app.core.units import EARTH_RATE_DEG_H

# --- geometry ------------------------------------------------------------------------------


def earth_rate_vector(
    latitude_deg: float, earth_rate_deg_h: float = EARTH_RATE_DEG_H
) -> np.ndarray:
    """Earth's rotation in the local north-east-up frame: (Ω cos φ, 0, Ω sin φ).

    Parameters
    ----------
    latitude_deg : float
        φ (°).
    earth_rate_deg_h : float
        Ω (°/h).

    Returns
    -------
    numpy.ndarray
        The vector (°/h).

    References
    ----------
    lab-reference §1.
    """
    phi = math.radians(latitude_deg)
    return np.array([earth_rate_deg_h * math.cos(phi), 0.0, earth_rate_deg_h * math.sin(phi)])


def axis_vectors(
    yaw_deg: float, h_deg, v_deg, pitch_deg: float = 0.0, roll_deg: float = 0.0
) -> np.ndarray:
    """Unit vectors of the gyro axis in north-east-up for dial angles h, v.

    u = R_yaw(ψ)·R_pitch(p)·R_roll(r)·u_t with u_t = (cos v cos h, cos v sin h, sin v).

    Parameters
    ----------
    yaw_deg : float
        ψ, the true azimuth of the table's reference direction (°).
    h_deg, v_deg : array_like
        Horizontal (clockwise) and vertical (elevation) dial angles (°).
    pitch_deg, roll_deg : float
        The table's pitch and roll (°).

    Returns
    -------
    numpy.ndarray
        Unit vectors, shape (…, 3).

    References
    ----------
    lab-reference §1.
    """
    h, v = np.radians(np.asarray(h_deg, dtype=float)), np.radians(np.asarray(v_deg, dtype=float))
    h, v = np.broadcast_arrays(h, v)
    x, y, z = np.cos(v) * np.cos(h), np.cos(v) * np.sin(h), np.sin(v)
    r, p, psi = math.radians(roll_deg), math.radians(pitch_deg), math.radians(yaw_deg)
    y, z = y * math.cos(r) + z * math.sin(r), -y * math.sin(r) + z * math.cos(r)  # roll
    x, z = x * math.cos(p) - z * math.sin(p), x * math.sin(p) + z * math.cos(p)  # pitch
    north, east = x * math.cos(psi) - y * math.sin(psi), x * math.sin(psi) + y * math.cos(psi)
    return np.stack([north, east, z], axis=-1)


def true_rate(
    latitude_deg: float, vectors: np.ndarray, earth_rate_deg_h: float = EARTH_RATE_DEG_H
) -> np.ndarray:
    """The rate each sensitive axis sees: Ω_vec·u.

    Parameters
    ----------
    latitude_deg : float
        φ (°).
    vectors : numpy.ndarray
        Unit axis vectors in north-east-up, one per row.
    earth_rate_deg_h : float
        Ω (°/h).

    Returns
    -------
    numpy.ndarray
        The true rates (°/h).

    References
    ----------
    lab-reference §1.
    """
    return vectors @ earth_rate_vector(latitude_deg, earth_rate_deg_h)


# --- a lab run: positions on the turntable --------------------------------------------------


@dataclass(frozen=True)
class Setup:
    """The secret truth of one run: where the table points and how it is tilted."""

    latitude_deg: float
    azimuth_deg: float = 0.0  # true azimuth of position 1 (heading) / of the vertical plane
    earth_rate_deg_h: float = EARTH_RATE_DEG_H
    pitch_deg: float = 0.0
    roll_deg: float = 0.0
    mount_elevation_deg: float = 0.0  # heading part: axis elevation above the table plane


@dataclass
class SimulatedRun:
    positions: list[np.ndarray]
    times_s: list[np.ndarray]
    dial_angles_deg: list[float]  # what the student reads on the dial
    true_angles_deg: list[float]  # where the table really stopped
    turn_on_bias_deg_h: float
    indexing_errors_deg: list[float]
    temperatures_c: list[np.ndarray] = field(default_factory=list)  # case temperature


def indexing_errors(preset: GyroPreset, seed: int, n_positions: int) -> np.ndarray:
    """Where each stop really lands: stop k ≥ 2 off by N(0, σ_idx); stop 1 is the reference.

    Parameters
    ----------
    preset : GyroPreset
        Its ``indexing_sigma_arcsec`` is σ_idx.
    seed : int
        Seed of the draw.
    n_positions : int
        How many stops.

    Returns
    -------
    numpy.ndarray
        The errors (°), the first 0.
    """
    errors = np.zeros(n_positions)
    for move in range(1, n_positions):
        rng = np.random.Generator(
            np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(9, move)))
        )
        errors[move] = rng.normal() * preset.indexing_sigma_arcsec / 3600.0
    return errors


def simulate_run(
    preset: GyroPreset,
    setup: Setup,
    part: str,
    dial_angles_deg: Sequence[float],
    seconds_per_position: float,
    *,
    settle_s: float = 0.0,
    seed: int = 0,
    extra_indexing_deg: Sequence[float] | None = None,
    start_s: float = 0.0,
) -> SimulatedRun:
    """Readings at each dial angle of one part, as the simulated gyro on its turntable gives them.

    ``part`` "heading" turns the horizontal dial h, "latitude" the vertical dial v; every
    stop after the first lands off by the preset's indexing error.

    Parameters
    ----------
    preset : GyroPreset
        The gyro and its turntable (:mod:`app.core.presets`).
    setup : Setup
        Station and table: latitude, Earth rate, true azimuth, pitch and roll.
    part : {"heading", "latitude"}
        Which dial turns.
    dial_angles_deg : sequence of float
        The dial angles (°).
    seconds_per_position : float
        Recording time per position (s).
    settle_s : float
        Time skipped after each turn (s).
    seed : int
        Seed of every random stream.
    extra_indexing_deg : sequence of float, optional
        A fixed extra error at each stop (°; error-analysis experiments).
    start_s : float
        How long the gyro has been on when the first stop begins (s; warm-up).

    Returns
    -------
    SimulatedRun
        Each position's readings (°/h) and times (s), the dial and true angles, the
        turn-on bias and the indexing errors (the run's truth).

    References
    ----------
    lab-reference §1 and §5; IEEE Std 952-1997 (the error model).
    """
    if part not in ("heading", "latitude"):
        raise ValueError("part must be 'heading' or 'latitude'")
    stream = GyroStream(preset, seed)
    errors = indexing_errors(preset, seed, len(dial_angles_deg))
    if extra_indexing_deg is not None:
        errors = errors + np.asarray(extra_indexing_deg, dtype=float)
    per_position = max(1, int(round(seconds_per_position * preset.sample_rate_hz)))
    settle = int(round(settle_s * preset.sample_rate_hz))
    dh, dv = preset.misalignment_deg
    positions, times, true_angles, dial_read, temperatures = [], [], [], [], []
    clock = int(round(start_s * preset.sample_rate_hz))
    if clock:
        stream.read(np.zeros(clock))
    for nominal, error in zip(dial_angles_deg, errors, strict=True):
        actual = nominal + error
        if part == "heading":
            vector = axis_vectors(
                setup.azimuth_deg,
                actual + dh,
                setup.mount_elevation_deg + dv,
                setup.pitch_deg,
                setup.roll_deg,
            )
        else:
            vector = axis_vectors(
                setup.azimuth_deg, dh, actual + dv, setup.pitch_deg, setup.roll_deg
            )
        rate = float(true_rate(setup.latitude_deg, vector, setup.earth_rate_deg_h))
        count = settle + per_position
        temperatures.append(stream.temperatures_c(count)[settle:])
        measured = stream.read(np.full(count, rate), float(vector[2]))
        positions.append(measured[settle:])
        times.append((clock + settle + np.arange(per_position)) / preset.sample_rate_hz)
        clock += count
        true_angles.append(float(actual))
        dial_read.append(read_dial(actual, preset.dial_resolution_deg))
    return SimulatedRun(
        positions,
        times,
        dial_read,
        true_angles,
        stream.turn_on_bias_deg_h,
        [float(e) for e in errors],
        temperatures,
    )


def read_dial(angle_deg: float, resolution_deg: float) -> float:
    """What a student reads on a dial with the given resolution.

    Parameters
    ----------
    angle_deg : float
        The true angle (°).
    resolution_deg : float
        The dial's smallest division (°); 0 reads exactly.

    Returns
    -------
    float
        The angle rounded to the resolution (°).
    """
    if resolution_deg <= 0:
        return float(angle_deg)
    return float(np.round(angle_deg / resolution_deg) * resolution_deg)


def simulate_static(
    preset: GyroPreset,
    setup: Setup,
    seconds: float,
    *,
    seed: int = 0,
    elevation_deg: float = 0.0,
    start_s: float = 0.0,
) -> np.ndarray:
    """A long record at one fixed orientation (for the Allan deviation).

    Parameters
    ----------
    preset : GyroPreset
        The simulated gyro.
    setup : Setup
        Station and table.
    seconds : float
        Record length (s).
    seed : int
        Seed of the noise.
    elevation_deg : float
        Axis elevation (°).
    start_s : float
        How long the gyro has been on when the record starts (s; warm-up).

    Returns
    -------
    numpy.ndarray
        The readings (°/h) at the preset's sample rate.

    References
    ----------
    IEEE Std 952-1997 (the error model).
    """
    stream = GyroStream(preset, seed)
    vector = axis_vectors(setup.azimuth_deg, 0.0, elevation_deg, setup.pitch_deg, setup.roll_deg)
    rate = float(true_rate(setup.latitude_deg, vector, setup.earth_rate_deg_h))
    count = max(1, int(round(seconds * preset.sample_rate_hz)))
    skip = int(round(start_s * preset.sample_rate_hz))
    while skip > 0:  # the gyro's history since switch-on, in bounded blocks
        block = min(skip, 1_000_000)
        stream.read(np.zeros(block))
        skip -= block
    return stream.read(np.full(count, rate), float(vector[2]))
