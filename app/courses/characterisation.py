"""A real gyro's Allan characterisation, uploaded by the teacher for an assignment.

The teacher records the bench's gyro at rest (ideally hours) and uploads the record, with
its sample rate or its times (the bridge's CSV: gaps and temperature too).  Gaps, spikes
and a warm-up are dealt with and said (:mod:`app.core.static_record`); the IEEE 952 terms
the curve resolves, with 68 % intervals, and bounds for the rest, are stored on the
assignment (:mod:`app.core.allan_fit`); from then on the position means of readings that
did not come from the simulated gyro (typed, CSV, API, the serial bridge) get their
covariance from that noise model -- ``uncertainty_model`` "allan" -- instead of assuming
white noise (lab-reference §3).
"""

from __future__ import annotations

import io
import json
import math
from dataclasses import dataclass
from datetime import UTC, datetime

import numpy as np

from app.core.allan import analyse_record
from app.core.exceptions import UserError
from app.core.flicker import DEFAULT_BAND_S
from app.core.matlab_files import is_matlab_file, matlab_record
from app.core.noise_model import GyroNoise
from app.core.numpy_files import is_npy, is_npz, numpy_record
from app.core.static_record import StaticRecord, read_static_record
from app.core.text_files import text_lines
from app.core.units import DEG_PER_HOUR, UNIT_SYMBOLS, canonical_unit
from app.core.workbook_sheets import is_workbook
from app.models import Assignment, utcnow

MAX_RATE_HZ = 10_000.0
MIN_RECORD_S = 600.0  # shorter records say little about the slow terms


@dataclass(frozen=True)
class StationNoise:
    """The characterised gyro: its noise model and the rate its readings come at."""

    noise: GyroNoise
    rate_hz: float


def _check_length(seconds: float) -> None:
    if not seconds >= MIN_RECORD_S:
        raise UserError(
            "characterisation.too_short",
            seconds=round(seconds) if math.isfinite(seconds) else 0,
            minimum=round(MIN_RECORD_S),
        )


def read_record(source, column: str | None = None) -> StaticRecord:
    """The static record in ``source`` (bytes or a binary file): a MATLAB data file's
    (:func:`app.core.matlab_files.matlab_record`), a NumPy array's or archive's
    (:func:`app.core.numpy_files.numpy_record`), else a text record's, read in blocks of
    lines (:func:`app.core.static_record.read_static_record`, lost readings kept for the
    preparation to mend)."""
    if isinstance(source, bytes | bytearray):
        source = io.BytesIO(source)
    magic = source.read(20)
    source.seek(0)
    if is_matlab_file(magic):
        return matlab_record(source.read(), column)
    if is_npy(magic):
        return numpy_record(source.read(), column)
    if is_workbook(magic):  # a zip: NumPy's archive (a workbook arrives as its text)
        data = source.read()
        if is_npz(data):
            return numpy_record(data, column)
        source.seek(0)
    return read_static_record(text_lines(source), column=column, finite=False)


