"""Fibre-optic gyro on a manual two-axis turntable: a seeded, vectorised simulator.

True rate (lab-reference §1, §5).  In the local north-east-up frame Earth's rate is
Ω_vec = (Ω cos φ, 0, Ω sin φ).  The gyro axis in the turntable frame, for horizontal dial
angle h (clockwise) and vertical dial angle v (elevation), is u_t = (cos v cos h,
cos v sin h, sin v); the table is rolled by r (right side down), pitched by p (reference
direction up) and yawed to the true azimuth ψ of its reference direction, so
u = R_yaw(ψ)·R_pitch(p)·R_roll(r)·u_t and the true rate is Ω_vec·u.

Measured rate, each term switchable by setting it to zero (IEEE Std 952 error model):

    ω_k = (1 + ΔK/K)·Ω_vec·u + b0 + b_on + ḃ·t + g·u_up + x_k + r_k + n_k, then quantised

* b0 constant bias, b_on turn-on bias ~ N(0, σ_on) drawn once per run (seed);
* g·u_up: g-dependent bias (axis up vs down), °/h per g;
* n_k angle random walk: white, σ = 60·N/√Δt °/h (N in °/√h, Δt in s);
* x_k bias instability B: flicker (1/f) noise, the sum of the Gauss–Markov components of
  :mod:`app.core.flicker` (a flat Allan floor 0.664·B over the preset's band of correlation
  times), each with the exact discretisation x_k = φ·x_(k−1) + σ·√(1−φ²)·w_k,
  φ = e^(−Δt/T_j); plus, where the preset has one, a Gauss–Markov bias (σ_m, T_m) the same
  way;
* ḃ·t linear bias drift, °/h per hour;
* warm-up: b_0·e^(−t/τ_w) after switch-on, while the case temperature rises as
  ambient + ΔT·(1 − e^(−t/τ_w)) (:meth:`GyroStream.temperatures_c`);
* r_k rate random walk: r_k = r_(k−1) + K·√Δt_h·w_k (K in °/h/√h);
* quantisation: the angle ∫ω dt is floored to the angle LSB and differenced;
* turntable: each stop after the first lands at its dial angle plus an indexing error
  ~ N(0, σ_idx); the dial reads to its resolution; the sensitive axis may be misaligned
  from the dial by (δh, δv).

Reproducibility: every noise source has its own random stream spawned from the seed, all
recursions carry their state, and cumulative sums continue from the previous value, so
generating samples 0..n in one call or in any chunking gives bit-identical values
(:class:`GyroStream`), and a live stream can be resumed by regenerating to its position.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from app.core.flicker import flicker_components
from app.core.presets import GyroPreset
from app.core.units import EARTH_RATE_DEG_H, SECONDS_PER_HOUR

AMBIENT_C = 20.0


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


# --- the sensor: a resumable stream ----------------------------------------------------------


def _turn_on_draw(run_seq: np.random.SeedSequence, sigma_deg_h: float) -> float:
    """This switch-on's bias b₀ ~ N(0, σ_on²), from the stream's fourth seed."""
    return float(np.random.Generator(np.random.PCG64(run_seq)).normal(0.0, 1.0) * sigma_deg_h)


def turn_on_bias_deg_h(preset: GyroPreset, seed: int) -> float:
    """The turn-on bias a :class:`GyroStream` of ``preset`` and ``seed`` has, without
    building the stream (its correlated components cost ~0.5 ms to set up).

    Parameters
    ----------
    preset : GyroPreset
        Its ``turn_on_bias_sigma_deg_h`` is σ_on.
    seed : int
        The stream's seed.

    Returns
    -------
    float
        b₀ (°/h), equal to ``GyroStream(preset, seed).turn_on_bias_deg_h``.
    """
    run_seq = np.random.SeedSequence(seed).spawn(4)[3]
    return _turn_on_draw(run_seq, preset.turn_on_bias_sigma_deg_h)


_COPY_SEED = np.random.SeedSequence(0)  # any: a copy's state is overwritten at once


def _generator_copy(rng: np.random.Generator) -> np.random.Generator:
    """A new generator at ``rng``'s state (its own bit generator, same kind)."""
    bits = type(rng.bit_generator)(_COPY_SEED)
    bits.state = rng.bit_generator.state
    return np.random.Generator(bits)


