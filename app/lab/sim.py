"""The simulated gyro behind a lab session: secret truth, the virtual turntable, samples.

Everything is derived from the session's secret seed, so any server process produces the
same samples for the same take (what a process keeps, ``lab.gyro_history``, only saves
replaying the gyro's history), and nothing here is sent to the browser except measured
readings.
"""

from __future__ import annotations

import hashlib
import math
import secrets
from dataclasses import replace
from datetime import UTC, datetime
from functools import lru_cache

import numpy as np

from app.core.gyro_stream import turn_on_bias_deg_h
from app.core.presets import PRESETS
from app.core.simulate import axis_vectors, read_dial, true_rate
from app.lab.gyro_history import stream_after
from app.models import LabSession, utcnow

MAX_DWELL_S = 1800.0
MAX_SETTLE_S = 120.0
MAX_PAUSE_S = 1800.0  # a longer pause between recordings counts as 30 min of gyro time
POWER_CYCLE_S = 6 * 3600.0  # after 6 h of gyro time the timeline starts a new power cycle
READ_AHEAD = 1_024  # samples of a live recording's noise made at a time (≈ 1 ms)


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
    return _drawn_turn_on_bias(preset_for(session), derived_seed(session, "power-on"))


# The draw is a pure function of (preset, seed) and costs ≈ 0.1 ms (a SeedSequence spawned):
# the class dashboard asks it of every streamed session on every view.
_drawn_turn_on_bias = lru_cache(maxsize=4096)(turn_on_bias_deg_h)


def indexing_error_deg(session: LabSession, turn: int | str) -> float:
    """The error of the table's stop after turn number ``turn`` (0 = the start, exact;
    "plane" = the horizontal dial set for part B)."""
    if turn == 0:
        return 0.0
    preset = preset_for(session)
    rng = np.random.default_rng(derived_seed(session, "turn", turn))
    return float(rng.normal() * preset.indexing_sigma_arcsec / 3600.0)


FIRST_PASS = 4  # positions 1–4; with the symmetric order 5–8 revisit 4, 3, 2, 1


def position_count(session: LabSession) -> int:
    """4 positions per part, or 8 in the symmetric order 1-2-3-4-4-3-2-1."""
    return 2 * FIRST_PASS if session.symmetric_order else FIRST_PASS


def nominal_angle(session: LabSession, part: str, position: int) -> float:
    """The dial angle of ``position``; positions 5–8 of the symmetric order are those of
    4, 3, 2, 1 again (lab-reference §3: a linear drift then cancels)."""
    if position > FIRST_PASS:
        position = 2 * FIRST_PASS + 1 - position
    if part == "heading":
        sign = -1.0 if session.heading_rotation == "ccw" else 1.0
        return session.heading_start_deg + sign * 90.0 * (position - 1)
    return session.latitude_start_deg + session.latitude_step_deg * (position - 1)


def table_errors(session: LabSession) -> dict[str, float]:
    """The virtual turntable's pitch and roll and the gyro axis's misalignment from the dial
    zero (horizontal, vertical), degrees: drawn by an assignment, else from the session's
    seed and the preset's σ."""
    preset = preset_for(session)
    rng = np.random.default_rng(derived_seed(session, "table"))
    drawn = rng.normal(size=4)
    tilt, misalignment = preset.table_tilt_sigma_deg, preset.misalignment_sigma_deg
    values = {
        "pitch_deg": (session.sim_pitch_deg, drawn[0] * tilt),
        "roll_deg": (session.sim_roll_deg, drawn[1] * tilt),
        "misalign_h_deg": (session.sim_misalign_h_deg, drawn[2] * misalignment),
        "misalign_v_deg": (session.sim_misalign_v_deg, drawn[3] * misalignment),
    }
    return {
        key: float(stored if stored is not None else own) for key, (stored, own) in values.items()
    }


def plane_dial_deg(session: LabSession) -> float:
    """Part B's vertical plane: where the student set the horizontal dial for it, else where
    the table stands at the end of part A (° clockwise from heading position 1)."""
    if session.sim_plane_dial_deg is not None:
        return session.sim_plane_dial_deg
    return nominal_angle(session, "heading", session.sim_table_heading) - session.heading_start_deg


def north_dial_deg(session: LabSession, azimuth_1_deg: float, angle_1_deg: float) -> float:
    """The horizontal dial (° clockwise from heading position 1, in (−180, 180]) that points
    the axis north when position 1, at dial angle ``angle_1_deg``, has azimuth
    ``azimuth_1_deg`` (the handout's step 4: turn by θ, then the axis points north)."""
    turn = angle_1_deg - azimuth_1_deg - session.heading_start_deg
    return -((-turn + 180.0) % 360.0 - 180.0)


def gyro_clock_s(session: LabSession, now: datetime | None = None) -> float:
    """Seconds since the session's simulated gyro was switched on.  The clock runs with the
    wall clock between recordings (turning the table, waiting), a pause longer than
    ``MAX_PAUSE_S`` counting as that long: the gyro stays on."""
    if session.sim_clock_at is None:
        return session.sim_clock_s
    now = now or utcnow()
    at = session.sim_clock_at
    if at.tzinfo is None:
        at = at.replace(tzinfo=UTC)
    elapsed = (now - at).total_seconds()
    return session.sim_clock_s + min(max(elapsed, 0.0), MAX_PAUSE_S)


def set_gyro_clock(session: LabSession, gyro_s: float, now: datetime | None = None) -> None:
    session.sim_clock_s = float(gyro_s)
    session.sim_clock_at = now or utcnow()