def characterise(
    source, rate_hz: float | None, unit: str | None = None, column: str | None = None
) -> dict:
    """Fit the record's Allan deviation; the stored summary (JSON-ready).

    ``source`` is the record's bytes or a binary file (an upload spooled to disk), read in
    blocks of lines; ``rate_hz`` None takes the rate from the record's times; ``unit``
    None takes it from the record's header (else °/h); ``column`` names the rates' column
    (one axis of a multi-axis record)."""
    if rate_hz is not None and (
        not (isinstance(rate_hz, int | float) and math.isfinite(rate_hz))
        or not (0 < rate_hz <= MAX_RATE_HZ)
    ):
        raise UserError(
            "characterisation.bad_rate",
        )
    record = read_record(source, column)
    if rate_hz is not None:
        _check_length(record.values.size / rate_hz)
    elif record.times_s is not None and record.times_s.size > 1:
        _check_length(float(record.times_s[-1] - record.times_s[0]))
    result = analyse_record(record, rate_hz, unit=canonical_unit(unit) if unit else None)
    if not unit and any(note["key"] == "allan.note_unit_doubt" for note in result.notes):
        raise UserError(  # a unit read by default that no gyro's floor fits: ask, not store
            "characterisation.unit_doubt",
            floor=f"{result.adev_min_deg_h:.3g}",
            unit=UNIT_SYMBOLS[record.unit or DEG_PER_HOUR],
        )
    _check_length(result.samples / result.rate_hz)  # what is left after trimming
    if result.rate_hz > MAX_RATE_HZ:
        raise UserError(
            "characterisation.bad_rate",
        )
    noise = result.model_noise()  # the fitted curve's where the resolved terms leave out noise
    seconds = result.samples / result.rate_hz
    return {
        "rate_hz": result.rate_hz,
        "samples": result.samples,
        "record_s": float(seconds),
        "terms": {name: term.to_json() for name, term in result.terms.items()},
        "arw_deg_rt_h": noise.arw_deg_rt_h,
        "bias_instability_deg_h": noise.bias_instability_deg_h,
        "rrw_deg_h_rt_h": noise.rrw_deg_h_rt_h,
        "quantization_deg": result.quantization_deg,
        "flicker_band_s": list(noise.flicker_band_s),
        "markov_sigma_deg_h": noise.markov_sigma_deg_h,
        "markov_corr_time_s": noise.markov_corr_time_s,
        "sine_amplitude_deg_h": noise.sine_amplitude_deg_h,
        "sine_period_s": noise.sine_period_s,
        "ramp_deg_h_per_h": noise.ramp_deg_h_per_h,
        "dwell": result.dwell.to_json(),
        "recommended_dwell_s": result.dwell.recommended_s,
        "notes": result.notes,
        "uploaded_at": utcnow().strftime("%Y-%m-%d %H:%M"),
    }


def store(assignment: Assignment, summary: dict | None) -> None:
    assignment.gyro_characterisation = None if summary is None else json.dumps(summary)


def summary_of(assignment: Assignment | None, with_time: bool = False) -> dict | None:
    """The stored characterisation; ``with_time`` adds ``uploaded``, the upload's aware UTC
    datetime (stored as "YYYY-MM-DD HH:MM" UTC) for pages that show it in local time."""
    if assignment is None or not assignment.gyro_characterisation:
        return None
    summary = json.loads(assignment.gyro_characterisation)
    if with_time:
        try:
            uploaded = datetime.strptime(summary.get("uploaded_at", ""), "%Y-%m-%d %H:%M")
            summary["uploaded"] = uploaded.replace(tzinfo=UTC)
        except ValueError:
            summary["uploaded"] = None
    return summary


def station_noise(assignment: Assignment | None) -> StationNoise | None:
    """The assignment's characterised gyro, if the teacher uploaded one."""
    summary = summary_of(assignment)
    if summary is None:
        return None
    if "terms" not in summary:  # stored before bias instability was flicker noise: its B
        # was the Gauss–Markov peak / 0.664, the same floor
        summary.setdefault("flicker_band_s", list(DEFAULT_BAND_S))
    noise = GyroNoise(
        arw_deg_rt_h=summary["arw_deg_rt_h"],
        bias_instability_deg_h=summary["bias_instability_deg_h"],
        rrw_deg_h_rt_h=summary["rrw_deg_h_rt_h"],
        angle_lsb_deg=summary["quantization_deg"] * float(np.sqrt(12.0)),
        flicker_band_s=tuple(summary.get("flicker_band_s", DEFAULT_BAND_S)),
        markov_sigma_deg_h=summary.get("markov_sigma_deg_h", 0.0),
        markov_corr_time_s=summary.get("markov_corr_time_s", 0.0),
        sine_amplitude_deg_h=summary.get("sine_amplitude_deg_h", 0.0),
        sine_period_s=summary.get("sine_period_s", 0.0),
        ramp_deg_h_per_h=summary.get("ramp_deg_h_per_h", 0.0),
    )
    return StationNoise(noise, summary["rate_hz"])
