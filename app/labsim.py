"""The simulated gyro behind a lab session: secret truth, the virtual turntable, samples.

Everything is derived from the session's secret seed, so any server process produces the
same samples for the same take (no per-process state), and nothing here is sent to the
browser except measured readings.
"""

from __future__ import annotations

import hashlib
import secrets
from dataclasses import replace

import numpy as np

from app.core.simulate import PRESETS, GyroStream, axis_vectors, read_dial, true_rate
from app.models import LabSession

MAX_DWELL_S = 1800.0
MAX_SETTLE_S = 120.0


def new_truth() -> tuple[int, float]:
    """A random seed and a random true azimuth of heading position 1."""
    seed = secrets.randbits(62)
    azimuth = secrets.randbelow(360_000) / 1000.0
    return seed, azimuth


def derived_seed(session: LabSession, *labels: object) -> int:
    text = ":".join(str(x) for x in (session.sim_seed, *labels))
    return int.from_bytes(hashlib.sha256(text.encode()).digest()[:8], "little") >> 2


def preset_for(session: LabSession):
    """The session's gyro, with an assignment's indexing-error override applied."""
    preset = PRESETS.get(session.simulator_preset, PRESETS["teaching-fog"])
    if session.sim_indexing_sigma_arcsec is not None:
        preset = replace(preset, indexing_sigma_arcsec=session.sim_indexing_sigma_arcsec)
    return preset


def turn_on_bias(session: LabSession) -> float:
    """The session's turn-on bias: drawn by its assignment, else by the preset's model."""
    if session.sim_turn_on_bias_deg_h is not None:
        return session.sim_turn_on_bias_deg_h
    return GyroStream(preset_for(session), derived_seed(session, "power-on")).turn_on_bias_deg_h


def indexing_error_deg(session: LabSession, turn: int) -> float:
    """The error of the table's stop after turn number ``turn`` (0 = the start, exact)."""
    if turn == 0:
        return 0.0
    preset = preset_for(session)
    rng = np.random.default_rng(derived_seed(session, "turn", turn))
    return float(rng.normal() * preset.indexing_sigma_arcsec / 3600.0)


def nominal_angle(session: LabSession, part: str, position: int) -> float:
    if part == "heading":
        sign = -1.0 if session.heading_rotation == "ccw" else 1.0
        return session.heading_start_deg + sign * 90.0 * (position - 1)
    return session.latitude_start_deg + session.latitude_step_deg * (position - 1)


class SimulatedTake:
    """Samples of one simulated recording, generated block by block on demand."""

    def __init__(
        self, session: LabSession, part: str, position: int, attempt: int, settle_s: float
    ) -> None:
        preset = preset_for(session)
        turn_on = turn_on_bias(session)
        self.preset = preset
        self.stream = GyroStream(preset, derived_seed(session, part, position, attempt))
        self.stream.turn_on_bias_deg_h = turn_on  # one power-on per session
        nominal = nominal_angle(session, part, position)
        actual = nominal + indexing_error_deg(session, session.sim_turns)
        self.dial_angle_deg = read_dial(nominal, preset.dial_resolution_deg)
        if part == "heading":
            # dial angles are relative to position 1, which points at the secret azimuth
            vector = axis_vectors(session.sim_azimuth_deg, actual - session.heading_start_deg, 0.0)
        else:
            vector = axis_vectors(0.0, 0.0, actual)
        self.true_rate = float(true_rate(session.latitude_deg, vector, session.earth_rate_deg_h))
        self.up = float(vector[2])
        self.rate_hz = preset.sample_rate_hz
        self.skip = int(round(settle_s * self.rate_hz))
        self.produced = 0
        if self.skip:
            self.stream.read(np.full(self.skip, self.true_rate), self.up)

    def next(self, count: int) -> tuple[np.ndarray, np.ndarray]:
        """The next ``count`` samples and their times (s since recording started)."""
        values = self.stream.read(np.full(count, self.true_rate), self.up)
        times = (self.skip + self.produced + np.arange(count)) / self.rate_hz
        self.produced += count
        return values, times