WARM_AFTER_TIME_CONSTANTS = 5.0  # e^(−5): the warm-up bias has fallen below 1 %
MAX_WAIT_S = 3600.0


def warm_up_state(session: LabSession, now: datetime | None = None) -> dict:
    """How long the session's simulated gyro has been on and how long until it is warm
    (five warm-up time constants of its preset after switch-on), in whole minutes."""
    preset = preset_for(session)
    on_s = gyro_clock_s(session, now)
    warm_s = WARM_AFTER_TIME_CONSTANTS * preset.warmup_time_constant_s
    left_s = max(0.0, warm_s - on_s) if preset.warmup_bias_deg_h else 0.0
    return {
        "on_minutes": int(on_s // 60),
        "warm_minutes": math.ceil(warm_s / 60),
        "left_minutes": math.ceil(left_s / 60),
        "warm": left_s <= 0,
    }


def wait_for_gyro(session: LabSession, seconds: float, now: datetime | None = None) -> float:
    """Let the simulated gyro run on for ``seconds`` (0 < s ≤ 1 h) without recording: its
    clock, and so its warm-up, advances.  Returns the new gyro time (s since switch-on)."""
    if not (math.isfinite(seconds) and 0 < seconds <= MAX_WAIT_S):
        raise ValueError("wait between 0 and 3600 s")
    gyro = gyro_clock_s(session, now) + seconds
    set_gyro_clock(session, gyro, now)
    return gyro


class SimulatedTake:
    """Samples of one recording from the session's one simulated gyro.

    The gyro's noise is a single timeline per power cycle (``POWER_CYCLE_S``), generated
    from the session's seed: a recording that starts at gyro time t regenerates the noise
    state up to t (slow bias, random walk and warm-up carry over from every earlier
    recording, the turns and the waits in between), then produces its samples.  Sample
    times are gyro seconds since switch-on, one clock for every position and both parts.
    """

    def __init__(
        self,
        session: LabSession,
        part: str,
        position: int,
        settle_s: float = 0.0,
        *,
        start_s: float | None = None,
        dwell_s: float = 0.0,
    ) -> None:
        """``dwell_s``: the recording's length, whose noise is made here (a live recording
        builds its take in the thread pool: made later, frame by frame, the noise would be
        the event loop's work, ≈ 1 ms a position that holds up every student's frames)."""
        preset = preset_for(session)
        self.preset = preset
        self.rate_hz = preset.sample_rate_hz
        clock = gyro_clock_s(session) if start_s is None else start_s
        begin = int(math.ceil((clock + settle_s) * self.rate_hz - 1e-9))
        cycle, index = divmod(begin, int(POWER_CYCLE_S * self.rate_hz))
        self.first_index = begin
        # the gyro's history since switch-on (slow bias, random walk and warm-up carry over
        # from every earlier recording, the turns and the waits in between)
        self.stream = stream_after(
            preset, derived_seed(session, "gyro", cycle), turn_on_bias(session), index
        )
        table = table_errors(session)
        nominal = nominal_angle(session, part, position)
        actual = nominal + indexing_error_deg(session, session.sim_turns)
        self.dial_angle_deg = read_dial(nominal, preset.dial_resolution_deg)
        if part == "heading":
            # dial angles are relative to position 1, which points at the secret azimuth
            horizontal = actual - session.heading_start_deg
            elevation = 0.0
        else:
            plane = plane_dial_deg(session)
            horizontal = plane + indexing_error_deg(session, f"plane {plane}")
            elevation = actual
        vector = axis_vectors(
            session.sim_azimuth_deg,
            horizontal + table["misalign_h_deg"],
            elevation + table["misalign_v_deg"],
            table["pitch_deg"],
            table["roll_deg"],
        )
        self.true_rate = float(true_rate(session.latitude_deg, vector, session.earth_rate_deg_h))
        self.up = float(vector[2])
        self.produced = 0
        self._ahead, self._used = np.empty(0), 0  # noise made ahead, and how much is used
        if dwell_s > 0:
            self._ahead = self._read(self.samples_in(dwell_s))

    def samples_in(self, dwell_s: float) -> int:
        """How many samples a recording of ``dwell_s`` seconds holds (at least one)."""
        return max(1, int(round(dwell_s * self.rate_hz)))

    def _read(self, count: int) -> np.ndarray:
        return self.stream.read(np.full(count, self.true_rate), self.up)

    @property
    def end_s(self) -> float:
        """Gyro time after the last sample produced."""
        return (self.first_index + self.produced) / self.rate_hz

    def next(self, count: int) -> tuple[np.ndarray, np.ndarray]:
        """The next ``count`` samples and their gyro times (s since switch-on).

        The gyro's noise is made ahead -- the whole recording's when the take was built
        with its ``dwell_s``, past that ``READ_AHEAD`` samples at a time -- and handed out
        in the pieces asked for: a live recording asks for a few samples per frame, and
        making them frame by frame cost a numpy call per noise component (19 for the
        tactical FOG) each time -- ≈ 1.2 s of the 60-student class's ≈ 16 s of server CPU
        (bench/README.md).  The samples are the same, however they are cut
        (``GyroStream`` reads any chunking identically)."""
        while self._ahead.size - self._used < count:
            block = max(READ_AHEAD, count - (self._ahead.size - self._used))
            self._ahead = np.concatenate([self._ahead[self._used :], self._read(block)])
            self._used = 0
        values = self._ahead[self._used : self._used + count]
        self._used += count
        times = (self.first_index + self.produced + np.arange(count)) / self.rate_hz
        self.produced += count
        return values, times
