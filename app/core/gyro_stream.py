"""The gyro's sensor errors as a seeded, resumable stream (IEEE Std 952 error model).

Measured rate, each term switchable by setting it to zero:

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
* quantisation: the angle ∫ω dt is floored to the angle LSB and differenced.

The true rate Ω_vec·u and the turntable: :mod:`app.core.simulate`.

Reproducibility: every noise source has its own random stream spawned from the seed, all
recursions carry their state, and cumulative sums continue from the previous value, so
generating samples 0..n in one call or in any chunking gives bit-identical values, and a
live stream can be resumed by regenerating to its position -- or from a copy of its state
(:meth:`GyroStream.copy`).
"""

from __future__ import annotations

import math

import numpy as np

from app.core.flicker import flicker_components
from app.core.presets import GyroPreset
from app.core.units import SECONDS_PER_HOUR

AMBIENT_C = 20.0


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