class GyroStream:
    """Sensor errors for consecutive samples; ``read(true_rates)`` consumes the next block."""

    def __init__(self, preset: GyroPreset, seed: int) -> None:
        self.preset = preset
        arw_seq, gm_seq, rrw_seq, run_seq = np.random.SeedSequence(seed).spawn(4)
        self._arw = np.random.Generator(np.random.PCG64(arw_seq))
        self._rrw = np.random.Generator(np.random.PCG64(rrw_seq))
        self.turn_on_bias_deg_h = _turn_on_draw(run_seq, preset.turn_on_bias_sigma_deg_h)
        dt = preset.dt_s
        terms = flicker_components(preset.bias_instability_deg_h, preset.flicker_band_s)
        if preset.markov_sigma_deg_h > 0 and preset.markov_corr_time_s > 0:
            terms.append((preset.markov_sigma_deg_h**2, preset.markov_corr_time_s))
        # one recursion per correlated component: (φ, σ, state, its own random stream)
        self._correlated = []
        children = gm_seq.spawn(len(terms))
        for (variance, corr), child in zip(terms, children, strict=True):
            rng = np.random.Generator(np.random.PCG64(child))
            sigma = math.sqrt(variance)
            state = float(rng.normal()) * sigma  # stationary start
            self._correlated.append([math.exp(-dt / corr), sigma, state, rng])
        self._rrw_state = 0.0
        self._angle = 0.0  # accumulated angle (deg) for quantisation
        self.samples_read = 0

    def copy(self) -> GyroStream:
        """An independent copy of the stream's state: it reads on exactly as this stream
        would, and reading either leaves the other as it was.

        Each random generator is rebuilt from its bit generator's state (≈ 20 µs each,
        ≈ 0.4 ms for the 21 of a tactical FOG) rather than through ``copy.deepcopy``,
        which pickles every generator (≈ 1.3–1.8 ms a stream); the preset, immutable,
        is shared.

        Returns
        -------
        GyroStream
            A stream at the same sample, with the same recursion states.
        """
        twin = object.__new__(GyroStream)
        twin.__dict__.update(self.__dict__)
        twin._arw, twin._rrw = _generator_copy(self._arw), _generator_copy(self._rrw)
        twin._correlated = [
            [phi, sigma, state, _generator_copy(rng)] for phi, sigma, state, rng in self._correlated
        ]
        return twin

    def _warmup_decay(self, count: int) -> np.ndarray:
        """e^(−t/τ_w) at the next ``count`` samples, t from switch-on."""
        seconds = (self.samples_read + np.arange(count)) * self.preset.dt_s
        return np.exp(-seconds / self.preset.warmup_time_constant_s)

    def temperatures_c(self, count: int, ambient_c: float = AMBIENT_C) -> np.ndarray:
        """Case temperature (°C) at the next ``count`` samples (call before ``read``):
        ambient + ΔT·(1 − e^(−t/τ_w)).  The warm-up bias follows it,
        b_w = −(b_0/ΔT)·(T − T_final) = b_0·e^(−t/τ_w)."""
        p = self.preset
        if not p.warmup_temperature_rise_c or p.warmup_time_constant_s <= 0:
            return np.full(count, ambient_c)
        return ambient_c + p.warmup_temperature_rise_c * (1.0 - self._warmup_decay(count))

    def read(self, true_rates: np.ndarray, g_component: np.ndarray | float = 0.0) -> np.ndarray:
        """Measured rates (°/h) for the next ``len(true_rates)`` samples."""
        p = self.preset
        true_rates = np.asarray(true_rates, dtype=float)
        n = true_rates.size
        rate = (1.0 + p.scale_factor_ppm * 1e-6) * true_rates
        rate = rate + p.constant_bias_deg_h + self.turn_on_bias_deg_h
        rate = rate + p.g_sensitivity_deg_h_per_g * np.asarray(g_component, dtype=float)
        if p.drift_deg_h_per_h:
            hours = (self.samples_read + np.arange(n)) * p.dt_s / SECONDS_PER_HOUR
            rate = rate + p.drift_deg_h_per_h * hours
        if p.warmup_bias_deg_h and p.warmup_time_constant_s > 0:
            rate = rate + p.warmup_bias_deg_h * self._warmup_decay(n)
        white = self._arw.standard_normal(n)
        if p.arw_deg_rt_h:
            rate = rate + p.white_sigma_deg_h * white
        if self._correlated and n:
            from scipy.signal import lfilter  # imported when first needed: ~1 s

            for component in self._correlated:
                phi, sigma, state, rng = component
                drive = sigma * math.sqrt(1.0 - phi * phi) * rng.standard_normal(n)
                values, _ = lfilter([1.0], [1.0, -phi], drive, zi=[phi * state])
                component[2] = float(values[-1])
                rate = rate + values
        if p.rrw_deg_h_rt_h and n:  # its own stream: not drawn when the preset has none
            rrw_noise = self._rrw.standard_normal(n)
            steps = p.rrw_deg_h_rt_h * math.sqrt(p.dt_s / SECONDS_PER_HOUR) * rrw_noise
            walk = np.cumsum(np.concatenate([[self._rrw_state], steps]))[1:]
            self._rrw_state = float(walk[-1])
            rate = rate + walk
        if p.angle_lsb_deg and n:
            dt_h = p.dt_s / SECONDS_PER_HOUR
            angle = np.cumsum(np.concatenate([[self._angle], rate * dt_h]))
            counts = np.diff(np.floor(angle / p.angle_lsb_deg))
            self._angle = float(angle[-1])
            rate = counts * p.angle_lsb_deg / dt_h
        self.samples_read += n
        return rate


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
